//! # truss-diagnose: where simulation and measurement disagree, and which effect is missing
//!
//! An engineer has built trusses (or reassembled one many times) and measured them. This
//! crate compares the measurements with the Monte Carlo prediction of a baseline job case,
//! says where they disagree, names the physical effect the model is missing with its fitted
//! size, writes the updated job, and shows the disagreement shrink.
//!
//! ```text
//! truss diagnose --job BASELINE.json --case NAME --measured M.csv [--measured-members MM.csv]
//!                [--measurement-sigma MM] [--samples N] [--candidates A,B] [--threads T]
//!                --out DIR
//! truss synth-measured --job J --case NAME --specimens N --seed S --effect 'NAME:P=V,…[;…]'
//!                [--measurement-sigma MM] [--all-nodes] [--members-out MM.csv] > M.csv
//! ```
//!
//! ## Workflow
//!
//! 1. **Where** ([`comparison`], [`comparison::statistics`]). The baseline case is simulated with N samples (default
//!    max(2000, 20·n), at most 10 000, for n specimens: the simulation's noise is at most
//!    a twentieth of the data's in variance) under the job's seed and the case's name, so
//!    every later simulation sees the same random words (common random numbers), with the
//!    instrument's noise σ_m added to every simulated coordinate. Means, standard
//!    deviations and covariances of every measured coordinate's displacement, of the top
//!    surface's height (piston), tan θ_x and tan θ_y, θ_P's percentiles, a KS test on θ_P and
//!    an energy-distance test on the displacement vectors, each with a 95 % interval and a
//!    sentence; Holm-adjusted p-values say which disagree.
//! 2. **Which effect** ([`candidates`], [`likelihood`], [`selection`]).
//!    Each candidate's Gaussian synthetic likelihood ℓ is maximised over its parameters
//!    (finite-difference derivatives with steps adapted to ℓ's own scale, [`likelihood::derivatives`]);
//!    candidates are compared with the baseline by a likelihood-ratio test (χ²_k, Bonferroni
//!    over the candidates, the statistic Λ = 2(ℓ̂ − ℓ₀)/(c·λ̄) deflated by c = 1 + n/N for
//!    the simulation's own noise and by λ̄ = max(1, tr(A⁻¹B)/k) for misspecification) and
//!    with each other by the BIC of a misspecified likelihood, −2ℓ/c + tr(A⁻¹B)·ln n (Gao &
//!    Song 2010; tr(A⁻¹B) = k·λ̄, the effective number of parameters, never below k), so
//!    ΔBIC = k·λ̄·ln n − 2(ℓ̂ − ℓ₀)/c = λ̄·(k ln n − Λ) against the baseline: λ̄ raises a
//!    candidate's penalty rather than shrinking its likelihood, which would make the
//!    likelihoods of candidates with different λ̄ incomparable. The verdict is one of
//!    - `named`: the best candidate by BIC is significant and better than the baseline by
//!      ΔBIC ≤ −2; candidates within ΔBIC 2 of it are listed as *indistinguishable*, and
//!      so are significant candidates it does not fit significantly closer than (Vuong's
//!      test for non-nested models, z < 1.96 on the per-specimen differences of the two
//!      maximised ℓ: BIC may prefer it, but the data do not show it fits closer);
//!    - `cannot_tell`: some candidate improves the fit but not both significantly and by
//!      that margin; or none does, and the intervals are too wide to show that the baseline
//!      agrees within tolerance (see [`comparison::statistics`]): more specimens are needed;
//!    - `none`: no candidate improves the fit and the baseline agrees within tolerance;
//!    - `unexplained`: no candidate improves the fit, yet the baseline disagrees (a
//!      Holm-significant statistic, with at least 30 specimens; with fewer: `cannot_tell`).
//!
//!    The named effect's parameters (and those of candidates indistinguishable from it) get
//!    95 % **profile-likelihood intervals** ([`likelihood::profile`]): the values θⱼ where
//!    2(ℓ̂ − ℓ_p(θⱼ)) ≤ χ²₁(0.95)·c·λⱼ, ℓ_p the maximum over the other parameters, with the
//!    test's adjustments (c as above, λⱼ = max(1, (A⁻¹BA⁻¹)ⱼⱼ/(A⁻¹)ⱼⱼ) the one-parameter
//!    form of λ̄), found by root-finding on the profile with common random numbers and cut
//!    at the plausible range (flagged). They follow ℓ where it is far from quadratic (slack
//!    cables, a fit near the edge of the range) and reduce to the sandwich Wald interval
//!    where it is quadratic. For a statement about all k parameters at once, the joint
//!    95 % region (threshold χ²_k(0.95)·c·λ̄) is projected on each parameter as well
//!    (`joint_interval`). Every candidate also carries its Wald interval, c·A⁻¹BA⁻¹
//!    ([`likelihood::fit`]), reported beside the profile one.
//! 3. **Add it, and look again**: the named effect is added at its fitted values, every
//!    effect of the model is re-fitted jointly, each effect added in an earlier step is
//!    tested for removal given the others and tried swapped for a rival that explains the
//!    same thing better jointly ([`selection::update`]), and step 2 runs again against the updated
//!    model with the remaining candidates, and so on ([`selection::step`], [`selection`]): stepwise
//!    selection, until no candidate is significant and clearly better, or a named effect
//!    spoils a model that agreed in distribution (the discrepancy grows beyond its noise,
//!    or turns significant: it is then not added; [`selection::step`]), or none is left. An effect
//!    removed because another took over what it explained is listed as indistinguishable
//!    from it, with the measurement that would separate them. Effects that show only
//!    together (backlash with a diagonal pretension, each alone fitting poorly) are found
//!    by a pair step ([`selection::pair`]): candidates whose effects interact
//!    ([`candidates::Candidate::interacts_with`]), one of them significant at the step and
//!    neither named, are fitted jointly against the current model and named together in
//!    place of the step's effect when significant and better by ΔBIC ≤ −2, or listed as an
//!    alternative reading (`a + b`) when within ΔBIC 2 of it. The false
//!    discovery rate over the steps is held at α/2 by ForwardStop on the steps'
//!    Bonferroni-adjusted p-values ([`selection::forward_stop`]; removals only take effects
//!    out); the other half of α = 0.05 is the comparison's ([`comparison::statistics::LEVEL`]), so that on
//!    data missing nothing any verdict but agreement has a rate of at most α.
//!    `DIR/updated-job.json` is the baseline job with every effect of the final model in
//!    the case (same case name), which mc-shard and mc-merge run as usual.
//! 4. **The gap shrinks**: each step's discrepancy before and after, and the baseline's
//!    against the final model's, statistic by statistic.
//! 5. **What the data cannot tell apart, and what they do not determine**
//!    ([`selection::confound`]): the final model's effects fitted jointly once more, each
//!    value with that fit's interval (profile where the Wald one is cut at the range); a
//!    parameter whose interval covers most of its plausible range is reported "not
//!    determined by these data", with no physical reading. Each significant rival is added
//!    to the final model and all re-fitted: one that moves an effect's parameters out of
//!    their intervals, or is itself significant given the model and widens them
//!    two-fold, is listed as confounded with it (a
//!    temperature field's offset and vertical gradient against a longeron length bias),
//!    never one whose joint re-fit ends below the model's ℓ̂ (the model is the rival at
//!    its null, so that fit is short of the maximum),
//!    with the measurement that would separate them. What cannot be told apart from each
//!    effect (a step's own indistinguishable candidates, effects it took over from, rivals
//!    confounded with it) is one record, [`selection::indistinguishable`], for effects
//!    named and swapped in alike, which both reports read.
//! 6. **What the data could not have seen** ([`selection::unseen`],
//!    [`likelihood::power`]): for every candidate not in the final model, the smallest
//!    effect its test against the final model (the step after the last kept one, with that
//!    test's α_K, c, λ̄ and k) would have detected with 80 % power, one parameter at a time
//!    in its own unit: Λ under the shift δ of internal coordinate j is non-central
//!    χ²_k(λ), λ = δ²·Aⱼⱼ/(c·λ̄) (A = −∂²ℓ/∂t² at the candidate's fit, n times the
//!    information per specimen), and δ solves P(χ²_k(λ) > q) = 0.8, q the test's critical
//!    value. The most visible parameter (smallest limit as a share of its plausible range)
//!    is reported in words ("`length_bias` bias.longeron below 1.8 µm"); a parameter
//!    whose limit lies beyond its plausible range, or with no curvature, is "not
//!    detectable at any size within its plausible range". One-sided parameters (a
//!    clearance, a diagonal shortening) move only the way their range allows; the test's
//!    χ²_k reference is kept, so the limit is that of the selection's own test. The
//!    verdict `none` reads "no effect above these sizes is missing".
//!
//! Outputs: `DIR/diagnosis.json` (schema in [`report`]), `DIR/diagnosis.md`, and the SVG
//! plots of [`report::plot`], each written through a temporary file and never through a link (a
//! link, a non-file or a file this writer cannot prove it wrote (crate `run-dir`: another
//! writer's, a user's) at any of [`OUTPUTS`] is refused before the work), with the directory
//! locked while they are written and listed in `.truss-diagnose.manifest` (crate
//! `run-dir`). The measured files are read only if they are regular files of at most
//! 64 MiB (`/dev/zero` or a FIFO is refused at once). Progress goes to stderr.
//!
//! ## Candidate effects
//!
//! `backlash`, `gravity`, `thermal_gradient`, `length_bias`, `length_sigma`,
//! `diagonal_pretension`, registered in [`candidates::REGISTRY`] (each in a file of its own
//! with its parameters and ranges; see [`candidates`]). `backlash` turns the
//! prism's nodes into truss-core's pin joints whose clearances scatter uniformly among the
//! joints about a fitted mean (its two parameters: the mean and the half-width, the spread
//! resolved with the members measured; see [`candidates::backlash::Backlash`]); on node positions
//! alone its main trace, the top surface lowered as the diagonals pull the joints across
//! their clearance, is much what a length error or a uniform temperature change leaves. The
//! members measured one by one (`--measured-members`) show whether the members themselves
//! are off, and so tell it from the length effects; a temperature change they cannot rule
//! out, and the diagnosis then lists it as indistinguishable.
//!
//! ## Measured data
//!
//! See [`comparison::measured`]: CSV with a header, any column and row order, quoting and CRLF; bad rows
//! (and rows with extra fields) are errors with their line; specimens missing a compared
//! node are left out and counted; outlier rows (a coordinate beyond 10 robust SD) are left
//! out and listed by specimen and line; member rows of specimens the node file lacks, and
//! member errors beyond 1 % of the member's length, are refused; a specimen that repeats
//! another's coordinates exactly is refused, naming the copies. Against the stated noise
//! σ_m ([`comparison::checks`]), before anything is simulated: a coordinate with the same
//! value in every specimen is refused; a coordinate whose scatter is below σ_m (χ² lower
//! tail, Bonferroni over the coordinates, family-wise 10⁻³), and pairs of specimens closer
//! together than two draws of the noise allow (the same test on their distance), are
//! warned of on stderr and in `diagnosis.json`'s `data.checks[]` and `diagnosis.md`. With
//! `--measured-members` each specimen's own measured members enter its likelihood
//! ([`likelihood::conditional`]).

