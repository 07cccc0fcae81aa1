//! Reading and verifying shards: one job, every digest, every global index exactly once.
//!
//! ## The verification contract
//!
//! Before anything is computed:
//!
//! 1. Every file is read strictly with [`shard_record::read_shard`]: a torn last line, a missing
//!    end line, a corrupt line (or one longer than [`shard_record::MAX_LINE_BYTES`]), an index
//!    out of order, a wrong closing digest, or a converged θ_P outside [0, π/2] rad is an
//!    error naming the file and line. A file named on the command line must be a regular file
//!    (a FIFO or a device is refused before it is opened).
//! 2. All files carry the job id of the first file read, and the same cases.
//! 3. Each global index `0..job_samples` is held at least once. Where shards overlap, every
//!    overlapping sample must be identical, compared by a 64-bit fingerprint of the bytes of
//!    its line (so a different number, to the last bit, is a different sample); the first
//!    disagreeing index and both files are named. Two files of the same range must have the same
//!    closing digest, that is byte-identical sample lines.
//! 4. A missing index range is an error naming the ranges and their cases, unless partial
//!    results were asked for; failed samples are an error (with their count, first indices and
//!    reasons) unless they were allowed.
//!
//! ## Memory
//!
//! Per sample only what the statistics need is kept, in dense per-case columns indexed by the
//! sample's position in its case: a state byte, θ_P, tan θ_x, tan θ_y, decenter_x, decenter_y,
//! despace, a loose-joint and a floating byte, the holding force and, until verification
//! ends, the fingerprint and the number of the file that held it: 76 bytes per sample (64
//! after). `decenter` is not kept: it is `decenter_x.hypot(decenter_y)`, the writer's own
//! definition (`truss_core::measure`), recomputed when asked for. A case's columns are allocated when its first sample is read. The
//! parsed sample lines are not kept.
//!
//! ## Threads
//!
//! Files are parsed in parallel (one file per reader thread at a time); the readers send batches
//! of compact samples to one thread that stores them by global index. Because samples are stored
//! by global index, nothing depends on the order of the files or on the thread count.

use crate::errors::{FailedCase, MergeError, MissingRange};
use crate::rng::mix64;
use shard_record::{Begin, Budget, CaseInfo, Sample, ScanError, ShardRange, read_shard};
use std::path::{Path, PathBuf};

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

