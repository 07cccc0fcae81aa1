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

//!
//! Shard files are read here; samples already in memory (a run in-process, shards read back
//! by the Python package) become the same [`Dataset`] through [`collect::Collector`].

mod collect;
mod store;

pub use collect::Collector;
pub use store::{
    CaseData, Dataset, LoadOptions, Point, REASONS_KEPT, ShardWriter, check_coverage, fingerprint,
};

use crate::errors::MergeError;
use shard_record::{Begin, ScanError, ShardRange, read_shard};
use std::path::{Path, PathBuf};
use store::{Conflict, Rec, Store};

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
    let mut store = Store::new(&reference.begin.cases);

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

    let cases = store.into_cases();
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
