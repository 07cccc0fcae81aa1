//! `mc-shard inputs`: each sample's drawn inputs, regenerated from the seed, as CSV: the
//! input matrix for regression and sensitivity work beside the shards' outputs (which
//! `mc-merge --export` writes, keyed by the same `index`).
//!
//! ## Format
//!
//! One header row, then one row per sample in index order:
//!
//! | column | meaning | unit |
//! |---|---|---|
//! | `index` | global sample index (the shard lines' `index`) | |
//! | `case` | case name | |
//! | `sample` | index within the case | |
//! | `length_error:ID` | member ID's drawn length error (natural minus nominal length), one column per member | mm |
//! | `clearance:ID` | joint ID's drawn clearance, one column per joint of a case that draws clearances | mm |
//!
//! Members and joints appear in model order; when the cases chosen have different models,
//! the columns are the union in order of first appearance and a cell is empty where the
//! sample's model has no such member or joint, or its case draws no clearances. Numbers are
//! written in the shortest form that reads back to the same `f64` (full precision). The
//! values are the *drawn* errors, before effects (gravity, temperature) add to them. The
//! draws are those of [`crate::sampler::draw_sample`], so they are the very numbers the
//! shards' samples were solved with.
//!
//! The file is written to a temporary file beside `--out` and renamed when complete (crate
//! `run-dir`): a full disk leaves the old file at its name, and a link there is refused.

use crate::job::Job;
use crate::sampler::{draw_sample, stream_key};
use shard_record::ShardRange;
use std::collections::BTreeMap;
use std::io::Write;

/// Writes the inputs of global indices `range` of `job` (only case `case`'s, if given) as
/// CSV to `out`; returns the number of rows.
pub fn write_inputs(
    job: &Job,
    case: Option<usize>,
    range: ShardRange,
    out: &mut dyn Write,
) -> std::io::Result<u64> {
    let cases: Vec<usize> = (0..job.cases.len())
        .filter(|&c| case.is_none_or(|x| x == c))
        .filter(|&c| {
            let r = ShardRange::new(
                job.cases[c].start,
                job.cases[c].start + job.cases[c].samples,
            );
            r.start < range.end && range.start < r.end
        })
        .collect();
    // Columns: the union of member ids, then of joint ids (of cases drawing clearances).
    let mut members: Vec<String> = Vec::new();
    let mut joints: Vec<String> = Vec::new();
    for &c in &cases {
        let model = &job.cases[c].model;
        for m in model.members() {
            if !members.contains(&m.id) {
                members.push(m.id.clone());
            }
        }
        if job.cases[c].backlash.is_some() {
            for j in model.joints() {
                if !joints.contains(&j.id) {
                    joints.push(j.id.clone());
                }
            }
        }
    }
    let member_col: BTreeMap<&str, usize> = members
        .iter()
        .enumerate()
        .map(|(i, m)| (m.as_str(), i))
        .collect();
    let joint_col: BTreeMap<&str, usize> = joints
        .iter()
        .enumerate()
        .map(|(i, j)| (j.as_str(), i))
        .collect();
    let mut header = vec!["index".to_string(), "case".into(), "sample".into()];
    header.extend(members.iter().map(|m| format!("length_error:{m}")));
    header.extend(joints.iter().map(|j| format!("clearance:{j}")));
    writeln!(
        out,
        "{}",
        header
            .iter()
            .map(|h| csv_field(h))
            .collect::<Vec<_>>()
            .join(",")
    )?;

    let (mut errors, mut clearances) = (Vec::new(), Vec::new());
    let mut row = Vec::new();
    let mut rows = 0;
    for &c in &cases {
        let case = &job.cases[c];
        let key = stream_key(job.seed, &case.name);
        let from = range.start.max(case.start) - case.start;
        let to = range.end.min(case.start + case.samples) - case.start;
        // Each member's and joint's column in this case's model.
        let m_cols: Vec<usize> = case
            .model
            .members()
            .iter()
            .map(|m| member_col[m.id.as_str()])
            .collect();
        let j_cols: Vec<usize> = if case.backlash.is_some() {
            case.model
                .joints()
                .iter()
                .map(|j| joint_col[j.id.as_str()])
                .collect()
        } else {
            Vec::new()
        };
        let name = csv_field(&case.name);
        for k in from..to {
            draw_sample(&key, case, k, &mut errors, &mut clearances);
            row.clear();
            row.resize(members.len() + joints.len(), String::new());
            for (&col, e) in m_cols.iter().zip(&errors) {
                row[col] = e.to_string();
            }
            for (&col, e) in j_cols.iter().zip(&clearances) {
                row[members.len() + col] = e.to_string();
            }
            writeln!(out, "{},{name},{k},{}", case.start + k, row.join(","))?;
            rows += 1;
        }
    }
    Ok(rows)
}

/// A CSV field, quoted when it holds a comma, quote or newline (RFC 4180).
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}
