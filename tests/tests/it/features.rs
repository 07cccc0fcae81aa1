//! The release builds that `scripts/test.sh` makes one after another share their compiled
//! third-party crates: the binaries, the slow statistical checks (the tests of every crate
//! with `#[ignore]`d tests, in one build) and the Python extension give each third-party
//! crate the same features, so cargo compiles it once. The feature unifier `workspace-hack`
//! (cargo-hakari's) makes it so; this test reads `cargo tree` and fails, naming the crate and
//! the features, when a dependency change needs `cargo hakari generate` again. Without it,
//! a clean clone's CI compiled most release dependencies three times.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Each third-party crate's features in the build `cargo tree` `args` describe (the name
/// `default` left out: what it enables is listed by itself).
fn features(args: &[&str]) -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args(["tree", "--offline", "--prefix", "none", "--no-dedupe"])
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo tree runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut crates: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in String::from_utf8(out.stdout).unwrap().lines() {
        if line.contains("(/") {
            continue; // a workspace crate: a path, not the registry
        }
        let name = line.split(' ').next().unwrap_or_default().to_string();
        let entry = crates.entry(name).or_default();
        if let Some(feature) = line.split(" feature \"").nth(1) {
            let feature = feature.trim_end_matches(|c| c != '"').trim_end_matches('"');
            if feature != "default" {
                entry.insert(feature.to_string());
            }
        }
    }
    crates
}

/// The crates whose tests hold `#[ignore]`d checks, as `scripts/test.sh` finds them.
fn crates_with_slow_checks() -> Vec<String> {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("../crates");
    let mut found = BTreeSet::new();
    for entry in std::fs::read_dir(&crates).unwrap() {
        let dir = entry.unwrap().path();
        let mut stack = vec![dir.join("src"), dir.join("tests")];
        while let Some(d) = stack.pop() {
            let Ok(entries) = std::fs::read_dir(&d) else {
                continue;
            };
            for e in entries {
                let p = e.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|x| x == "rs")
                    && std::fs::read_to_string(&p).unwrap().contains("#[ignore")
                {
                    found.insert(dir.file_name().unwrap().to_string_lossy().into_owned());
                }
            }
        }
    }
    found.into_iter().collect()
}

#[test]
fn release_builds_share_their_dependencies() {
    let binaries = features(&[
        "-e",
        "normal,build,features",
        "-p",
        "mc-shard",
        "-p",
        "mc-merge",
        "-p",
        "truss-cli",
        "-p",
        "truss-mc",
    ]);
    let python = features(&["-e", "normal,build,features", "-p", "truss-py"]);
    let slow = crates_with_slow_checks();
    assert!(slow.contains(&"truss-core".to_string()), "{slow:?}");
    let mut args = vec!["-e", "all,features"];
    for c in &slow {
        args.extend(["-p", c]);
    }
    let slow_checks = features(&args);
    for (build, other) in [
        ("the Python extension", &python),
        ("the slow checks", &slow_checks),
    ] {
        for (name, f) in other {
            if let Some(g) = binaries.get(name) {
                assert_eq!(
                    f, g,
                    "{name}: features in {build} differ from the binaries'; run `cargo hakari generate`"
                );
            }
        }
    }
}
