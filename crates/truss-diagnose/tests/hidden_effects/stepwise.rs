//! The stepwise selection end to end: two effects hidden at once, where the
//! effect named first is only a stand-in for one found later, so a later step must swap it
//! out or remove it. These are two of `scripts/diagnose-check.sh`'s pairs (seed 301, 200
//! specimens), tried here against the two true effects and the stand-in only, at N = 500
//! (every candidate at the default N is the script's). Each fails with the backward
//! elimination and the swap switched off. A third check hides two effects that show only
//! together (backlash and a diagonal pretension) and needs the pair step.

use super::{RIVALS, diagnose_with, final_parameter, job, make, make_from};
use std::path::Path;

/// The record of `effect` leaving the model, which must have added it at an earlier step.
fn removal<'a>(v: &'a serde_json::Value, effect: &str) -> &'a serde_json::Value {
    let (step, r) = v["steps"]
        .as_array()
        .unwrap()
        .iter()
        .find_map(|s| {
            s["removed_effects"]
                .as_array()?
                .iter()
                .find(|r| r["name"] == effect)
                .map(|r| (s["number"].as_u64().unwrap(), r))
        })
        .unwrap_or_else(|| panic!("{effect} never removed: {}", v["steps"]));
    assert!(r["added_in_step"].as_u64().unwrap() < step, "{r}");
    r
}

/// Each `(effect, parameter, truth)` inside the final model's 95 % interval of that
/// parameter (its joint fit's, [`final_parameter`]).
fn check_truths(v: &serde_json::Value, truths: &[(&str, &str, f64)]) {
    for &(effect, name, truth) in truths {
        let p = final_parameter(v, effect, name);
        let f = |x: &serde_json::Value| x.as_f64().unwrap();
        let (lo, hi) = (f(&p["interval"]["lower"]), f(&p["interval"]["upper"]));
        assert!(
            lo <= truth && truth <= hi,
            "{effect}.{name}: truth {truth} outside [{lo}, {hi}] (fit {})",
            p["value"]
        );
    }
}

/// Where each step's named effect is profiled (`selection::step`'s module doc): at step 1,
/// and at a later step whose update leaves it alone in the model (no joint re-fit); a later
/// step whose effect joins others keeps its Wald intervals, the joint re-fit giving the
/// final numbers. Returns how many later steps skipped their profiles.
fn check_profiles(v: &serde_json::Value) -> usize {
    let mut skipped = 0;
    for s in v["steps"].as_array().unwrap() {
        if s["named_effect"] == "none" {
            continue;
        }
        let alone = s["refitted"].as_array().is_none_or(|r| r.is_empty());
        let want = if s["number"] == 1 || alone {
            "profile"
        } else {
            "wald"
        };
        skipped += usize::from(want == "wald");
        for p in s["parameters"].as_array().unwrap() {
            assert_eq!(p["interval"]["method"], want, "step {}: {p}", s["number"]);
        }
    }
    skipped
}

/// The diagnosis of 200 specimens (seed 301) with `effects` hidden, against `candidates`
/// at N = 500, and the effects it names, sorted.
fn diagnose_pair(
    name: &str,
    effects: &str,
    candidates: &[&str],
) -> (serde_json::Value, Vec<String>) {
    let dir = tempfile::tempdir().unwrap();
    let m = make(dir.path(), name, effects, 200, 301);
    let v = diagnose_with(
        (&job(), "as-built"),
        dir.path(),
        &m,
        None,
        500,
        Some(candidates),
    );
    let named = named(&v);
    (v, named)
}

