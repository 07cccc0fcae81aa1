//! The workspace's cross-crate tests, one binary: the pipeline, golden reproducibility,
//! the dependency graph, the README's commands, and the cron round script.

mod cron;
mod golden;
mod layers;
mod pipeline;
mod readme;
