//! The README's commands run verbatim: every line of its ```sh blocks is checked, so that the
//! README cannot rot.
//!
//! - Our binaries (`truss`, `truss-mc`, `mc-shard`, `mc-merge`, bare or as
//!   `target/release/…`): the subcommand's `--help` must succeed and name every flag the
//!   README uses; then the command is run, in order, in a scratch directory, with the paper's
//!   job replaced by a tiny one (`jobs/paper-3.1.json` → 2 stages, two cases of 5,000
//!   samples, one named `sigma-0.0063` as the README's `reproduce` expects), `[--flag]`
//!   written as `--flag`, and `> file` redirected; it must exit 0. Lines with placeholders
//!   (`<…>`, `JOB`) or inputs the README does not make (`truss diagnose`'s measured data)
//!   are only checked, not run.
//! - Scripts (`scripts/…`): the file exists, is executable, and names every flag used.
//! - `kubectl … -f FILE`: the file exists. `cargo run … -p BIN -- ARGS` runs as `BIN ARGS`;
//!   other `cargo` lines are not checked.
//! - Other schedulers' clients (`aws`, `gcloud`, `condor_submit_dag`): every file of `jobs/`
//!   they name (also as `file://…` or `--config=…`) exists. `pip install .`: the
//!   repository's root has the `pyproject.toml` it builds (the Python tests install it).
//!
//! The binaries are the ones `cargo test --workspace` builds beside this test's executable
//! (`target/debug`); run alone (`cargo test -p pipeline-tests`) with them missing, the test
//! says so and fails.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// The commands of the README's ```sh blocks: continuation lines joined, comments dropped.
fn readme_commands() -> Vec<String> {
    let text = std::fs::read_to_string(root().join("README.md")).unwrap();
    let mut commands = Vec::new();
    let mut in_sh = false;
    let mut current = String::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_sh = line.trim() == "```sh";
            continue;
        }
        if !in_sh {
            continue;
        }
        let line = match line.find(" #") {
            Some(at) => &line[..at],
            None if line.trim_start().starts_with('#') => "",
            None => line,
        };
        let line = line.trim();
        if let Some(part) = line.strip_suffix('\\') {
            current.push_str(part.trim());
            current.push(' ');
            continue;
        }
        current.push_str(line);
        if !current.trim().is_empty() {
            commands.push(current.trim().to_string());
        }
        current.clear();
    }
    commands
}

/// Where `cargo test --workspace` put the binaries: beside `target/debug/deps/it-…`.
fn binary(name: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let path = exe.parent().unwrap().parent().unwrap().join(name);
    assert!(
        path.exists(),
        "{} not built: run `cargo test --workspace` (it builds every binary)",
        path.display()
    );
    path
}

/// Our binary a command word names, if it is one.
fn our_binary(word: &str) -> Option<&'static str> {
    let name = word.strip_prefix("target/release/").unwrap_or(word);
    ["truss", "truss-mc", "mc-shard", "mc-merge"]
        .into_iter()
        .find(|b| *b == name)
}

/// The binary of a `cargo run [--release] -p PACKAGE -- ARGS` line, if it is one of ours.
fn cargo_run(words: &[String]) -> Option<&'static str> {
    if words.first().map(String::as_str) != Some("cargo")
        || words.get(1).map(String::as_str) != Some("run")
    {
        return None;
    }
    let p = words.iter().position(|w| w == "-p")?;
    words.iter().any(|w| w == "--").then_some(())?;
    our_binary(words.get(p + 1)?)
}

