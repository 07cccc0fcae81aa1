//! The data checks before anything is fitted, end to end through `run`: the issue's
//! copy-paste slip (30 rows of one specimen, no effect, once diagnosed as gravity at
//! p < 1e-16) is refused, naming the copies, and nothing is written.

use super::{job, make};
use truss_diagnose::settings::Settings;
use truss_diagnose::{DiagnoseOptions, run};

/// One specimen of the baseline (no effect) written 30 times under 30 specimen ids: refused
/// before any simulation, with the 29 copies named as one range of the first one, and no
/// diagnosis.json written.
#[test]
fn thirty_copies_of_one_specimen_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // (One specimen made: synth refused a single one, "0 of 1 samples failed", before.)
    let one = make(dir.path(), "one", "none", 1, 5);
    let text = std::fs::read_to_string(&one).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.filter(|r| r.starts_with("S0001,")).collect();
    let mut copies = format!("{header}\n");
    for k in 1..=30 {
        for r in &rows {
            let (_, rest) = r.split_once(',').unwrap();
            copies += &format!("C{k:02},{rest}\n");
        }
    }
    let measured = dir.path().join("copies.csv");
    std::fs::write(&measured, copies).unwrap();
    let out = dir.path().join("out");
    let e = run(&DiagnoseOptions {
        job: job(),
        case: "as-built".into(),
        measured: measured.clone(),
        measured_members: None,
        out: out.clone(),
        settings: Settings {
            samples: Some(300),
            measurement_sigma: 0.001,
            quiet: true,
            ..Settings::default()
        },
        plots: false,
    })
    .expect_err("30 copies of one specimen are refused")
    .to_string();
    let n = rows.len();
    let expected = format!(
        "\"C02\" to \"C30\" (29 specimens, first lines {} to {}) repeat \"C01\" (line 2)",
        2 + n,
        2 + 29 * n
    );
    assert!(
        e.starts_with(&format!("{}: 29 specimen(s) repeat", measured.display()))
            && e.contains(&expected),
        "{e}"
    );
    assert!(!out.join("diagnosis.json").exists());
}
