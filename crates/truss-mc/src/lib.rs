//! # truss-mc: the paper's Monte Carlo on one machine, from job to report
//!
//! `truss-mc run-all --job JOB.json --out DIR` splits the job into shards, runs them as
//! concurrent child processes (each `truss-mc run --shard i/K`, mc-shard's runner), shows
//! one progress display, and merges the directory into `DIR/report` ([`run_all`]). Every
//! other command of `mc-shard` (`plan`, `run`, `reproduce`, `status`, `work`) is available
//! here too, unchanged, so this one binary is all a single machine needs.
//!
//! ## Why this crate
//!
//! `run-all` is the one command that needs both the runner and the merge. It lives above
//! both so that neither depends on the other: `mc-shard`, the worker binary that runs on
//! every cluster node, links neither the merge's statistics and plots nor an async runtime,
//! and a change to the merge never rebuilds it; `mc-merge` never links the solver. The
//! dependency graph is drawn in the README ("The pieces") and checked by
//! `tests/tests/it/layers.rs` of the workspace's pipeline tests.
//!
//! ## Exit codes
//!
//! The scheme every truss-mc binary shares (`truss-exit`); `run-all` exits with 2 for bad
//! arguments (`--shards 0`, `--workers 0`) before anything starts, with 5 when a shard
//! process met a file in the way (another job's shard, a damaged file: move it away; a shard
//! another live process writes: wait for it or stop it) or `DIR/report` is a symbolic link,
//! with
//! the verification code (6) when a shard process failed otherwise or the audit before the
//! merge found a line that differs from its re-solve, with the merge's code when the merge
//! failed (7 for failed samples: rerun with `--allow-failed`), and with 130 / 143 when
//! SIGINT / SIGTERM stopped it (its workers stopped too, every finished sample kept; see
//! [`run_all`]). `truss-mc completions bash|zsh|fish` and `truss-mc man` print its shell
//! completions and man page.

pub mod cli;
pub mod commands;
pub mod run_all;
