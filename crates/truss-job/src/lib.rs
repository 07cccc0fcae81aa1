//! # truss-job: what a truss Monte Carlo job is, and how one sample is computed
//!
//! The job file ([`job`]: a model, a seed, and cases of length-error distributions,
//! clearances and effects) is read, validated and written here; its id ([`Job::id`]) hashes
//! the canonical job with the [`NUMERICS_VERSION`]. Sample `k` of a case draws its numbers
//! from a ChaCha20 stream keyed by (job seed, case name, `k`) in a documented order
//! ([`sampler`], [`distribution`]), gets the case's deterministic [`effects`], and is solved
//! by [`solve::SampleSolver`], which returns a domain result ([`solve::SampleResult`]).
//! Many samples are solved on N threads by [`engine::Engine`], which hands the results back
//! in index order whatever the thread count.
//!
//! Everything that needs samples depends on this crate and the solver: the shard runner
//! (`mc-shard`, which writes results as wire records), the diagnosis (`truss-diagnose`) and
//! the tolerance study (`truss-tolerance`).
//! It depends on nothing of ours but `truss-core`, and knows no file format but the job's.

pub mod budget;
pub mod distribution;
pub mod effects;
pub mod engine;
pub mod errors;
pub mod job;
pub mod lot;
pub mod sampler;
pub mod solve;

pub use engine::Engine;
pub use errors::JobError;
pub use job::{Job, NUMERICS_VERSION};
