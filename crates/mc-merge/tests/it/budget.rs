//! The alignment budget in the merge (`mc_merge::budget`), on synthetic shards whose laws
//! are known: θ_P Rayleigh(σ_t), decenter = 1000 mm × the tangents (Rayleigh(1000 σ_t) mm),
//! despace N(0, (700 σ_t mm)²) (see `common::SynthJob::sample`).
//!
//! By hand, at the 95th percentile (Rayleigh: σ√(−2 ln 0.05) = 2.4477 σ; |N(0, s²)|:
//! 1.9600 s), for the case at σ = 0.0033 mm with σ_t = 2e-5 and the budget θ_P ≤ 20″
//! (9.6963e-5 rad), decenter ≤ 0.05 mm, |despace| ≤ 0.03 mm:
//!
//! ```text
//! θ_P95       = 4.8954e-5 rad    limit/q = 1.9807
//! decenter95  = 0.048954 mm      limit/q = 1.0214   ← binds
//! |despace|95 = 0.027440 mm      limit/q = 1.0933
//! σ_allow     = 0.0033 · 1.0214 = 0.0033705 mm; every line passes
//! ```
//!
//! The case at σ = 0.0066 (σ_t = 4e-5) fails decenter and despace and has the same σ_allow;
//! so has the σ-series of the two. 4,000 samples per case: the percentiles' sampling error is
//! about 1.5 %, so the figures are checked to 5 %.

use crate::common::{SynthCase, SynthJob};
use shard_record::Budget;

const THETA: f64 = 9.696_273_622_190_722e-5;

fn report() -> mc_merge::Report {
    let mut job = SynthJob::new(
        43,
        vec![
            SynthCase::rayleigh("s1", 4000, 2e-5, &[("sigma", 0.0033)]),
            SynthCase::rayleigh("s2", 4000, 4e-5, &[("sigma", 0.0066)]),
        ],
    );
    job.budget = Some(Budget {
        percentile: 95.0,
        theta_p: Some(THETA),
        decenter: Some(0.05),
        despace: Some(0.03),
    });
    let dir = tempfile::tempdir().unwrap();
    job.write_split(dir.path(), 2);
    let settings = mc_merge::Settings {
        replicates: 100,
        gof_replicates: 19,
        ..Default::default()
    };
    mc_merge::merge(&[dir.path().to_path_buf()], &settings)
        .unwrap()
        .report
}

fn near(got: f64, want: f64, rel: f64) -> bool {
    (got / want - 1.0).abs() < rel
}

#[test]
fn the_budget_says_which_lines_pass_and_the_sigma_that_meets_all() {
    let r = report();
    let b = r.budget.as_ref().expect("a budget section");
    assert_eq!(b.percentile.0, 95.0);
    let q: Vec<&str> = b.lines.iter().map(|l| l.quantity).collect();
    assert_eq!(q, ["theta_p", "decenter", "despace"]);
    let s1 = &b.cases[0];
    let values: Vec<f64> = s1.lines.iter().map(|l| l.value.get().unwrap()).collect();
    for (got, want) in values.iter().zip([4.8954e-5, 0.048954, 0.027440]) {
        assert!(near(*got, want, 0.05), "{got} vs {want}");
    }
    assert_eq!(s1.binding, Some("decenter"));
    assert!(near(s1.allowable_sigma.get().unwrap(), 0.0033705, 0.05));
    // The allowable σ is σ · min(limit/q) of the report's own percentiles, exactly.
    let own = 0.0033
        * s1.lines
            .iter()
            .map(|l| l.limit.0 / l.value.get().unwrap())
            .fold(f64::INFINITY, f64::min);
    assert_eq!(s1.allowable_sigma.get().unwrap(), own);
    let (lo, hi) = s1.allowable_sigma.interval().unwrap();
    assert!(lo < own && own < hi, "{lo} {own} {hi}");
    assert!(s1.binding_share.unwrap().0 > 0.5);
    // Each line's verdict is its percentile against its limit.
    for l in &s1.lines {
        assert_eq!(l.passes, Some(l.value.get().unwrap() <= l.limit.0));
    }
    let s2 = &b.cases[1];
    assert_eq!(s2.passes, Some(false));
    assert_eq!(
        s2.lines.iter().map(|l| l.passes).collect::<Vec<_>>(),
        [Some(true), Some(false), Some(false)]
    );
    assert!(near(s2.allowable_sigma.get().unwrap(), 0.0033705, 0.05));
    assert_eq!(b.series.len(), 1);
    let series = &b.series[0];
    assert_eq!(series.binding, Some("decenter"));
    assert!(near(series.allowable_sigma.get().unwrap(), 0.0033705, 0.05));
    assert!(!series.extrapolated);
    // The decenter and despace sections follow their laws.
    let c = &r.cases[0];
    let d = c.decenter.as_ref().unwrap();
    assert!(near(
        d.law.sigma.as_ref().unwrap().get().unwrap(),
        0.02,
        0.05
    ));
    let z = c.despace.as_ref().unwrap();
    assert!(near(
        z.law.std.as_ref().unwrap().get().unwrap(),
        0.014,
        0.05
    ));
}

/// The table's first section names the budget's verdict and the binding line.
#[test]
fn the_table_opens_with_the_budget() {
    let r = report();
    let table = mc_merge::table::render(&r, 2);
    let budget = table.find("budget").expect("a budget section");
    let cases = table.find("θ_P95").unwrap();
    assert!(budget < cases, "{table}");
    assert!(table.contains("binds: decenter"), "{table}");
}

/// report.md opens with the budget: its section comes before the answer, with the
/// allowable σ and the binding line.
#[test]
fn the_readable_report_opens_with_the_budget() {
    let mut job = SynthJob::new(
        44,
        vec![
            SynthCase::rayleigh("s1", 400, 2e-5, &[("sigma", 0.0033)]),
            SynthCase::rayleigh("s2", 400, 4e-5, &[("sigma", 0.0066)]),
        ],
    );
    job.budget = Some(Budget {
        percentile: 95.0,
        theta_p: Some(THETA),
        decenter: Some(0.05),
        despace: None,
    });
    let dir = tempfile::tempdir().unwrap();
    let shards = dir.path().join("shards");
    std::fs::create_dir_all(&shards).unwrap();
    job.write_split(&shards, 2);
    let out = dir.path().join("report");
    let options = mc_merge::Options {
        paths: vec![shards],
        out: Some(out.clone()),
        plots: false,
        progress: false,
        settings: mc_merge::Settings {
            replicates: 50,
            gof_replicates: 19,
            ..Default::default()
        },
    };
    mc_merge::run(&options, &mut Vec::new()).unwrap();
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    let budget = md
        .find("## The alignment budget")
        .expect("a budget section");
    let answer = md.find("## The answer").unwrap();
    assert!(budget < answer, "{md}");
    let section = &md[budget..answer];
    assert!(section.contains("decenter binds"), "{section}");
    assert!(
        section.contains("Allowable σ meeting every line, series"),
        "{section}"
    );
}
