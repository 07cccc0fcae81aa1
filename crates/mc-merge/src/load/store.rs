//! The verified samples in memory: per-case columns ([`CaseData`]), the [`Dataset`] of a
//! job, the store that fills the columns by global index whatever the order the samples
//! arrive in (from reader threads, [`super::load`], or from memory, [`super::collect`]), and the
//! coverage check that refuses missing and failed samples unless tolerated.

use crate::errors::{FailedCase, MergeError, MissingRange};
use crate::rng::mix64;
use shard_record::{Budget, CaseInfo, Sample, ShardRange};
use std::path::PathBuf;

/// How many failure reasons (the lowest indices) to keep per case.
pub const REASONS_KEPT: usize = 5;

const EMPTY: u8 = 0;
const CONVERGED: u8 = 1;
const FAILED: u8 = 2;

/// What to tolerate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoadOptions {
    /// Compute on the samples present when some index ranges are missing.
    pub allow_partial: bool,
    /// Compute on the converged samples when some failed.
    pub allow_failed: bool,
    /// Reader threads (files are read in parallel; results do not depend on it).
    pub threads: usize,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            allow_partial: false,
            allow_failed: false,
            threads: truss_threads::available(),
        }
    }
}

/// One converged sample, as kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// Global sample index.
    pub index: u64,
    /// θ_P (rad).
    pub theta: f64,
    /// tan θ_x (dimensionless).
    pub tan_x: f64,
    /// tan θ_y (dimensionless).
    pub tan_y: f64,
    /// The holding force \[N\] (NaN where the sample does not record it).
    pub holding: f64,
    /// decenter_x \[mm\] (NaN where the sample does not record it: a shard of numerics
    /// version 7 or earlier).
    pub decenter_x: f64,
    /// decenter_y \[mm\] (NaN where not recorded).
    pub decenter_y: f64,
    /// despace \[mm\] (NaN where not recorded).
    pub despace: f64,
}

impl Point {
    /// `√(decenter_x² + decenter_y²)` \[mm\] (NaN where not recorded).
    pub fn decenter(&self) -> f64 {
        self.decenter_x.hypot(self.decenter_y)
    }

    /// Whether the sample records its decenter and despace.
    pub fn placed(&self) -> bool {
        !(self.decenter_x.is_nan() || self.decenter_y.is_nan() || self.despace.is_nan())
    }
}

#[derive(Debug, Default)]
struct Columns {
    state: Vec<u8>,
    fingerprint: Vec<u64>,
    theta: Vec<f64>,
    tan_x: Vec<f64>,
    tan_y: Vec<f64>,
    /// 0: not recorded, 1: no loose joint, 2: at least one.
    loose: Vec<u8>,
    /// 0: not recorded, 1: not floating, 2: floating.
    floating: Vec<u8>,
    /// The holding force \[N\]; NaN: not recorded.
    holding: Vec<f64>,
    /// The compression ratio of the stage that stands for the limit; NaN: the limit's own.
    limit_ratio: Vec<f64>,
    /// decenter_x, decenter_y, despace \[mm\]; NaN: not recorded.
    decenter_x: Vec<f64>,
    decenter_y: Vec<f64>,
    despace: Vec<f64>,
}

fn zeroed<T: Clone>(n: usize, v: T) -> Result<Vec<T>, String> {
    let mut out = Vec::new();
    out.try_reserve_exact(n)
        .map_err(|e| format!("cannot allocate memory for {n} samples: {e}"))?;
    out.resize(n, v);
    Ok(out)
}

impl Columns {
    fn new(n: usize) -> Result<Self, String> {
        Ok(Self {
            state: zeroed(n, EMPTY)?,
            fingerprint: zeroed(n, 0)?,
            theta: zeroed(n, 0.0)?,
            tan_x: zeroed(n, 0.0)?,
            tan_y: zeroed(n, 0.0)?,
            loose: zeroed(n, 0)?,
            floating: zeroed(n, 0)?,
            holding: zeroed(n, f64::NAN)?,
            limit_ratio: zeroed(n, f64::NAN)?,
            decenter_x: zeroed(n, f64::NAN)?,
            decenter_y: zeroed(n, f64::NAN)?,
            despace: zeroed(n, f64::NAN)?,
        })
    }
}

