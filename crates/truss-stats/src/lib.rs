//! # truss-stats: the statistics shared by truss-mc's merge and diagnosis
//!
//! No solver and no file format: numbers in, numbers out, so that the merge (`mc-merge`) and
//! the diagnosis (`truss-diagnose`) depend on it and on nothing of each other.
//!
//! - [`rng`]: counter-based random numbers (a value is a pure function of seed, stream,
//!   replicate and counter) and the sequential SplitMix64 stream with Box–Muller normals that
//!   tests and benchmarks draw from.
//! - [`quantile`]: Hyndman–Fan definition 1 quantiles, weighted positions, and the
//!   distribution-free order-statistic interval.
//! - [`bootstrap`]: the Poisson bootstrap of quantiles and statistics, percentile and BCa
//!   intervals.
//! - [`bisect`]: where a nondecreasing function reaches a value (bisection, bracketing).
//! - [`two_sample`]: moments, the two-sample Kolmogorov–Smirnov statistic and its p-value,
//!   and Holm's step-down adjustment.

pub mod bisect;
pub mod bootstrap;
pub mod quantile;
pub mod rng;
pub mod two_sample;
