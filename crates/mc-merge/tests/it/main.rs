//! mc-merge's integration tests, one binary: statistics, sweeps, the command line, plots, the
//! readable reports and the report directory.

mod authorship;
mod budget;
mod cli;
mod collect;
mod common;
mod export;
#[path = "../../../run-dir/tests/support/hostile.rs"]
mod hostile;
mod plots;
mod readable;
mod report_dir;
mod schema;
mod shared_dir;
mod statistics;
mod sweep;
