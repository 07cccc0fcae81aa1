//! Hidden-effect checks (test it on data in which the effect is hidden): measured
//! data made by `synth` from the baseline case of `jobs/diagnose-baseline.json` (the paper's
//! 5-stage prism, σ = 6.3 µm on battens and longerons, section 3.1) with an effect the
//! diagnosis is not told, under a seed independent of the job's, with 1 µm instrument noise;
//! the diagnosis must name the effect, recover its parameters within their intervals (the
//! joint 95 % profile-likelihood region's projections, `check_recovered`) and cut the
//! discrepancy by at least half; data without an effect must give `none`; too few
//! specimens must say `cannot_tell`.
//!
//! The backlash check uses section 4.2.3's job (`jobs/paper-4.2.3.json`) instead.
//!
//! Two tiers here. The default run's checks are small (40–60 specimens, N = 300 simulated
//! samples, the true effect tried against one or two others; the small backlash and
//! two-effect checks, some 20 s each in the debug build, are `#[ignore]`d with the slow tier).
//! The `#[ignore]`d ones (run by scripts/test.sh in its one optimised build) try every
//! candidate but backlash, or the effect's rivals, on 50–200 specimens, and the null-data
//! false-positive rate over 20 seeds at 100 specimens (at 30:
//! `ONLY=null-fpr scripts/diagnose-check.sh`), and (in `hidden_effects/stepwise.rs`) two
//! pairs of effects in which the stepwise selection must swap out or remove an effect it
//! named first. Each runs at the smallest N at which it still passes and still fails under
//! the deliberate fault its doc names (shown once, by hand, when the size was chosen): a
//! check that no fault can fail guards nothing.
//! `scripts/diagnose-check.sh` runs the full checks of the stepwise selection (null over ten
//! seeds, each effect over three, pairs and mean shifts over three seeds, backlash with and
//! without members; 200 specimens, default N, every candidate) with the release build; too
//! slow for CI, run when the diagnosis changes.

#[path = "hidden_effects/confounding.rs"]
mod confounding;
#[path = "hidden_effects/data_checks.rs"]
mod data_checks;
#[path = "hidden_effects/stepwise.rs"]
mod stepwise;

use std::path::{Path, PathBuf};
use truss_diagnose::settings::Settings;
use truss_diagnose::synth::{SynthOptions, synth, write_specimens};
use truss_diagnose::{DiagnoseOptions, run};

fn job() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs/diagnose-baseline.json")
}

/// Parameter `name` of `effect` in the final model's joint fit (`final_fit`: the numbers
/// the report reads last, with their intervals).
pub(crate) fn final_parameter<'a>(
    v: &'a serde_json::Value,
    effect: &str,
    name: &str,
) -> &'a serde_json::Value {
    v["final_fit"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["name"] == effect)
        .and_then(|e| {
            e["parameters"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["name"] == name)
        })
        .unwrap_or_else(|| panic!("no {effect} {name} in {}", v["final_fit"]))
}

fn make(dir: &Path, name: &str, effect: &str, specimens: usize, seed: u64) -> PathBuf {
    make_with_members(dir, name, effect, specimens, seed, None)
}

fn make_with_members(
    dir: &Path,
    name: &str,
    effect: &str,
    specimens: usize,
    seed: u64,
    members_out: Option<PathBuf>,
) -> PathBuf {
    make_from(
        (&job(), "as-built"),
        dir,
        name,
        effect,
        specimens,
        seed,
        members_out,
    )
}

/// Measured data from case `case` of job `job` with `effect` added.
fn make_from(
    (job, case): (&Path, &str),
    dir: &Path,
    name: &str,
    effect: &str,
    specimens: usize,
    seed: u64,
    members_out: Option<PathBuf>,
) -> PathBuf {
    let mut out = Vec::new();
    synth(
        &SynthOptions {
            job: job.to_path_buf(),
            case: case.into(),
            specimens,
            seed,
            effect: effect.into(),
            measurement_sigma: 0.001,
            all_nodes: false,
            members_out,
        },
        &mut out,
    )
    .unwrap();
    let p = dir.join(format!("{name}.csv"));
    std::fs::write(&p, out).unwrap();
    p
}

/// Every candidate but backlash, the slowest to simulate (each of its evaluations solves the
/// pin-jointed truss): the slow checks of the other effects try these, and
/// `scripts/diagnose-check.sh` tries all six.
const ALL_BUT_BACKLASH: [&str; 5] = [
    "gravity",
    "thermal_gradient",
    "length_bias",
    "length_sigma",
    "diagonal_pretension",
];

