//! The workspace's cross-crate tests, one binary: the pipeline, golden reproducibility,
//! the dependency graph, and the README's commands.

mod golden;
mod layers;
mod pipeline;
mod readme;