/// The shard files among `paths`: each directory contributes its `*.jsonl` regular files
/// (not recursively, sorted by name); each file is taken as given, if it is a regular file
/// (links followed; a FIFO or a device is refused, [`run_dir::RunDirError::NotRegular`]).
pub fn shard_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, MergeError> {
    let mut files = vec![];
    for path in paths {
        let io = |source| MergeError::Io {
            path: path.clone(),
            source,
        };
        let meta = std::fs::metadata(path).map_err(io)?;
        if !meta.is_dir() && !meta.is_file() {
            // A FIFO would block the open, a device (`/dev/zero`) never ends.
            return Err(run_dir::RunDirError::NotRegular {
                path: path.clone(),
                kind: run_dir::errors::file_kind(&meta.file_type()),
            }
            .into());
        }
        if meta.is_dir() {
            let mut found = vec![];
            for entry in std::fs::read_dir(path).map_err(io)? {
                let entry = entry.map_err(io)?;
                let p = entry.path();
                if p.extension().is_some_and(|e| e == "jsonl") && p.is_file() {
                    found.push(p);
                }
            }
            found.sort();
            files.extend(found);
        } else {
            files.push(path.clone());
        }
    }
    if files.is_empty() {
        return Err(MergeError::NoShards {
            paths: paths.to_vec(),
        });
    }
    Ok(files)
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

/// Reads the header line of `path`, if it parses and checks (otherwise the strict reader
/// reports the problem).
fn peek_header(path: &Path) -> Result<Option<Begin>, MergeError> {
    let io = |source| MergeError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut reader = std::io::BufReader::new(std::fs::File::open(path).map_err(io)?);
    let mut line = vec![];
    if shard_record::read_line(&mut reader, &mut line, shard_record::MAX_BEGIN_LINE_BYTES)
        .map_err(io)?
        .is_none()
    {
        return Ok(None);
    }
    Ok(match shard_record::parse_record(&line) {
        Ok(shard_record::Record::Begin(b)) if line.ends_with(b"\n") && b.check().is_ok() => Some(b),
        _ => None,
    })
}

struct Reference {
    path: PathBuf,
    begin: Begin,
}

fn compare_headers(reference: &Reference, path: &Path, begin: &Begin) -> Result<(), MergeError> {
    let r = &reference.begin;
    if begin.job_id != r.job_id {
        return Err(MergeError::OtherJob {
            path: path.to_path_buf(),
            found: begin.job_id.clone(),
            expected: r.job_id.clone(),
            reference: reference.path.clone(),
        });
    }
    let what = if begin.job_samples != r.job_samples {
        Some(format!(
            "job_samples ({} vs {})",
            begin.job_samples, r.job_samples
        ))
    } else if begin.cases != r.cases {
        Some("the cases (names, ranges or parameters)".to_string())
    } else if begin.budget != r.budget {
        Some("the budget".to_string())
    } else {
        None
    };
    match what {
        Some(what) => Err(MergeError::HeaderMismatch {
            path: path.to_path_buf(),
            reference: reference.path.clone(),
            what,
        }),
        None => Ok(()),
    }
}

/// A parsed sample on its way from a reader thread to the columns.
struct Rec {
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
    /// decenter_x, decenter_y, despace \[mm\]; NaN: not recorded.
    placement: [f64; 3],
    /// `Some` for a failed sample.
    reason: Option<Box<str>>,
}

impl Rec {
    fn new(line: u64, s: &Sample, bytes: &[u8]) -> Self {
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

enum Msg {
    Batch {
        file: usize,
        recs: Vec<Rec>,
    },
    Done {
        file: usize,
        range: ShardRange,
        sha256: String,
    },
    Failed {
        file: usize,
        error: ScanError,
    },
}

const BATCH: usize = 4096;

/// The per-case columns plus, during loading, which file filled each slot.
struct Store {
    cases: Vec<CaseData>,
    starts: Vec<u64>,
    owner: Vec<Vec<u32>>,
}

impl Store {
    /// Stores one sample; on a disagreeing duplicate returns (first owner, index, case).
    fn put(&mut self, file: usize, r: Rec) -> Result<(), Conflict> {
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

enum Conflict {
    Disagree {
        first: usize,
        line: u64,
        index: u64,
        case: String,
    },
    Memory(String),
}

/// Reads one file in a worker thread, sending its samples in batches.
fn read_one(
    file: usize,
    path: &Path,
    tx: &std::sync::mpsc::SyncSender<Msg>,
    abort: &std::sync::atomic::AtomicBool,
) {
    use std::sync::atomic::Ordering;
    let mut batch = Vec::with_capacity(BATCH);
    let mut stopped = false;
    let result = read_shard(path, |line, sample, bytes| {
        if abort.load(Ordering::Relaxed) {
            stopped = true;
            return Err("stopped: another file failed".into());
        }
        sample.check_angles()?;
        batch.push(Rec::new(line, sample, bytes));
        if batch.len() == BATCH {
            let recs = std::mem::replace(&mut batch, Vec::with_capacity(BATCH));
            if tx.send(Msg::Batch { file, recs }).is_err() {
                stopped = true;
                return Err("stopped".into());
            }
        }
        Ok(())
    });
    if stopped {
        return;
    }
    let msg = match result {
        Ok(scan) => {
            if !batch.is_empty() {
                let _ = tx.send(Msg::Batch { file, recs: batch });
            }
            match scan.tail {
                shard_record::Tail::Complete(end) => Msg::Done {
                    file,
                    range: scan.begin.range,
                    sha256: end.sha256,
                },
                _ => Msg::Failed {
                    file,
                    error: ScanError::Incomplete {
                        path: path.to_path_buf(),
                        samples: scan.digest.samples(),
                        expected: scan.begin.range.len(),
                    },
                },
            }
        }
        Err(error) => Msg::Failed { file, error },
    };
    let _ = tx.send(msg);
}

/// Reads and verifies `files` (see the module doc) with `threads` reader threads. Nothing is
/// returned unless everything verifies (or is tolerated by `options`). Header problems are
/// reported in the order the files were given; a file that does not read is preferred to a
/// disagreeing overlap; a disagreeing overlap names both files and the first disagreeing index
/// of the pair.
pub fn load(files: &[PathBuf], options: LoadOptions) -> Result<Dataset, MergeError> {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    if files.is_empty() {
        return Err(MergeError::NoShards { paths: vec![] });
    }
    // 1. Headers, in file order: one job, the same cases.
    let mut reference: Option<Reference> = None;
    let mut writers: std::collections::BTreeMap<(String, String, u32), usize> = Default::default();
    for path in files {
        let Some(begin) = peek_header(path)? else {
            // Let the strict reader name what is wrong with the header.
            read_shard(path, |_, _, _| Ok(()))?;
            return Err(MergeError::Shard(ScanError::Corrupt {
                path: path.clone(),
                line: 1,
                message: "unreadable begin line".into(),
            }));
        };
        *writers
            .entry((
                begin.program.clone(),
                begin.program_version.clone(),
                begin.format_version,
            ))
            .or_default() += 1;
        match &reference {
            None => {
                reference = Some(Reference {
                    path: path.clone(),
                    begin,
                })
            }
            Some(r) => compare_headers(r, path, &begin)?,
        }
    }
    let reference = reference.expect("at least one file");
    let mut store = Store {
        cases: reference
            .begin
            .cases
            .iter()
            .cloned()
            .map(CaseData::new)
            .collect(),
        starts: reference.begin.cases.iter().map(|c| c.start).collect(),
        owner: vec![vec![]; reference.begin.cases.len()],
    };

    // 2. Samples, files read in parallel, stored by global index.
    let threads = options.threads.clamp(1, files.len());
    let next = AtomicUsize::new(0);
    let abort = AtomicBool::new(false);
    let mut scan_errors: Vec<(usize, ScanError)> = vec![];
    let mut conflict: Option<(usize, Conflict)> = None;
    let mut done: Vec<(usize, ShardRange, String)> = vec![];
    std::thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::sync_channel::<Msg>(4 * threads);
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, abort) = (&next, &abort);
            scope.spawn(move || {
                loop {
                    let f = next.fetch_add(1, Ordering::Relaxed);
                    if f >= files.len() || abort.load(Ordering::Relaxed) {
                        break;
                    }
                    read_one(f, &files[f], &tx, abort);
                }
            });
        }
        drop(tx);
        // Keep draining after an error so that no reader blocks on a full channel.
        for msg in rx {
            match msg {
                Msg::Batch { file, recs } => {
                    if conflict.is_some() || !scan_errors.is_empty() {
                        continue;
                    }
                    for r in recs {
                        if let Err(c) = store.put(file, r) {
                            conflict = Some((file, c));
                            abort.store(true, Ordering::Relaxed);
                            break;
                        }
                    }
                }
                Msg::Done {
                    file,
                    range,
                    sha256,
                } => done.push((file, range, sha256)),
                Msg::Failed { file, error } => {
                    abort.store(true, Ordering::Relaxed);
                    scan_errors.push((file, error));
                }
            }
        }
    });
    // The earliest file's problem first. (With several bad files and several threads, which
    // problems are found before the readers stop may vary; every one reported is real.)
    if let Some((_, e)) = scan_errors.into_iter().min_by_key(|(f, _)| *f) {
        return Err(e.into());
    }
    if let Some((file, c)) = conflict {
        return Err(match c {
            Conflict::Disagree {
                first,
                line,
                index,
                case,
            } => MergeError::OverlapDisagrees {
                first: files[first].clone(),
                second: files[file].clone(),
                line,
                index,
                case,
            },
            Conflict::Memory(message) => MergeError::Internal { message },
        });
    }
    done.sort_by_key(|d| d.0);
    for (k, (file, range, sha)) in done.iter().enumerate() {
        if let Some((first, _, first_sha)) = done[..k].iter().find(|d| d.1 == *range && d.2 != *sha)
        {
            return Err(MergeError::DuplicateDiffers {
                first: files[*first].clone(),
                second: files[*file].clone(),
                range: *range,
                first_sha256: first_sha.clone(),
                second_sha256: sha.clone(),
            });
        }
    }

    let mut cases = store.cases;
    for case in &mut cases {
        if let Some(c) = &mut case.columns {
            c.fingerprint = Vec::new();
        }
    }
    drop(store.owner);
    let budget = reference.begin.budget;
    let data = Dataset {
        budget,
        job_id: reference.begin.job_id,
        job_samples: reference.begin.job_samples,
        cases,
        files: files.to_vec(),
        writers: writers
            .into_iter()
            .map(
                |((program, program_version, format_version), files)| ShardWriter {
                    program,
                    program_version,
                    format_version,
                    files,
                },
            )
            .collect(),
    };
    check_coverage(&data, options)?;
    Ok(data)
}

/// Refuses missing ranges and failed samples unless tolerated.
fn check_coverage(data: &Dataset, options: LoadOptions) -> Result<(), MergeError> {
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
