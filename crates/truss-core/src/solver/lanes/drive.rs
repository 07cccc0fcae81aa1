//! The driver of a batch: fills its slots (as many as [`super::in_flight_for`] says, at most
//! [`IN_FLIGHT`]) with solves, polls each until it waits for a kernel or ends, runs the
//! kernels they wait for, and repeats; a slot whose solve ended takes the next one at once.

use super::{BatchKernels, IN_FLIGHT, Kernels, LaneSlots};
use std::future::Future;
use std::pin::Pin;
use std::task::{Context, Poll, Waker};

/// A solve in a lane: it borrows the lane's mailbox (`'s`) and owns what it works on.
pub type LaneSolve<'s, T> = Pin<Box<dyn Future<Output = T> + 's>>;

/// The solves a batch runs, and what becomes of each one's end.
pub trait LaneWork<'a> {
    /// What a solve ends with (typically the sample solver it owned, and its result).
    type Done;

    /// The next solve, its kernels run through `kernels`; `None` when there is none (the
    /// range is done, or the run is stopping): the lanes in flight then finish.
    fn next<'s>(&mut self, kernels: Kernels<'s>) -> Option<LaneSolve<'s, Self::Done>>
    where
        'a: 's;

    /// A solve ended (lanes end in any order; the work keeps its own order).
    fn done(&mut self, done: Self::Done);
}

/// Runs `work`'s solves `in_flight` at a time (at most [`IN_FLIGHT`]; see
/// [`super::in_flight_for`]) until it has no more and every one ended. `kernels` keeps the
/// batched kernels' buffers from one call to the next.
pub fn run_lanes<'a, W: LaneWork<'a>>(work: &mut W, kernels: &mut BatchKernels, in_flight: usize) {
    let slots = LaneSlots::new(in_flight);
    let mut all: [Option<LaneSolve<'_, W::Done>>; IN_FLIGHT] = std::array::from_fn(|_| None);
    let lanes = &mut all[..slots.in_flight()];
    let mut context = Context::from_waker(Waker::noop());
    let mut more = true;
    loop {
        for (l, lane) in lanes.iter_mut().enumerate() {
            loop {
                if lane.is_none() && more {
                    *lane = work.next(Kernels::Lane(slots.lane(l)));
                    more = lane.is_some();
                }
                let Some(solve) = lane else {
                    break;
                };
                if slots.lane(l).waiting() {
                    break;
                }
                match solve.as_mut().poll(&mut context) {
                    Poll::Ready(done) => {
                        *lane = None;
                        work.done(done);
                    }
                    Poll::Pending => break,
                }
            }
        }
        if lanes.iter().all(Option::is_none) {
            return;
        }
        kernels.run(&slots);
    }
}
