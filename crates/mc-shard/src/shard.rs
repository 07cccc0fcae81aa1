//! One shard file: created, or found and verified, then appended to line by line.
//!
//! Opening a shard:
//! - takes an exclusive lock on the file (an OS file lock, `flock`), so two processes never
//!   write one shard; a second gets [`ShardError::Locked`];
//! - an empty file, or one torn while its header was written, starts afresh;
//! - a file of another job id or range is an error and is left untouched;
//! - a complete file is verified (every line, and the closing digest) and left as it is;
//! - otherwise the valid prefix is kept (a torn last line is cut off) and writing resumes at
//!   the next index, with the digest of the lines kept: the finished file is byte-identical
//!   to one written without interruption.
//!
//! Each batch of lines is written with one `write` call as soon as it is complete and in
//! order, so a crash loses at most the lines not yet written.

use crate::errors::ShardError;
use shard_record::{
    Begin, Record, SampleDigest, ScanError, ShardRange, ShardScan, Tail, scan_shard, to_line,
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
        /// Its verified contents.
        scan: ShardScan,
    },
    /// A writer positioned at the next sample to compute.
    Writer(ShardWriter),
}

/// An open, locked shard file being written.
pub struct ShardWriter {
    path: PathBuf,
    file: File,
    digest: SampleDigest,
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
        let file = OpenOptions::new()
            .read(true)
            .append(true)
            .create(true)
            .open(&path)
            .map_err(io)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(ShardError::Locked { path });
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(io(e)),
        }
        let fresh = |file: File| -> Result<Opened, ShardError> {
            file.set_len(0).map_err(io)?;
            let mut w = ShardWriter {
                path: path.clone(),
                file,
                digest: SampleDigest::new(),
                range,
                resumed: 0,
            };
            w.write_raw(to_line(&Record::Begin(begin.clone())).as_bytes())?;
            Ok(Opened::Writer(w))
        };
        if file.metadata().map_err(io)?.len() == 0 {
            return fresh(file);
        }
        let scan = match scan_shard(&path, |_, _, _| Ok(())) {
            Ok(scan) => scan,
            Err(ScanError::NoHeader { .. }) => return fresh(file),
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
        if matches!(scan.tail, Tail::Complete(_)) {
            return Ok(Opened::Complete { path, scan });
        }
        // Keep the valid prefix: header and whole sample lines.
        file.set_len(scan.valid_len).map_err(io)?;
        Ok(Opened::Writer(ShardWriter {
            path: path.clone(),
            file,
            resumed: scan.digest.samples(),
            digest: scan.digest,
            range,
        }))
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The global index of the next sample line.
    pub fn next_index(&self) -> u64 {
        self.range.start + self.digest.samples()
    }

    /// Sample lines kept from an interrupted run.
    pub fn resumed(&self) -> u64 {
        self.resumed
    }

    /// Appends sample lines (each with its `\n`, the next indices in order), given with
    /// whether each failed, in one write.
    pub fn append(&mut self, bytes: &[u8], lines: &[(usize, bool)]) -> Result<(), ShardError> {
        let mut at = 0;
        for &(len, failed) in lines {
            self.digest.add_line(&bytes[at..at + len], failed);
            at += len;
        }
        self.write_raw(bytes)
    }

    /// Failed samples among the lines so far.
    pub fn failed(&self) -> u64 {
        self.digest.end().failed
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
        let end = self.digest.end();
        self.write_raw(to_line(&Record::End(end.clone())).as_bytes())?;
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
