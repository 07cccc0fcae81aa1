//! The README runs as pasted: its ```sh and ```python blocks, in order, in a clean shell in a
//! fresh copy of the repository, with nothing rewritten.
//!
//! [`readme_runs_as_pasted`] (slow, ignored by a plain `cargo test`; `scripts/test.sh` runs
//! it) copies the repository's files as a clone would have them (`git ls-files`: tracked
//! and new files, nothing ignored) into `target/readme-test/clone` (its `target/` is kept
//! from the last run, as a build cache, and nothing else; or, under `scripts/test.sh`, its
//! `target/release` is a copy of the test command's own build: [`seed_release_build`]), and
//! runs one `bash` there with an empty environment but `HOME`, `LANG=C.UTF-8`, a `PATH` of
//! the system's directories and the user's cargo, and that build's settings when it was
//! given: the only set-up is what the README itself says (its own `PATH`
//! line, its own virtual environment). Each ```sh block is pasted as it is; each ```python
//! block is given to the `python` that shell finds at that point. The one change to the
//! clone: `jobs/paper-3.1.json` holds the paper's job with 2,000 samples per case instead
//! of 50,000 (same model, seed and cases), so that the Monte Carlo takes seconds; every
//! command is the README's, byte for byte. It fails on the first command that exits other
//! than 0 (naming its README line), if a file is left outside `runs/` (and the build's
//! `target/`), or if an output the README promises is missing: the main command ending with
//! the path of `report.html`, a rerun saying it reused every shard, the reports, the
//! diagnosis, the tolerance study.
//!
//! Not run, only checked (a list in [`not_run`], each with its reason): the test command
//! itself, the benchmarks, and the clients of clusters and clouds a test cannot reach
//! (Slurm with its shared directory, Kubernetes, AWS Batch, Google Cloud Batch, HTCondor):
//! [`readme_commands_are_checked`] (fast) checks that each file they name exists, that a
//! script names every flag used, and that no command anywhere writes outside `runs/`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// A fenced block of the README: its language, the README line of its first line, its text.
struct Block {
    lang: String,
    line: usize,
    text: String,
}

/// The README's ```sh and ```python blocks, in order.
fn blocks() -> Vec<Block> {
    let text = std::fs::read_to_string(root().join("README.md")).unwrap();
    let mut out = Vec::new();
    let mut open: Option<Block> = None;
    for (n, line) in text.lines().enumerate() {
        if let Some(fence) = line.trim_start().strip_prefix("```") {
            match open.take() {
                Some(b) => {
                    if b.lang == "sh" || b.lang == "python" {
                        out.push(b);
                    }
                }
                None => {
                    open = Some(Block {
                        lang: fence.trim().to_string(),
                        line: n + 2,
                        text: String::new(),
                    })
                }
            }
            continue;
        }
        if let Some(b) = &mut open {
            b.text.push_str(line);
            b.text.push('\n');
        }
    }
    out
}

/// A command of a ```sh block: its first README line and its words (continuation lines
/// joined, the comment dropped).
struct Cmd {
    line: usize,
    text: String,
}

impl Cmd {
    fn words(&self) -> Vec<&str> {
        self.text.split_whitespace().collect()
    }
}

/// The commands of a ```sh block.
fn commands(b: &Block) -> Vec<Cmd> {
    let mut out = Vec::new();
    let mut current = String::new();
    let mut first = 0;
    for (k, line) in b.text.lines().enumerate() {
        let code = match line.find(" #") {
            Some(at) => &line[..at],
            None if line.trim_start().starts_with('#') => "",
            None => line,
        };
        if current.is_empty() {
            first = b.line + k;
        }
        if let Some(part) = code.trim_end().strip_suffix('\\') {
            current.push_str(part.trim());
            current.push(' ');
            continue;
        }
        current.push_str(code.trim());
        if !current.trim().is_empty() {
            out.push(Cmd {
                line: first,
                text: current.trim().to_string(),
            });
        }
        current.clear();
    }
    out
}

