//! The integration tests of truss-tolerance, one binary: the allocation's closed form and
//! optimality, the percentile law, the brute-force check of the shares, the refusals, production lots'
//! shares, and the end-to-end study (fast on a 2-stage prism; the paper's 5-stage case in the slow tier).

mod allocation;
mod brute_force;
mod common;
mod lots;
mod refusals;
mod study;
