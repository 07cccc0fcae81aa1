//! Which range a process runs: from `--range A..B`, `--shard I/K`, or the environment of a
//! batch system, in that order of precedence; and the case and sample lookups that the
//! commands (and the Python package) share, with their messages.
//!
//! | source | shard |
//! |---|---|
//! | `--range A..B` | exactly `A..B` |
//! | `--shard I/K` | shard I of K (0-based; see [`shard_record::ShardRange`] for the partition) |
//! | `MC_SHARD_INDEX` with `MC_SHARD_COUNT` or `--shards K` | shard `INDEX` of `COUNT`: the generic pair, for HTCondor (`$(Process)`) and any other scheduler; set on purpose, it overrides a scheduler's variables |
//! | `SLURM_ARRAY_TASK_ID` with `SLURM_ARRAY_TASK_COUNT` | shard `ID` of `COUNT` (a full array `--array=0-(K-1)`) |
//! | `AWS_BATCH_JOB_ARRAY_INDEX` with `AWS_BATCH_JOB_ARRAY_SIZE` | shard `INDEX` of `SIZE` (an AWS Batch array job of size K sets both in every child) |
//! | `BATCH_TASK_INDEX` with `BATCH_TASK_COUNT` | shard `INDEX` of `COUNT` (a Google Cloud Batch task group of `taskCount` K sets both in every task) |
//! | `JOB_COMPLETION_INDEX` (Kubernetes Indexed Job) with `MC_SHARD_COUNT` or `--shards K` | shard `INDEX` of `K` |
//! | none of these | the whole job, one shard |
//!
//! ## Refusals
//!
//! Every refusal is a usage error (exit 2) naming the variables:
//! - half a pair: an index without its count, or a count without its index (`MC_SHARD_COUNT`
//!   alone counts only for `JOB_COMPLETION_INDEX`);
//! - two schedulers' index variables at once (which one placed this process is not known:
//!   set `MC_SHARD_INDEX`/`MC_SHARD_COUNT` or give `--shard I/K` to say);
//! - a count given twice that disagrees: `--shards K` or `MC_SHARD_COUNT` against the
//!   scheduler's own count;
//! - a value that is not a whole number (or one beyond 2⁶⁴ − 1, called too large), an index
//!   not below its count, or a count from the environment beyond 1 to
//!   [`MAX_SHARDS`] (the bound of `--shards`);
//! - `--shards K` with no index variable set (it would otherwise run the whole job);
//! - a Slurm array that does not start at 0 (`SLURM_ARRAY_TASK_MIN` set and not 0: its task
//!   ids are not the shard indices).

use crate::cli::MAX_SHARDS;
use crate::errors::RunError;
use crate::job::Job;
use shard_record::ShardRange;

/// Where a range came from, for messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// `--range`.
    Range,
    /// `--shard`.
    Shard,
    /// The generic pair `MC_SHARD_INDEX`, `MC_SHARD_COUNT`.
    Generic,
    /// Slurm's array variables.
    Slurm,
    /// AWS Batch's array variables.
    AwsBatch,
    /// Google Cloud Batch's task variables.
    GoogleBatch,
    /// Kubernetes' completion index.
    Kubernetes,
    /// No selection: the whole job.
    Whole,
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Source::Range => "--range",
            Source::Shard => "--shard",
            Source::Generic => GENERIC_INDEX,
            Source::Slurm => "SLURM_ARRAY_TASK_ID",
            Source::AwsBatch => "AWS_BATCH_JOB_ARRAY_INDEX",
            Source::GoogleBatch => "BATCH_TASK_INDEX",
            Source::Kubernetes => "JOB_COMPLETION_INDEX",
            Source::Whole => "the whole job",
        })
    }
}

/// The generic index variable.
pub const GENERIC_INDEX: &str = "MC_SHARD_INDEX";

/// The generic count variable (also the count of a Kubernetes Indexed Job).
pub const GENERIC_COUNT: &str = "MC_SHARD_COUNT";

