//! # truss-exit: one exit-code scheme for every truss-mc binary
//!
//! `truss`, `truss-mc`, `mc-shard` and `mc-merge` exit with these codes, so that a script or
//! a batch system can tell what happened whichever binary it ran:
//!
//! | code | constant | meaning |
//! |---|---|---|
//! | 0 | [`OK`] | success |
//! | 1 | [`INTERNAL`] | internal error (a bug) |
//! | 2 | [`USAGE`] | usage error: bad arguments, a range outside the job |
//! | 3 | [`INVALID_INPUT`] | invalid input: a job, model file or measured data (the message names the JSON path or line) |
//! | 4 | [`IO`] | a file or directory could not be read or written |
//! | 5 | [`IN_THE_WAY`] | a file in the way: a shard of another job, locked by another process, or damaged |
//! | 6 | [`VERIFICATION`] | verification failed: shards incomplete or not verifying at the merge; a shard process of `run-all` failed |
//! | 7 | [`FAILED_SAMPLES`] | failed samples: a solve did not converge (`truss solve`, a diagnosis's simulation), or the merge found failed samples without `--allow-failed` |
//! | 130 | [`INTERRUPTED_SIGINT`] | interrupted by SIGINT (Ctrl-C): the finished samples are kept; rerun the same command to resume |
//! | 143 | [`INTERRUPTED_SIGTERM`] | interrupted by SIGTERM (`kill`, a supervisor, a time limit): likewise |

/// Success.
pub const OK: u8 = 0;
/// An internal error (a bug).
pub const INTERNAL: u8 = 1;
/// Bad arguments, or a range outside the job.
pub const USAGE: u8 = 2;
/// A job, model file or measured data is invalid.
pub const INVALID_INPUT: u8 = 3;
/// A file or directory could not be read or written.
pub const IO: u8 = 4;
/// A file is in the way: another job's shard, locked, or damaged.
pub const IN_THE_WAY: u8 = 5;
/// Shards do not verify, or a shard process failed.
pub const VERIFICATION: u8 = 6;
/// Samples failed: a solve did not converge.
pub const FAILED_SAMPLES: u8 = 7;
/// Interrupted by SIGINT (128 + 2, as a shell reports it); finished samples are kept.
pub const INTERRUPTED_SIGINT: u8 = 130;
/// Interrupted by SIGTERM (128 + 15); finished samples are kept.
pub const INTERRUPTED_SIGTERM: u8 = 143;

/// The scheme in one line, for every binary's `--help`.
pub const SUMMARY: &str = "Exit codes: 0 success, 1 internal error, 2 usage error, 3 invalid input (job, model, measured data), 4 I/O error, 5 a file in the way (another job's shard, locked, damaged), 6 verification failed (shards incomplete or not verifying; a shard process failed), 7 failed samples (a solve did not converge), 130 interrupted by SIGINT, 143 interrupted by SIGTERM (finished samples kept; rerun to resume).";

#[cfg(test)]
mod tests {
    /// The codes are distinct, and the summary states each.
    #[test]
    fn codes_are_distinct_and_summarised() {
        let codes = [
            super::OK,
            super::INTERNAL,
            super::USAGE,
            super::INVALID_INPUT,
            super::IO,
            super::IN_THE_WAY,
            super::VERIFICATION,
            super::FAILED_SAMPLES,
        ];
        for (i, c) in codes.iter().enumerate() {
            assert_eq!(*c as usize, i);
            assert!(super::SUMMARY.contains(&format!("{c} ")), "{c}");
        }
        for c in [super::INTERRUPTED_SIGINT, super::INTERRUPTED_SIGTERM] {
            assert!(super::SUMMARY.contains(&format!("{c} ")), "{c}");
        }
    }
}
