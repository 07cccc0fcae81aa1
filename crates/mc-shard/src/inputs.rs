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
//! | `length_error:ID` | member ID's drawn length error (natural minus nominal length; its own part plus its production lot's shared part where its group has one, see `truss_job::lot`), one column per member | mm |
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

/// The columns of the inputs of some cases of a job (see the module doc): the union of their
/// member ids, then of the joint ids of those that draw clearances; and per case, where each
/// of its members and joints goes. `mc-shard inputs` writes it as CSV, the Python package as
/// a 2-D array, so both hold the same numbers.
#[derive(Debug, Clone)]
pub struct InputTable {
    /// Member ids, the first columns.
    pub members: Vec<String>,
    /// Joint ids, the columns after the members'.
    pub joints: Vec<String>,
    /// Per case of the job: `None` when it is not in the table, else its stream key and each
    /// of its members' and (drawn) joints' column.
    cases: Vec<Option<CaseColumns>>,
}

/// A case's place in the table.
#[derive(Debug, Clone)]
struct CaseColumns {
    key: [u8; 32],
    members: Vec<usize>,
    joints: Vec<usize>,
}

/// Scratch for [`InputTable::row`]: the draws of one sample.
#[derive(Debug, Clone, Default)]
pub struct Draws {
    errors: Vec<f64>,
    clearances: Vec<f64>,
}

impl InputTable {
    /// The table of the samples of `job` in the global indices `range` (only case `case`'s,
    /// if given).
    pub fn new(job: &Job, case: Option<usize>, range: ShardRange) -> Self {
        let chosen = |c: usize| {
            let r = ShardRange::new(
                job.cases[c].start,
                job.cases[c].start + job.cases[c].samples,
            );
            case.is_none_or(|x| x == c) && r.start < range.end && range.start < r.end
        };
        let (mut members, mut joints) = (Vec::<String>::new(), Vec::<String>::new());
        for (c, case) in job.cases.iter().enumerate().filter(|(c, _)| chosen(*c)) {
            for m in case.model.members() {
                if !members.contains(&m.id) {
                    members.push(m.id.clone());
                }
            }
            if job.cases[c].backlash.is_some() {
                for j in case.model.joints() {
                    if !joints.contains(&j.id) {
                        joints.push(j.id.clone());
                    }
                }
            }
        }
        let column = |ids: &[String]| -> BTreeMap<String, usize> {
            ids.iter()
                .enumerate()
                .map(|(i, m)| (m.clone(), i))
                .collect()
        };
        let (member_col, joint_col) = (column(&members), column(&joints));
        let cases = (0..job.cases.len())
            .map(|c| {
                let case = &job.cases[c];
                chosen(c).then(|| CaseColumns {
                    key: stream_key(job.seed, &case.name),
                    members: case
                        .model
                        .members()
                        .iter()
                        .map(|m| member_col[&m.id])
                        .collect(),
                    joints: if case.backlash.is_some() {
                        case.model
                            .joints()
                            .iter()
                            .map(|j| joint_col[&j.id])
                            .collect()
                    } else {
                        Vec::new()
                    },
                })
            })
            .collect();
        Self {
            members,
            joints,
            cases,
        }
    }

    /// The number of columns: members, then joints.
    pub fn width(&self) -> usize {
        self.members.len() + self.joints.len()
    }

    /// The CSV header's input columns: `length_error:ID` per member, `clearance:ID` per joint.
    pub fn header(&self) -> Vec<String> {
        let members = self.members.iter().map(|m| format!("length_error:{m}"));
        members
            .chain(self.joints.iter().map(|j| format!("clearance:{j}")))
            .collect()
    }

    /// The inputs of sample `k` of case `c` \[mm\] into `row` ([`InputTable::width`] cells;
    /// `None` where its model has no such member or joint, or its case draws no clearances).
    /// Returns false, leaving `row` alone, when the case is not in the table.
    pub fn row(
        &self,
        job: &Job,
        c: usize,
        k: u64,
        draws: &mut Draws,
        row: &mut [Option<f64>],
    ) -> bool {
        let Some(Some(columns)) = self.cases.get(c) else {
            return false;
        };
        draw_sample(
            &columns.key,
            &job.cases[c],
            k,
            &mut draws.errors,
            &mut draws.clearances,
        );
        row.fill(None);
        for (&col, &e) in columns.members.iter().zip(&draws.errors) {
            row[col] = Some(e);
        }
        for (&col, &e) in columns.joints.iter().zip(&draws.clearances) {
            row[self.members.len() + col] = Some(e);
        }
        true
    }
}

/// Writes the inputs of global indices `range` of `job` (only case `case`'s, if given) as
/// CSV to `out`; returns the number of rows.
pub fn write_inputs(
    job: &Job,
    case: Option<usize>,
    range: ShardRange,
    out: &mut dyn Write,
) -> std::io::Result<u64> {
    let table = InputTable::new(job, case, range);
    let mut header = vec!["index".to_string(), "case".into(), "sample".into()];
    header.extend(table.header());
    writeln!(
        out,
        "{}",
        header
            .iter()
            .map(|h| csv_field(h))
            .collect::<Vec<_>>()
            .join(",")
    )?;
    let mut draws = Draws::default();
    let mut row = vec![None; table.width()];
    let mut rows = 0;
    for (c, case) in job.cases.iter().enumerate() {
        let from = range.start.max(case.start);
        let to = range.end.min(case.start + case.samples);
        let name = csv_field(&case.name);
        for index in from..to {
            let k = index - case.start;
            if !table.row(job, c, k, &mut draws, &mut row) {
                break;
            }
            let cells: Vec<String> = row
                .iter()
                .map(|v| v.map_or(String::new(), |e| e.to_string()))
                .collect();
            writeln!(out, "{index},{name},{k},{}", cells.join(","))?;
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
