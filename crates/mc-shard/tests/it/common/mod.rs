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

/// Rewrites the complete shard file `path` with `edit` applied to its samples and fresh,
/// valid digests: a forged file that every digest check passes.
pub fn forge_shard(path: &Path, edit: impl Fn(&mut shard_record::Sample)) {
    use shard_record::{Record, ShardEncoder, Status, parse_record};
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let Ok(Record::Begin(begin)) = parse_record(lines.next().unwrap().as_bytes()) else {
        panic!("no header")
    };
    let (mut encoder, mut out) = ShardEncoder::new(&begin);
    for line in lines {
        if let Ok(Record::Sample(mut s)) = parse_record(line.as_bytes()) {
            edit(&mut s);
            encoder.push(s.to_line().as_bytes(), s.status == Status::Failed, &mut out);
        }
    }
    out.extend_from_slice(&encoder.end().1);
    std::fs::write(path, out).unwrap();
}

/// The only `.jsonl` shard file in `dir`.
pub fn only_shard(dir: &Path) -> PathBuf {
    let files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    files[0].clone()
}
