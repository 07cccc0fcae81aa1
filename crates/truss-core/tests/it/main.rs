//! truss-core's integration tests, one binary (as ripgrep does): verification against
//! hand solutions and the paper, invariances, model faults, the prism, decenter and
//! despace, and backlash.

mod backlash;
mod common;
mod hand_solutions;
mod holding;
mod invariance;
mod limit;
mod model_errors;
mod placement;
mod prism;