/// The verified samples of one case.
#[derive(Debug)]
pub struct CaseData {
    /// The case as the headers describe it.
    pub info: CaseInfo,
    /// Samples present (converged or failed).
    pub present: u64,
    /// Failed samples present.
    pub failed: u64,
    /// The failure reasons of the lowest failed indices (at most [`REASONS_KEPT`]).
    pub failed_reasons: Vec<(u64, String)>,
    columns: Option<Columns>,
}

impl CaseData {
    fn new(info: CaseInfo) -> Self {
        Self {
            info,
            present: 0,
            failed: 0,
            failed_reasons: vec![],
            columns: None,
        }
    }

    /// The converged samples in global index order.
    pub fn points(&self) -> impl Iterator<Item = Point> + Clone + '_ {
        let start = self.info.start;
        self.columns.iter().flat_map(move |c| {
            c.state
                .iter()
                .enumerate()
                .filter(|(_, s)| **s == CONVERGED)
                .map(move |(k, _)| Point {
                    index: start + k as u64,
                    theta: c.theta[k],
                    tan_x: c.tan_x[k],
                    tan_y: c.tan_y[k],
                    holding: c.holding[k],
                    decenter_x: c.decenter_x[k],
                    decenter_y: c.decenter_y[k],
                    despace: c.despace[k],
                })
        })
    }

    /// Number of converged samples.
    pub fn converged(&self) -> u64 {
        self.present - self.failed
    }

    /// The failed global indices, ascending, as half-open ranges.
    pub fn failed_ranges(&self) -> Vec<ShardRange> {
        self.runs(FAILED)
    }

    /// The missing global indices, ascending, as half-open ranges.
    pub fn missing_ranges(&self) -> Vec<ShardRange> {
        if self.columns.is_none() {
            return if self.info.samples > 0 {
                vec![self.info.range()]
            } else {
                vec![]
            };
        }
        self.runs(EMPTY)
    }

    fn runs(&self, which: u8) -> Vec<ShardRange> {
        let Some(c) = &self.columns else {
            return vec![];
        };
        let mut out: Vec<ShardRange> = vec![];
        for (k, &s) in c.state.iter().enumerate() {
            if s == which {
                let i = self.info.start + k as u64;
                match out.last_mut() {
                    Some(r) if r.end == i => r.end = i + 1,
                    _ => out.push(ShardRange::new(i, i + 1)),
                }
            }
        }
        out
    }

    /// Loose-joint counts among converged samples: (samples recording the field, samples with
    /// at least one loose joint).
    pub fn loose_joints(&self) -> (u64, u64) {
        self.flag_counts(|c| &c.loose)
    }

    /// Floating counts among converged samples: (samples recording the field, samples with a
    /// floating stage).
    pub fn floating(&self) -> (u64, u64) {
        self.flag_counts(|c| &c.floating)
    }

    /// Converged samples whose equilibrium is a stage of the limit's continuation, not the
    /// limit itself (`limit_ratio` recorded: the last attempt at `ρ = 0` did not
    /// converge), and the largest such ratio (0 where there are none).
    pub fn limit_stages(&self) -> (u64, f64) {
        let Some(c) = &self.columns else {
            return (0, 0.0);
        };
        let mut count = 0;
        let mut largest: f64 = 0.0;
        for (s, r) in c.state.iter().zip(&c.limit_ratio) {
            if *s == CONVERGED && r.is_finite() {
                count += 1;
                largest = largest.max(*r);
            }
        }
        (count, largest)
    }

    /// (converged samples whose flag column is recorded, those whose flag is set) for a
    /// column of 0 (not recorded), 1 (not set), 2 (set).
    fn flag_counts(&self, column: impl Fn(&Columns) -> &Vec<u8>) -> (u64, u64) {
        let Some(c) = &self.columns else {
            return (0, 0);
        };
        let mut recorded = 0;
        let mut set = 0;
        for (s, l) in c.state.iter().zip(column(c)) {
            if *s == CONVERGED && *l > 0 {
                recorded += 1;
                set += u64::from(*l == 2);
            }
        }
        (recorded, set)
    }
}