/// Diagnoses `measured` against the baseline with N = `samples`, every candidate but
/// backlash.
fn diagnose(dir: &Path, measured: &Path, samples: usize) -> serde_json::Value {
    diagnose_with_members(dir, measured, None, samples)
}

/// [`diagnose`] with the members measured one by one.
fn diagnose_with_members(
    dir: &Path,
    measured: &Path,
    members: Option<PathBuf>,
    samples: usize,
) -> serde_json::Value {
    diagnose_with(
        (&job(), "as-built"),
        dir,
        measured,
        members,
        samples,
        Some(&ALL_BUT_BACKLASH),
    )
}

/// Diagnoses with N samples per evaluation and only the `candidates` given (all if `None`):
/// the fast checks of the default run try the true effect against the one or two the
/// full checks find it easiest to confuse with.
fn diagnose_with(
    (job, case): (&Path, &str),
    dir: &Path,
    measured: &Path,
    members: Option<PathBuf>,
    samples: usize,
    candidates: Option<&[&str]>,
) -> serde_json::Value {
    let out = dir.join("out");
    let s = run(&DiagnoseOptions {
        job: job.to_path_buf(),
        case: case.into(),
        measured: measured.to_path_buf(),
        measured_members: members,
        out: out.clone(),
        settings: Settings {
            samples: Some(samples),
            measurement_sigma: 0.001,
            quiet: true,
            candidates: candidates.map(|c| c.iter().map(|s| s.to_string()).collect()),
            ..Settings::default()
        },
        plots: false,
    })
    .unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("diagnosis.json")).unwrap())
            .unwrap();
    assert_eq!(v["named_effect"], s.named_effect.as_str());
    v
}

/// `effect` hidden in `specimens` specimens of the baseline made under `seed` (named `name`
/// in `dir`), diagnosed with N = `samples` against only `candidates`.
fn hidden(
    dir: &Path,
    name: &str,
    effect: &str,
    (specimens, seed): (usize, u64),
    samples: usize,
    candidates: &[&str],
) -> serde_json::Value {
    let m = make(dir, name, effect, specimens, seed);
    diagnose_with(
        (&job(), "as-built"),
        dir,
        &m,
        None,
        samples,
        Some(candidates),
    )
}

/// The discrepancy at least halved by the named effect.
fn check_halved(v: &serde_json::Value) {
    let (before, after) = (
        v["discrepancy_before"].as_f64().unwrap(),
        v["discrepancy_after"].as_f64().unwrap(),
    );
    assert!(after <= 0.5 * before, "discrepancy {before} → {after}");
}

