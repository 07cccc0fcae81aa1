//! A sample's line depends only on the job and its index: the same bytes for any split of
//! the job into shards, any thread count, any order of the cases, and a fresh process.

use crate::common::*;
use mc_shard::{Job, RunOptions, run_shard};
use proptest::prelude::*;
use shard_record::ShardRange;
use std::path::Path;

fn run(job: &Job, dir: &Path, range: ShardRange, threads: usize) {
    run_shard(
        job,
        dir,
        range,
        &RunOptions {
            threads,
            quiet: true,
        },
    )
    .unwrap();
}

fn job(n: u64) -> Job {
    Job::from_json(&small_job(n), Path::new(".")).unwrap()
}

#[test]
fn one_shard_equals_many_shards_and_any_thread_count() {
    let job = job(60);
    let n = job.samples();
    let whole = tempfile::tempdir().unwrap();
    run(&job, whole.path(), ShardRange::new(0, n), 1);
    let reference = sample_lines(whole.path());
    assert_eq!(reference.len() as u64, n);
    for (k, threads) in [(2, 4), (7, 3), (120, 2)] {
        let dir = tempfile::tempdir().unwrap();
        for r in ShardRange::partition(k, n).unwrap() {
            run(&job, dir.path(), r, threads);
        }
        assert_eq!(
            sample_lines(dir.path()),
            reference,
            "{k} shards, {threads} threads"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    /// Any split points give the same lines.
    #[test]
    fn any_split_gives_the_same_bytes(cuts in proptest::collection::btree_set(1u64..80, 0..5), threads in 1usize..4) {
        let job = job(40);
        let n = job.samples();
        let whole = tempfile::tempdir().unwrap();
        run(&job, whole.path(), ShardRange::new(0, n), 2);
        let dir = tempfile::tempdir().unwrap();
        let mut bounds = vec![0];
        bounds.extend(cuts);
        bounds.push(n);
        for w in bounds.windows(2) {
            run(&job, dir.path(), ShardRange::new(w[0], w[1]), threads);
        }
        prop_assert_eq!(sample_lines(dir.path()), sample_lines(whole.path()));
    }
}

/// Reordering the cases changes the global indices, not any case's results.
#[test]
fn case_order_does_not_change_a_cases_results() {
    let text = small_job(25);
    let spec: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut swapped = spec.clone();
    swapped["cases"].as_array_mut().unwrap().reverse();
    let a = Job::from_json(&text, Path::new(".")).unwrap();
    let b = Job::from_json(&swapped.to_string(), Path::new(".")).unwrap();
    assert_ne!(a.id, b.id, "a different job");
    let (da, db) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run(&a, da.path(), ShardRange::new(0, 50), 2);
    run(&b, db.path(), ShardRange::new(0, 50), 2);
    let strip = |lines: Vec<String>| -> Vec<(String, u64, String)> {
        let mut v: Vec<_> = lines
            .iter()
            .map(|l| {
                let mut s: serde_json::Value = serde_json::from_str(l).unwrap();
                let key = (
                    s["case"].as_str().unwrap().to_string(),
                    s["sample"].as_u64().unwrap(),
                );
                s.as_object_mut().unwrap().remove("index");
                (key.0, key.1, s.to_string())
            })
            .collect();
        v.sort();
        v
    };
    assert_eq!(
        strip(sample_lines(da.path())),
        strip(sample_lines(db.path()))
    );
}

/// A solver reused across samples gives the same line as a fresh one: no state leaks from
/// one sample to the next.
#[test]
fn a_sample_does_not_depend_on_the_samples_before_it() {
    let job = job(30);
    let mut warm = mc_shard::worker::Worker::new(&job);
    for index in 0..job.samples() {
        let fresh = mc_shard::worker::Worker::new(&job).sample(index).to_line();
        assert_eq!(warm.sample(index).to_line(), fresh, "index {index}");
    }
}
