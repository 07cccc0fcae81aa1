//! Shared job builders for the integration tests.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A small job: a 2-stage prism, two cases, `n` samples each.
pub fn small_job(n: u64) -> String {
    format!(
        r#"{{
  "model": {{"prism": {{"stages": 2}}}},
  "seed": 7,
  "cases": [
    {{"name": "normal", "samples": {n},
      "length_errors": {{"batten": {{"normal": {{"sigma": 0.0063}}}}, "longeron": {{"normal": {{"sigma": 0.0063}}}}}}}},
    {{"name": "uniform", "samples": {n},
      "length_errors": {{"longeron": {{"uniform": {{"low": -0.02, "high": 0.02}}}}}}}}
  ]
}}"#
    )
}

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The sample lines of every shard file in `dir`, in index order.
pub fn sample_lines(dir: &Path) -> Vec<String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
        .collect();
    files.sort();
    files
        .iter()
        .flat_map(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            text.lines()
                .filter(|l| l.starts_with(r#"{"record":"sample""#))
                .map(String::from)
                .collect::<Vec<_>>()
        })
        .collect()
}
