//! mc-shard's integration tests, one binary: jobs, sampling, determinism, backlash, the
//! command line, and concurrent cron workers.

mod backlash;
mod binary;
mod cli;
mod common;
mod determinism;
#[path = "../../../run-dir/tests/support/hostile.rs"]
mod hostile;
mod interrupt;
mod job;
mod limit_reference;
mod pool;
mod sampling;
mod schedulers;
mod schema;
mod shared_dir;
mod verify;
mod work;
