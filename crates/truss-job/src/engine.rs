//! The parallel sample engine: the samples of a job solved on N threads and handed back in
//! index order. Everything that solves many samples in process goes through it: the shard
//! runner and its audit's re-solves (`mc-shard`), the Python bindings' `Job.run`
//! (`truss-py`), the tolerance study's runs and the diagnosis's simulations. It is also where
//! a solver of many samples at once would plug in: its contract is "solve these indices, hand
//! me each result in order".
//!
//! ## Contract
//!
//! [`Engine::run`] solves the indices it is given (a range of global sample indices, or a
//! list of them) with one [`SampleSolver`] per thread. Workers take chunks of [`chunk_for`]
//! consecutive positions from a shared counter; for each sample, on the worker that solved
//! it, `each` adds what the caller keeps to the chunk (it sees the [`SampleResult`] and the
//! solver that produced it, for what the result does not carry: the drawn length errors,
//! the displacements). The calling thread receives the chunks and hands them to `take` in
//! position order, each once. A sample's result depends only on the job and its index, so
//! what `take` sees never depends on the thread count or the scheduling.
//!
//! While it waits, the calling thread calls `take(None)` once every [`TICK`], for a caller
//! that must check for an interrupt on its own thread (Python's signal handlers). An error
//! from `take` stops the workers before their next sample; it is returned, and nothing more
//! is handed over. A `halt` check ([`Engine::halting_when`]: a signal flag) stops the
//! workers the same way, but what they finished is still handed over up to the first gap,
//! and [`Engine::run`] returns how many samples were: a crash or a stop loses at most the
//! samples in flight.

use crate::job::Job;
use crate::solve::{SampleResult, SampleSolver};
use std::collections::BTreeMap;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{RecvTimeoutError, sync_channel};
use std::time::{Duration, Instant};
use truss_core::SolveOptions;
use truss_core::solver::lanes::{
    BatchKernels, Kernels, LANES, LaneSolve, LaneWork, in_flight_for, run_lanes,
};

/// Positions a worker takes at a time, for models up to [`CHUNK_UNKNOWNS`] unknowns. Each
/// chunk wakes the calling thread once (the runner: one write): at 16 (about 0.2 ms of
/// 5-stage samples) those wakeups, on a machine with as many cores as workers, held two
/// threads to 1.73 times one on `scripts/bench-shard.sh`'s job; at 64, 1.84 times.
pub const CHUNK: u64 = 64;

/// The unknowns of the paper's 5-stage prism (15 free nodes × 3), the model [`CHUNK`] is
/// sized for. A larger model's chunk is smaller in proportion (see [`chunk_for`]).
pub const CHUNK_UNKNOWNS: u64 = 45;

/// The chunk of `job`: [`CHUNK`] positions scaled by `CHUNK_UNKNOWNS / n` for the largest
/// model's `n` unknowns, so that a chunk is about the same solver work whatever the model
/// (a sample's cost grows about linearly with its unknowns: the banded factorisation),
/// and never fewer than one sample per lane.
///
/// A chunk is what a worker holds before handing it over, so it bounds both the balance
/// between threads at the end of a run and what a crash loses: 64 samples of the 300-stage
/// prism with free play are about half an hour of one core, and with fewer than 64 samples
/// in a run only one thread would work. Which worker solves a sample never changes its
/// result, so the chunk moves no byte of the output.
pub fn chunk_for(job: &Job) -> u64 {
    let largest = job
        .cases
        .iter()
        .map(|c| c.structure.free_dofs() as u64)
        .max()
        .unwrap_or(0)
        .max(1);
    (CHUNK * CHUNK_UNKNOWNS / largest).clamp(LANES as u64, CHUNK)
}

/// How often the calling thread calls `take(None)` while a run lasts.
pub const TICK: Duration = Duration::from_millis(100);

/// Which samples to solve: global sample indices of the job.
#[derive(Debug, Clone)]
pub enum Indices<'a> {
    /// A range of indices, in order.
    Range(Range<u64>),
    /// These indices, in this order (repeats allowed).
    List(&'a [u64]),
}