/// The named effect; its intervals computed from the profile likelihood; the truth inside
/// the joint 95 % region's projection on every parameter (`joint_interval`: all k parameters
/// at once with 95 % confidence; requiring each of k parameters inside its own 95 %
/// interval would fail a calibrated method with probability up to 1 − 0.95^k, 19 % for
/// the four of a thermal gradient); the discrepancy at least halved.
fn check_recovered(v: &serde_json::Value, effect: &str, truth: &[(&str, f64)]) {
    assert_eq!(v["verdict"], "named", "{}", v["reason"]);
    assert_eq!(v["named_effect"], effect, "{}", v["reason"]);
    for (name, value) in truth {
        let p = v["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == *name)
            .unwrap();
        assert_eq!(p["interval"]["method"], "profile", "{name}");
        let ends =
            |i: &serde_json::Value| (i["lower"].as_f64().unwrap(), i["upper"].as_f64().unwrap());
        let (lo, hi) = ends(&p["interval"]);
        let (jlo, jhi) = ends(&p["joint_interval"]);
        assert!(
            jlo <= lo && hi <= jhi,
            "{name}: joint [{jlo}, {jhi}] does not hold [{lo}, {hi}]"
        );
        assert!(
            jlo <= *value && *value <= jhi,
            "{name}: truth {value} outside the joint [{jlo}, {jhi}] (own [{lo}, {hi}], fit {})",
            p["value"]
        );
    }
    check_halved(v);
}

/// A gradient of 0.002 K/mm along x on a uniform 2 K, 80 specimens, every candidate but
/// backlash, N = 600: named and all four parameters recovered. Fails with the profile
/// thresholds scaled by 0.05 (intervals 4.5 times too narrow): `gradient_y`'s truth 0 falls
/// outside.
#[test]
#[ignore = "slow statistical check (about 10 s): scripts/test.sh runs it"]
fn hidden_thermal_gradient_is_named_and_recovered() {
    let dir = tempfile::tempdir().unwrap();
    let m = make(
        dir.path(),
        "thermal",
        "thermal_gradient:gradient_x=0.002,offset=2",
        80,
        21,
    );
    let v = diagnose(dir.path(), &m, 600);
    check_recovered(
        &v,
        "thermal_gradient",
        &[
            ("gradient_x", 0.002),
            ("gradient_y", 0.0),
            ("gradient_z", 0.0),
            ("offset", 2.0),
        ],
    );
}

/// A longeron scatter of 12 µm (the stated 6.3), 200 specimens, every candidate but
/// backlash, N = 600: named, both scatters recovered. Fails with the profile thresholds
/// scaled by 0.05: the battens' 6.3 µm falls outside.
#[test]
#[ignore = "slow statistical check (about 10 s): scripts/test.sh runs it"]
fn hidden_length_sigma_is_named_and_recovered() {
    let dir = tempfile::tempdir().unwrap();
    let m = make(
        dir.path(),
        "sigma",
        "length_sigma:sigma.longeron=0.012",
        200,
        23,
    );
    let v = diagnose(dir.path(), &m, 600);
    check_recovered(
        &v,
        "length_sigma",
        &[("sigma.longeron", 0.012), ("sigma.batten", 0.0063)],
    );
}

#[test]
fn no_hidden_effect_gives_none() {
    let dir = tempfile::tempdir().unwrap();
    let v = hidden(
        dir.path(),
        "none",
        "none",
        (40, 1),
        300,
        &["diagonal_pretension", "length_sigma"],
    );
    assert_eq!(v["named_effects"], serde_json::json!([]));
    assert_eq!(v["steps"].as_array().unwrap().len(), 1);
    // With 40 specimens the intervals may be too wide to show agreement within tolerance.
    assert!(
        v["verdict"] == "none" || v["verdict"] == "cannot_tell",
        "{}",
        v["reason"]
    );
    assert_eq!(v["named_effect"], "none");
    assert_eq!(v["discrepancy_before"], v["discrepancy_after"]);
}

/// A small temperature gradient on 12 specimens: the data can neither show it nor show that
/// the baseline agrees within tolerance.
#[test]
fn too_few_specimens_cannot_tell() {
    let dir = tempfile::tempdir().unwrap();
    let v = hidden(
        dir.path(),
        "few",
        "thermal_gradient:gradient_x=0.0005",
        (12, 25),
        300,
        &["thermal_gradient", "length_bias"],
    );
    assert_eq!(v["verdict"], "cannot_tell", "{}", v["reason"]);
    assert_eq!(v["named_effect"], "none");
}

/// A hidden diagonal pretension is named and recovered; and the same measurements written
/// as other software might (rows shuffled, columns reordered, quoted fields, CRLF, an extra
/// marker node and a specimen missing a node) give the same diagnosis, with the incomplete
/// specimen counted.
#[test]
fn hidden_diagonal_pretension_is_recovered_whatever_the_csv_details() {
    let dir = tempfile::tempdir().unwrap();
    let m = make(
        dir.path(),
        "plain",
        "diagonal_pretension:length_error=-0.05",
        40,
        24,
    );
    let text = std::fs::read_to_string(&m).unwrap();
    let mut rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // A deterministic shuffle: reverse, then interleave halves.
    rows.reverse();
    let half = rows.len() / 2;
    let (a, b) = rows.split_at(half);
    let mut shuffled: Vec<&Vec<&str>> = a.iter().zip(b).flat_map(|(x, y)| [x, y]).collect();
    shuffled.extend(b.iter().skip(a.len()));
    let mut other = String::from("\"z\",\"x\",\"y\",\"node\",\"specimen\"\r\n");
    for r in &shuffled {
        other.push_str(&format!(
            "{},{},{},\"{}\",\"{}\"\r\n",
            r[4], r[2], r[3], r[1], r[0]
        ));
        if r[1] == "n5.0" {
            other.push_str(&format!("1,2,3,\"marker\",\"{}\"\r\n", r[0]));
        }
    }
    other.push_str("1900,0,0,n5.0,EXTRA\r\n1900,380,0,n5.1,EXTRA\r\n");
    let p = dir.path().join("other.csv");
    std::fs::write(&p, other).unwrap();
    let d1 = dir.path().join("1");
    let d2 = dir.path().join("2");
    std::fs::create_dir_all(&d1).unwrap();
    std::fs::create_dir_all(&d2).unwrap();
    let fast = |dir: &Path, m: &Path| {
        diagnose_with(
            (&job(), "as-built"),
            dir,
            m,
            None,
            300,
            Some(&["diagonal_pretension", "length_sigma"]),
        )
    };
    let v1 = fast(&d1, &m);
    check_recovered(&v1, "diagonal_pretension", &[("length_error", -0.05)]);
    assert_eq!(
        v1["named_effects"],
        serde_json::json!(["diagonal_pretension"])
    );
    let v2 = fast(&d2, &p);
    assert_eq!(v2["data"]["left_out_count"], 1);
    assert_eq!(v2["data"]["unknown_nodes"][0], "marker");
    assert_eq!(v1["named_effect"], v2["named_effect"]);
    let value = |v: &serde_json::Value| v["parameters"][0]["value"].as_f64().unwrap();
    assert!((value(&v1) - value(&v2)).abs() < 1e-9 * value(&v1).abs());
}

/// Members measured one by one (`--measured-members`) enter the likelihood: a hidden longeron
/// bias is still named, its interval contains the truth, and the batten bias's interval is
/// at least halved against the node positions alone ([`check_narrower`]). 80 specimens,
/// every candidate but backlash, N = 300. Fails with the member terms of the likelihood
/// zeroed (members read, not used): the batten intervals come out equal.
#[test]
#[ignore = "slow statistical check (about 15 s): scripts/test.sh runs it"]
fn member_measurements_narrow_a_length_effect() {
    let dir = tempfile::tempdir().unwrap();
    let members = dir.path().join("members.csv");
    let m = make_with_members(
        dir.path(),
        "bias",
        "length_bias:bias.longeron=0.003",
        80,
        22,
        Some(members.clone()),
    );
    let d1 = dir.path().join("nodes");
    let d2 = dir.path().join("members");
    let alone = diagnose(&d1, &m, 300);
    let both = diagnose_with_members(&d2, &m, Some(members), 300);
    assert_eq!(both["data"]["member_rows"], 80 * 33);
    check_recovered(&both, "length_bias", &[("bias.longeron", 0.003)]);
    check_narrower(&both, &alone);
}

/// The candidates a backlash is confused with on node positions (crate doc), and itself:
/// the slow backlash checks try these three; `scripts/diagnose-check.sh` tries all six
/// (backlash-201…205, paper-backlash+mm), where every step after backlash, each of its
/// evaluations solving the pin-jointed truss, costs minutes.
const RIVALS: [&str; 3] = ["backlash", "length_bias", "diagonal_pretension"];

/// The backlash check on section 4.2.3's truss at σ = 0.033 mm (diagonals
/// U[−0.099, 0] mm): a common clearance of 0.0105 mm (the mean of the paper's
/// U[0.004, 0.017]) hidden through the candidate in 50 specimens with their members measured
/// one by one, diagnosed against the rigid case `rigid-sigma-0.033` of
/// `jobs/paper-4.2.3.json` with backlash and its [`RIVALS`] at N = 600 (most of its time is
/// the model with backlash, not N: at N = 300 it took as long): named, the clearance
/// recovered within its interval, the gap at least halved, and `updated-job.json` holds the
/// joints. Fails with the profile thresholds scaled by 0.05.
///
/// The spread is not checked here: at N = 1200 on 200 specimens it came out
/// 0.0025 [0.0008, 0.0040] mm on these equal clearances (resolved away from 0), while at the
/// default N = 4000 (`scripts/diagnose-check.sh`, seeds 201–203, which fails a check whose
/// spread is resolved on equal clearances) its interval reached 0 each time. The paper's
/// clearances themselves (made by the job's own backlash case) are
/// [`hidden_backlash_is_named_fast`]'s; `scripts/diagnose-check.sh` prints their fitted mean
/// and spread against 0.0105 and 0.0065 mm. Naming them is a check of power, not a certainty:
/// with the earlier, centred joints, ten data sets (seeds 31–40, the default N = 4000) named
/// backlash in 8. With free play (a loaded pin bears on its hole's edge) backlash is a larger
/// effect: `scripts/diagnose-check.sh` (200 specimens) recovers a common clearance of
/// 0.0105 mm as 0.01056 [0.00991, 0.01124] and closes the gap from 1.233 to 0.014, and names
/// backlash on the paper's clearances from node positions alone.
#[test]
#[ignore = "slow statistical check (about 25 s): scripts/test.sh runs it"]
fn hidden_backlash_is_named_with_member_measurements() {
    let dir = tempfile::tempdir().unwrap();
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs/paper-4.2.3.json");
    let rigid = (paper.as_path(), "rigid-sigma-0.033");
    let d1 = dir.path().join("common");
    std::fs::create_dir_all(&d1).unwrap();
    let members = d1.join("members.csv");
    let m = make_from(
        rigid,
        &d1,
        "common",
        "backlash:clearance=0.0105",
        50,
        31,
        Some(members.clone()),
    );
    let v = diagnose_with(rigid, &d1, &m, Some(members), 600, Some(&RIVALS));
    check_recovered(&v, "backlash", &[("clearance", 0.0105)]);
    let updated = std::fs::read_to_string(d1.join("out/updated-job.json")).unwrap();
    let job: serde_json::Value = serde_json::from_str(&updated).unwrap();
    let case = job["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "rigid-sigma-0.033")
        .unwrap();
    assert_eq!(case["model"]["prism"]["backlash"], true, "{case}");
    let clearance = &case["backlash"]["clearance"];
    assert!(
        clearance["constant"].is_object() || clearance["uniform"].is_object(),
        "{case}"
    );
}

/// Conditioning each specimen's node term on its own measured members narrows the
/// backlash clearance's interval, compared with the distribution-only use of the same
/// member measurements, on the same data (paper clearances, 80 specimens, N = 150, backlash
/// against the length bias). Fails with the conditioning switched off (the two intervals
/// are then the same).
#[test]
#[ignore = "slow statistical check (about 10 s): scripts/test.sh runs it"]
fn conditioning_on_members_narrows_the_clearance() {
    let dir = tempfile::tempdir().unwrap();
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs/paper-4.2.3.json");
    let members = dir.path().join("members.csv");
    let m = make_from(
        (&paper, "backlash-sigma-0.033"),
        dir.path(),
        "paper",
        "none",
        80,
        34,
        Some(members.clone()),
    );
    let run_with = |condition: bool, name: &str| {
        let out = dir.path().join(name);
        run(&DiagnoseOptions {
            job: paper.clone(),
            case: "rigid-sigma-0.033".into(),
            measured: m.clone(),
            measured_members: Some(members.clone()),
            out: out.clone(),
            settings: Settings {
                samples: Some(150),
                measurement_sigma: 0.001,
                quiet: true,
                candidates: Some(vec!["backlash".into(), "length_bias".into()]),
                condition_on_members: condition,
                ..Settings::default()
            },
            plots: false,
        })
        .unwrap();
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("diagnosis.json")).unwrap())
                .unwrap();
        let step = v["steps"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["named_effect"] == "backlash")
            .cloned()
            .unwrap_or_else(|| panic!("backlash not named: {}", v["reason"]));
        let i = &step["parameters"][0]["interval"];
        let (lo, hi) = (i["lower"].as_f64().unwrap(), i["upper"].as_f64().unwrap());
        eprintln!(
            "condition {condition}: clearance {} [{lo}, {hi}]",
            step["parameters"][0]["value"]
        );
        hi - lo
    };
    let conditioned = run_with(true, "conditioned");
    let distribution = run_with(false, "distribution");
    assert!(
        conditioned < distribution,
        "{conditioned} !< {distribution}"
    );
}