/// Why a command is not run by [`readme_runs_as_pasted`], if it is not.
fn not_run(words: &[&str]) -> Option<&'static str> {
    let first = *words.first()?;
    Some(match first {
        "scripts/test.sh" => "the test command itself, which runs this test",
        "cargo" if words.get(1) == Some(&"bench") => "a benchmark: minutes of timing",
        f if f.starts_with("scripts/bench-") => "a benchmark: minutes of timing",
        f if f.starts_with("scripts/slurm/") => {
            "needs a Slurm cluster and its shared directory (scripts/slurm/e2e-test.sh runs these scripts on a local one)"
        }
        "kubectl" => "needs a Kubernetes cluster",
        "aws" => "needs AWS Batch",
        "gcloud" => "needs Google Cloud Batch",
        "condor_submit_dag" => "needs an HTCondor pool",
        _ => return None,
    })
}

/// The flags (`--x`, `--x=…`) of `words`.
fn flags<'a>(words: &[&'a str]) -> Vec<&'a str> {
    words
        .iter()
        .filter(|w| w.starts_with("--") && w.len() > 2)
        .map(|w| w.split('=').next().unwrap())
        .collect()
}

/// Where a command writes (`> FILE`, `--out DIR`, `-o FILE`, `--export FILE`,
/// `--members-out FILE`), as written.
fn outputs<'a>(words: &[&'a str]) -> Vec<&'a str> {
    words
        .windows(2)
        .filter(|w| [">", "--out", "-o", "--export", "--members-out"].contains(&w[0]))
        .map(|w| w[1])
        .collect()
}

/// Every README command is one this test runs or checks; the ones not run name existing
/// files and flags; nothing writes outside `runs/` (the clusters' shared directories apart);
/// no optional flag is written in brackets inside a command.
#[test]
fn readme_commands_are_checked() {
    let blocks = blocks();
    assert!(
        blocks.iter().filter(|b| b.lang == "python").count() >= 3,
        "the README's Python blocks"
    );
    let mut run = 0;
    for b in blocks.iter().filter(|b| b.lang == "sh") {
        for c in commands(b) {
            let words = c.words();
            let at = format!("README.md:{}: `{}`", c.line, c.text);
            assert!(
                !c.text.contains("[-") && !c.text.contains('<') || not_run(&words).is_some(),
                "{at}: an optional flag or a placeholder in a command that runs; put it in prose"
            );
            for out in outputs(&words) {
                assert!(
                    out.starts_with("runs/") || out.starts_with("/shared/"),
                    "{at}: writes {out}, outside runs/"
                );
            }
            let Some(_) = not_run(&words) else {
                run += 1;
                continue;
            };
            let first = words[0];
            if first.starts_with("scripts/") {
                let path = root().join(first);
                let meta = std::fs::metadata(&path).unwrap_or_else(|_| panic!("{at}: no {first}"));
                use std::os::unix::fs::PermissionsExt;
                assert!(
                    meta.permissions().mode() & 0o111 != 0,
                    "{at}: not executable"
                );
                let text = std::fs::read_to_string(&path).unwrap();
                // Flags after a lone `--` belong to the batch system.
                let own: Vec<&str> = words.iter().take_while(|w| **w != "--").copied().collect();
                for flag in flags(&own) {
                    assert!(text.contains(flag), "{at}: {first} has no {flag}");
                }
            } else if first != "cargo" {
                let files: Vec<&str> = words
                    .iter()
                    .map(|w| {
                        w.trim_start_matches("file://")
                            .trim_start_matches("--config=")
                    })
                    .filter(|w| w.starts_with("jobs/"))
                    .collect();
                assert!(
                    !files.is_empty() || words.contains(&"wait"),
                    "{at}: names no file of jobs/"
                );
                for f in files {
                    assert!(root().join(f).is_file(), "{at}: no {f}");
                }
            }
        }
    }
    assert!(run >= 25, "{run} commands run");
}

