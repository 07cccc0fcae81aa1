//! What the data cannot tell apart, and what they do not determine: the final model's
//! joint fit, its undetermined parameters and the rivals confounded with its effects.

use super::{final_parameter, hidden};

/// Self-weight at 45° in the horizontal plane (g_x = g_y = −0.707 g) in 60 specimens,
/// tried against gravity and a diagonal pretension: gravity is named, g_x and g_y are
/// determined and hold the truth in their intervals, g_z is reported not determined (a
/// vertical self-weight barely moves the top of this stiff prism), and `diagnosis.md` gives
/// it no reading while `updated-job.json` keeps its best-fitting value.
#[test]
fn horizontal_self_weight_leaves_g_z_undetermined_fast() {
    let dir = tempfile::tempdir().unwrap();
    let v = hidden(
        dir.path(),
        "horizontal",
        "gravity:g_x=-0.7071,g_y=-0.7071",
        (60, 27),
        300,
        &["gravity", "diagonal_pretension"],
    );
    assert_eq!(
        v["named_effects"],
        serde_json::json!(["gravity"]),
        "{}",
        v["reason"]
    );
    for axis in ["g_x", "g_y"] {
        let p = final_parameter(&v, "gravity", axis);
        assert_eq!(p["determined"], true, "{p}");
        let (lo, hi) = (
            p["interval"]["lower"].as_f64().unwrap(),
            p["interval"]["upper"].as_f64().unwrap(),
        );
        let truth = -std::f64::consts::FRAC_1_SQRT_2;
        assert!(lo <= truth && truth <= hi, "{p}");
    }
    let gz = final_parameter(&v, "gravity", "g_z");
    assert_eq!(gz["determined"], false, "{gz}");
    let md = std::fs::read_to_string(dir.path().join("out/diagnosis.md")).unwrap();
    assert!(
        md.contains("g_z = ") && md.contains("not determined by these data"),
        "{md}"
    );
    assert!(!md.contains("along +z") && !md.contains("along −z"), "{md}");
    let updated = std::fs::read_to_string(dir.path().join("out/updated-job.json")).unwrap();
    let job: serde_json::Value = serde_json::from_str(&updated).unwrap();
    let direction = &job["cases"][0]["effects"]["gravity"]["direction"];
    let g = job["cases"][0]["effects"]["gravity"]["g"].as_f64().unwrap() / 9.80665;
    let fitted = direction[2].as_f64().unwrap() * g;
    assert!(
        (fitted - gz["value"].as_f64().unwrap()).abs() < 1e-9,
        "{direction} {g}"
    );
}

