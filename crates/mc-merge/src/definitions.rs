//! The definitions of every statistic, in words, as written into `report.json`.

use crate::report::{BootstrapDefinition, Definitions, Real};
use crate::settings::Settings;

/// Units.
pub const UNITS: &str = "angles θ_P and percentiles in rad (the table also prints arcsec, 1 rad = 648000/π arcsec); tan θ_x, tan θ_y dimensionless; σ (member length standard deviation) in mm; slopes in rad/mm; stages a count";

/// The percentile definition.
pub const PERCENTILE: &str = "inverse empirical CDF, Hyndman & Fan (1996) definition 1: the p-quantile is the smallest sample value x with F_n(x) >= p, i.e. x_(k) with k the smallest rank such that k >= p*n (p*n in IEEE double precision); with integer weights w_i (bootstrap) the first value, in ascending order with ties broken by global sample index, whose cumulative weight reaches p*W, W = sum of the weights";

/// The bootstrap.
pub const BOOTSTRAP: &str = "Poisson bootstrap: in replicate r every converged sample i gets the weight w_i ~ Poisson(1), a pure function of (seed, r, global sample index i), so results do not depend on how the job was split into shards nor on the order of the files; a replicate's percentile is the weighted definition-1 percentile; replicates whose weights are all zero (probability e^-n) are left out and counted";

/// The generator.
pub const RNG: &str = "counter-based SplitMix64: key_r = mix64(mix64(seed XOR 0x626f6f74) + (r+1)*0x9e3779b97f4a7c15), u = mix64(key_r + (i+1)*0x9e3779b97f4a7c15) with mix64 the SplitMix64 finaliser (Steele, Lea & Flood 2014); weight = the Poisson(1) inverse CDF at u/2^64 (table of floor(F(k)*2^64))";

/// Percentile interval.
pub const PERCENTILE_INTERVAL: &str =
    "[q*_((1-c)/2), q*_((1+c)/2)]: definition-1 quantiles of the replicate percentiles";

/// BCa interval.
pub const BCA_INTERVAL: &str = "Efron (1987) BCa: levels Phi(z0 + (z0 + z_a)/(1 - a (z0 + z_a))) of the replicate distribution; z0 = Phi^-1((#{q* < q} + #{q* = q}/2)/B); acceleration from the empirical influence function of the quantile, U_i = p - 1{x_i <= q}, a = sum U^3 / (6 (sum U^2)^1.5); null when z0 is infinite or the adjusted levels leave (0, 1)";

/// Order-statistic interval.
pub const ORDER_STATISTIC: &str = "distribution-free interval [x_(l), x_(u)] with K ~ Binomial(n, p) (exact, statrs): l the largest rank with P(K <= l-1) <= (1-c)/2, u the smallest with P(K <= u-1) >= (1+c)/2; coverage = P(l <= K <= u-1) >= c; null when n is too small";

/// The Rayleigh law.
pub const RAYLEIGH: &str = "paper section 3.2: tan θ_x, tan θ_y ~ N(0, σ_t²) (eqs. 19-20) so θ_P ~ Rayleigh(σ_t) (eq. 26). Per component: mean (Student-t interval), sample standard deviation with divisor n-1 (chi²(n-1) interval), zero-mean ML scale sqrt(sum x²/n) (chi²(n) interval). sigma_t pooled = sqrt(sum(tan²θ_x + tan²θ_y)/(2n)), the zero-mean ML estimate from both components, chi²(2n) interval. ML Rayleigh fit of θ_P: σ̂² = sum θ²/(2n), exact interval from 2n σ̂²/σ² ~ chi²(2n). Rayleigh percentiles θ_P^α = sqrt(-2 σ̂² ln(1-α)) (eq. 28), interval mapped from σ's interval. relative_difference = (Rayleigh - empirical)/empirical with the Poisson-bootstrap percentile interval (replicate σ*² = sum w θ²/(2W)). All sums in global index order";

/// Goodness of fit.
pub const GOF: &str = "θ Rayleigh(σ) <=> θ² exponential(mean 2σ²): Kolmogorov-Smirnov D and Anderson-Darling A² of exponentiality with the mean estimated by ML (D'Agostino & Stephens 1986, §4.9), Stephens' modified D* = (D - 0.2/n)(sqrt n + 0.26 + 0.5/sqrt n) and A* = A²(1 + 0.6/n). p-values by Monte Carlo null calibration (the statistics are scale invariant, so the null does not depend on σ): M exponential samples of size n (Rényi's representation, counter-based stream 0x676f6621), p = (1 + #{T_sim >= T})/(M + 1), standard error sqrt(p(1-p)/M); for n > 2000 the modified statistics' null is simulated at n = 2000. Verdict: 'holds' when both p-values are >= the level, else 'rejected'. Effect size: relative difference of the Rayleigh and empirical target percentiles, and max CDF gap = D";

/// Sweeps.
pub const SWEEP: &str = "σ-series: cases whose parameters agree except sigma (>= 2 distinct σ); stages-series likewise. Points: the target percentile with its BCa interval (percentile interval where BCa is null). Least-squares lines through the origin and with intercept; R² = 1 - SS_res/SS_tot with SS_tot about the mean. Allowable σ = (target - intercept)/slope. Intervals of slopes, intercepts, R² and allowable σ: percentile intervals over the bootstrap replicates, each replicate series refitted. Stages: each percentile divided by that of the smallest stage count; ratio interval from the replicate ratios; relative_interval = own interval / reference value";

/// Loose joints.
pub const LOOSE: &str = "fraction of converged samples that record loose_joints with loose_joints >= 1, Clopper-Pearson exact interval";

/// Floating stages.
pub const FLOATING: &str = "fraction of converged samples that record floating with floating = true (some stage's tilt held by pretension alone, not by the members that bear), Clopper-Pearson exact interval; where it exceeds the tail the target percentile reads (1 - target/100), a case caveat says so";

/// The holding force.
pub const HOLDING: &str = "holding force [N] of a converged sample (recorded where floating is): the largest force on one node of the top surface, in any direction, that to first order moves θ_P by at most 1 % and lets no bearing one-sided member (a taut cable, a joint on its hole's edge) go, from the tangent stiffness at the equilibrium (0 where the equilibrium is not stable against some small load); percentiles by the θ_P percentile definition; loose: held by less than loose_below = 1e-6 N, Clopper-Pearson exact interval, among all samples that record it and among those above the target percentile of θ_P (tail); where any sample of the tail is loose, a case caveat says so";

/// A sample held by less than this force \[N\] on a top node is loosely held (the holding
/// force's summaries and caveat).
pub const LOOSE_HOLDING_FORCE: f64 = 1e-6;

/// The definitions block of the report.
pub fn definitions(settings: &Settings) -> Definitions {
    Definitions {
        units: UNITS,
        percentile: PERCENTILE,
        bootstrap: BootstrapDefinition {
            kind: "poisson",
            description: BOOTSTRAP,
            replicates: settings.replicates,
            seed: settings.bootstrap_seed,
            rng: RNG,
            confidence: Real(settings.confidence),
            percentile_interval: PERCENTILE_INTERVAL,
            bca_interval: BCA_INTERVAL,
        },
        order_statistic: ORDER_STATISTIC,
        rayleigh: RAYLEIGH,
        gof: GOF,
        sweep: SWEEP,
        loose_joints: LOOSE,
        floating: FLOATING,
        holding_force: HOLDING,
    }
}
