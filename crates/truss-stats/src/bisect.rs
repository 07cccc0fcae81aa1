//! Where a nondecreasing function of one variable reaches a value: bisection to the last
//! digits, and the doubling that brackets it from 0. The merge's folded-normal quantile and
//! the tolerance study's Gaussian-tilt quantile and σ allocations all invert this way.

/// The point of `[lo, hi]` where the nondecreasing `f` reaches `target`: bisection, keeping
/// `f(lo) < target ≤ f(hi)`, until the bracket is within 1e-15 of `hi` (relative) or after
/// 200 halvings; the bracket's midpoint. Where `f` stays below `target` the answer is `hi`'s
/// end of the bracket, where it starts above it `lo`'s.
pub fn bisect(f: impl Fn(f64) -> f64, target: f64, (mut lo, mut hi): (f64, f64)) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-15 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// A bracket `[lo, hi]` of where the nondecreasing `f` on `[0, ∞)` reaches `target`: `hi`
/// doubled from 1 while `f(hi) < target`, `lo` its last value below (0 at first). Loops
/// forever where `f` never reaches `target`; the callers' functions grow without bound.
pub fn bracket_from_zero(f: impl Fn(f64) -> f64, target: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (0.0, 1.0);
    while f(hi) < target {
        lo = hi;
        hi *= 2.0;
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// √2 as the root of x² = 2, to the last digits, from a bracket found by doubling.
    #[test]
    fn finds_the_square_root_of_two() {
        let f = |x: f64| x * x;
        let (lo, hi) = bracket_from_zero(f, 2.0);
        assert_eq!((lo, hi), (1.0, 2.0));
        let r = bisect(f, 2.0, (lo, hi));
        assert!((r - std::f64::consts::SQRT_2).abs() <= 4e-16, "{r}");
    }

    /// A step function: the answer is the step, within the tolerance.
    #[test]
    fn finds_a_step() {
        let r = bisect(|x| if x < 0.3 { 0.0 } else { 1.0 }, 0.5, (0.0, 1.0));
        assert!((r - 0.3).abs() <= 1e-15, "{r}");
    }
}
