//! What a hostile neighbour leaves in a shared run directory, for the tests of every crate
//! that writes or reads one (crate `run-dir`'s rules): a user's file that a planted link
//! points at, a FIFO, and running a binary under a memory limit and a deadline, so that a
//! regression (reading `/dev/zero` whole, waiting on a FIFO) fails the test instead of
//! taking the machine. Included by path (`#[path = …] mod hostile;`) from each crate's
//! integration tests.

#![allow(dead_code)]

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// What a user's file holds.
pub const THEIRS: &str = "the user's own file";

/// A user's file in `dir`, for a planted link to point at.
pub fn precious(dir: &Path) -> PathBuf {
    let p = dir.join("precious.txt");
    std::fs::write(&p, THEIRS).unwrap();
    p
}

/// Asserts the user's file `p` still holds what it held.
pub fn assert_untouched(p: &Path) {
    let text = std::fs::read_to_string(p).unwrap();
    assert!(text == THEIRS, "{} was written through a link", p.display());
}

/// A FIFO `name` in `dir` (made with `mkfifo`).
pub fn fifo(dir: &Path, name: &str) -> PathBuf {
    let p = dir.join(name);
    let made = Command::new("mkfifo").arg(&p).status().unwrap();
    assert!(made.success(), "mkfifo {}", p.display());
    p
}

/// A finished command's exit code and stderr.
pub fn code(o: &Output) -> (Option<i32>, String) {
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Runs `program` with `args` under a 2 GB address-space limit and a 30 s deadline (a
/// panic past it); returns its exit code and stderr.
pub fn run_bounded<S: AsRef<OsStr>>(program: &Path, args: &[S]) -> (Option<i32>, String) {
    let mut child = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 2000000; exec \"$0\" \"$@\"")
        .arg(program)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > Duration::from_secs(30) {
            child.kill().unwrap();
            panic!("{} did not finish in 30 s", program.display());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = child.wait_with_output().unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Runs `program` with `args` and its stdout on `/dev/full` (every write fails: a full
/// disk); returns its exit code and stderr.
pub fn run_into_full<S: AsRef<OsStr>>(program: &Path, args: &[S]) -> (Option<i32>, String) {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    code(
        &Command::new(program)
            .args(args)
            .stdout(full)
            .output()
            .unwrap(),
    )
}