/// A tiny stand-in for the paper's job.
const TINY_JOB: &str = r#"{
  "model": {"prism": {"stages": 2}},
  "seed": 20210325,
  "cases": [
    {"name": "sigma-0.0033", "samples": 5000,
     "length_errors": {"batten": {"normal": {"sigma": 0.0033}}, "longeron": {"normal": {"sigma": 0.0033}}}},
    {"name": "sigma-0.0063", "samples": 5000,
     "length_errors": {"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}}}
  ]
}"#;

/// The flags (`--x`, `--x=…`) of `words`.
fn flags(words: &[String]) -> Vec<String> {
    words
        .iter()
        .filter(|w| w.starts_with("--") && w.len() > 2)
        .map(|w| w.split('=').next().unwrap().to_string())
        .collect()
}

/// Whether `text` names `flag` as a whole word (`--shard` is not named by `--shards`).
fn names_flag(text: &str, flag: &str) -> bool {
    text.match_indices(flag).any(|(at, _)| {
        !text[at + flag.len()..]
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    })
}

/// Checks one of our binaries' command: its help names every flag; runs it when it can.
fn check_ours(bin: &str, words: &[String], scratch: &Path, job: &Path) {
    // `[--detail]` is an optional flag the README shows: use it.
    let mut args: Vec<String> = words[1..]
        .iter()
        .map(|w| w.trim_start_matches('[').trim_end_matches(']').to_string())
        .collect();
    let mut stdout_to = None;
    if let Some(at) = args.iter().position(|a| a == ">") {
        stdout_to = Some(scratch.join(&args[at + 1]));
        args.truncate(at);
    }
    let sub: Vec<&str> = match args.first() {
        Some(a) if !a.starts_with('-') && bin != "mc-merge" => {
            // `truss model prism`: two levels of subcommands.
            let mut sub = vec![a.as_str()];
            if let Some(b) = args.get(1).filter(|b| *b == "prism") {
                sub.push(b);
            }
            sub
        }
        _ => vec![],
    };
    let help = Command::new(binary(bin))
        .args(&sub)
        .arg("--help")
        .output()
        .unwrap();
    assert!(help.status.success(), "{bin} {sub:?} --help failed");
    let help_text = String::from_utf8_lossy(&help.stdout);
    for flag in flags(&args) {
        assert!(
            names_flag(&help_text, &flag),
            "README: `{}`: {bin} {} has no {flag}",
            words.join(" "),
            sub.join(" ")
        );
    }
    let placeholder = args.iter().any(|a| a.contains('<') || a == "JOB");
    let needs_measurements = bin == "truss" && sub.first() == Some(&"diagnose");
    if placeholder || needs_measurements {
        return;
    }
    let args: Vec<String> = args
        .into_iter()
        .map(|a| {
            if a.starts_with("jobs/paper-") {
                job.display().to_string()
            } else {
                a
            }
        })
        .collect();
    let out = Command::new(binary(bin))
        .args(&args)
        .current_dir(scratch)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "README: `{}` failed ({:?}): {}",
        words.join(" "),
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    if let Some(to) = stdout_to {
        std::fs::write(to, &out.stdout).unwrap();
    }
}

/// Every command of the README's ```sh blocks exists with its flags, and those that can run
/// on a tiny job do.
#[test]
fn readme_commands_run() {
    let commands = readme_commands();
    assert!(commands.len() >= 15, "{commands:#?}");
    let scratch = tempfile::tempdir().unwrap();
    let job = scratch.path().join("tiny-job.json");
    std::fs::write(&job, TINY_JOB).unwrap();
    let mut ran_ours = 0;
    for command in &commands {
        let words: Vec<String> = command.split_whitespace().map(String::from).collect();
        let first = words[0].as_str();
        if let Some(bin) = our_binary(first) {
            check_ours(bin, &words, scratch.path(), &job);
            ran_ours += 1;
        } else if first.starts_with("scripts/") {
            let path = root().join(first);
            let meta = std::fs::metadata(&path).unwrap_or_else(|_| panic!("{command}: no {first}"));
            use std::os::unix::fs::PermissionsExt;
            assert!(
                meta.permissions().mode() & 0o111 != 0,
                "{first} is not executable"
            );
            let text = std::fs::read_to_string(&path).unwrap();
            // Flags after a lone `--` belong to the batch system.
            let own: Vec<String> = words.iter().take_while(|w| *w != "--").cloned().collect();
            for flag in flags(&own) {
                assert!(
                    text.contains(&flag),
                    "README: `{command}`: {first} has no {flag}"
                );
            }
        } else if first == "kubectl" {
            if let Some(at) = words.iter().position(|w| w == "-f") {
                assert!(root().join(&words[at + 1]).exists(), "{command}");
            }
        } else if ["aws", "gcloud", "condor_submit_dag"].contains(&first) {
            let files: Vec<&str> = words
                .iter()
                .map(|w| {
                    w.trim_start_matches("file://")
                        .trim_start_matches("--config=")
                })
                .filter(|w| w.starts_with("jobs/"))
                .collect();
            assert!(
                !files.is_empty(),
                "README: `{command}` names no file of jobs/"
            );
            for f in files {
                assert!(root().join(f).is_file(), "README: `{command}`: no {f}");
            }
        } else if first == "pip" {
            assert_eq!(words[1..], ["install", "."], "README: `{command}`");
            assert!(root().join("pyproject.toml").is_file());
        } else if let Some(bin) = cargo_run(&words) {
            // `cargo run --release -p BIN -- ARGS` runs BIN ARGS (the binary is built here).
            let at = words
                .iter()
                .position(|w| w == "--")
                .expect("cargo run … --");
            let mut run = vec![bin.to_string()];
            run.extend(words[at + 1..].iter().cloned());
            check_ours(bin, &run, scratch.path(), &job);
            ran_ours += 1;
        } else {
            assert_eq!(
                first, "cargo",
                "a README command this test does not know: {command}"
            );
        }
    }
    assert!(ran_ours >= 10, "{ran_ours}");
    assert!(names_flag("--shard I/K", "--shard") && !names_flag("--shards K", "--shard"));
    // The README's merge and export ran on what its runs wrote.
    assert!(scratch.path().join("runs/p31/report/report.json").exists());
    assert!(scratch.path().join("runs/p31-samples.csv").exists());
    assert!(
        scratch
            .path()
            .join("runs/paper-3.1/report/report.json")
            .exists()
    );
}
