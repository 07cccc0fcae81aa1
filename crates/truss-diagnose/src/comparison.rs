//! The data and the comparison: the baseline job and the cases derived from it, the
//! measured specimens, the simulation of a case at the measured coordinates, and the
//! statistics that say where a case and the measurements disagree.
//!
//! - [`baseline`]: the baseline job and case, and the jobs derived from it;
//! - [`measured`]: the measured node and member files;
//! - [`checks`]: the data against the stated instrument noise, before anything is fitted;
//! - [`simulate`]: N samples of a derived case at the measured coordinates;
//! - [`statistics`]: every statistic of the measurements against a simulation.

pub mod baseline;
pub mod checks;
pub mod measured;
pub mod simulate;
pub mod statistics;
