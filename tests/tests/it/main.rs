//! The workspace's cross-crate tests, one binary: the pipeline, the alignment budget, golden
//! reproducibility, the dependency graph, circles of imports between files, no untested doc
//! examples, the release builds' shared features, the README's commands, and the cron round
//! script.

mod budget;
mod circles;
mod cron;
mod doc_examples;
mod features;
mod golden;
mod layers;
mod pipeline;
mod readme;
