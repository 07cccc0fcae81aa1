//! # truss-threads: how many worker threads a truss-mc command starts
//!
//! Every command that works on several threads (the shard runner and `run-all`'s workers,
//! the merge's bootstraps, the tolerance study, the diagnosis, the Python bindings) takes
//! its default count and its bound from here, so that "all cores" means the same in each.
//! Results never depend on the count (each crate's tests prove it byte for byte); only the
//! wall time does.
//!
//! A leaf crate with no dependencies: the merge, which links neither the solver nor the job,
//! reaches it as readily as the job crate's sample engine.

/// The most worker threads (or `run-all` workers) a command starts.
pub const MAX_THREADS: usize = 1024;

/// The default count: the threads this process may run at once (its cores, or fewer where
/// an affinity mask or a cgroup's CPU quota limits it), 1 if that cannot be told.
pub fn available() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `given`, or [`available`] when none is given.
pub fn or_available(given: Option<usize>) -> usize {
    given.unwrap_or_else(available)
}

/// Whether a command accepts `threads`: 1 to [`MAX_THREADS`].
pub fn accepted(threads: usize) -> bool {
    (1..=MAX_THREADS).contains(&threads)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default is a count a command accepts, and a given count is kept.
    #[test]
    fn the_default_is_accepted_and_a_given_count_kept() {
        assert!(accepted(available()));
        assert_eq!(or_available(Some(3)), 3);
        assert_eq!(or_available(None), available());
        assert!(!accepted(0) && accepted(1) && accepted(MAX_THREADS) && !accepted(MAX_THREADS + 1));
    }
}
