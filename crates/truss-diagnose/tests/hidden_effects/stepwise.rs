//! The stepwise selection end to end (issue 14): two effects hidden at once, where the
//! effect named first is only a stand-in for one found later, so a later step must swap it
//! out or remove it. These are two of `scripts/diagnose-check.sh`'s pairs (seed 301, 200
//! specimens), each a few tens of seconds in release.

use super::{diagnose, make};

/// The step at which `effect` left the model, and the record of its leaving.
fn removal<'a>(v: &'a serde_json::Value, effect: &str) -> (u64, &'a serde_json::Value) {
    v["steps"]
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
        .unwrap_or_else(|| panic!("{effect} never removed: {}", v["steps"]))
}

/// The final model's fitted value and 95 % interval of `effect`'s parameter `name`.
fn fitted(v: &serde_json::Value, effect: &str, name: &str) -> (f64, f64, f64) {
    let step = v["steps"]
        .as_array()
        .unwrap()
        .iter()
        .rev()
        .find(|s| s["kept"] == true)
        .unwrap();
    let p = step["refitted"]
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
        .unwrap_or_else(|| panic!("{effect}.{name} not in the final model"));
    let f = |x: &serde_json::Value| x.as_f64().unwrap();
    (
        f(&p["value"]),
        f(&p["interval"]["lower"]),
        f(&p["interval"]["upper"]),
    )
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
/// pretension's uniform shortening first looks like a length bias, which is named at step 1;
/// once the scatter is in the model, step 2 swaps the bias for the pretension (the swapped
/// model better by far more than the ΔBIC of 2 a swap needs), and the fitted values hold the
/// truth.
#[test]
#[ignore = "slow statistical check (tens of seconds): scripts/test.sh runs it in release"]
fn a_stand_in_is_swapped_for_the_effect_it_stood_for() {
    let dir = tempfile::tempdir().unwrap();
    let m = make(
        dir.path(),
        "pretension-sigma",
        "diagonal_pretension:length_error=-0.05;length_sigma:sigma.batten=0.015",
        200,
        301,
    );
    let v = diagnose(dir.path(), &m);
    assert_eq!(
        named(&v),
        ["diagonal_pretension", "length_sigma"],
        "{}",
        v["reason"]
    );
    let (step, r) = removal(&v, "length_bias");
    assert!(r["added_in_step"].as_u64().unwrap() < step, "{r}");
    assert_eq!(r["replaced_by"], "diagonal_pretension", "{r}");
    assert!(r["delta_bic"].as_f64().unwrap() <= -2.0, "{r}");
    for (effect, name, truth) in [
        ("diagonal_pretension", "length_error", -0.05),
        ("length_sigma", "sigma.batten", 0.015),
    ] {
        let (value, lo, hi) = fitted(&v, effect, name);
        assert!(
            lo <= truth && truth <= hi,
            "{effect}.{name}: truth {truth} outside [{lo}, {hi}] (fit {value})"
        );
    }
}

/// A temperature field (0.002 K/mm along x on a uniform 2 K) and a batten scatter of 15 µm:
/// the uniform part shortens every member alike, so a length bias is named before the field;
/// once the field is in the model the bias explains nothing more and is removed, listed as
/// taken over by the field, and the fitted values hold the truth.
#[test]
#[ignore = "slow statistical check (tens of seconds): scripts/test.sh runs it in release"]
fn an_effect_a_later_one_explains_is_removed() {
    let dir = tempfile::tempdir().unwrap();
    let m = make(
        dir.path(),
        "thermal-sigma",
        "thermal_gradient:gradient_x=0.002,offset=2;length_sigma:sigma.batten=0.015",
        200,
        301,
    );
    let v = diagnose(dir.path(), &m);
    assert_eq!(
        named(&v),
        ["length_sigma", "thermal_gradient"],
        "{}",
        v["reason"]
    );
    let (step, r) = removal(&v, "length_bias");
    assert!(r["added_in_step"].as_u64().unwrap() < step, "{r}");
    assert!(r["replaced_by"].is_null(), "{r}");
    assert_eq!(r["explained_by"], "thermal_gradient", "{r}");
    for (effect, name, truth) in [
        ("thermal_gradient", "gradient_x", 0.002),
        ("thermal_gradient", "offset", 2.0),
        ("length_sigma", "sigma.batten", 0.015),
    ] {
        let (value, lo, hi) = fitted(&v, effect, name);
        assert!(
            lo <= truth && truth <= hi,
            "{effect}.{name}: truth {truth} outside [{lo}, {hi}] (fit {value})"
        );
    }
}
