//! Length errors shared by a production lot (`truss_job::lot`), checked on the drawn inputs
//! (no solve): the within-lot correlation σ_lot²/(σ_lot² + σ_part²) for every distribution
//! of the lot part, independence across lots, identical errors where σ_part = 0, no other
//! draw moved by adding a lot, and the refusals by JSON path.
//!
//! Sampling intervals: with n independent samples, Fisher's z = atanh(r) of a sample
//! correlation r is normal about atanh(ρ) with standard deviation 1/√(n − 3); the checks
//! use its 99 % interval, ±2.576/√(n − 3), at a fixed seed (so they are deterministic).

use std::path::Path;
use truss_job::Job;
use truss_job::sampler::{draw_sample_with_lots, stream_key};

const N: u64 = 20_000;

/// A 5-stage prism job with the battens' length errors `battens` (a group's JSON).
fn job(battens: &str) -> Job {
    let text = format!(
        r#"{{"model": {{"prism": {{"stages": 5}}}}, "seed": 43,
            "cases": [{{"name": "lots", "samples": {N},
                        "length_errors": {{"batten": {battens},
                                           "longeron": {{"normal": {{"sigma": 0.004}}}}}}}}]}}"#
    );
    Job::from_json(&text, Path::new(".")).unwrap()
}

/// The drawn length errors of every sample, `[sample][member]`, and each sample's lot draws.
fn draws(job: &Job) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let case = &job.cases[0];
    let key = stream_key(job.seed, &case.name);
    let (mut e, mut c, mut l) = (Vec::new(), Vec::new(), Vec::new());
    let mut errors = Vec::new();
    let mut lots = Vec::new();
    for k in 0..case.samples {
        draw_sample_with_lots(&key, case, k, &mut e, &mut c, &mut l);
        errors.push(e.clone());
        lots.push(l.clone());
    }
    (errors, lots)
}

fn column(job: &Job, errors: &[Vec<f64>], id: &str) -> Vec<f64> {
    let m = job.cases[0].model.member_index(id).unwrap();
    errors.iter().map(|e| e[m]).collect()
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt()
}

/// Whether `r` lies in the 99 % sampling interval of a correlation `rho` over `N` samples.
fn within(r: f64, rho: f64) -> bool {
    (r.atanh() - rho.atanh()).abs() <= 2.576 / ((N - 3) as f64).sqrt()
}

/// Each distribution as a lot part: the battens of one level are correlated by
/// σ_lot²/(σ_lot² + σ_part²) (σ_part 4 µm), those of two levels not at all, and every batten's
/// variance is σ_part² + σ_lot².
#[test]
fn lots_have_the_stated_within_lot_correlation_for_every_distribution() {
    let part = 0.004f64;
    for (lot, sd) in [
        (r#"{"normal": {"sigma": 0.003}}"#, 0.003),
        (
            r#"{"uniform": {"low": -0.005, "high": 0.005}}"#,
            0.01 / 12f64.sqrt(),
        ),
        (
            r#"{"truncated_normal": {"sigma": 0.004, "limit": 0.006}}"#,
            // σ·√(1 − 2aφ(a)/erf(a/√2)) at a = 1.5 (see truss_job::distribution).
            0.004 * 0.742_646_9,
        ),
    ] {
        let j = job(&format!(
            r#"{{"normal": {{"sigma": {part}}}, "lot": {{"by": "level", {}}}}}"#,
            &lot[1..lot.len() - 1]
        ));
        let case = &j.cases[0];
        assert_eq!(case.lots.len(), 1);
        assert_eq!(case.lots[0].lots.len(), 6, "levels 0 to 5");
        let rho = sd * sd / (sd * sd + part * part);
        assert!((case.parameters["lot_share"] - rho).abs() < 1e-6, "{lot}");
        let (errors, lots) = draws(&j);
        assert!(lots.iter().all(|l| l.len() == 6));
        let a = column(&j, &errors, "batten.2.0");
        let b = column(&j, &errors, "batten.2.1");
        let other = column(&j, &errors, "batten.3.1");
        let r = correlation(&a, &b);
        assert!(within(r, rho), "{lot}: within-lot r = {r}, expected {rho}");
        let r0 = correlation(&a, &other);
        assert!(within(r0, 0.0), "{lot}: across lots r = {r0}");
        // Variance σ_part² + σ_lot², within its χ² interval (99 %: ±2.576·√(2/n) relative).
        let n = N as f64;
        let var = a.iter().map(|x| x * x).sum::<f64>() / n;
        let expected = part * part + sd * sd;
        assert!(
            (var / expected - 1.0).abs() < 2.576 * (2.0 / n).sqrt(),
            "{lot}: variance {var} vs {expected}"
        );
    }
}

/// A lot whose members have no scatter of their own (σ_part = 0) gives them identical
/// errors, the lot's draw, in every sample; a member of the group in no list is a lot of its
/// own, and a constant lot part shifts its members by the constant.
#[test]
fn a_lot_without_own_scatter_gives_its_members_identical_errors() {
    let j = job(
        r#"{"normal": {"sigma": 0}, "lot": {"by": [["batten.1.0", "batten.1.1", "batten.4.2"]],
                                             "uniform": {"low": -0.01, "high": 0.01}}}"#,
    );
    assert_eq!(
        j.cases[0].lots[0].lots.len(),
        1 + 15,
        "the list, then 15 lots of one"
    );
    let (errors, lots) = draws(&j);
    let a = column(&j, &errors, "batten.1.0");
    for id in ["batten.1.1", "batten.4.2"] {
        assert_eq!(column(&j, &errors, id), a, "{id}");
    }
    let first: Vec<f64> = lots.iter().map(|l| l[0]).collect();
    assert_eq!(a, first);
    assert!(a.iter().any(|&x| x != 0.0));
    assert_ne!(column(&j, &errors, "batten.1.2"), a);
    assert_ne!(
        column(&j, &errors, "batten.1.2"),
        column(&j, &errors, "batten.2.2")
    );
    let shifted = job(
        r#"{"normal": {"sigma": 0.004}, "lot": {"by": "level", "constant": {"value": 0.002}}}"#,
    );
    let plain = job(r#"{"normal": {"sigma": 0.004}}"#);
    let ((s, _), (p, _)) = (draws(&shifted), draws(&plain));
    for (x, y) in column(&shifted, &s, "batten.3.1")
        .iter()
        .zip(column(&plain, &p, "batten.3.1"))
    {
        assert_eq!(*x, y + 0.002);
    }
}

