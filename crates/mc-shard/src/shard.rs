//! One shard file: created, or found and verified, then appended to line by line.
//!
//! Opening a shard:
//! - a new shard file is created whole with its begin line: written to a temporary file with
//!   an unpredictable name beside it and linked into place only if the name is still free
//!   (crate `run-dir`); a symbolic link or a non-file at the shard's name is refused, and an
//!   existing file is opened without following a link ([`ShardError::Files`]);
//! - takes an exclusive lock on the file (an OS file lock, `flock`), so two processes never
//!   write one shard; a second gets [`ShardError::Locked`], naming the holder's pid;
//! - an empty file, or one torn while its header was written (its bytes a beginning of a
//!   begin record), starts afresh; a file that does not begin with a begin record is not a
//!   shard and is left untouched ([`ShardError::NotAShard`]);
//! - a file of another job id or range, or whose header differs from the job's in any case
//!   or parameter, is an error and is left untouched;
//! - a complete file is verified (every line, every checkpoint, the closing digests, which
//!   cover the begin line) and left as it is;
//! - otherwise the prefix verified by its last checkpoint is kept (the lines after it, at
//!   most [`shard_record::CHECKPOINT_EVERY`], and a torn last line are cut off and solved
//!   again), and writing resumes at the next index: the finished file is byte-identical to
//!   one written without interruption. A kept line that no longer matches its checkpoint is
//!   an error ([`ShardError::Corrupt`]), never sealed under a fresh digest;
//! - a file to be resumed or started afresh that has more than one name (a hard link, say
//!   from a user's backup copy) is refused and left untouched
//!   ([`run_dir::RunDirError::HardLinked`]): appending would grow the other name's file too;
//! - an incomplete file of format version 1 (no checkpoints: its lines cannot be verified)
//!   is not resumed ([`ShardError::OldFormat`]).
//!
//! Each batch of lines is written with one `write` call as soon as it is complete and in
//! order, so a crash loses at most the lines not yet written.

use crate::errors::ShardError;
use run_dir::lock::Lock;
use shard_record::{
    Begin, CHECKPOINT_EVERY, ScanError, ShardEncoder, ShardRange, ShardScan, Tail, scan_shard,
};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The program name written in shard headers.
pub const PROGRAM: &str = "mc-shard";

/// What opening a shard found.
pub enum Opened {
    /// The shard was already complete; nothing to do.
    Complete {
        /// The file.
        path: PathBuf,
        /// Its verified contents (boxed: a header is far larger than a writer).
        scan: Box<ShardScan>,
    },
    /// A writer positioned at the next sample to compute.
    Writer(ShardWriter),
}

/// An open, locked shard file being written.
pub struct ShardWriter {
    path: PathBuf,
    file: File,
    encoder: ShardEncoder,
    range: ShardRange,
    /// Lines kept from an earlier, interrupted run.
    resumed: u64,
}