/// `scripts/test.sh --help` says what the test command runs, what it installs and how long
/// it takes, and runs nothing: given a `PATH` of only `bash`, `sed` and `dirname`, it prints
/// its header and exits 0 with nothing on stderr (a phase started would announce itself
/// there, and installing or building would fail without its tools); an argument it does not
/// know is refused (exit 2) the same way.
#[test]
fn test_command_help_runs_nothing() {
    let bin = tempfile::tempdir().unwrap();
    for tool in ["bash", "sed", "dirname"] {
        let found = ["/usr/bin", "/bin"]
            .iter()
            .map(|d| Path::new(d).join(tool))
            .find(|p| p.is_file())
            .unwrap_or_else(|| panic!("no {tool}"));
        std::os::unix::fs::symlink(found, bin.path().join(tool)).unwrap();
    }
    let run = |arg: &str| {
        Command::new(root().join("scripts/test.sh"))
            .arg(arg)
            .current_dir(bin.path())
            .env_clear()
            .env("PATH", bin.path())
            .output()
            .unwrap()
    };
    let o = run("--help");
    let (out, err) = (
        String::from_utf8(o.stdout).unwrap(),
        String::from_utf8(o.stderr).unwrap(),
    );
    assert!(
        o.status.success() && err.is_empty(),
        "{:?}: {err}",
        o.status
    );
    let said = out.split_whitespace().collect::<Vec<_>>().join(" ");
    for step in [
        "1. Build",
        "2. The tests",
        "3. The Python",
        "4. The end-to-end",
        "5. The README",
    ] {
        assert!(said.contains(step), "--help names no step {step:?}:\n{out}");
    }
    for installs in ["apt-get", "chromium", "slurmctld", "PyPI", "target/py-venv"] {
        assert!(
            said.contains(installs),
            "--help does not say it installs {installs}:\n{out}"
        );
    }
    assert!(
        said.contains("Takes about")
            && said.contains("from a clean clone")
            && said.contains("once built"),
        "--help says not how long:\n{out}"
    );
    assert!(!said.contains("WARM_"), "a placeholder in --help:\n{out}");
    let o = run("--fast");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8(o.stderr).unwrap();
    assert!(
        err.starts_with("test.sh: takes no arguments (got: --fast)"),
        "{err}"
    );
}

/// The files of the repository as a clone has them: tracked and new, none ignored.
fn repository_files() -> Vec<PathBuf> {
    let out = Command::new("git")
        .args([
            "ls-files",
            "-z",
            "--cached",
            "--others",
            "--exclude-standard",
        ])
        .current_dir(root())
        .output()
        .expect("git runs");
    assert!(out.status.success());
    out.stdout
        .split(|&b| b == 0)
        .filter(|p| !p.is_empty())
        .map(|p| PathBuf::from(String::from_utf8(p.to_vec()).unwrap()))
        .filter(|p| root().join(p).is_file())
        .collect()
}

/// Every file under `dir` (relative), but those under `skip`.
fn files_under(dir: &Path, skip: &[&str]) -> BTreeSet<PathBuf> {
    fn walk(dir: &Path, base: &Path, skip: &[&str], out: &mut BTreeSet<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(base).unwrap().to_path_buf();
            if skip.iter().any(|s| rel.starts_with(s)) {
                continue;
            }
            if p.is_dir() && !p.is_symlink() {
                walk(&p, base, skip, out);
            } else {
                out.insert(rel);
            }
        }
    }
    let mut out = BTreeSet::new();
    walk(dir, dir, skip, &mut out);
    out
}

/// A fresh copy of the repository in `target/readme-test/clone`, keeping its `target/`.
fn fresh_clone() -> PathBuf {
    let clone = root().join("target/readme-test/clone");
    std::fs::create_dir_all(&clone).unwrap();
    for e in std::fs::read_dir(&clone).unwrap() {
        let p = e.unwrap().path();
        if p.file_name() == Some("target".as_ref()) {
            continue;
        }
        if p.is_dir() && !p.is_symlink() {
            std::fs::remove_dir_all(&p).unwrap();
        } else {
            std::fs::remove_file(&p).unwrap();
        }
    }
    // Each copy keeps its file's modification time, so that the kept build rebuilds only
    // the crates whose files changed since (a new time on every file rebuilt them all).
    for f in repository_files() {
        let (from, to) = (root().join(&f), clone.join(&f));
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(&from, &to).unwrap();
        let modified = std::fs::metadata(&from).unwrap().modified().unwrap();
        std::fs::File::options()
            .write(true)
            .open(&to)
            .unwrap()
            .set_modified(modified)
            .unwrap();
    }
    // The paper's job, 2,000 samples per case: the README's commands unchanged, seconds of
    // Monte Carlo.
    let path = clone.join("jobs/paper-3.1.json");
    let mut job: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    for case in job["cases"].as_array_mut().unwrap() {
        case["samples"] = 2000.into();
    }
    std::fs::write(&path, serde_json::to_string_pretty(&job).unwrap()).unwrap();
    clone
}