impl Indices<'_> {
    /// How many samples.
    pub fn len(&self) -> u64 {
        match self {
            Indices::Range(r) => r.end.saturating_sub(r.start),
            Indices::List(l) => l.len() as u64,
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The index at position `p`.
    fn at(&self, p: u64) -> u64 {
        match self {
            Indices::Range(r) => r.start + p,
            Indices::List(l) => l[p as usize],
        }
    }

    /// Whether every index lies in `0..samples`.
    fn within(&self, samples: u64) -> bool {
        match self {
            Indices::Range(r) => r.end <= samples,
            Indices::List(l) => l.iter().all(|&i| i < samples),
        }
    }
}

impl From<Range<u64>> for Indices<'_> {
    fn from(r: Range<u64>) -> Self {
        Indices::Range(r)
    }
}

impl<'a> From<&'a [u64]> for Indices<'a> {
    fn from(l: &'a [u64]) -> Self {
        Indices::List(l)
    }
}

/// A job's samples on N threads (see the module doc).
#[derive(Clone)]
pub struct Engine<'a> {
    job: &'a Job,
    threads: usize,
    options: SolveOptions,
    halt: Option<&'a (dyn Fn() -> bool + Sync)>,
    lanes: bool,
}

impl<'a> Engine<'a> {
    /// An engine for `job` on `threads` threads (at least 1), with the default solver
    /// options, solving in lanes unless the environment says `TRUSS_LANES=off` (for
    /// benchmarks and for debugging: the results are the same bits).
    pub fn new(job: &'a Job, threads: usize) -> Self {
        Self {
            job,
            threads: threads.max(1),
            options: SolveOptions::default(),
            halt: None,
            lanes: std::env::var_os("TRUSS_LANES").is_none_or(|v| v != "off"),
        }
    }

    /// Whether each worker solves [`LANES`] samples side by side, their kernels batched
    /// (the default; see [`truss_core::solver::lanes`]), or one sample at a time. The
    /// results are the same bits either way.
    pub fn in_lanes(mut self, lanes: bool) -> Self {
        self.lanes = lanes;
        self
    }

    /// With these solver options (for example, recording iterations).
    pub fn with_options(mut self, options: SolveOptions) -> Self {
        self.options = options;
        self
    }

    /// Workers stop before their next sample once `halt` is true (see the module doc).
    pub fn halting_when(mut self, halt: &'a (dyn Fn() -> bool + Sync)) -> Self {
        self.halt = Some(halt);
        self
    }