/// Slurm's first array index: 0 for an array whose task ids are shard indices.
pub const SLURM_MIN: &str = "SLURM_ARRAY_TASK_MIN";

/// A batch system's index variable and the variable of its count (`None`: it sets no count,
/// and `MC_SHARD_COUNT` or `--shards` gives it).
struct Scheduler {
    source: Source,
    index: &'static str,
    count: Option<&'static str>,
}

/// The schedulers whose variables are read, after the generic pair.
const SCHEDULERS: [Scheduler; 4] = [
    Scheduler {
        source: Source::Slurm,
        index: "SLURM_ARRAY_TASK_ID",
        count: Some("SLURM_ARRAY_TASK_COUNT"),
    },
    Scheduler {
        source: Source::AwsBatch,
        index: "AWS_BATCH_JOB_ARRAY_INDEX",
        count: Some("AWS_BATCH_JOB_ARRAY_SIZE"),
    },
    Scheduler {
        source: Source::GoogleBatch,
        index: "BATCH_TASK_INDEX",
        count: Some("BATCH_TASK_COUNT"),
    },
    Scheduler {
        source: Source::Kubernetes,
        index: "JOB_COMPLETION_INDEX",
        count: None,
    },
];

/// Every environment variable [`select`] reads (for tests that must start from none).
pub const VARIABLES: [&str; 10] = [
    GENERIC_INDEX,
    GENERIC_COUNT,
    SLURM_MIN,
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_COUNT",
    "AWS_BATCH_JOB_ARRAY_INDEX",
    "AWS_BATCH_JOB_ARRAY_SIZE",
    "BATCH_TASK_INDEX",
    "BATCH_TASK_COUNT",
    "JOB_COMPLETION_INDEX",
];

