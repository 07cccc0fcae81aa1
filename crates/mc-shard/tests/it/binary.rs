//! The `mc-shard` binary as the tests run it (this test binary's own: truss-mc's tests
//! share `common` by path, where `CARGO_BIN_EXE_mc-shard` is not defined).

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `mc-shard` binary with `args` (the environment as inherited).
pub fn mc_shard(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mc-shard"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs shard `shard` (`I/K`) of `job` into `out`, quietly, and asserts it succeeded.
pub fn run_shard(job: &Path, out: &Path, shard: &str) {
    let o = mc_shard(&[
        "run",
        "--job",
        job.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--shard",
        shard,
        "-q",
    ]);
    assert!(
        o.status.success(),
        "shard {shard}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}
