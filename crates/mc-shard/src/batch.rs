//! Solving a range of a job in memory, on T threads, for a caller that keeps the samples
//! instead of writing a shard file (the Python package): the same [`Worker`] as the runner,
//! so each sample is the record its shard line holds.
//!
//! Workers take chunks of consecutive indices from a shared counter and send each finished
//! chunk to the calling thread, which hands the chunks to `take` in index order. The order of
//! what `take` sees, and each sample's record, depend only on the job and the range, never
//! on the thread count. Between chunks, and while it waits for one, the calling thread calls
//! `take(None)` once every [`TICK`], so a caller can check for an interrupt; an error from
//! `take` stops the workers before their next sample and is returned.

use crate::job::Job;
use crate::worker::Worker;
use shard_record::ShardRange;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{RecvTimeoutError, sync_channel};
use std::time::{Duration, Instant};

/// Indices a worker takes at a time (as the runner's chunks: few wakeups of the caller).
const CHUNK: u64 = 64;

/// How often the calling thread calls `take(None)` (as long as the run lasts).
pub const TICK: Duration = Duration::from_millis(100);

/// Solves the indices `range` of `job` on `threads` threads; `each` turns a worker and an
/// index into a result (for example the worker's record of it), and `take` receives the
/// results in index order, one chunk at a time, or `None` while it waits (see the module
/// doc).
///
/// # Panics
/// If `range` reaches beyond the job (a bug in the caller; check it with
/// [`ShardRange::within`]).
pub fn solve_range<T: Send, E>(
    job: &Job,
    range: ShardRange,
    threads: usize,
    each: impl Fn(&mut Worker<'_>, u64) -> T + Sync,
    mut take: impl FnMut(Option<Vec<T>>) -> Result<(), E>,
) -> Result<(), E> {
    assert!(range.end <= job.samples(), "range {range} beyond the job");
    let threads = threads.max(1);
    let next = AtomicU64::new(range.start);
    let stop = AtomicBool::new(false);
    let (tx, rx) = sync_channel::<(u64, Vec<T>)>(4 * threads);
    std::thread::scope(|scope| {
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, stop, each) = (&next, &stop, &each);
            scope.spawn(move || {
                let mut worker = Worker::new(job);
                loop {
                    let start = next.fetch_add(CHUNK, Ordering::Relaxed);
                    if start >= range.end || stop.load(Ordering::Relaxed) {
                        return;
                    }
                    let end = (start + CHUNK).min(range.end);
                    let mut chunk = Vec::with_capacity((end - start) as usize);
                    for index in start..end {
                        if stop.load(Ordering::Relaxed) {
                            return;
                        }
                        chunk.push(each(&mut worker, index));
                    }
                    if tx.send((start, chunk)).is_err() {
                        return;
                    }
                }
            });
        }
        drop(tx);
        let mut pending: BTreeMap<u64, Vec<T>> = BTreeMap::new();
        let mut expect = range.start;
        let mut ticked = Instant::now();
        let result = loop {
            if ticked.elapsed() >= TICK {
                ticked = Instant::now();
                if let Err(e) = take(None) {
                    break Err(e);
                }
            }
            match rx.recv_timeout(TICK) {
                Ok((start, chunk)) => {
                    pending.insert(start, chunk);
                    let mut failed = None;
                    while let Some(chunk) = pending.remove(&expect) {
                        expect += chunk.len() as u64;
                        if let Err(e) = take(Some(chunk)) {
                            failed = Some(e);
                            break;
                        }
                    }
                    if let Some(e) = failed {
                        break Err(e);
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break Ok(()),
            }
        };
        if result.is_err() {
            stop.store(true, Ordering::Relaxed);
            // Let blocked senders finish: the workers see the flag after their chunk.
            while rx.recv().is_ok() {}
        }
        result
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(samples: u64) -> Job {
        let text = format!(
            r#"{{"model": {{"prism": {{"stages": 1}}}}, "seed": 3, "cases": [
                {{"name": "a", "samples": {samples},
                  "length_errors": {{"longeron": {{"normal": {{"sigma": 0.01}}}}}}}}]}}"#
        );
        Job::from_json(&text, std::path::Path::new(".")).unwrap()
    }

    /// Every index arrives once, in order, as the worker's record of it, for any thread
    /// count; an error from `take` stops the run and is returned.
    #[test]
    fn results_arrive_in_index_order_for_any_thread_count() {
        let job = job(300);
        let one_by_one: Vec<String> = {
            let mut w = Worker::new(&job);
            (0..300).map(|i| w.sample(i).to_line()).collect()
        };
        for threads in [1, 2, 5] {
            let mut got = Vec::new();
            let range = ShardRange::new(10, 290);
            solve_range(
                &job,
                range,
                threads,
                |w, i| w.sample(i).to_line(),
                |chunk| {
                    got.extend(chunk.unwrap_or_default());
                    Ok::<_, ()>(())
                },
            )
            .unwrap();
            assert_eq!(got, one_by_one[10..290], "{threads} threads");
        }
        let mut calls = 0;
        let r = solve_range(
            &job,
            ShardRange::new(0, 300),
            2,
            |w, i| w.sample(i).to_line(),
            |_| {
                calls += 1;
                Err("stop")
            },
        );
        assert_eq!((r, calls), (Err("stop"), 1));
    }
}
