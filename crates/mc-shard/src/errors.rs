//! Errors of mc-shard's runner, each carrying what is needed to find the fault (the errors of
//! a command, and their exit codes, are [`crate::commands`]').

use run_dir::RunDirError;
use std::path::PathBuf;
use truss_job::JobError;

/// A shard that cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    /// The file or directory could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file holds a shard of another job (or range); it is never appended to.
    #[error("{}: holds a shard of job {found_job} range {found_range}, not of job {job} range {range}; it is never appended to (move it away, or use another --out)", path.display())]
    OtherJob {
        /// The file.
        path: PathBuf,
        /// Its job id.
        found_job: String,
        /// Its range.
        found_range: shard_record::ShardRange,
        /// Our job id.
        job: String,
        /// Our range.
        range: shard_record::ShardRange,
    },
    /// The file's header names this job and range but differs from the job in its cases or
    /// their parameters: it was edited, or written from another version of the job.
    #[error("{}: its begin line names this job and range but its cases or parameters differ from the job's (the header was changed); it is never appended to or counted (move it away and run again)", path.display())]
    HeaderMismatch {
        /// The file.
        path: PathBuf,
    },
    /// An incomplete file of a format version without checkpoints: its kept lines could not
    /// be verified, so it is not resumed.
    #[error("{}: an incomplete shard of format version {version}, which has no checkpoints, so its lines cannot be verified; it is not resumed (move it away and run again)", path.display())]
    OldFormat {
        /// The file.
        path: PathBuf,
        /// Its format version.
        version: u32,
    },
    /// The directory's worker pool record (`claims/pool.json`) is of another job, or damaged.
    #[error("{}: {message}", path.display())]
    Pool {
        /// The pool record.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Another process holds the file's lock: it is writing this shard now. (Locks are never
    /// stale: the operating system releases one when its holder exits, however it ends.)
    #[error("{}: {LOCKED} ({}): wait for it or stop it", path.display(), run_dir::errors::holder_words(*holder))]
    Locked {
        /// The file.
        path: PathBuf,
        /// The holder's pid, when this machine can see it.
        holder: Option<u32>,
    },
    /// A file at the shard's name that does not begin with a begin record: not a shard, so
    /// it is neither truncated nor appended to.
    #[error("{}: does not begin with a shard's begin line: it is not a shard file, and is never truncated or appended to (move it away, or use another --out)", path.display())]
    NotAShard {
        /// The file.
        path: PathBuf,
    },
    /// A symbolic link or a non-file at a name to be written (the shard, a quarantine
    /// marker, the claims or quarantine directory), or an output that could not be written.
    #[error(transparent)]
    Files(#[from] run_dir::RunDirError),
    /// The file is damaged in a way no crash produces (a bad line before the end).
    #[error(transparent)]
    Corrupt(shard_record::ScanError),
}

/// What a live shard lock's message says; `truss-mc run-all` recognises it in a child's
/// error, to advise waiting rather than moving the file away.
pub const LOCKED: &str = "another process is writing this shard";

impl ShardError {
    /// Whether the file is in the way in a way a rerun does not cure (damaged, another job's,
    /// not a shard, a link or a non-file at its name): a cron worker sets such a shard aside.
    pub fn is_damage(&self) -> bool {
        matches!(
            self,
            ShardError::Corrupt(_)
                | ShardError::OtherJob { .. }
                | ShardError::HeaderMismatch { .. }
                | ShardError::OldFormat { .. }
                | ShardError::NotAShard { .. }
                | ShardError::Files(RunDirError::Link { .. } | RunDirError::NotAFile { .. })
        )
    }
}

/// Why a run could not start or finish.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The job is invalid.
    #[error(transparent)]
    Job(#[from] JobError),
    /// The shard file is in the way.
    #[error(transparent)]
    Shard(#[from] ShardError),
    /// The requested range or shard does not exist, or the arguments disagree.
    #[error("{0}")]
    Usage(String),
}
