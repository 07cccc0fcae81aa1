//! The workspace's cross-crate tests, one binary: the pipeline, golden reproducibility,
//! the dependency graph, circles of imports between files, the README's commands, and the
//! cron round script.

mod circles;
mod cron;
mod golden;
mod layers;
mod pipeline;
mod readme;