/// The script: each block as pasted, the commands [`not_run`] left out (as comments), each
/// block announced on stdout and stderr; the first failure names its script line.
fn script(blocks: &[Block]) -> (String, Vec<usize>) {
    let mut s = String::from(
        "set -eE -o pipefail\n\
         trap 'echo \"readme-test: FAILED (exit $?) at script line $LINENO: $BASH_COMMAND\" >&2' ERR\n",
    );
    // The README line of each script line (0: not the README's).
    let mut lines = vec![0, 0];
    let mut push = |s: &mut String, text: &str, readme: usize| {
        s.push_str(text);
        s.push('\n');
        lines.push(readme);
    };
    for b in blocks {
        // Announced with the seconds since the start, so the log shows each block's time.
        let mark = format!("=== README.md:{} ({}) at ${{SECONDS}} s", b.line, b.lang);
        push(&mut s, &format!("echo \"{mark}\"; echo \"{mark}\" >&2"), 0);
        if b.lang == "python" {
            push(&mut s, "python - <<'README_PYTHON_BLOCK'", b.line);
            for (k, l) in b.text.lines().enumerate() {
                push(&mut s, l, b.line + k);
            }
            push(&mut s, "README_PYTHON_BLOCK", b.line);
            continue;
        }
        let skipped: BTreeSet<usize> = commands(b)
            .iter()
            .filter(|c| not_run(&c.words()).is_some())
            .map(|c| c.line)
            .collect();
        for (k, l) in b.text.lines().enumerate() {
            if skipped.contains(&(b.line + k)) {
                assert!(!l.trim_end().ends_with('\\'), "README.md:{}", b.line + k);
                push(&mut s, &format!("# not run here: {l}"), 0);
            } else {
                push(&mut s, l, b.line + k);
            }
        }
    }
    (s, lines)
}

/// The user's cargo, as rustup puts it on `PATH` (else the one running this test).
fn cargo_dir() -> PathBuf {
    let home = std::env::var_os("HOME")
        .map(PathBuf::from)
        .unwrap_or_default();
    let rustup = home.join(".cargo/bin");
    if rustup.join("cargo").is_file() {
        return rustup;
    }
    let cargo = std::env::var_os("CARGO").expect("cargo runs the tests");
    Path::new(&cargo).parent().unwrap().to_path_buf()
}

/// The text between the marks of the block at README line `line` and the next.
fn section(log: &str, line: usize) -> &str {
    let mark = format!("=== README.md:{line} (");
    let start = log
        .find(&mark)
        .unwrap_or_else(|| panic!("no block at line {line}"));
    let rest = &log[start..];
    let body = &rest[rest.find('\n').map_or(rest.len(), |n| n + 1)..];
    &body[..body.find("=== README.md:").unwrap_or(body.len())]
}

/// The build settings `scripts/test.sh` compiles with (the release profile with debug
/// assertions on and no line tables, the workspace through clippy-driver, the Python PyO3
/// configures for): cargo's fingerprints include them, so a copy given the build must be
/// given them too.
const BUILD_SETTINGS: [&str; 6] = [
    "CARGO_PROFILE_RELEASE_DEBUG_ASSERTIONS",
    "CARGO_PROFILE_RELEASE_OVERFLOW_CHECKS",
    "CARGO_PROFILE_RELEASE_DEBUG",
    "RUSTC_WORKSPACE_WRAPPER",
    "CLIPPY_ARGS",
    "PYO3_PYTHON",
];

/// When `TRUSS_README_BUILD` names a release build of this repository (`scripts/test.sh`
/// gives its own, `target/ci/release`), the copy's `target/release` becomes a copy of it, and
/// the settings it was built with ([`BUILD_SETTINGS`], those set here) are returned for the
/// copy's shell: cargo's fingerprints hold a workspace crate's path relative to the workspace
/// and its files' times, which the copy keeps, so the README's `cargo build --release` finds
/// every crate built and compiles nothing that this build compiled (a file changed since
/// would be rebuilt, as in any checkout). Without it the copy builds for itself, as a fresh
/// clone does. A copy, not links: the copy's cargo rewrites some of its files.
fn seed_release_build(clone: &Path) -> Vec<(String, std::ffi::OsString)> {
    let Some(build) = std::env::var_os("TRUSS_README_BUILD") else {
        return Vec::new();
    };
    let build = PathBuf::from(build);
    assert!(
        build.join(".fingerprint").is_dir(),
        "TRUSS_README_BUILD={}: not a cargo build directory",
        build.display()
    );
    let release = clone.join("target/release");
    if release.exists() {
        std::fs::remove_dir_all(&release).unwrap();
    }
    std::fs::create_dir_all(clone.join("target")).unwrap();
    let status = Command::new("cp")
        .args(["-a", "--reflink=auto"])
        .arg(&build)
        .arg(&release)
        .status()
        .expect("cp runs");
    assert!(status.success(), "copying {} failed", build.display());
    BUILD_SETTINGS
        .iter()
        .filter_map(|k| Some((k.to_string(), std::env::var_os(k)?)))
        .collect()
}