impl ShardWriter {
    /// Opens (or creates) the shard of `range` for job `begin.job_id` in `dir` (see the module
    /// doc).
    pub fn open(dir: &Path, begin: &Begin) -> Result<Opened, ShardError> {
        let range = begin.range;
        std::fs::create_dir_all(dir).map_err(|source| ShardError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let path = dir.join(range.file_name());
        let io = |source| ShardError::Io {
            path: path.clone(),
            source,
        };
        create(&path, begin)?;
        let file = run_dir::input::open_own(&path, OpenOptions::new().read(true).append(true))?;
        match run_dir::lock::try_lock(&file).map_err(io)? {
            Lock::Taken => {}
            Lock::Held { holder } => return Err(ShardError::Locked { path, holder }),
        }
        let fresh = |file: File| -> Result<Opened, ShardError> {
            run_dir::input::check_single_name(&file, &path)?;
            file.set_len(0).map_err(io)?;
            let (encoder, header) = ShardEncoder::new(begin);
            let mut w = ShardWriter {
                path: path.clone(),
                file,
                encoder,
                range,
                resumed: 0,
            };
            w.write_raw(&header)?;
            Ok(Opened::Writer(w))
        };
        if file.metadata().map_err(io)?.len() == 0 {
            return fresh(file);
        }
        let scan = match scan_shard(&path, |_, _, _| Ok(())) {
            Ok(scan) => scan,
            Err(ScanError::NoHeader { .. }) if torn_header(&file).map_err(io)? => {
                return fresh(file);
            }
            Err(ScanError::NoHeader { .. }) => return Err(ShardError::NotAShard { path }),
            Err(e) => return Err(ShardError::Corrupt(e)),
        };
        if scan.begin.job_id != begin.job_id || scan.begin.range != range {
            return Err(ShardError::OtherJob {
                path,
                found_job: scan.begin.job_id.clone(),
                found_range: scan.begin.range,
                job: begin.job_id.clone(),
                range,
            });
        }
        if !scan.begin.same_shard(begin) {
            return Err(ShardError::HeaderMismatch { path });
        }
        if matches!(scan.tail, Tail::Complete(_)) {
            return Ok(Opened::Complete {
                path,
                scan: Box::new(scan),
            });
        }
        if scan.begin.checkpoint_every.is_none() {
            return Err(ShardError::OldFormat {
                path,
                version: scan.begin.format_version,
            });
        }
        // Never cut or grow a file that has another name too (a user's backup linked to it).
        run_dir::input::check_single_name(&file, &path)?;
        // Keep the verified prefix: header, and sample lines up to the last checkpoint.
        file.set_len(scan.valid_len).map_err(io)?;
        Ok(Opened::Writer(ShardWriter {
            path: path.clone(),
            file,
            resumed: scan.digest.samples(),
            encoder: ShardEncoder::resume(&scan),
            range,
        }))
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The global index of the next sample line.
    pub fn next_index(&self) -> u64 {
        self.range.start + self.encoder.samples()
    }

    /// Sample lines kept from an interrupted run.
    pub fn resumed(&self) -> u64 {
        self.resumed
    }

    /// Appends sample lines (each with its `\n`, the next indices in order), given with
    /// whether each failed, in one write.
    /// Checkpoint lines fall between them as the format requires.
    pub fn append(&mut self, bytes: &[u8], lines: &[(usize, bool)]) -> Result<(), ShardError> {
        let mut out = Vec::with_capacity(bytes.len() + 256);
        let mut at = 0;
        for &(len, failed) in lines {
            self.encoder.push(&bytes[at..at + len], failed, &mut out);
            at += len;
        }
        self.write_raw(&out)
    }

    /// Failed samples among the lines so far.
    pub fn failed(&self) -> u64 {
        self.encoder.failed()
    }

    /// Ends an interrupted file: a stop checkpoint (so a rerun keeps every line written;
    /// see [`shard_record`]'s format) and a sync to disk.
    pub fn stop(&mut self) -> Result<(), ShardError> {
        if let Some(line) = self.encoder.stop_checkpoint() {
            self.write_raw(&line)?;
        }
        self.sync()
    }

    /// Syncs the lines written so far to disk (before stopping without the end line).
    pub fn sync(&self) -> Result<(), ShardError> {
        self.file.sync_all().map_err(|source| ShardError::Io {
            path: self.path.clone(),
            source,
        })
    }

    /// Writes the end line, syncs the file to disk, and returns the end record.
    pub fn finish(mut self) -> Result<shard_record::End, ShardError> {
        assert_eq!(
            self.next_index(),
            self.range.end,
            "finish before the last sample"
        );
        let (end, line) = self.encoder.end();
        self.write_raw(&line)?;
        self.file.sync_all().map_err(|source| ShardError::Io {
            path: self.path.clone(),
            source,
        })?;
        Ok(end)
    }

    fn write_raw(&mut self, bytes: &[u8]) -> Result<(), ShardError> {
        self.file.write_all(bytes).map_err(|source| ShardError::Io {
            path: self.path.clone(),
            source,
        })
    }
}

/// How every begin line starts (the record's tag is written first).
const BEGIN_PREFIX: &[u8] = br#"{"record":"begin""#;

/// Creates the shard file `path` holding `begin`'s line, unless something is at that name
/// already; refuses a link or a non-file there.
fn create(path: &Path, begin: &Begin) -> Result<(), ShardError> {
    run_dir::output::check_final(path)?;
    if std::fs::symlink_metadata(path).is_ok() {
        return Ok(());
    }
    let mut out = run_dir::OutputFile::create(path)?;
    let (_, header) = ShardEncoder::new(begin);
    out.write_all(&header).map_err(|source| ShardError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    // Another process may have created it meanwhile: then that file is opened and checked.
    out.commit_new()?;
    Ok(())
}

/// Whether a file without a complete first line holds the beginning of a begin record (a
/// writer stopped while writing its header), read from its start.
fn torn_header(file: &File) -> std::io::Result<bool> {
    use std::io::Read;
    let mut head = Vec::with_capacity(BEGIN_PREFIX.len());
    let mut reader = file;
    std::io::Seek::seek(&mut reader, std::io::SeekFrom::Start(0))?;
    reader
        .take(BEGIN_PREFIX.len() as u64)
        .read_to_end(&mut head)?;
    Ok(BEGIN_PREFIX.starts_with(&head))
}

/// The header of `range` of `job`.
pub fn begin(job: &crate::job::Job, range: ShardRange) -> Begin {
    Begin::new(
        PROGRAM,
        env!("CARGO_PKG_VERSION"),
        &job.id,
        range,
        job.samples(),
        case_infos(job),
    )
    .with_checkpoints(CHECKPOINT_EVERY)
    .with_budget(budget(job))
}

/// The job's alignment budget as a shard header carries it (rad, mm).
pub fn budget(job: &crate::job::Job) -> Option<shard_record::Budget> {
    job.budget.map(|b| shard_record::Budget {
        percentile: b.percentile,
        theta_p: b.theta_p,
        decenter: b.decenter,
        despace: b.despace,
    })
}

/// The job's cases as a shard header lists them.
pub fn case_infos(job: &crate::job::Job) -> Vec<shard_record::CaseInfo> {
    job.cases
        .iter()
        .map(|c| shard_record::CaseInfo {
            name: c.name.clone(),
            start: c.start,
            samples: c.samples,
            parameters: c.parameters.clone(),
        })
        .collect()
}
