//! `mc-merge --export`: the flat CSV / JSON Lines export of every sample, verified like a
//! merge (crate doc of `mc_merge::export`).

use crate::common::{SynthCase, SynthJob};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn job() -> SynthJob {
    SynthJob::new(
        3,
        vec![
            SynthCase::rayleigh("a", 250, 2e-5, &[("sigma", 0.0033)]),
            SynthCase::rayleigh("b", 150, 4e-5, &[("sigma", 0.0066)]),
        ],
    )
}

fn mc_merge(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mc-merge"))
        .arg(dir)
        .args(args)
        .output()
        .unwrap()
}

/// The raw text of `key`'s value in a sample line (up to the next comma or brace).
fn raw<'a>(line: &'a str, key: &str) -> &'a str {
    let Some(at) = line.find(&format!("\"{key}\":")) else {
        return "";
    };
    let rest = &line[at + key.len() + 3..];
    let end = rest.find([',', '}']).unwrap();
    rest[..end].trim_matches('"')
}

/// The sample lines of the shard files in `dir`, in index order.
fn shard_lines(files: &[PathBuf]) -> Vec<String> {
    let mut files = files.to_vec();
    files.sort();
    files
        .iter()
        .flat_map(|f| {
            std::fs::read_to_string(f)
                .unwrap()
                .lines()
                .filter(|l| l.starts_with(r#"{"record":"sample""#))
                .map(String::from)
                .collect::<Vec<_>>()
        })
        .collect()
}

/// One CSV row per sample in index order, a header, and every number the very text of the
/// shard line; the JSON Lines export holds the same values.
#[test]
fn csv_export_has_one_row_per_sample_with_the_shard_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let shards = dir.path().join("shards");
    std::fs::create_dir_all(&shards).unwrap();
    let files = job().write_split(&shards, 3);
    let csv = dir.path().join("samples.csv");
    let o = mc_merge(&shards, &["--export", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("exported 400 samples"));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut rows = text.lines();
    assert_eq!(
        rows.next().unwrap(),
        "index,case,sample,status,theta_p,tan_theta_x,tan_theta_y,decenter_x,decenter_y,decenter,despace,iterations,slack_cables,loose_joints,holding_force"
    );
    let rows: Vec<&str> = rows.collect();
    let lines = shard_lines(&files);
    assert_eq!(rows.len(), 400);
    assert_eq!(lines.len(), 400);
    // The header line above pins the column list; its keys are the shard lines' keys.
    let columns = mc_merge::export::COLUMNS;
    for (row, line) in rows.iter().zip(&lines) {
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(cells.len(), columns.len(), "{row}");
        for (cell, key) in cells.iter().zip(columns) {
            assert_eq!(*cell, raw(line, key), "{key} of {line}");
        }
    }
    assert!(rows[0].starts_with("0,a,0,"));
    assert!(rows[399].starts_with("399,b,149,"));

    let jsonl = dir.path().join("samples.jsonl");
    let o = mc_merge(&shards, &["--export", jsonl.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let objects: Vec<serde_json::Value> = std::fs::read_to_string(&jsonl)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(objects.len(), 400);
    for (o, line) in objects.iter().zip(&lines) {
        let l: serde_json::Value = serde_json::from_str(line).unwrap();
        for key in [
            "index",
            "case",
            "theta_p",
            "tan_theta_x",
            "tan_theta_y",
            "decenter",
            "despace",
        ] {
            assert_eq!(o[key], l[key], "{key}");
        }
    }
}

/// A missing shard fails the verification with exit code 6 and writes no export; an
/// unknown extension is a usage error (2).
#[test]
fn export_of_unverified_shards_fails_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let shards = dir.path().join("shards");
    std::fs::create_dir_all(&shards).unwrap();
    let files = job().write_split(&shards, 3);
    std::fs::remove_file(&files[1]).unwrap();
    let csv = dir.path().join("samples.csv");
    let o = mc_merge(&shards, &["--export", csv.to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(6),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!csv.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no partial file"
    );
    let o = mc_merge(&shards, &["--export", "samples.txt"]);
    assert_eq!(o.status.code(), Some(2));
}
