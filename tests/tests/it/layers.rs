//! The workspace's dependency graph points one way (README, "The pieces"): this test reads
//! `cargo metadata` and fails if a forbidden edge comes back. Normal dependencies only, and
//! transitively: tests and benchmarks may reach further.
//!
//! - the runner (`mc-shard`) never links the merge (`mc-merge`) nor an async runtime;
//! - the merge never links the solver (`truss-core`) nor the job (`truss-job`);
//! - the solver links nothing of ours; nor do the statistics, the wire format, the run
//!   directory's file rules (`run-dir`, so every writer, however low, can share them), the
//!   unit conversions (`truss-units`), the exit codes and the thread count (`truss-threads`,
//!   which every crate that starts threads shares, the merge as well as the job's engine);
//! - the plot style (`truss-plot`) links only the unit conversions, so the merge, the
//!   diagnosis and the tolerance study can all draw with it;
//! - the diagnosis links neither the runner, the merge nor the wire format;
//! - the tolerance study links the solver, the job, the statistics, the file rules, the
//!   units, the plot style and the thread count, and nothing else of ours;
//! - the Python bindings link the runner's side (solver, job, wire format, runner) and the
//!   merge (whose statistics they hand to Python, not a second implementation of them), never
//!   the orchestration, the diagnosis, the tolerance study or an async runtime.
//!
//! The feature unifier `workspace-hack` (cargo-hakari's) is left out of the graph: every crate
//! depends on it, it holds no code, and it names only third-party crates, with the features
//! some build of the workspace already gives them.

use std::collections::{BTreeMap, BTreeSet};

/// The feature unifier: no code, a build setting (see the module's doc).
const FEATURE_UNIFIER: &str = "workspace-hack";

/// Each workspace package's normal dependencies (any package, by name), without the feature
/// unifier.
fn normal_dependencies() -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let deps = p["dependencies"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|d| d["kind"].is_null())
                .map(|d| d["name"].as_str().unwrap().to_string())
                .filter(|d| d != FEATURE_UNIFIER)
                .collect();
            (p["name"].as_str().unwrap().to_string(), deps)
        })
        .filter(|(name, _)| name != FEATURE_UNIFIER)
        .collect()
}

/// Everything `package` links, through workspace packages.
fn closure(graph: &BTreeMap<String, BTreeSet<String>>, package: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut stack = vec![package.to_string()];
    while let Some(p) = stack.pop() {
        for d in graph.get(&p).into_iter().flatten() {
            if seen.insert(d.clone()) {
                stack.push(d.clone());
            }
        }
    }
    seen
}

#[test]
fn dependencies_point_one_way() {
    let graph = normal_dependencies();
    let ours: BTreeSet<String> = graph.keys().cloned().collect();
    for name in [
        "truss-core",
        "truss-stats",
        "truss-job",
        "mc-shard",
        "mc-merge",
        "truss-tolerance",
        "run-dir",
        "truss-py",
        "truss-units",
        "truss-plot",
        "truss-exit",
        "truss-threads",
    ] {
        assert!(ours.contains(name), "workspace package {name} is missing");
    }
    let forbidden: [(&str, &[&str]); 12] = [
        (
            "mc-shard",
            &["mc-merge", "tokio", "plotters", "statrs", "truss-stats"],
        ),
        ("mc-merge", &["truss-core", "truss-job", "mc-shard"]),
        ("truss-core", &[]),
        ("truss-stats", &[]),
        ("shard-record", &[]),
        ("run-dir", &[]),
        ("truss-units", &[]),
        ("truss-exit", &[]),
        ("truss-threads", &[]),
        (
            "truss-plot",
            &["truss-core", "truss-job", "truss-stats", "run-dir"],
        ),
        (
            "truss-diagnose",
            &["mc-shard", "mc-merge", "shard-record", "truss-mc"],
        ),
        (
            "truss-py",
            &["truss-mc", "truss-diagnose", "truss-tolerance", "tokio"],
        ),
    ];
    for (package, banned) in forbidden {
        let links = closure(&graph, package);
        for b in banned {
            assert!(
                !links.contains(*b),
                "{package} must not link {b} (README, The pieces)"
            );
        }
        if banned.is_empty() {
            let own: Vec<&String> = links.intersection(&ours).collect();
            assert!(
                own.is_empty(),
                "{package} must link nothing of ours, links {own:?}"
            );
        }
    }
    // The plot style sits on the unit conversions alone.
    let plot: Vec<String> = closure(&graph, "truss-plot")
        .intersection(&ours)
        .cloned()
        .collect();
    assert_eq!(plot, ["truss-units"]);
    // truss-job sits directly on the solver and on nothing else of ours.
    let job: Vec<String> = closure(&graph, "truss-job")
        .intersection(&ours)
        .cloned()
        .collect();
    assert_eq!(job, ["truss-core"]);
    // truss-tolerance sits on the job, the solver, the statistics, the run directory's file
    // rules, the units, the plot style and the thread count: not the runner, the merge, the
    // wire format or the diagnosis.
    let tolerance: Vec<String> = closure(&graph, "truss-tolerance")
        .intersection(&ours)
        .cloned()
        .collect();
    assert_eq!(
        tolerance,
        [
            "run-dir",
            "truss-core",
            "truss-job",
            "truss-plot",
            "truss-stats",
            "truss-threads",
            "truss-units"
        ]
    );
}
