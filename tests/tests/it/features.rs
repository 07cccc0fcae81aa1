//! The builds that `scripts/test.sh` makes one after another into its one build directory
//! (`target/ci`) share their compiled third-party crates: every test target of the
//! workspace, the binaries and the Python extension give each third-party crate the same
//! features, so cargo compiles it
//! once. The feature unifier `workspace-hack`
//! (cargo-hakari's) makes it so; this test reads `cargo tree` and fails, naming the crate and
//! the features, when a dependency change needs `cargo hakari generate` again. Without it,
//! a clean clone's CI compiled most release dependencies three times.

use std::collections::{BTreeMap, BTreeSet};

/// Each third-party crate's features in the build `cargo tree` `args` describe (the name
/// `default` left out: what it enables is listed by itself). Every feature node is printed at
/// least once with repeated subtrees elided, which is all this needs: without the elision
/// the workspace's tree is 3.5 million lines and 7 s.
fn features(args: &[&str]) -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args(["tree", "--offline", "--prefix", "none"])
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

#[test]
fn the_ci_builds_share_their_dependencies() {
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
    let tests = features(&["-e", "all,features", "--workspace"]);
    assert!(tests.contains_key("proptest"), "{tests:?}");
    for (build, other) in [("the Python extension", &python), ("the tests", &tests)] {
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