/// The backlash check on the paper's clearances (U[0.004, 0.017] mm per joint, made by the
/// job's own backlash case, not through the candidate): 40 specimens with their members
/// measured, tried against backlash's [`RIVALS`] at N = 300, name backlash alone, and the gap
/// is at least halved. Fails with the candidate's clearance applied a tenth too small (it
/// cannot then reach the data within its plausible range).
#[test]
#[ignore = "about 20 s in the debug build since backlash and the confounding re-fits run at the cables' limit: scripts/test.sh runs it"]
fn hidden_backlash_is_named_fast() {
    let dir = tempfile::tempdir().unwrap();
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs/paper-4.2.3.json");
    let rigid = (paper.as_path(), "rigid-sigma-0.033");
    let members = dir.path().join("members.csv");
    let m = make_from(
        (&paper, "backlash-sigma-0.033"),
        dir.path(),
        "paper",
        "none",
        40,
        33,
        Some(members.clone()),
    );
    let v = diagnose_with(rigid, dir.path(), &m, Some(members), 300, Some(&RIVALS));
    assert_eq!(
        v["named_effects"],
        serde_json::json!(["backlash"]),
        "{}",
        v["reason"]
    );
    check_halved(&v);
}

/// The fast forward selection (with the slow tier): self-weight (a mean shift) and a longeron
/// scatter twice the stated (a change of scatter) hidden at once in 60 specimens, tried
/// against gravity, length_sigma and diagonal_pretension: both are named, one per step, and the
/// third step names nothing; each step's discrepancy shrinks, and `updated-job.json` holds
/// both effects.
#[test]
#[ignore = "about 20 s in the debug build since backlash and the confounding re-fits run at the cables' limit: scripts/test.sh runs it"]
fn two_hidden_effects_are_both_named_fast() {
    let dir = tempfile::tempdir().unwrap();
    let v = hidden(
        dir.path(),
        "two",
        "gravity:g_x=1;length_sigma:sigma.longeron=0.0126",
        (60, 26),
        300,
        &["gravity", "length_sigma", "diagonal_pretension"],
    );
    let named: Vec<&str> = v["named_effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    let mut sorted = named.clone();
    sorted.sort();
    assert_eq!(sorted, ["gravity", "length_sigma"], "{}", v["reason"]);
    assert_eq!(v["named_effect"], named[0]);
    let steps = v["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 3);
    assert!(
        !steps[2]["kept"].as_bool().unwrap(),
        "{}",
        steps[2]["reason"]
    );
    for s in &steps[..2] {
        assert!(s["kept"].as_bool().unwrap());
        assert!(s["discrepancy_after"].as_f64() < s["discrepancy_before"].as_f64());
    }
    assert_eq!(v["discrepancy_before"], steps[0]["discrepancy_before"]);
    assert_eq!(v["discrepancy_after"], steps[1]["discrepancy_after"]);
    let updated = std::fs::read_to_string(dir.path().join("out/updated-job.json")).unwrap();
    let job: serde_json::Value = serde_json::from_str(&updated).unwrap();
    let case = &job["cases"][0];
    assert!(case["effects"]["gravity"].is_object(), "{case}");
    let sigma = case["length_errors"]["longeron"]["normal"]["sigma"]
        .as_f64()
        .unwrap();
    assert!(sigma > 0.0063 * 1.3, "{case}");
    let md = std::fs::read_to_string(dir.path().join("out/diagnosis.md")).unwrap();
    assert!(md.contains("## Step 1:") && md.contains("## Step 3:"));
    assert!(!md.contains("p = 0.00e0"), "{md}");
}

/// The fast thermal check (the default run's version): a gradient of 0.002 K/mm along x
/// and a uniform 2 K on 40 specimens, tried against the temperature field and a diagonal
/// pretension:
/// the field is named alone, the truth inside the joint region, the gap at least halved.
#[test]
fn hidden_thermal_gradient_is_named_fast() {
    let dir = tempfile::tempdir().unwrap();
    let v = hidden(
        dir.path(),
        "thermal",
        "thermal_gradient:gradient_x=0.002,offset=2",
        (40, 21),
        300,
        &["thermal_gradient", "diagonal_pretension"],
    );
    assert_eq!(
        v["named_effects"],
        serde_json::json!(["thermal_gradient"]),
        "{}",
        v["reason"]
    );
    check_recovered(
        &v,
        "thermal_gradient",
        &[("gradient_x", 0.002), ("offset", 2.0)],
    );
}

/// The fast member-measurement check (the default run's version): a longeron bias of
/// 3 µm on 40 specimens, with and without their members measured one by one: named either
/// way, and the batten bias's interval at least halved with the members ([`check_narrower`]).
#[test]
fn member_measurements_narrow_a_length_effect_fast() {
    let dir = tempfile::tempdir().unwrap();
    let members = dir.path().join("members.csv");
    let m = make_with_members(
        dir.path(),
        "bias",
        "length_bias:bias.longeron=0.003",
        40,
        22,
        Some(members.clone()),
    );
    let (d1, d2) = (dir.path().join("nodes"), dir.path().join("members"));
    let only = Some(&["length_bias", "diagonal_pretension"][..]);
    let alone = diagnose_with((&job(), "as-built"), &d1, &m, None, 300, only);
    let both = diagnose_with((&job(), "as-built"), &d2, &m, Some(members), 300, only);
    check_recovered(&both, "length_bias", &[("bias.longeron", 0.003)]);
    assert_eq!(alone["named_effect"], "length_bias", "{}", alone["reason"]);
    check_narrower(&both, &alone);
}

/// The batten bias's interval at least halved by the member measurements. Node positions
/// barely see the battens' lengths, their measurements see them directly (600 and more
/// observations). The longerons' bias the nodes see well: given each specimen's measured
/// members its node positions say nothing more about the members' mean (the conditioned
/// likelihood, [`truss_diagnose::likelihood::conditional`]), so its interval comes from the member
/// observations alone and is about as wide as from the nodes alone (1.2 against 1.1 µm on
/// 40 specimens, seed 22).
fn check_narrower(both: &serde_json::Value, alone: &serde_json::Value) {
    let width = |v: &serde_json::Value, name: &str| {
        let p = v["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .unwrap();
        p["interval"]["upper"].as_f64().unwrap() - p["interval"]["lower"].as_f64().unwrap()
    };
    let (b, a) = (width(both, "bias.batten"), width(alone, "bias.batten"));
    assert!(b < 0.5 * a, "batten: {b} with members, {a} without");
}

/// The null check: data made from the baseline itself, 20 seeds at 100 specimens,
/// every candidate but backlash (the slowest to simulate; its null behaviour is that of the
/// others), N = 200 (2 of 20 named something). Fails with the test statistic Λ left
/// without its correction for the simulation's noise and misspecification (`c·λ̄`): 5 of 20. A false positive is any named effect or the verdict `unexplained`. The
/// rate must not be significantly above α = 0.05: at most 3 of 20 (for a rate of exactly
/// α, P(≥ 4 of 20) = 0.016). The same check at 30 specimens (where the comparison's
/// large-sample intervals are least trusted) is `ONLY=null-fpr scripts/diagnose-check.sh`.
#[test]
#[ignore = "slow statistical check (about 20 s): scripts/test.sh runs it"]
fn null_data_false_positive_rate_is_at_most_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let n = 100;
    let mut wrong = Vec::new();
    for seed in 501..521 {
        let d = dir.path().join(format!("{n}-{seed}"));
        std::fs::create_dir_all(&d).unwrap();
        let m = make(&d, "null", "none", n, seed);
        let v = diagnose(&d, &m, 200);
        if v["named_effects"] != serde_json::json!([]) || v["verdict"] == "unexplained" {
            wrong.push(format!(
                "seed {seed}: {} {}",
                v["verdict"], v["named_effects"]
            ));
        }
    }
    eprintln!(
        "{n} specimens: {} of 20 false positives {wrong:?}",
        wrong.len()
    );
    assert!(wrong.len() <= 3, "{n} specimens: {wrong:?}");
}

/// One typo row (z × 10) among 60 null specimens: it is left out as an outlier, listed in
/// diagnosis.json by specimen and line, and no effect is named.
#[test]
fn one_bad_row_is_an_outlier_not_an_effect() {
    let dir = tempfile::tempdir().unwrap();
    let m = make(dir.path(), "null", "none", 60, 3);
    let text = std::fs::read_to_string(&m).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Line 50 of the file (index 49): its z times ten.
    let mut f: Vec<String> = lines[49].split(',').map(String::from).collect();
    let z: f64 = f[4].parse().unwrap();
    f[4] = format!("{}", 10.0 * z);
    let specimen = f[0].clone();
    lines[49] = f.join(",");
    std::fs::write(&m, lines.join("\n") + "\n").unwrap();
    let v = diagnose_with(
        (&job(), "as-built"),
        dir.path(),
        &m,
        None,
        300,
        Some(&["length_sigma", "diagonal_pretension"]),
    );
    let o = &v["data"]["outliers"];
    assert_eq!(o.as_array().unwrap().len(), 1, "{o}");
    assert_eq!(o[0]["specimen"], specimen.as_str());
    assert_eq!(o[0]["line"], 50);
    assert_eq!(v["data"]["specimens_used"], 59);
    assert_eq!(v["named_effects"], serde_json::json!([]), "{}", v["reason"]);
}

/// The refusals, each naming what is wrong: `--samples` above the documented 10 000,
/// `--threads 0`, and `synth-measured` parameters outside their range or not finite (`clearance=-0.01`
/// was silently taken as 0, `gradient_x=nan` gave an internal error).
#[test]
fn out_of_range_settings_and_effects_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let m = make(dir.path(), "few", "none", 6, 1);
    let refused = |settings: Settings| {
        run(&DiagnoseOptions {
            job: job(),
            case: "as-built".into(),
            measured: m.clone(),
            measured_members: None,
            out: dir.path().join("out"),
            settings: Settings {
                quiet: true,
                ..settings
            },
            plots: false,
        })
        .unwrap_err()
        .to_string()
    };
    let e = refused(Settings {
        samples: Some(100_000_000),
        ..Settings::default()
    });
    assert!(
        e.contains("--samples 100000000: must be from 100 to 10000"),
        "{e}"
    );
    let e = refused(Settings {
        threads: Some(0),
        ..Settings::default()
    });
    assert!(e.contains("--threads 0: must be from 1 to 1024"), "{e}");
    let synth_err = |effect: &str| {
        let mut out = Vec::new();
        synth(
            &SynthOptions {
                job: job(),
                case: "as-built".into(),
                specimens: 5,
                seed: 1,
                effect: effect.into(),
                measurement_sigma: 0.001,
                all_nodes: false,
                members_out: None,
            },
            &mut out,
        )
        .unwrap_err()
        .to_string()
    };
    let e = synth_err("backlash:clearance=-0.01");
    assert!(
        e.contains("clearance = -0.01 is outside its plausible range [0, 0.05] mm"),
        "{e}"
    );
    let e = synth_err("thermal_gradient:gradient_x=nan");
    assert!(e.contains("gradient_x = nan is outside"), "{e}");
}

/// The example: the three battens of level 3 each 5 µm short (a bad batch: the
/// batten group's mean 0.8 µm short), 200 specimens as in the issue, the default N,
/// three candidates. Nothing is named, the verdict is `none` and reads "no effect above
/// these sizes is missing", and the report says how large each candidate would have had
/// to be, the batten bias's limit above the batch's mean shift (about 15 s in release).
#[test]
#[ignore = "slow statistical check: run in release"]
fn a_bad_batch_below_the_limits_is_reported_as_unseen() {
    use truss_diagnose::comparison::baseline::Baseline;
    use truss_diagnose::comparison::measured::Coordinate;
    use truss_diagnose::comparison::simulate::{Noise, simulate, top_indices};
    let dir = tempfile::tempdir().unwrap();
    let baseline = Baseline::read(&job(), "as-built").unwrap();
    let mut batch = baseline
        .job_of(&baseline.derived_case(), 200, Some(91))
        .unwrap();
    let case = &mut batch.cases[0];
    let model = case.model.clone();
    for (m, member) in model.members().iter().enumerate() {
        if member.id.starts_with("batten.3.") {
            let d = case.member_errors[m].unwrap();
            case.member_errors[m] = Some(d.shifted(-0.005));
        }
    }
    let top = model.top_surface().unwrap().nodes;
    let coords = Coordinate::of_nodes(&model, &top);
    let noise = Noise {
        sigma: 0.001,
        seed: 91,
    };
    let sim = simulate(
        &batch,
        &coords,
        200,
        Some((noise, top_indices(&coords, top).unwrap())),
        1,
    )
    .unwrap();
    let mut csv = Vec::new();
    write_specimens(&mut csv, &model, &top, &sim.x_noisy).unwrap();
    let measured = dir.path().join("batch.csv");
    std::fs::write(&measured, csv).unwrap();
    let out = dir.path().join("out");
    let summary = run(&DiagnoseOptions {
        job: job(),
        case: "as-built".into(),
        measured,
        measured_members: None,
        out: out.clone(),
        settings: Settings {
            samples: None,
            measurement_sigma: 0.001,
            quiet: true,
            candidates: Some(
                ["length_bias", "thermal_gradient", "length_sigma"]
                    .map(String::from)
                    .to_vec(),
            ),
            threads: Some(1),
            ..Default::default()
        },
        plots: false,
    })
    .unwrap();
    assert!(summary.named_effects.is_empty(), "{}", summary.reason);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("diagnosis.json")).unwrap())
            .unwrap();
    let md = std::fs::read_to_string(out.join("diagnosis.md")).unwrap();
    eprintln!(
        "{}\n{}",
        summary.answer.join("\n"),
        &md[..md.len().min(2500)]
    );
    let unseen = v["unseen"].as_array().unwrap();
    assert_eq!(unseen.len(), 3, "{unseen:?}");
    let bias = unseen.iter().find(|u| u["name"] == "length_bias").unwrap();
    let batten = bias["limit"]["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "bias.batten")
        .unwrap();
    let size = batten["size"].as_f64().unwrap();
    assert!(size > 0.005 * 3.0 / 18.0, "{batten}");
    assert!(md.contains("**Could not have been seen**"), "{md}");
    // The answer's limits line names the three candidates tried.
    let limits = summary
        .answer
        .iter()
        .find(|l| l.starts_with("- Could not have been seen"))
        .expect("the answer states the limits");
    for name in ["length_bias", "thermal_gradient", "length_sigma"] {
        assert!(limits.contains(name), "{limits}");
    }
    assert_eq!(
        summary.verdict,
        truss_diagnose::selection::decide::Verdict::None,
        "{}",
        summary.reason
    );
    assert!(
        md.contains("no effect above these sizes is missing"),
        "{md}"
    );
}
