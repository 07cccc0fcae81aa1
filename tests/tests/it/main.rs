//! The workspace's cross-crate tests, one binary: the pipeline, golden reproducibility, and
//! the dependency graph.

mod golden;
mod layers;
mod pipeline;