/// Chooses the range (see the module doc); `env` looks up environment variables.
pub fn select(
    range: Option<&str>,
    shard: Option<&str>,
    shards: Option<u64>,
    samples: u64,
    env: impl Fn(&str) -> Option<String>,
) -> Result<(ShardRange, Source), RunError> {
    let usage = |e: shard_record::ShardRangeError| RunError::Usage(e.to_string());
    if let Some(text) = range {
        let r: ShardRange = text.parse().map_err(usage)?;
        return Ok((r.within(samples).map_err(usage)?, Source::Range));
    }
    if let Some(text) = shard {
        let (i, k) = ShardRange::parse_shard_spec(text).map_err(usage)?;
        return Ok((
            ShardRange::for_shard(i, k, samples).map_err(usage)?,
            Source::Shard,
        ));
    }
    let number = |name: &str| -> Result<Option<u64>, RunError> {
        let Some(v) = env(name) else { return Ok(None) };
        let digits = v.trim();
        digits.parse().map(Some).map_err(|_| {
            RunError::Usage(
                if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
                    format!(
                        "environment variable {name}={v:?} is too large for a shard index or count"
                    )
                } else {
                    format!("environment variable {name}={v:?} is not a whole number")
                },
            )
        })
    };
    // A count from the environment, bounded as `--shards` is.
    let count = |name: &str| -> Result<Option<u64>, RunError> {
        match number(name)? {
            Some(k) if !(1..=MAX_SHARDS).contains(&k) => Err(RunError::Usage(format!(
                "environment variable {name}={k}: a shard count must be 1 to {MAX_SHARDS}"
            ))),
            k => Ok(k),
        }
    };
    let half = |set: &str, unset: &str| {
        RunError::Usage(format!(
            "{set} is set but {unset} is not: set both, or neither"
        ))
    };
    // A count stated by the user: --shards K, else MC_SHARD_COUNT.
    let generic_count = count(GENERIC_COUNT)?;
    let stated = match (shards, generic_count) {
        (Some(k), Some(c)) if k != c => {
            return Err(RunError::Usage(format!(
                "--shards {k} disagrees with {GENERIC_COUNT}={c}"
            )));
        }
        (Some(k), _) => Some((k, format!("--shards {k}"))),
        (None, Some(c)) => Some((c, format!("{GENERIC_COUNT}={c}"))),
        (None, None) => None,
    };
    let shard_of = |i: u64, k: u64, source: Source| {
        Ok((ShardRange::for_shard(i, k, samples).map_err(usage)?, source))
    };
    if let Some(i) = number(GENERIC_INDEX)? {
        let (k, _) = stated.ok_or_else(|| {
            RunError::Usage(format!(
                "{GENERIC_INDEX} is set but {GENERIC_COUNT} is not: set both (or give --shards K)"
            ))
        })?;
        return shard_of(i, k, Source::Generic);
    }
    let mut found = Vec::new();
    for s in &SCHEDULERS {
        let index = number(s.index)?;
        let count = s.count.map(count).transpose()?.flatten();
        match (index, count, s.count) {
            (Some(i), Some(k), _) => found.push((s, i, Some(k))),
            (Some(i), None, None) => found.push((s, i, None)),
            (Some(_), None, Some(count_name)) => return Err(half(s.index, count_name)),
            (None, Some(_), Some(count_name)) => return Err(half(count_name, s.index)),
            (None, _, _) => {}
        }
    }
    if let [(s, _, Some(_))] = found.as_slice()
        && s.source == Source::Slurm
        && let Some(min) = number(SLURM_MIN)?
        && min != 0
    {
        return Err(RunError::Usage(format!(
            "{SLURM_MIN}={min}: the array does not start at 0, so SLURM_ARRAY_TASK_ID is not \
             the shard index: submit it as --array=0-(K-1) (or give --shard I/K)"
        )));
    }
    match found.as_slice() {
        [] if generic_count.is_some() => Err(RunError::Usage(format!(
            "{GENERIC_COUNT} is set but neither {GENERIC_INDEX} nor JOB_COMPLETION_INDEX is: \
             set one of them too, or unset {GENERIC_COUNT}"
        ))),
        [] if shards.is_some() => Err(RunError::Usage(format!(
            "--shards {} is given but no shard index is set ({GENERIC_INDEX}, \
             JOB_COMPLETION_INDEX, or a batch system's): set one, or give --shard I/K",
            shards.unwrap_or_default()
        ))),
        [] => Ok((ShardRange::new(0, samples), Source::Whole)),
        [(s, i, Some(k))] => match &stated {
            Some((stated, said)) if stated != k => Err(RunError::Usage(format!(
                "{said} disagrees with {}={k}",
                s.count.unwrap_or(GENERIC_COUNT)
            ))),
            _ => shard_of(*i, *k, s.source.clone()),
        },
        [(s, i, None)] => {
            let (k, _) = stated.ok_or_else(|| {
                RunError::Usage(format!(
                    "{} is set: give the shard count with --shards K or {GENERIC_COUNT}",
                    s.index
                ))
            })?;
            shard_of(*i, k, s.source.clone())
        }
        several => Err(RunError::Usage(format!(
            "the index variables of several batch systems are set ({}): set \
             {GENERIC_INDEX} and {GENERIC_COUNT}, or give --shard I/K, to say which shard \
             this is",
            several
                .iter()
                .map(|(s, i, _)| format!("{}={i}", s.index))
                .collect::<Vec<_>>()
                .join(", ")
        ))),
    }
}

