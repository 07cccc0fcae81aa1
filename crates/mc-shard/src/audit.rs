//! `mc-shard audit`: replaying a seeded random sample of a run's lines and comparing them
//! byte for byte.
//!
//! Digests prove that a shard is the file its writer wrote; they cannot prove that the
//! writer wrote the right numbers (a file rewritten with fresh digests, a bad machine, a
//! build with other numerics all verify). Determinism makes that cheap to check: a sample's
//! line depends only on the job and its index, so re-solving a few chosen lines and
//! comparing bytes tests the whole run statistically. With K lines audited and a fraction
//! f of all lines wrong, the audit misses every wrong one with probability about
//! (1 − f)^K: K = 300 finds a 1 % fault with probability 95 %.
//!
//! ## Procedure
//!
//! 1. The shard files (`*.jsonl` in the directories given, or the files themselves, in
//!    name order) are scanned by [`shard_record::scan_shard`]: every line's format, every
//!    checkpoint and end digest. Each header must be this job's (its id, sample count and
//!    cases with their parameters); a file that fails is a verification failure.
//! 2. K of the verified sample lines are chosen by reservoir sampling (Algorithm R) driven
//!    by a ChaCha20 stream seeded with `--seed` (default 0): a uniform K-subset, the same
//!    for the same files and seed. Incomplete shards contribute their verified lines.
//! 3. Each chosen line is re-solved ([`crate::worker::Worker`], on T threads) and its line
//!    compared with the file's, byte for byte.
//!
//! The result goes to `audit.json` beside the shards (the first directory given, or the
//! first file's directory; written through a temporary file, never through a link): `job_id`, `seed`, `samples_requested`, `samples_checked`,
//! `lines_in_shards`, `files`, `seconds`, and `mismatches` (each with `file`, `line` (from
//! 1), `index`, `case`, `sample`, `found` and `expected` lines). A mismatch or a file that
//! does not verify exits with the verification code (6); another job's shard with 5.

use crate::job::Job;
use crate::worker::Worker;
use rand_chacha::ChaCha20Rng;
use rand_core::{Rng, SeedableRng};
use serde::Serialize;
use shard_record::{ScanError, scan_shard};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The largest `--samples` an audit accepts (it holds the chosen lines in memory: about
/// 300 bytes each).
pub const MAX_AUDIT_SAMPLES: u64 = 1_000_000;

/// What to audit.
#[derive(Debug, Clone)]
pub struct AuditOptions {
    /// Lines to re-solve (at most [`MAX_AUDIT_SAMPLES`]).
    pub samples: u64,
    /// Seed of the choice.
    pub seed: u64,
    /// Threads for the re-solves.
    pub threads: usize,
}

/// One audited line that differs from its re-solve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mismatch {
    /// The shard file.
    pub file: PathBuf,
    /// Its line number, from 1.
    pub line: u64,
    /// The global sample index.
    pub index: u64,
    /// The case's name.
    pub case: String,
    /// The index within the case.
    pub sample: u64,
    /// The file's line (without `\n`).
    pub found: String,
    /// The re-solved line (without `\n`).
    pub expected: String,
}

/// The outcome of an audit, as `audit.json` holds it.
#[derive(Debug, Clone, Serialize)]
pub struct AuditReport {
    /// The job's id.
    pub job_id: String,
    /// The seed of the choice.
    pub seed: u64,
    /// Lines asked for.
    pub samples_requested: u64,
    /// Lines re-solved and compared (fewer than asked when the shards hold fewer).
    pub samples_checked: u64,
    /// Verified sample lines in the shard files.
    pub lines_in_shards: u64,
    /// The shard files read.
    pub files: Vec<PathBuf>,
    /// Wall time of the audit \[s\].
    pub seconds: f64,
    /// The lines that differ from their re-solve.
    pub mismatches: Vec<Mismatch>,
    /// Where this report was written.
    #[serde(skip)]
    pub written_to: PathBuf,
}

/// Why an audit could not be completed.
#[derive(Debug, thiserror::Error)]
pub enum AuditError {
    /// A shard file does not verify (its format, a checkpoint or its end line).
    #[error("{0}")]
    Scan(ScanError),
    /// A shard file belongs to another job, or its header differs from the job's.
    #[error("{}: {message}", path.display())]
    OtherJob {
        /// The file.
        path: PathBuf,
        /// What differs.
        message: String,
    },
    /// No shard file was found.
    #[error("no shard files (*.jsonl) in {0}")]
    NoShards(String),
    /// A file or directory could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// `--samples` out of bounds.
    #[error("--samples must be 1 to {MAX_AUDIT_SAMPLES}, not {0}")]
    Samples(u64),
    /// A file named is not a regular file, or `audit.json` is a link or could not be
    /// written.
    #[error(transparent)]
    Files(#[from] run_dir::RunDirError),
    /// The audit found lines that differ from their re-solve ([`AuditReport::verdict`]).
    #[error("audit: {} of {checked} re-solved lines differ from the shards (verification failed; details in {}): {}", .mismatches.len(), .report.display(), .mismatches.iter().take(5).map(|m| format!("{}:{}: index {} (case {:?}, sample {})", m.file.display(), m.line, m.index, m.case, m.sample)).collect::<Vec<_>>().join("; "))]
    Mismatch {
        /// The lines that differ.
        mismatches: Vec<Mismatch>,
        /// Lines compared.
        checked: u64,
        /// The audit.json written.
        report: PathBuf,
    },
}

impl AuditReport {
    /// The audit's summary line; a line that differs from its re-solve is an error
    /// ([`AuditError::Mismatch`]).
    pub fn verdict(&self) -> Result<String, AuditError> {
        if !self.mismatches.is_empty() {
            return Err(AuditError::Mismatch {
                mismatches: self.mismatches.clone(),
                checked: self.samples_checked,
                report: self.written_to.clone(),
            });
        }
        Ok(format!(
            "audit: {} of {} sample lines in {} file(s) re-solved in {:.2} s (seed {}): all byte-identical; {}",
            self.samples_checked,
            self.lines_in_shards,
            self.files.len(),
            self.seconds,
            self.seed,
            self.written_to.display()
        ))
    }
}

/// The shard files of `paths`: `*.jsonl` regular files of directories (name order), and
/// files, which must be regular files (a FIFO or a device is refused before it is opened).
pub fn shard_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, AuditError> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let io = |source| AuditError::Io {
                path: p.clone(),
                source,
            };
            let mut found: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(io)?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.is_file() && f.extension().is_some_and(|e| e == "jsonl"))
                .collect();
            found.sort();
            files.extend(found);
        } else {
            run_dir::input::check_regular(p)?;
            files.push(p.clone());
        }
    }
    if files.is_empty() {
        let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
        return Err(AuditError::NoShards(names.join(", ")));
    }
    Ok(files)
}