/// The verified content of all shards of one job.
#[derive(Debug)]
pub struct Dataset {
    /// The job id (SHA-256 hex of the job).
    pub job_id: String,
    /// Samples of the job.
    pub job_samples: u64,
    /// The cases, in job order.
    pub cases: Vec<CaseData>,
    /// The files read, in the order read.
    pub files: Vec<PathBuf>,
    /// The programs that wrote the files, as their headers name them, in order.
    pub writers: Vec<ShardWriter>,
    /// The job's alignment budget, as the headers carry it.
    pub budget: Option<Budget>,
}

/// A program that wrote shard files of the dataset, as the files' begin lines name it.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct ShardWriter {
    /// The program (`mc-shard`).
    pub program: String,
    /// Its version.
    pub program_version: String,
    /// The shard format version it wrote.
    pub format_version: u32,
    /// How many of the files it wrote.
    pub files: usize,
}

impl Dataset {
    /// Samples present over all cases.
    pub fn present(&self) -> u64 {
        self.cases.iter().map(|c| c.present).sum()
    }

    /// Missing index ranges over all cases, split at case boundaries.
    pub fn missing(&self) -> Vec<MissingRange> {
        self.cases
            .iter()
            .flat_map(|c| {
                c.missing_ranges().into_iter().map(|r| MissingRange {
                    start: r.start,
                    end: r.end,
                    case: c.info.name.clone(),
                })
            })
            .collect()
    }
}

/// Folds 64-bit words into a hash with the SplitMix64 mix.
struct Fold(u64);

impl Fold {
    fn word(&mut self, w: u64) {
        self.0 = mix64(self.0 ^ w);
    }

    fn bytes(&mut self, s: &[u8]) {
        self.word(s.len() as u64);
        for chunk in s.chunks(8) {
            let mut b = [0u8; 8];
            b[..chunk.len()].copy_from_slice(chunk);
            self.word(u64::from_le_bytes(b));
        }
    }
}

/// A 64-bit fingerprint of a sample line's exact bytes, to compare overlapping copies of the
/// same index: two copies agree only if their lines are identical, byte for byte.
pub fn fingerprint(line: &[u8]) -> u64 {
    let mut h = Fold(0x243f_6a88_85a3_08d3);
    h.bytes(line);
    h.0
}

/// A parsed sample on its way from a reader thread to the columns.
pub(super) struct Rec {
    index: u64,
    line: u64,
    fingerprint: u64,
    theta: f64,
    tan_x: f64,
    tan_y: f64,
    /// 0: not recorded, 1: no loose joint, 2: at least one.
    loose: u8,
    /// 0: not recorded, 1: not floating, 2: floating.
    floating: u8,
    /// The holding force \[N\]; NaN: not recorded.
    holding: f64,
    /// The compression ratio of the stage that stands for the limit; NaN: not recorded.
    limit_ratio: f64,
    /// decenter_x, decenter_y, despace \[mm\]; NaN: not recorded.
    placement: [f64; 3],
    /// `Some` for a failed sample.
    reason: Option<Box<str>>,
}

impl Rec {
    pub(super) fn new(line: u64, s: &Sample, bytes: &[u8]) -> Self {
        let a = s.angles();
        Rec {
            index: s.index,
            line,
            fingerprint: fingerprint(bytes),
            theta: a.map_or(0.0, |a| a.theta_p),
            tan_x: a.map_or(0.0, |a| a.tan_theta_x),
            tan_y: a.map_or(0.0, |a| a.tan_theta_y),
            loose: match s.loose_joints {
                None => 0,
                Some(0) => 1,
                Some(_) => 2,
            },
            floating: match s.floating {
                None => 0,
                Some(false) => 1,
                Some(true) => 2,
            },
            holding: s.holding_force.unwrap_or(f64::NAN),
            limit_ratio: s.limit_ratio.unwrap_or(f64::NAN),
            placement: s
                .placement()
                .map_or([f64::NAN; 3], |p| [p.decenter_x, p.decenter_y, p.despace]),
            reason: match a {
                Some(_) => None,
                None => Some(s.reason.clone().unwrap_or_default().into_boxed_str()),
            },
        }
    }
}

/// The per-case columns plus, during loading, which file filled each slot.
pub(super) struct Store {
    cases: Vec<CaseData>,
    starts: Vec<u64>,
    owner: Vec<Vec<u32>>,
}