    /// The job.
    pub fn job(&self) -> &'a Job {
        self.job
    }

    /// Solves `indices`, `each` filling a chunk per [`chunk_for`] samples on the workers, and
    /// `take` receiving the chunks in order, or `None` every [`TICK`] while it waits.
    /// Returns how many samples were handed over: all of them unless the halt check stopped
    /// the run.
    ///
    /// # Panics
    /// If an index is beyond the job (a bug in the caller), or a worker panics.
    pub fn run<'i, C: Default + Send, E>(
        &self,
        indices: impl Into<Indices<'i>>,
        each: impl Fn(&mut C, &SampleSolver<'a>, SampleResult) + Sync,
        mut take: impl FnMut(Option<C>) -> Result<(), E>,
    ) -> Result<u64, E> {
        let indices = indices.into();
        assert!(
            indices.within(self.job.samples()),
            "indices beyond the job's {} samples",
            self.job.samples()
        );
        let total = indices.len();
        let chunk_size = chunk_for(self.job);
        let in_flight = self
            .job
            .cases
            .iter()
            .map(|c| in_flight_for(&c.structure))
            .max()
            .unwrap_or(LANES);
        let threads = (self.threads as u64).min(total.div_ceil(chunk_size)).max(1) as usize;
        let next = AtomicU64::new(0);
        let stop = AtomicBool::new(false);
        let halted = || stop.load(Ordering::Relaxed) || self.halt.is_some_and(|h| h());
        // One message per chunk: its first position, its sample count, and what `each` kept.
        let (tx, rx) = sync_channel::<(u64, u64, C)>(64 * threads);
        std::thread::scope(|scope| {
            for _ in 0..threads {
                let tx = tx.clone();
                let (next, each, halted, indices) = (&next, &each, &halted, &indices);
                scope.spawn(move || {
                    let mut pool = vec![SampleSolver::with_options(self.job, self.options.clone())];
                    let mut kernels = BatchKernels::default();
                    loop {
                        let start = next.fetch_add(chunk_size, Ordering::Relaxed);
                        if start >= total || halted() {
                            return;
                        }
                        let end = (start + chunk_size).min(total);
                        let mut chunk = C::default();
                        let mut done = 0;
                        if self.lanes {
                            let mut work = InOrder {
                                job: self.job,
                                options: &self.options,
                                indices,
                                next: start,
                                end,
                                delivered: start,
                                pool: &mut pool,
                                parked: BTreeMap::new(),
                                chunk: &mut chunk,
                                each,
                                halted,
                            };
                            run_lanes(&mut work, &mut kernels, in_flight);
                            done = work.delivered - start;
                        } else {
                            let solver = &mut pool[0];
                            for p in start..end {
                                if halted() {
                                    break;
                                }
                                let result = solver.solve(indices.at(p));
                                each(&mut chunk, solver, result);
                                done += 1;
                            }
                        }
                        // A halted worker still sends what it finished.
                        if done > 0 && tx.send((start, done, chunk)).is_err() {
                            return;
                        }
                        if done < end - start {
                            return;
                        }
                    }
                });
            }
            drop(tx);
            let mut pending: BTreeMap<u64, (u64, C)> = BTreeMap::new();
            let mut expect = 0;
            let mut ticked = Instant::now();
            let result = loop {
                if ticked.elapsed() >= TICK {
                    ticked = Instant::now();
                    if let Err(e) = take(None) {
                        break Err(e);
                    }
                }
                match rx.recv_timeout(TICK) {
                    Ok((start, done, chunk)) => {
                        pending.insert(start, (done, chunk));
                        let mut failed = None;
                        while let Some((done, chunk)) = pending.remove(&expect) {
                            expect += done;
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
                    Err(RecvTimeoutError::Disconnected) => break Ok(expect),
                }
            };
            if result.is_err() {
                stop.store(true, Ordering::Relaxed);
                // Let blocked senders finish: the workers see the flag after their sample.
                while rx.recv().is_ok() {}
            }
            result
        })
    }

    /// Each sample of `indices` mapped by `each` (on the worker that solved it), in order.
    pub fn map<'i, T: Send>(
        &self,
        indices: impl Into<Indices<'i>>,
        each: impl Fn(&SampleSolver<'a>, SampleResult) -> T + Sync,
    ) -> Vec<T> {
        let indices = indices.into();
        let mut out = Vec::with_capacity(indices.len() as usize);
        let run = self.run(
            indices,
            |chunk: &mut Vec<T>, solver, result| chunk.push(each(solver, result)),
            |chunk| {
                out.extend(chunk.unwrap_or_default());
                Ok::<_, std::convert::Infallible>(())
            },
        );
        match run {
            Ok(_) => out,
            Err(never) => match never {},
        }
    }

    /// The results of `indices`, in order.
    pub fn results<'i>(&self, indices: impl Into<Indices<'i>>) -> Vec<SampleResult> {
        self.map(indices, |_, result| result)
    }
}