/// Self-weight tilted from the prism's axis z, 200 specimens, tried against gravity and a
/// diagonal pretension, N = 300: at 45° (g_x = g_z = −0.707 g) and at 30° (g_x = −0.5,
/// g_z = −0.866 g). Gravity is named; g_x and g_y are determined; every component
/// determined holds its truth in its interval; and each component's profile interval is
/// its Wald interval (an invariance: self-weight is a load proportional to g, so ℓ is
/// quadratic in each component and its profile interval is the Wald one,
/// `likelihood::profile`'s hand derivation), end by end where neither end is cut at the
/// range and the fit is inside it, to a fifth of the Wald half-width. Fails with gravity's
/// old \|g\| ≤ 1 (the ball projection restored in `Gravity::project`): g_z's profile ends
/// where the ball leaves it room beside g_x, not where ℓ does, at −0.34 against its Wald
/// +0.08 (45°, seed 2), at −0.55 against −0.13 (30°, seed 3, where g_z was "determined"
/// on [−0.92, −0.55]). Seeds 2–8 pass at both angles; with the ball seeds 2, 3 and 7 fail
/// at both (at 45° seed 7 on g_x). Seed 1 fails either way: its specimens put g_y at
/// −0.105 g, its interval [−0.18, −0.03] missing the 0 (a miss of one interval in twenty).
#[test]
#[ignore = "slow statistical check (a few seconds): scripts/test.sh runs it"]
fn tilted_self_weight_is_recovered_with_honest_intervals() {
    use std::f64::consts::FRAC_1_SQRT_2;
    for (name, effect, truth, seed) in [
        (
            "tilt-45",
            "gravity:g_x=-0.7071,g_z=-0.7071",
            [-FRAC_1_SQRT_2, 0.0, -FRAC_1_SQRT_2],
            2,
        ),
        (
            "tilt-30",
            "gravity:g_x=-0.5,g_z=-0.866",
            [-0.5, 0.0, -0.866],
            3,
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let v = hidden(
            dir.path(),
            name,
            effect,
            (200, seed),
            300,
            &["gravity", "diagonal_pretension"],
        );
        assert_eq!(
            v["named_effects"],
            serde_json::json!(["gravity"]),
            "{name}: {}",
            v["reason"]
        );
        for (axis, truth) in ["g_x", "g_y", "g_z"].into_iter().zip(truth) {
            let p = final_parameter(&v, "gravity", axis);
            if axis != "g_z" {
                assert_eq!(p["determined"], true, "{name} {p}");
            }
            let end = |i: &str, e: &str| p[i][e].as_f64().unwrap();
            let (lo, hi) = (end("interval", "lower"), end("interval", "upper"));
            if p["determined"] == true {
                assert!(
                    lo <= truth && truth <= hi,
                    "{name}: truth {truth} outside {p}"
                );
            }
            let value = p["value"].as_f64().unwrap();
            if value.abs() >= 1.0 - 1e-9 {
                continue;
            }
            let half = 0.5 * (end("wald_interval", "upper") - end("wald_interval", "lower"));
            for e in ["lower", "upper"] {
                let cut = format!("{e}_at_range_end");
                if p["interval"][&cut] == true || p["wald_interval"][&cut] == true {
                    continue;
                }
                let (profile, wald) = (end("interval", e), end("wald_interval", e));
                assert!(
                    (profile - wald).abs() <= 0.2 * half,
                    "{name} {axis} {e}: profile {profile} against Wald {wald} (half-width {half}): {p}"
                );
            }
        }
    }
}

/// The mean shifts node positions nearly confuse: a temperature field without offset and
/// every longeron 3 µm short, in 60 specimens, tried against the field and the length
/// bias. Either both are named, or the one named lists the other as confounded with it
/// (in `confounding` and as indistinguishable at its step), naming the field's offset or
/// vertical gradient, and `diagnosis.md` says the two cannot be told apart and what would
/// separate them.
#[test]
fn an_absorbed_length_bias_is_said_fast() {
    let dir = tempfile::tempdir().unwrap();
    let v = hidden(
        dir.path(),
        "field-longeron",
        "thermal_gradient:gradient_x=-0.001;length_bias:bias.longeron=-0.003",
        (60, 31),
        300,
        &["thermal_gradient", "length_bias"],
    );
    let named: Vec<&str> = v["named_effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap())
        .collect();
    if named.len() == 2 {
        return;
    }
    assert_eq!(named.len(), 1, "{}", v["reason"]);
    let (effect, rival) = match named[0] {
        "thermal_gradient" => ("thermal_gradient", "length_bias"),
        _ => ("length_bias", "thermal_gradient"),
    };
    let c = v["confounding"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["effect"] == effect && c["rival"] == rival)
        .unwrap_or_else(|| panic!("{rival} not confounded: {}", v["confounding"]));
    let confounded: Vec<&str> = c["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    if effect == "thermal_gradient" {
        assert!(
            confounded.contains(&"offset") || confounded.contains(&"gradient_z"),
            "{confounded:?}"
        );
    }
    let step = v["steps"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["named_effect"] == effect)
        .unwrap();
    assert!(
        step["indistinguishable"]
            .as_array()
            .unwrap()
            .iter()
            .any(|r| r == rival),
        "{step}"
    );
    let md = std::fs::read_to_string(dir.path().join("out/diagnosis.md")).unwrap();
    assert!(
        md.contains(&format!("Cannot be told apart: `{effect}` and `{rival}`"))
            && md.contains("What would separate them"),
        "{md}"
    );
}

/// A uniform temperature offset of 2 K with every batten 3 µm long, in 100 specimens, tried
/// against the temperature field and the length bias: the field's offset and vertical
/// gradient take up the batten bias, and the joint fit with `length_bias` added stays at
/// the bias's null (on this seed; the ridge is flat, so where its maximum sits is chance).
/// The rival must still be listed as confounded with the field's offset or vertical
/// gradient: here only the ridge probe finds it (`along_ridge`), and without the probe
/// nothing was listed. Both named passes too.
#[test]
#[ignore = "slow statistical check (a few seconds): scripts/test.sh runs it"]
fn a_batten_bias_on_a_flat_ridge_is_said() {
    let dir = tempfile::tempdir().unwrap();
    let v = hidden(
        dir.path(),
        "offset-batten",
        "thermal_gradient:offset=2;length_bias:bias.batten=0.003",
        (100, 302),
        300,
        &["thermal_gradient", "length_bias"],
    );
    let named = v["named_effects"].as_array().unwrap();
    if named.len() == 2 {
        return;
    }
    assert_eq!(named, &["thermal_gradient"], "{}", v["reason"]);
    let c = v["confounding"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["effect"] == "thermal_gradient" && c["rival"] == "length_bias")
        .unwrap_or_else(|| panic!("length_bias not confounded: {}", v["confounding"]));
    assert!(
        c["parameters"].as_array().unwrap().iter().any(|p| {
            (p["name"] == "offset" || p["name"] == "gradient_z") && p["moved"] == true
        }),
        "{c}"
    );
    let md = std::fs::read_to_string(dir.path().join("out/diagnosis.md")).unwrap();
    assert!(
        md.contains("Cannot be told apart: `thermal_gradient` and `length_bias`"),
        "{md}"
    );
}

/// One clear effect (self-weight along +x, 60 specimens) against gravity and a diagonal
/// pretension: gravity named alone, every parameter of its final fit determined or not as
/// its interval says, and no rival listed as confounded with it.
#[test]
fn one_clear_effect_lists_no_confounding_fast() {
    let dir = tempfile::tempdir().unwrap();
    let v = hidden(
        dir.path(),
        "gravity-x",
        "gravity:g_x=1",
        (60, 33),
        300,
        &["gravity", "diagonal_pretension"],
    );
    assert_eq!(
        v["named_effects"],
        serde_json::json!(["gravity"]),
        "{}",
        v["reason"]
    );
    assert_eq!(
        v["confounding"],
        serde_json::json!([]),
        "{}",
        v["confounding"]
    );
    let md = std::fs::read_to_string(dir.path().join("out/diagnosis.md")).unwrap();
    assert!(!md.contains("Cannot be told apart"), "{md}");
}