/// A chosen line: file number, line number, index, and its bytes.
type Chosen = (usize, u64, u64, Vec<u8>);

/// Audits the shards in `paths` against `job` (see the module doc) and writes `audit.json`.
/// Mismatches are in the returned report, not an error.
pub fn audit(
    job: &Job,
    paths: &[PathBuf],
    options: &AuditOptions,
) -> Result<AuditReport, AuditError> {
    if options.samples == 0 || options.samples > MAX_AUDIT_SAMPLES {
        return Err(AuditError::Samples(options.samples));
    }
    let started = Instant::now();
    let files = shard_files(paths)?;
    let k = options.samples as usize;
    let mut rng = ChaCha20Rng::seed_from_u64(options.seed);
    let mut reservoir: Vec<Chosen> = Vec::with_capacity(k.min(1 << 16));
    let mut seen: u64 = 0;
    for (f, path) in files.iter().enumerate() {
        let expected = crate::shard::begin(job, shard_record::ShardRange::new(0, 0));
        let scan = scan_shard(path, |line, sample, bytes| {
            let item = (f, line, sample.index, bytes.to_vec());
            if reservoir.len() < k {
                reservoir.push(item);
            } else {
                // A uniform draw from 0..=seen (bias below 2^-40 for any real count).
                let j = ((u128::from(rng.next_u64()) * u128::from(seen + 1)) >> 64) as usize;
                if j < k {
                    reservoir[j] = item;
                }
            }
            seen += 1;
            Ok(())
        })
        .map_err(AuditError::Scan)?;
        let b = &scan.begin;
        let mut same = b.clone();
        same.range = expected.range;
        if b.job_id != job.id {
            return Err(AuditError::OtherJob {
                path: path.clone(),
                message: format!(
                    "holds a shard of job {}, not of this job {}",
                    b.job_id, job.id
                ),
            });
        }
        if !same.same_shard(&expected) {
            return Err(AuditError::OtherJob {
                path: path.clone(),
                message: "its header names this job but its cases or parameters differ from the job's (the header was changed)".into(),
            });
        }
    }
    let mismatches = resolve(job, &files, &reservoir, options.threads.max(1));
    let dir = match paths.first() {
        Some(p) if p.is_dir() => p.clone(),
        _ => files[0]
            .parent()
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf),
    };
    let mut report = AuditReport {
        job_id: job.id.clone(),
        seed: options.seed,
        samples_requested: options.samples,
        samples_checked: reservoir.len() as u64,
        lines_in_shards: seen,
        files,
        seconds: 0.0,
        mismatches,
        written_to: dir.join("audit.json"),
    };
    report.seconds = started.elapsed().as_secs_f64();
    let text = serde_json::to_string_pretty(&report).expect("the report serialises") + "\n";
    run_dir::write_file(&report.written_to, text.as_bytes())?;
    Ok(report)
}

/// Re-solves the chosen lines on `threads` threads; returns those that differ, in file and
/// line order.
fn resolve(job: &Job, files: &[PathBuf], chosen: &[Chosen], threads: usize) -> Vec<Mismatch> {
    let per = chosen.len().div_ceil(threads).max(1);
    let mut mismatches: Vec<Mismatch> = std::thread::scope(|scope| {
        let handles: Vec<_> = chosen
            .chunks(per)
            .map(|part| {
                scope.spawn(move || {
                    let mut worker = Worker::new(job);
                    part.iter()
                        .filter_map(|(f, line, index, bytes)| {
                            let again = worker.sample(*index);
                            let expected = again.to_line();
                            (expected.as_bytes() != bytes.as_slice()).then(|| Mismatch {
                                file: files[*f].clone(),
                                line: *line,
                                index: *index,
                                case: again.case.clone(),
                                sample: again.sample,
                                found: String::from_utf8_lossy(bytes).trim_end().to_string(),
                                expected: expected.trim_end().to_string(),
                            })
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("an audit thread panicked"))
            .collect()
    });
    mismatches.sort_by(|a, b| (&a.file, a.line).cmp(&(&b.file, b.line)));
    mismatches
}