pub mod candidates;
pub mod comparison;
mod errors;
pub mod likelihood;
pub mod report;
pub mod selection;
pub mod settings;
pub mod synth;

pub use errors::DiagnoseError;

use std::path::PathBuf;

/// Options of `truss diagnose`.
#[derive(Debug, Clone)]
pub struct DiagnoseOptions {
    /// The baseline job.
    pub job: PathBuf,
    /// The case.
    pub case: String,
    /// The node CSV.
    pub measured: PathBuf,
    /// The member CSV, if any.
    pub measured_members: Option<PathBuf>,
    /// Output directory.
    pub out: PathBuf,
    /// Settings.
    pub settings: settings::Settings,
    /// Draw plots.
    pub plots: bool,
}

/// What `run` found, for the caller's summary line.
#[derive(Debug, Clone)]
pub struct Summary {
    /// The verdict.
    pub verdict: selection::decide::Verdict,
    /// The first named effect or `none`.
    pub named_effect: String,
    /// Every effect added, in order.
    pub named_effects: Vec<String>,
    /// The reason.
    pub reason: String,
    /// Discrepancy before and after.
    pub discrepancy: (f64, f64),
    /// The answer's lines as the console prints them ([`report::Answer::plain_lines`]):
    /// the lines `diagnosis.md` opens with and `diagnosis.json`'s `answer.lines`, without
    /// Markdown's marks.
    pub answer: Vec<String>,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// The writer's name in its output directory's manifest (crate `run-dir`: a rerun removes
/// only the files it listed there, such as the `after` plots of a run that found an effect).
pub const WRITER: &str = "truss-diagnose";

/// Every file a diagnosis may write into its output directory.
pub const OUTPUTS: [&str; 7] = [
    "diagnosis.json",
    "diagnosis.md",
    "updated-job.json",
    "theta_p-ecdf-before.svg",
    "theta_p-ecdf-after.svg",
    "top-scatter-before.svg",
    "top-scatter-after.svg",
];

/// Fewest specimens accepted.
pub const MIN_SPECIMENS: usize = 5;

/// Most simulated samples per evaluation (`--samples`).
pub const MAX_SAMPLES: usize = 10_000;

/// Runs the diagnosis and writes `diagnosis.json`, `diagnosis.md`, `updated-job.json` and
/// the plots into the output directory: each through a temporary file, never through a
/// link (a link, a non-file or a file this writer cannot prove it wrote, at any of
/// [`OUTPUTS`], is refused before the work and again before the first write), with the
/// directory locked while they are written and a manifest of them kept ([`WRITER`]). What was left out of the data (outliers, unknown
/// nodes and members) is reported on stderr (even with `quiet`) and in `diagnosis.json`.
pub fn run(options: &DiagnoseOptions) -> Result<Summary, DiagnoseError> {
    let s = &options.settings;
    if !(s.measurement_sigma >= 0.0 && s.measurement_sigma.is_finite()) {
        return Err(DiagnoseError::Usage(
            "--measurement-sigma must be a non-negative number of mm".into(),
        ));
    }
    if let Some(n) = s.samples
        && !(100..=MAX_SAMPLES).contains(&n)
    {
        return Err(DiagnoseError::Usage(format!(
            "--samples {n}: must be from 100 to {MAX_SAMPLES}"
        )));
    }
    if let Some(t) = s.threads
        && !truss_threads::accepted(t)
    {
        return Err(DiagnoseError::Usage(format!(
            "--threads {t}: must be from 1 to {}",
            truss_threads::MAX_THREADS
        )));
    }
    // Before any work: no output may go through a link.
    run_dir::OutputDir::check(&options.out, WRITER, &OUTPUTS)?;
    let progress = settings::Progress::new(s.quiet);
    let base = comparison::baseline::Baseline::read(&options.job, &options.case)?;
    let mut data = comparison::measured::read(
        base.model(),
        &options.measured,
        options.measured_members.as_deref(),
        MIN_SPECIMENS,
    )?;
    data.report.checks = comparison::checks::check(&data, s.measurement_sigma)?;
    warn_left_out(&data.report);
    let d = selection::diagnose(&base, &data, s, &progress)?;
    let dir = &options.out;
    let mut out = run_dir::OutputDir::open(dir, WRITER)?;
    out.check_names(&OUTPUTS)?;
    let mut plots = Vec::new();
    if options.plots {
        plots.extend(report::plot::draw(
            &mut out,
            "before",
            &data,
            &d.simulations.0,
            d.top,
            "the baseline",
        )?);
        if let Some(sim) = &d.simulations.1 {
            let label = format!("with {}", d.named_effects().join(" and "));
            plots.extend(report::plot::draw(
                &mut out, "after", &data, sim, d.top, &label,
            )?);
        }
    }
    // One answer for the three reports: diagnosis.json, diagnosis.md and the summary.
    let answer = report::Answer::of(&data, &d);
    let mut files = vec![
        out.write(
            "diagnosis.json",
            report::json(&base, &data, &d, &answer, s.measurement_sigma).as_bytes(),
        )?,
        out.write(
            "diagnosis.md",
            report::markdown(&base, &data, &d, &answer, &plots).as_bytes(),
        )?,
        out.write(
            "updated-job.json",
            base.updated_job_json(&d.updated).as_bytes(),
        )?,
    ];
    files.extend(plots.iter().map(|p| dir.join(p)));
    out.finish()?;
    progress.note(&format!("wrote {}", dir.display()));
    Ok(Summary {
        verdict: d.verdict,
        named_effect: d.named_effect().to_string(),
        named_effects: d.named_effects().iter().map(|s| s.to_string()).collect(),
        reason: d.reason.clone(),
        discrepancy: (
            d.before.energy,
            d.after.as_ref().map_or(d.before.energy, |a| a.energy),
        ),
        answer: answer.plain_lines(),
        files,
    })
}

/// What reading the data left out, on stderr.
fn warn_left_out(r: &comparison::measured::DataReport) {
    let warn = |m: String| eprintln!("truss diagnose: warning: {m}");
    for o in &r.outliers {
        warn(format!("outlier left out: {}", o.words()));
    }
    if r.left_out_count > 0 {
        warn(format!(
            "{} specimens left out for a missing node (first: {})",
            r.left_out_count,
            r.first_left_out()
        ));
    }
    if !r.unknown_nodes.is_empty() {
        warn(format!(
            "node ids the model does not have, ignored: {}",
            r.unknown_nodes.join(", ")
        ));
    }
    if !r.unknown_members.is_empty() {
        warn(format!(
            "member ids the model does not have, ignored: {}",
            r.unknown_members.join(", ")
        ));
    }
    for c in &r.checks {
        warn(c.words.clone());
    }
}