/// The index of the case named `name`, or a usage error listing the job's cases.
pub fn case_named(job: &Job, name: &str) -> Result<usize, RunError> {
    job.case_named(name).ok_or_else(|| {
        RunError::Usage(format!(
            "no case {name:?} (cases: {})",
            job.cases
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })
}

/// Checks that case `c` of `job` has a sample `k` (counted within the case).
pub fn check_sample(job: &Job, c: usize, k: u64) -> Result<(), RunError> {
    let case = &job.cases[c];
    if k >= case.samples {
        return Err(RunError::Usage(format!(
            "case {:?} has samples 0..{}, not {k}",
            case.name, case.samples
        )));
    }
    Ok(())
}

/// The global indices `A..B` given as `text` (named `flag` in messages), within the job.
pub fn range_within(job: &Job, flag: &str, text: &str) -> Result<ShardRange, RunError> {
    text.parse::<ShardRange>()
        .and_then(|r| r.within(job.samples()))
        .map_err(|e| RunError::Usage(format!("{flag}: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Selects from the environment `vars` alone (no flags), for a job of 100 samples.
    fn from_env(
        vars: &[(&str, &str)],
        shards: Option<u64>,
    ) -> Result<(ShardRange, Source), String> {
        let env = |name: &str| {
            vars.iter()
                .find(|(k, _)| *k == name)
                .map(|(_, v)| v.to_string())
        };
        select(None, None, shards, 100, env).map_err(|e| e.to_string())
    }

    /// Each scheduler's pair selects shard INDEX of COUNT; flags come first; the generic pair
    /// overrides a scheduler.
    #[test]
    fn each_scheduler_selects_its_shard() {
        let third = ShardRange::new(33, 66);
        for (vars, source) in [
            (
                &[("MC_SHARD_INDEX", "1"), ("MC_SHARD_COUNT", "3")][..],
                Source::Generic,
            ),
            (
                &[
                    ("SLURM_ARRAY_TASK_ID", "1"),
                    ("SLURM_ARRAY_TASK_COUNT", "3"),
                ],
                Source::Slurm,
            ),
            (
                &[
                    ("AWS_BATCH_JOB_ARRAY_INDEX", "1"),
                    ("AWS_BATCH_JOB_ARRAY_SIZE", "3"),
                ],
                Source::AwsBatch,
            ),
            (
                &[("BATCH_TASK_INDEX", "1"), ("BATCH_TASK_COUNT", "3")],
                Source::GoogleBatch,
            ),
            (
                &[("JOB_COMPLETION_INDEX", "1"), ("MC_SHARD_COUNT", "3")],
                Source::Kubernetes,
            ),
        ] {
            assert_eq!(from_env(vars, None), Ok((third, source)), "{vars:?}");
        }
        assert_eq!(
            from_env(&[("MC_SHARD_INDEX", "2")], Some(3)),
            Ok((ShardRange::new(66, 100), Source::Generic))
        );
        assert_eq!(
            from_env(
                &[
                    ("MC_SHARD_INDEX", "0"),
                    ("MC_SHARD_COUNT", "2"),
                    ("SLURM_ARRAY_TASK_ID", "1"),
                    ("SLURM_ARRAY_TASK_COUNT", "2")
                ],
                None
            ),
            Ok((ShardRange::new(0, 50), Source::Generic))
        );
        let env = |_: &str| Some("7".to_string());
        assert_eq!(
            select(None, Some("1/4"), None, 100, env).unwrap(),
            (ShardRange::new(25, 50), Source::Shard)
        );
        assert_eq!(
            from_env(&[], None),
            Ok((ShardRange::new(0, 100), Source::Whole))
        );
        // `--shards 4` alone names no shard: refused (ambiguous_environments_are_refused).
        assert!(from_env(&[], Some(4)).is_err());
    }

    /// Half a pair, two schedulers, and disagreeing counts are refused, naming the variables.
    #[test]
    fn ambiguous_environments_are_refused() {
        for (vars, shards, words) in [
            (
                &[("AWS_BATCH_JOB_ARRAY_INDEX", "1")][..],
                None,
                &["AWS_BATCH_JOB_ARRAY_INDEX", "AWS_BATCH_JOB_ARRAY_SIZE"][..],
            ),
            (
                &[("AWS_BATCH_JOB_ARRAY_SIZE", "3")],
                None,
                &["AWS_BATCH_JOB_ARRAY_SIZE", "AWS_BATCH_JOB_ARRAY_INDEX"],
            ),
            (
                &[("BATCH_TASK_INDEX", "1")],
                None,
                &["BATCH_TASK_INDEX", "BATCH_TASK_COUNT"],
            ),
            (
                &[("BATCH_TASK_COUNT", "3")],
                None,
                &["BATCH_TASK_COUNT", "BATCH_TASK_INDEX"],
            ),
            (
                &[("SLURM_ARRAY_TASK_ID", "1")],
                None,
                &["SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_COUNT"],
            ),
            (
                &[("MC_SHARD_INDEX", "1")],
                None,
                &["MC_SHARD_INDEX", "MC_SHARD_COUNT"],
            ),
            (
                &[("MC_SHARD_COUNT", "3")],
                None,
                &["MC_SHARD_COUNT", "MC_SHARD_INDEX"],
            ),
            (
                &[("JOB_COMPLETION_INDEX", "1")],
                None,
                &["JOB_COMPLETION_INDEX", "MC_SHARD_COUNT"],
            ),
            (
                &[
                    ("SLURM_ARRAY_TASK_ID", "1"),
                    ("SLURM_ARRAY_TASK_COUNT", "3"),
                    ("BATCH_TASK_INDEX", "1"),
                    ("BATCH_TASK_COUNT", "3"),
                ],
                None,
                &[
                    "SLURM_ARRAY_TASK_ID=1",
                    "BATCH_TASK_INDEX=1",
                    "MC_SHARD_INDEX",
                ],
            ),
            (
                &[("BATCH_TASK_INDEX", "1"), ("BATCH_TASK_COUNT", "3")],
                Some(4),
                &["--shards 4", "BATCH_TASK_COUNT=3"],
            ),
            (
                &[
                    ("BATCH_TASK_INDEX", "1"),
                    ("BATCH_TASK_COUNT", "3"),
                    ("MC_SHARD_COUNT", "4"),
                ],
                None,
                &["MC_SHARD_COUNT=4", "BATCH_TASK_COUNT=3"],
            ),
            (
                &[("MC_SHARD_INDEX", "1"), ("MC_SHARD_COUNT", "3")],
                Some(4),
                &["--shards 4", "MC_SHARD_COUNT=3"],
            ),
            (
                &[
                    ("AWS_BATCH_JOB_ARRAY_INDEX", "x"),
                    ("AWS_BATCH_JOB_ARRAY_SIZE", "3"),
                ],
                None,
                &["AWS_BATCH_JOB_ARRAY_INDEX=\"x\"", "whole number"],
            ),
            (
                &[("BATCH_TASK_INDEX", "3"), ("BATCH_TASK_COUNT", "3")],
                None,
                &["shard 3 of 3"],
            ),
            // A count without any index: not the whole job in silence.
            (&[], Some(4), &["--shards 4", "MC_SHARD_INDEX"]),
            // Counts from the environment are bounded as --shards is.
            (
                &[("MC_SHARD_INDEX", "1"), ("MC_SHARD_COUNT", "2000000")],
                None,
                &["MC_SHARD_COUNT=2000000", "1 to 1000000"],
            ),
            (
                &[
                    ("SLURM_ARRAY_TASK_ID", "1"),
                    ("SLURM_ARRAY_TASK_COUNT", "18446744073709551616"),
                ],
                None,
                &["SLURM_ARRAY_TASK_COUNT", "too large"],
            ),
            // A 1-based Slurm array would run shard ID of COUNT one off.
            (
                &[
                    ("SLURM_ARRAY_TASK_ID", "1"),
                    ("SLURM_ARRAY_TASK_COUNT", "3"),
                    ("SLURM_ARRAY_TASK_MIN", "1"),
                ],
                None,
                &["SLURM_ARRAY_TASK_MIN=1", "--array=0-"],
            ),
        ] {
            let e = from_env(vars, shards).expect_err(&format!("{vars:?} is refused"));
            for w in words {
                assert!(e.contains(w), "{vars:?}: {e:?} names {w}");
            }
        }
    }
}
