//! mc-merge's integration tests, one binary: statistics, sweeps and the command line.

mod cli;
mod common;
mod export;
mod statistics;
mod sweep;