fn named(v: &serde_json::Value) -> Vec<String> {
    let mut n: Vec<String> = v["named_effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap().to_owned())
        .collect();
    n.sort();
    n
}

/// A diagonal pretension (every diagonal 0.05 mm short) and a batten scatter of 15 µm: the
/// pretension's uniform shortening first looks like a length bias, which is named at an
/// earlier step; once the scatter is in the model, a later step swaps the bias for the
/// pretension (the swapped model better by at least the ΔBIC of 2 a swap needs), and the
/// fitted values hold the truth.
#[test]
#[ignore = "slow statistical check (about 15 s): scripts/test.sh runs it"]
fn a_stand_in_is_swapped_for_the_effect_it_stood_for() {
    let (v, named) = diagnose_pair(
        "pretension-sigma",
        "diagonal_pretension:length_error=-0.05;length_sigma:sigma.batten=0.015",
        &["diagonal_pretension", "length_sigma", "length_bias"],
    );
    assert_eq!(
        named,
        ["diagonal_pretension", "length_sigma"],
        "{}",
        v["reason"]
    );
    let r = removal(&v, "length_bias");
    assert_eq!(r["replaced_by"], "diagonal_pretension", "{r}");
    assert!(check_profiles(&v) >= 1, "{}", v["steps"]);
    assert!(r["delta_bic"].as_f64().unwrap() <= -2.0, "{r}");
    // One record of what cannot be told apart: the pretension, swapped in and named by no
    // step, lists the bias it took over from in its record, and so, as the final model's
    // first effect, in the top-level field (both were empty while the markdown said so).
    let lists_bias =
        |a: &serde_json::Value| a.as_array().unwrap().iter().any(|x| x == "length_bias");
    let record = v["indistinguishable_by_effect"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["effect"] == "diagonal_pretension" && e["swapped_in"] == true)
        .unwrap_or_else(|| panic!("{}", v["indistinguishable_by_effect"]));
    assert!(lists_bias(&record["rivals"]), "{record}");
    if v["named_effect"] == "diagonal_pretension" {
        assert!(
            lists_bias(&v["indistinguishable"]),
            "{}",
            v["indistinguishable"]
        );
    }
    check_truths(
        &v,
        &[
            ("diagonal_pretension", "length_error", -0.05),
            ("length_sigma", "sigma.batten", 0.015),
        ],
    );
}

/// A temperature field (0.002 K/mm along x on a uniform 2 K) and a batten scatter of 15 µm:
/// the uniform part shortens every member alike, so a length bias is named before the field;
/// once the field is in the model the bias explains nothing more and is removed, listed as
/// taken over by the field, and the fitted values hold the truth.
#[test]
#[ignore = "slow statistical check (about 15 s): scripts/test.sh runs it"]
fn an_effect_a_later_one_explains_is_removed() {
    let (v, named) = diagnose_pair(
        "thermal-sigma",
        "thermal_gradient:gradient_x=0.002,offset=2;length_sigma:sigma.batten=0.015",
        &["thermal_gradient", "length_sigma", "length_bias"],
    );
    assert_eq!(
        named,
        ["length_sigma", "thermal_gradient"],
        "{}",
        v["reason"]
    );
    let r = removal(&v, "length_bias");
    assert!(r["replaced_by"].is_null(), "{r}");
    assert!(check_profiles(&v) >= 1, "{}", v["steps"]);
    assert_eq!(r["explained_by"], "thermal_gradient", "{r}");
    check_truths(
        &v,
        &[
            ("thermal_gradient", "gradient_x", 0.002),
            ("thermal_gradient", "offset", 2.0),
            ("length_sigma", "sigma.batten", 0.015),
        ],
    );
}

/// Effects that show only together: section 4.2.3's truss (`jobs/paper-4.2.3.json`, case
/// rigid-sigma-0.033) with pin joints in free play (clearances U[0.004, 0.017] mm, the
/// paper's) and every diagonal 35 µm short, 100 specimens (seed 601), node positions only,
/// against backlash's rivals at the default N (2,000). Each alone fits worse than a
/// longeron length bias (ΔBIC −883.5 and −881.0 against −886.4), which the selection
/// names without the pair step (and then stops: backlash re-fits to 0 given the bias);
/// fitted jointly the two reach ΔBIC −892.6, significant and lower by more than 2, so they
/// are named together at step 1, and the truths (mean clearance 0.0105 mm, −0.035 mm)
/// lie in the final fit's intervals. Fails with the pair step switched off (checked by
/// hand on the code before it: `length_bias` named alone).
#[test]
#[ignore = "slow statistical check (about 20 s): scripts/test.sh runs it"]
fn effects_that_show_only_together_are_named_as_a_pair() {
    let dir = tempfile::tempdir().unwrap();
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs/paper-4.2.3.json");
    let m = make_from(
        (&paper, "rigid-sigma-0.033"),
        dir.path(),
        "together",
        "backlash:clearance=0.0105,spread=0.0065;diagonal_pretension:length_error=-0.035",
        100,
        601,
        None,
    );
    let v = diagnose_with(
        (&paper, "rigid-sigma-0.033"),
        dir.path(),
        &m,
        None,
        2000,
        Some(&RIVALS),
    );
    assert_eq!(
        named(&v),
        ["backlash", "diagonal_pretension"],
        "{}",
        v["reason"]
    );
    let first = &v["steps"][0];
    let pair = &first["pair"];
    assert_eq!(pair["outcome"], "named", "{first}");
    assert_eq!(
        pair["effects"],
        serde_json::json!(["backlash", "diagonal_pretension"])
    );
    let bic = |x: &serde_json::Value| x.as_f64().unwrap();
    assert!(
        bic(&pair["delta_bic"]) <= bic(&pair["decision_delta_bic"]) - 2.0,
        "{pair}"
    );
    let length_bias = first["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "length_bias")
        .unwrap();
    assert_eq!(pair["decision_delta_bic"], length_bias["delta_bic"]);
    check_truths(
        &v,
        &[
            ("backlash", "clearance", 0.0105),
            ("diagonal_pretension", "length_error", -0.035),
        ],
    );
}
