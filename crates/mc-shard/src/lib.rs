//! # mc-shard: reproducible seeded shards of a truss Monte Carlo job
//!
//! Turns a job file (a model, a seed, and cases of length-error distributions; see
//! [`job`]) into samples, solves each with [`truss_core`], and writes the results as a shard
//! file in the JSON Lines format of [`shard_record`]. A 50,000-sample job can be split over
//! any number of processes, machines, array tasks of a batch scheduler (Slurm, AWS Batch,
//! Google Cloud Batch, Kubernetes, HTCondor) or cron runs and still give exactly
//! the same numbers.
//!
//! ## Determinism
//!
//! The global sample index runs over the cases in order; a shard is a contiguous range of
//! it. Sample `k` of a case draws its length errors from a ChaCha20 stream keyed by (job
//! seed, case name, `k`) in a documented order ([`sampler`]), turns words into numbers with
//! the pure-Rust `libm` ([`distribution`]), and is solved by a solver whose arithmetic is in
//! a fixed order. So a sample's line depends only on the job and its index: not on the
//! shard split, the thread count, the order of cases in a run, or the machine. Numbers are
//! written in shortest round-trip form. Tests check it byte for byte.
//!
//! ## Commands (see `mc-shard --help`)
//!
//! Their flags are parsed in [`cli`]; what each does, and the exit code of each failure
//! ([`commands::exit_code`]), is [`commands`]'.
//!
//! - `mc-shard plan --job JOB.json` — job id, cases, sample count, an estimate of the CPU time and
//!   a suggestion: this machine, and a cluster split only for a job of more than ten minutes
//!   ([`plan`]).
//! - `mc-shard run --job JOB.json --out DIR [--shard I/K | --range A..B] [--threads T]` —
//!   one shard (selection in [`select`]); crash-safe and resumable ([`shard`]).
//! - `mc-shard reproduce --job JOB.json --case NAME --sample K [--detail]` — the exact line
//!   of one sample, or its draws, iterations, displacements and forces ([`reproduce`]).
//! - `mc-shard status --job JOB.json --out DIR --shards K [--missing | --json]` — which
//!   shards are complete, partial, missing, bad or quarantined ([`status`]).
//! - `mc-shard work --job JOB.json --out DIR --shards K` — claim, run and repeat until no
//!   shard is left: for cron on machines sharing DIR; a damaged shard is quarantined and the
//!   others run ([`work`]).
//! - `mc-shard audit --job JOB.json DIR… [--samples K] [--seed S]` — re-solve K seeded
//!   random lines of a run and compare them byte for byte; `audit.json` ([`audit`]).
//! - `mc-shard inputs --job JOB.json [--case C] [--range A..B] --out inputs.csv` — each
//!   sample's drawn length errors and clearances in mm, keyed by index ([`inputs`]).
//! - `mc-shard completions bash|zsh|fish`, `mc-shard man` — shell completions and the man
//!   page, generated from the same definitions as `--help`.
//!
//! ## What is verified
//!
//! Shard files are format version 2 of [`shard_record`]: a checkpoint line every
//! [`shard_record::CHECKPOINT_EVERY`] sample lines and digests that cover the begin line. A
//! resume keeps only lines a checkpoint verifies (the rest, at most 100, are solved again;
//! after SIGINT/SIGTERM a stop checkpoint covers every line); a complete shard is verified
//! in full before it is skipped; a shard is resumed or skipped only if its header matches
//! the job (id, range, cases and their parameters). `audit` checks the numbers themselves.
//!
//! In memory, [`batch::solve_range`] solves a range on T threads and hands the records back in
//! index order (the Python package `truss_mc` runs jobs through it).
//!
//! Running every shard on one machine and merging (`truss-mc run-all`) lives in the crate
//! above both runner and merge, `truss-mc`: this crate, the worker that runs on every
//! cluster node, links neither the merge nor an async runtime.
//!
//! ## Exit codes
//!
//! The scheme every truss-mc binary shares (`truss-exit`): 0 success, 1 internal error, 2
//! usage error or a range outside the job, 3 invalid job (the message gives the JSON path of
//! the fault) or a file named for `audit` that is not a regular file, 4 a file could not be
//! read or written, 5 the shard file is in the way (another job's, locked by another
//! process, damaged, not a shard, a changed header, a symbolic link at its name or at
//! `claims/` or `quarantine/`; for `work`: a shard quarantined), 6 an audit found a line that differs from its re-solve or a shard
//! that does not verify, 130 / 143 `run` or `work` stopped by SIGINT / SIGTERM, every
//! finished sample kept ([`interrupt`]).

pub mod audit;
pub mod batch;
pub mod cli;
pub mod commands;
pub mod errors;
pub mod inputs;
pub mod interrupt;
pub mod plan;
pub mod progress;
pub mod reproduce;
pub mod runner;
pub mod select;
pub mod shard;
pub mod status;
pub mod work;
pub mod worker;

pub use errors::{RunError, ShardError};
pub use runner::{RunOptions, RunSummary, run_shard};
/// The job (spec, distributions, effects, sampler) lives in `truss-job`.
pub use truss_job::{Job, JobError, distribution, effects, job, sampler};