impl Store {
    /// An empty store for a job of `cases` (as the begin lines list them).
    pub(super) fn new(cases: &[CaseInfo]) -> Self {
        Self {
            cases: cases.iter().cloned().map(CaseData::new).collect(),
            starts: cases.iter().map(|c| c.start).collect(),
            owner: vec![vec![]; cases.len()],
        }
    }

    /// The case a global index belongs to, if any.
    pub(super) fn case_of(&self, index: u64) -> Option<usize> {
        let c = self
            .starts
            .partition_point(|&s| s <= index)
            .checked_sub(1)?;
        let info = &self.cases[c].info;
        (index < info.start + info.samples).then_some(c)
    }

    /// The cases' columns, without what only verification needed.
    pub(super) fn into_cases(self) -> Vec<CaseData> {
        let mut cases = self.cases;
        for case in &mut cases {
            if let Some(c) = &mut case.columns {
                c.fingerprint = Vec::new();
            }
        }
        cases
    }

    /// Stores one sample; on a disagreeing duplicate returns (first owner, index, case).
    pub(super) fn put(&mut self, file: usize, r: Rec) -> Result<(), Conflict> {
        let c = self.starts.partition_point(|&s| s <= r.index) - 1;
        let case = &mut self.cases[c];
        let k = (r.index - case.info.start) as usize;
        if case.columns.is_none() {
            let n = case.info.samples as usize;
            case.columns = Some(Columns::new(n).map_err(Conflict::Memory)?);
            self.owner[c] = zeroed(n, 0).map_err(Conflict::Memory)?;
        }
        let cols = case.columns.as_mut().expect("just allocated");
        if cols.state[k] != EMPTY {
            if cols.fingerprint[k] != r.fingerprint {
                return Err(Conflict::Disagree {
                    first: self.owner[c][k] as usize,
                    line: r.line,
                    index: r.index,
                    case: case.info.name.clone(),
                });
            }
            return Ok(());
        }
        cols.fingerprint[k] = r.fingerprint;
        self.owner[c][k] = file as u32;
        case.present += 1;
        cols.theta[k] = r.theta;
        cols.tan_x[k] = r.tan_x;
        cols.tan_y[k] = r.tan_y;
        cols.loose[k] = r.loose;
        cols.floating[k] = r.floating;
        cols.holding[k] = r.holding;
        cols.limit_ratio[k] = r.limit_ratio;
        [cols.decenter_x[k], cols.decenter_y[k], cols.despace[k]] = r.placement;
        match r.reason {
            None => cols.state[k] = CONVERGED,
            Some(why) => {
                cols.state[k] = FAILED;
                case.failed += 1;
                let reasons = &mut case.failed_reasons;
                let at = reasons.partition_point(|(i, _)| *i < r.index);
                if at < REASONS_KEPT {
                    reasons.insert(at, (r.index, why.into_string()));
                    reasons.truncate(REASONS_KEPT);
                }
            }
        }
        Ok(())
    }
}

pub(super) enum Conflict {
    Disagree {
        first: usize,
        line: u64,
        index: u64,
        case: String,
    },
    Memory(String),
}

/// Refuses missing ranges and failed samples unless tolerated.
pub fn check_coverage(data: &Dataset, options: LoadOptions) -> Result<(), MergeError> {
    let missing = data.missing();
    if !missing.is_empty() && !options.allow_partial {
        return Err(MergeError::Missing {
            ranges: missing,
            present: data.present(),
            expected: data.job_samples,
        });
    }
    let failed: Vec<FailedCase> = data
        .cases
        .iter()
        .filter(|c| c.failed > 0)
        .map(|c| FailedCase {
            case: c.info.name.clone(),
            count: c.failed,
            first_indices: c
                .failed_ranges()
                .iter()
                .flat_map(|r| r.start..r.end)
                .take(10)
                .collect(),
            first_reasons: c.failed_reasons.clone(),
        })
        .collect();
    if !failed.is_empty() && !options.allow_failed {
        return Err(MergeError::FailedSamples {
            total: failed.iter().map(|c| c.count).sum(),
            cases: failed,
        });
    }
    Ok(())
}
