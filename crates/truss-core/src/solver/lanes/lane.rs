//! One operation over all lanes, the form in which the batched kernels are written so that
//! the compiler vectorises them (a leaf: the kernels import it, it imports nothing).

/// `[f(0), …, f(W − 1)]`.
#[inline(always)]
pub(super) fn lanes<const W: usize>(f: impl Fn(usize) -> f64) -> [f64; W] {
    std::array::from_fn(f)
}