/// The README's blocks, in order, in a clean shell in a fresh copy of the repository (see
/// the module doc).
#[test]
#[ignore = "slow: builds the release binaries and the Python package in a copy of the repository (minutes the first time); scripts/test.sh runs it"]
fn readme_runs_as_pasted() {
    let blocks = blocks();
    let clone = fresh_clone();
    let settings = seed_release_build(&clone);
    let before = files_under(&clone, &["target"]);
    let (text, lines) = script(&blocks);
    let dir = root().join("target/readme-test");
    std::fs::write(dir.join("readme.sh"), &text).unwrap();
    let path = format!(
        "{}:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin",
        cargo_dir().display()
    );
    let stdout = std::fs::File::create(dir.join("stdout.log")).unwrap();
    let stderr = std::fs::File::create(dir.join("stderr.log")).unwrap();
    let started = std::time::Instant::now();
    let status = Command::new("bash")
        .args(["--noprofile", "--norc"])
        .arg(dir.join("readme.sh"))
        .current_dir(&clone)
        .env_clear()
        .env("HOME", std::env::var_os("HOME").unwrap_or_default())
        .env("LANG", "C.UTF-8")
        .env("PATH", path)
        .envs(settings)
        .stdin(std::process::Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .status()
        .unwrap();
    let out = std::fs::read_to_string(dir.join("stdout.log")).unwrap();
    let err = std::fs::read_to_string(dir.join("stderr.log")).unwrap();
    if !status.success() {
        let at = err
            .lines()
            .rev()
            .find_map(|l| l.split("at script line ").nth(1))
            .and_then(|l| l.split(':').next()?.parse::<usize>().ok())
            .map_or(0, |n| lines.get(n - 1).copied().unwrap_or(0));
        let tail: Vec<&str> = err.lines().rev().take(40).collect();
        panic!(
            "the README fails as pasted at README.md:{at} ({status}; logs in {}):\n{}",
            dir.display(),
            tail.into_iter().rev().collect::<Vec<_>>().join("\n")
        );
    }
    eprintln!(
        "readme-test: every block ran in {:.0} s",
        started.elapsed().as_secs_f64()
    );
    // Nothing written outside runs/ (and the build's target/).
    let after = files_under(&clone, &["target", "runs"]);
    let left: Vec<&PathBuf> = after.difference(&before).collect();
    assert!(left.is_empty(), "files left outside runs/: {left:?}");
    // What the README promises. The main command ends with the report's path; its rerun
    // reuses every shard.
    let main = blocks
        .iter()
        .find(|b| {
            b.text
                .contains("cargo run --release -p truss-mc -- run-all")
        })
        .unwrap();
    assert_eq!(
        section(&out, main.line).lines().last(),
        Some("report: runs/paper-3.1/report/report.html"),
        "{}",
        section(&out, main.line)
    );
    assert!(
        section(&out, main.line)
            .contains("\nanswer: θ_P95 against the target 9.69e-5 rad (19.99″):"),
        "{}",
        section(&out, main.line)
    );
    let rerun = blocks
        .iter()
        .find(|b| b.text.contains("cargo build --release --workspace"))
        .unwrap();
    assert!(
        section(&err, rerun.line).contains("shards complete (verified, not rerun)"),
        "{}",
        section(&err, rerun.line)
    );
    for f in [
        "runs/paper-3.1/report/report.html",
        "runs/paper-3.1/report/report.md",
        "runs/p31/report/report.json",
        "runs/p31-samples.csv",
        "runs/p31-samples.jsonl",
        "runs/prism5.json",
        "runs/truss.1",
        "runs/diagnosis/diagnosis.json",
        "runs/tolerance/tolerance.json",
    ] {
        assert!(clone.join(f).is_file(), "the README's {f} is missing");
    }
}
