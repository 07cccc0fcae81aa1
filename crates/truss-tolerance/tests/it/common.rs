//! Jobs for the tests, written into a scratch directory.

use std::path::PathBuf;

/// A job of an `stages`-stage prism with one case per `(name, length_errors JSON)`.
pub fn job(dir: &tempfile::TempDir, stages: usize, cases: &[(&str, &str)]) -> PathBuf {
    let cases: Vec<String> = cases
        .iter()
        .map(|(name, errors)| {
            format!(r#"{{"name": "{name}", "samples": 1000, "length_errors": {errors}}}"#)
        })
        .collect();
    let text = format!(
        r#"{{"model": {{"prism": {{"stages": {stages}}}}}, "seed": 20210325, "cases": [{}]}}"#,
        cases.join(", ")
    );
    let path = dir.path().join("job.json");
    std::fs::write(&path, text).unwrap();
    path
}

/// Both groups normal with σ \[mm\].
pub fn both(sigma: f64) -> String {
    format!(
        r#"{{"batten": {{"normal": {{"sigma": {sigma}}}}}, "longeron": {{"normal": {{"sigma": {sigma}}}}}}}"#
    )
}