/// Adding a lot to the battens leaves every other draw as it was (the longerons' bit for
/// bit, the battens' as their old draw plus the lot's, bit for bit), and the draws do not depend on which other
/// samples were drawn.
#[test]
fn a_lot_moves_no_other_draw() {
    let with =
        job(r#"{"normal": {"sigma": 0.004}, "lot": {"by": "level", "normal": {"sigma": 0.003}}}"#);
    let without = job(r#"{"normal": {"sigma": 0.004}}"#);
    assert_ne!(with.id, without.id);
    let ((e1, l1), (e0, _)) = (draws(&with), draws(&without));
    let case = &with.cases[0];
    for k in [0, 1, 777, (N - 1) as usize] {
        for (m, member) in case.model.members().iter().enumerate() {
            match case.member_lot[m] {
                None => assert_eq!(e1[k][m].to_bits(), e0[k][m].to_bits(), "{}", member.id),
                Some(l) => assert_eq!(e1[k][m].to_bits(), (e0[k][m] + l1[k][l]).to_bits()),
            }
        }
    }
    // Sample 777 drawn alone is the same.
    let key = stream_key(with.seed, &case.name);
    let (mut e, mut c, mut l) = (Vec::new(), Vec::new(), Vec::new());
    draw_sample_with_lots(&key, case, 777, &mut e, &mut c, &mut l);
    assert_eq!(e, e1[777]);
}

/// Bad lots are refused before any work, each by its JSON path.
#[test]
fn bad_lots_are_refused_by_path() {
    let refusal = |battens: &str| {
        let text = format!(
            r#"{{"model": {{"prism": {{"stages": 2}}}}, "seed": 1,
                "cases": [{{"name": "a", "samples": 1, "length_errors": {{"batten": {battens}}}}}]}}"#
        );
        Job::from_json(&text, Path::new("."))
            .unwrap_err()
            .to_string()
    };
    let lot = |by: &str| {
        format!(
            r#"{{"normal": {{"sigma": 0.001}}, "lot": {{"by": {by}, "normal": {{"sigma": 0.001}}}}}}"#
        )
    };
    for (battens, said) in [
        (
            lot(r#"[["batten.1.0", "batten.1.0"]]"#),
            "cases[0].length_errors.batten.lot.by[0][1]: member \"batten.1.0\" is named twice",
        ),
        (
            lot(r#"[["batten.1.0"], ["batten.2.1", "batten.1.0"]]"#),
            "cases[0].length_errors.batten.lot.by[1][1]: member \"batten.1.0\" is named twice",
        ),
        (
            lot(r#"[["batten.1.0", "longeron.1.0"]]"#),
            "cases[0].length_errors.batten.lot.by[0][1]: member \"longeron.1.0\" is not in group \"batten\"",
        ),
        (
            lot(r#"[["batten.9.0"]]"#),
            "cases[0].length_errors.batten.lot.by[0][0]: the model has no member \"batten.9.0\"",
        ),
        (
            lot(r#"[[]]"#),
            "cases[0].length_errors.batten.lot.by[0]: a lot needs at least one member",
        ),
        (
            lot(r#""stage""#),
            "cases[0].length_errors.batten.lot.by: expected \"level\" or lists",
        ),
        (
            r#"{"normal": {"sigma": 0.001}, "lot": {"by": "level", "normal": {"sigma": -1}}}"#
                .into(),
            "cases[0].length_errors.batten.lot: sigma must not be negative",
        ),
        (
            r#"{"normal": {"sigma": 0.5}, "lot": {"by": "level", "normal": {"sigma": 0.2}}}"#
                .into(),
            "cases[0].length_errors.batten: mean 0 mm, σ 0.5 mm: |mean| + 6σ = 3 mm, plus its lot part's",
        ),
    ] {
        let m = refusal(&battens);
        assert!(m.starts_with(said), "{battens}: {m}");
    }
}

/// `"level"` is the prism's; a model file must list its lots.
#[test]
fn level_needs_the_prism() {
    let dir = tempfile::tempdir().unwrap();
    let model = truss_core::prism::PrismOptions::with_stages(1)
        .model()
        .unwrap();
    std::fs::write(dir.path().join("m.json"), model.to_file().to_json()).unwrap();
    let text = r#"{"model": "m.json", "seed": 1, "cases": [{"name": "a", "samples": 1,
        "length_errors": {"batten": {"normal": {"sigma": 0.001},
                                     "lot": {"by": "level", "normal": {"sigma": 0.001}}}}}]}"#;
    let m = Job::from_json(text, dir.path()).unwrap_err().to_string();
    assert!(
        m.starts_with("cases[0].length_errors.batten.lot.by: \"level\" names the prism's levels"),
        "{m}"
    );
}