/// A chunk's samples solved in lanes, handed to `each` in position order: a sample that
/// ends before one issued earlier waits, with its solver, until that one has ended. Each
/// lane takes a solver from the pool (a new one when all are waiting).
struct InOrder<'e, 'a, C, F, H> {
    job: &'a Job,
    options: &'e SolveOptions,
    indices: &'e Indices<'e>,
    /// The next position to issue.
    next: u64,
    end: u64,
    /// The next position to hand to `each`.
    delivered: u64,
    pool: &'e mut Vec<SampleSolver<'a>>,
    parked: BTreeMap<u64, (SampleSolver<'a>, SampleResult)>,
    chunk: &'e mut C,
    each: &'e F,
    halted: &'e H,
}

impl<'a, C, F, H> LaneWork<'a> for InOrder<'_, 'a, C, F, H>
where
    F: Fn(&mut C, &SampleSolver<'a>, SampleResult),
    H: Fn() -> bool,
{
    type Done = (u64, SampleSolver<'a>, SampleResult);

    fn next<'s>(&mut self, kernels: Kernels<'s>) -> Option<LaneSolve<'s, Self::Done>>
    where
        'a: 's,
    {
        if self.next >= self.end || (self.halted)() {
            return None;
        }
        let p = self.next;
        self.next += 1;
        let index = self.indices.at(p);
        let mut solver = self
            .pool
            .pop()
            .unwrap_or_else(|| SampleSolver::with_options(self.job, self.options.clone()));
        Some(Box::pin(async move {
            let result = solver.solve_in(index, kernels).await;
            (p, solver, result)
        }))
    }

    fn done(&mut self, (p, solver, result): Self::Done) {
        self.parked.insert(p, (solver, result));
        while let Some((solver, result)) = self.parked.remove(&self.delivered) {
            (self.each)(self.chunk, &solver, result);
            self.pool.push(solver);
            self.delivered += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    fn job(samples: u64) -> Job {
        let text = format!(
            r#"{{"model": {{"prism": {{"stages": 1}}}}, "seed": 3, "cases": [
                {{"name": "a", "samples": {samples},
                  "length_errors": {{"longeron": {{"normal": {{"sigma": 0.01}}}}}}}},
                {{"name": "b", "samples": 50,
                  "length_errors": {{"batten": {{"uniform": {{"low": -0.01, "high": 0.01}}}}}}}}]}}"#
        );
        Job::from_json(&text, std::path::Path::new(".")).unwrap()
    }

    /// Every index arrives once, in order, as a solver alone gives it, for any thread count,
    /// a range across cases or a list in any order; `each` sees the solver of its sample.
    #[test]
    fn results_arrive_in_index_order_for_any_thread_count() {
        let job = job(300);
        let mut alone = SampleSolver::new(&job);
        let one_by_one: Vec<SampleResult> = (0..350).map(|i| alone.solve(i)).collect();
        let list: Vec<u64> = vec![349, 0, 7, 7, 200, 3];
        for threads in [1, 2, 5] {
            let engine = Engine::new(&job, threads);
            assert_eq!(engine.results(10..340), one_by_one[10..340], "{threads}");
            let got = engine.results(list.as_slice());
            let want: Vec<_> = list
                .iter()
                .map(|&i| one_by_one[i as usize].clone())
                .collect();
            assert_eq!(got, want, "{threads} threads, a list");
            let errors = engine.map(0..3, |s, _| s.last_errors().to_vec());
            for (k, e) in errors.iter().enumerate() {
                let mut drawn = Vec::new();
                let key = crate::sampler::stream_key(job.seed, "a");
                crate::sampler::draw_length_errors(&key, &job.cases[0], k as u64, &mut drawn);
                assert_eq!(e, &drawn);
            }
        }
        assert!(Engine::new(&job, 3).results(5..5).is_empty());
    }

    /// A sample's result, bit for bit (`{:?}` writes each `f64` in its shortest form that
    /// reads back to the same bits, so equal text is equal numbers, signs of zero included).
    fn bits(results: &[SampleResult]) -> Vec<String> {
        results.iter().map(|r| format!("{r:?}")).collect()
    }

    /// The same bits as one sample at a time for 1, 2 and 3 threads, in lanes or not, and
    /// for the range split in two at every offset (so at every offset modulo the lane
    /// count, chunk edges and case edges among them), each part in lanes on its own thread
    /// count.
    #[test]
    fn the_same_bits_for_any_thread_count_and_any_split() {
        let job = job(90);
        let n = job.samples();
        let mut alone = SampleSolver::new(&job);
        let reference = bits(&(0..n).map(|i| alone.solve(i)).collect::<Vec<_>>());
        for threads in [1, 2, 3] {
            for lanes in [true, false] {
                let whole = Engine::new(&job, threads).in_lanes(lanes).results(0..n);
                assert_eq!(bits(&whole), reference, "{threads} threads, lanes {lanes}");
            }
        }
        for cut in 0..=n {
            let threads = 1 + (cut % 3) as usize;
            let mut parts = Engine::new(&job, threads).in_lanes(true).results(0..cut);
            parts.extend(
                Engine::new(&job, 4 - threads)
                    .in_lanes(true)
                    .results(cut..n),
            );
            assert_eq!(
                bits(&parts),
                reference,
                "split at {cut}, {threads} threads first"
            );
        }
    }

    /// An error from `take` stops the run and is returned, nothing handed over after it.
    #[test]
    fn an_error_from_take_stops_the_run() {
        let job = job(300);
        let mut calls = 0;
        let r = Engine::new(&job, 2).run(
            0..300,
            |c: &mut Vec<u64>, _, r| c.push(r.index),
            |_| {
                calls += 1;
                Err("stop")
            },
        );
        assert_eq!((r, calls), (Err("stop"), 1));
    }

    /// A chunk is about the same solver work whatever the model: 64 samples of the paper's
    /// 5-stage prism (45 unknowns), 64·45/270 of the 30-stage one, and one per lane of the
    /// 300-stage one (2,700 unknowns), whose samples take seconds each with free play.
    #[test]
    fn the_chunk_shrinks_with_the_model() {
        let prism = |stages: usize| {
            let text = format!(
                r#"{{"model": {{"prism": {{"stages": {stages}}}}}, "seed": 3, "cases": [
                    {{"name": "a", "samples": 8,
                      "length_errors": {{"longeron": {{"normal": {{"sigma": 0.01}}}}}}}}]}}"#
            );
            Job::from_json(&text, std::path::Path::new(".")).unwrap()
        };
        let unknowns = |job: &Job| job.cases[0].structure.free_dofs() as u64;
        let (five, thirty, tall) = (prism(5), prism(30), prism(300));
        assert_eq!(unknowns(&five), CHUNK_UNKNOWNS);
        assert_eq!((unknowns(&thirty), unknowns(&tall)), (270, 2_700));
        assert_eq!(chunk_for(&five), CHUNK);
        assert_eq!(chunk_for(&thirty), 10);
        assert_eq!(chunk_for(&tall), LANES as u64);
        // A job's chunk is its largest model's.
        assert_eq!(chunk_for(&job(10)), CHUNK);
    }

    /// A halt stops the workers; what they finished is handed over up to the first gap, in
    /// order, and counted. On one thread that is exactly the samples solved before the halt
    /// (the partial chunk included), plus, in lanes, the ones issued before the halt (they
    /// finish); on several, a worker the scheduler held back may leave the gap
    /// anywhere, even at the start.
    #[test]
    fn a_halt_hands_over_what_was_finished() {
        let job = job(300);
        for (threads, lanes) in [(1, false), (1, true), (3, false), (3, true)] {
            let solved = AtomicUsize::new(0);
            let halt = || solved.load(Ordering::Relaxed) >= 100;
            let mut got = Vec::new();
            let handed = Engine::new(&job, threads)
                .in_lanes(lanes)
                .halting_when(&halt)
                .run(
                    0..350,
                    |c: &mut Vec<u64>, _, r| {
                        solved.fetch_add(1, Ordering::Relaxed);
                        c.push(r.index)
                    },
                    |chunk| {
                        got.extend(chunk.unwrap_or_default());
                        Ok::<_, ()>(())
                    },
                )
                .unwrap();
            assert_eq!(handed, got.len() as u64, "{threads} threads");
            assert_eq!(got, (0..handed).collect::<Vec<_>>(), "{threads} threads");
            if threads == 1 && !lanes {
                assert_eq!(handed, 100);
            } else if threads == 1 {
                // The lanes' samples issued before the halt finish: those in flight, and
                // those that ended before an earlier one (at most the rest of the chunk).
                assert!((100..=100 + CHUNK).contains(&handed), "{handed}");
            } else {
                assert!(handed < 350, "{handed}");
            }
        }
    }
}
