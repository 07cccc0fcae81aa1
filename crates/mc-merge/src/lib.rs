//! # mc-merge: from Monte Carlo shards to a tolerance decision
//!
//! Engineers design high-precision space trusses; a Monte Carlo over member-length errors
//! (written by `mc-shard` into shard files, format in [`shard_record`]) gives per sample the
//! distortion angle θ_P (rad) of the top surface and tan θ_x, tan θ_y. This crate answers: what is
//! the 95th-percentile distortion angle, how sure are we, does the paper's Rayleigh law hold, and
//! which member-length tolerance σ meets the pointing budget.
//!
//! ```text
//! mc-merge DIR_OR_FILES... [-o|--out REPORT_DIR] [-q|--quiet] [--percentiles 50,90,95,99]
//!          [--confidence 0.95] [--replicates 2000] [--bootstrap-seed 20210325]
//!          [--gof-replicates 1000] [--gof-level 0.05] [--target-angle 9.69e-5]
//!          [--target-percentile 95] [--threads N] [--allow-partial] [--allow-failed]
//!          [--no-plots] [--export FILE.csv|FILE.jsonl]
//! mc-merge completions bash|zsh|fish|elvish|powershell
//! mc-merge man
//! ```
//!
//! Every numeric flag has a documented limit, refused naming the flag ([`settings`] for the
//! statistics, [`cli`] for the rest).
//!
//! The binary is a thin shell around [`execute`] (a helper command, an export, or [`run`]: the
//! merge with its table and files); the statistics are reusable functions:
//! [`quantile`] (definition-1 percentiles, weighted percentiles, order-statistic interval),
//! [`bootstrap`] (split-invariant Poisson bootstrap, percentile and BCa intervals), [`rayleigh`]
//! (fit, χ² intervals, eq. 28), [`gof`] (KS and AD with estimated scale), [`sweep`] (line fits,
//! allowable σ).
//!
//! ## 1. Verification (nothing is computed unless it passes)
//!
//! See [`load`]: only regular files named, one job id across all files, each shard's closing
//! digest, every converged θ_P in [0, π/2], every global index
//! `0..job_samples` exactly once (byte-identical duplicates and agreeing overlaps accepted,
//! disagreeing overlaps refused naming both files and the first disagreeing index), no torn or
//! corrupt line, no incomplete file. A missing range is refused naming the index ranges and their
//! cases unless `--allow-partial`, which marks every figure with the coverage. Failed samples are
//! refused (count, indices, first reasons) unless `--allow-failed`, which says in every affected
//! figure that they were excluded.
//!
//! ## 2. Statistics, per case
//!
//! - **Percentiles** of θ_P (default 50, 90, 95, 99): the inverse empirical CDF, Hyndman & Fan
//!   definition 1, the smallest x with F_n(x) ≥ p ([`quantile`]). The same definition with integer
//!   weights gives the bootstrap replicates.
//! - **Bootstrap intervals** ([`bootstrap`]): Poisson bootstrap, B = 2000 by default, weights
//!   w ~ Poisson(1) drawn from a counter-based SplitMix64 generator keyed by (seed, replicate,
//!   global sample index) ([`rng`]), so every number is identical however the job was split and
//!   whatever the order of the files, and whatever the thread count. Percentile and BCa intervals;
//!   BCa with z₀ from the replicates (ties counted half) and the acceleration from the empirical
//!   influence function of the quantile, Uᵢ = p − 1{xᵢ ≤ q}, a = ΣU³/(6(ΣU²)^{3/2}) (Efron 1987).
//! - **Order-statistic interval**: distribution-free, exact from Binomial(n, p) (statrs), as a
//!   cross-check.
//! - **Rayleigh law** (paper §3.2, [`rayleigh`]): mean and standard deviation of tan θ_x and
//!   tan θ_y; σ_t pooled = √(Σ(tan²θ_x + tan²θ_y)/2n), the zero-mean ML estimate, and each
//!   component alone; the ML Rayleigh fit σ̂² = Σθ²/2n with its exact χ²(2n) interval; the
//!   Rayleigh percentiles θ_P^α = √(−2σ̂² ln(1−α)) (eq. 28) with intervals from σ's.
//! - **Goodness of fit** ([`gof`]): KS and AD of θ² against the exponential with the mean
//!   estimated (Stephens' modified statistics), p-values from a Monte Carlo null calibration
//!   (pivotal: the null does not depend on the scale); the effect size an engineer can judge:
//!   the relative difference of the Rayleigh and empirical target percentiles (with a bootstrap
//!   interval) and the max CDF gap; a verdict in words.
//! - **Loose joints**: fraction of samples with ≥ 1 loose backlash joint (Clopper–Pearson).
//! - **Decenter and despace** ([`placement`]), where the samples record them (mm): their
//!   percentiles (of decenter and |despace|) with the same three intervals; decenter's
//!   Rayleigh law (fit from Σ decenter²/2n, χ²(2n) interval, KS and AD of decenter² against
//!   the exponential), despace's normal law (folded-normal percentiles of |despace|, KS and
//!   AD with mean and spread estimated).
//! - **The budget** ([`budget`]), where the job states one: per case which lines pass and
//!   the allowable σ meeting every line, `σ·min over lines of limit/q`, with the line that
//!   binds; per σ-series the same from the lines through the origin. First in the table
//!   and in `report.md`.
//!
//! ## 3. Sweeps ([`sweep`])
//!
//! Cases whose parameters agree except `sigma` form a σ-series (≥ 2 distinct σ): the target
//! percentile against σ, least-squares lines through the origin and with intercept with R², and
//! the allowable σ for the target angle (default 9.69e-5 rad, the paper's 20 arcsec rounded: 19.99″, at the 95th percentile)
//! with a bootstrap interval from refitting every replicate series. Likewise `stages`: the
//! percentiles normalised to the smallest stage count (paper Fig. 9) with intervals, and the
//! stage count where it peaks.
//!
//! ## 4. Output
//!
//! With `--out REPORT_DIR`: `report.json` (schema in [`report`], summary below, and the
//! standalone JSON Schema `docs/report.schema.json`), SVG and PNG plots ([`plot`]), and
//! for people `report.md` and a self-contained `report.html` ([`readable`]: the same
//! results with their units, the plots linked or embedded), each written atomically and never through a link into a directory that holds no other
//! job's report and that no other merge is writing; a rerun removes only the files it listed
//! in its manifest ([`report_dir`]).
//! Unless `--quiet`: on stderr, where the merge is (the shards verified, each case's
//! statistics, the plots, the readable reports, with the seconds since it started), and a
//! table on stdout (angles in rad and arcsec) that ends with the answer ([`answer`]). With
//! `--export FILE`: every sample as a flat row ([`export`]; for pandas, `read_json(…,
//! lines=True, precise_float=True)`).
//!
//! ### report.json
//!
//! ```text
//! format "truss-mc-merge-report", format_version 1, program, program_version
//! job_id, job_samples
//! coverage   {complete, present, expected, missing: [{start, end, case}], missing_ranges}
//! failed     {total, excluded}
//! settings   {percentiles, confidence, replicates, bootstrap_seed, gof_replicates, gof_level,
//!             target_angle, target_percentile, allow_partial, allow_failed}
//! definitions {units, percentile, bootstrap {kind, description, replicates, seed, rng,
//!             confidence, percentile_interval, bca_interval}, order_statistic, rayleigh, gof,
//!             sweep, loose_joints}                                  (every definition in words)
//! cases[]    {name, parameters, expected, present, n, failed {count, ranges, reasons},
//!             caveats[], loose_joints {recorded, with_loose, fraction},
//!             bootstrap {replicates, empty_replicates},
//!             percentiles[] {percentile, value, percentile_bootstrap {lower, upper},
//!                            bca {lower, upper, z0, acceleration},
//!                            order_statistic {lower, upper, lower_rank, upper_rank, coverage},
//!                            caveats[]},
//!             rayleigh {tan_theta_x {mean, std, rms}, tan_theta_y {…}, sigma_t, sigma,
//!                       percentiles[] {percentile, value, empirical, relative_difference},
//!                       caveats[]},
//!             gof {verdict, summary, level, ks {statistic, modified, p_value, p_value_se},
//!                  ad {…}, null_calibration {sample_size, replicates},
//!                  effect {percentile, rayleigh, empirical, relative_difference, max_cdf_gap},
//!                  caveats[]}}
//! sweep      {percentile,
//!             sigma_series[] {name, fixed, points[] {case, x, value}, through_origin
//!                             {slope, intercept, r_squared}, with_intercept {…},
//!                             allowable_sigma {target_angle, target_arcsec, percentile,
//!                             through_origin, with_intercept, extrapolated},
//!                             replicates_used, caveats[]},
//!             stages_series[] {name, fixed, reference_stages, points[] {case, stages, value,
//!                             normalised, relative_interval}, peak_stages, caveats[]}}
//! answer     {target_angle, percentile, cases[] {case, value, against},
//!             allowable_sigma[] {series, sigma, extrapolated},
//!             rayleigh {tested, level, expected_by_chance,
//!                       cases[] {case, verdict, p_value, holm_p_value, relative_difference},
//!                       holm_rejected}}                  (drawn from the above, [`answer`])
//! ```
//!
//! A *figure* (`value`, `lower`, `upper`, optional `reason`) carries its interval; whatever
//! cannot be computed (0 or 1 sample, all values equal, too few samples for an interval) is
//! `null` with a `reason`. Every number is a finite JSON number: [`report::Real`] refuses to
//! serialise NaN or ∞. Angles in rad, σ in mm. The report holds nothing that depends on the
//! split or the file order, so it is byte-identical for any split.
//!
//! ## 5. Exit codes ([`MergeError::exit_code`])
//!
//! The scheme every truss-mc binary shares (`truss-exit`):
//!
//! | code | meaning |
//! | --- | --- |
//! | 0 | verified and reported |
//! | 1 | internal error (a bug) |
//! | 2 | usage error (also: an `--export` path among the shards) |
//! | 3 | a file named on the command line is not a regular file (a FIFO, a device) |
//! | 4 | I/O error |
//! | 5 | a file in the way: the report directory holds another job's `report.json`, another merge is writing it, or a link or a non-file stands at a name to be written |
//! | 6 | verification failure: torn, corrupt or incomplete shard, other job id, wrong digest, missing range, disagreeing overlap |
//! | 7 | failed samples present without `--allow-failed` |
//!
//! ## 6. Cost
//!
//! Per sample 26 bytes are kept after verification (38 during), plus, for the case being
//! analysed, a sorted copy (θ, global index: 16 bytes, 32 while sorting) and 8 bytes of
//! precomputed generator offsets. The bootstrap generates the weights of a replicate in sorted
//! order into a byte buffer per thread and walks the cumulative weight once (skipping 64-weight
//! blocks by their sum). Files are parsed by parallel reader threads. Measured on the 2-core
//! development machine (`scripts/bench-merge.sh`, medians): 50,000 samples with B = 2000 in
//! about 0.5 s and 8 MB peak RSS; 10 million samples in one case in about 2 minutes and
//! 560 MiB peak RSS (58 bytes per sample).

pub mod analysis;
pub mod answer;
pub mod budget;
pub mod cli;
pub mod definitions;
pub mod errors;
pub mod export;
pub mod gof;
pub mod load;
pub mod placement;
pub mod plot;
pub mod rayleigh;
pub mod readable;
pub mod report;
pub mod report_dir;
pub mod settings;
pub mod sweep;
pub mod table;

/// The statistics live in `truss-stats`, shared with the diagnosis.
pub use truss_stats::{bootstrap, quantile, rng};

pub use cli::Args;
pub use errors::MergeError;
pub use load::{Dataset, LoadOptions};
pub use report::Report;
pub use settings::{Options, Settings};

use analysis::{CaseAnalysis, analyse_case};
use gof::CalibrationCache;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

/// The result of a merge.
#[derive(Debug)]
pub struct Merge {
    /// The verified samples.
    pub dataset: Dataset,
    /// The report.
    pub report: Report,
}

/// Where a merge is, for a progress display: the shards verified, then each case's
/// statistics as they start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress<'a> {
    /// The shards verified: `files` files holding `samples` samples.
    Verified {
        /// Shard files read.
        files: usize,
        /// Samples present.
        samples: u64,
    },
    /// Case `index` (0-based) of `cases`, named `name`: its percentiles, bootstrap and
    /// Rayleigh test start.
    Case {
        /// The case's position.
        index: usize,
        /// How many cases the job has.
        cases: usize,
        /// Its name.
        name: &'a str,
    },
}

/// Verifies the shards at `paths` and computes the report, writing nothing. The settings are
/// checked first ([`Settings::validate`]).
pub fn merge(paths: &[PathBuf], settings: &Settings) -> Result<Merge, MergeError> {
    merge_with(paths, settings, &mut |_| {})
}

/// [`merge`], telling `progress` where it is.
pub fn merge_with(
    paths: &[PathBuf],
    settings: &Settings,
    progress: &mut dyn FnMut(Progress<'_>),
) -> Result<Merge, MergeError> {
    let settings = &settings.validate()?;
    let files = load::shard_files(paths)?;
    let dataset = load::load(
        &files,
        LoadOptions {
            allow_partial: settings.allow_partial,
            allow_failed: settings.allow_failed,
            threads: settings.threads,
        },
    )?;
    progress(Progress::Verified {
        files: dataset.files.len(),
        samples: dataset.present(),
    });
    let report = build_report_with(&dataset, settings, progress)?;
    Ok(Merge { dataset, report })
}

/// Computes the report of a verified dataset; the settings are checked first
/// ([`Settings::validate`]).
pub fn build_report(dataset: &Dataset, settings: &Settings) -> Result<Report, MergeError> {
    build_report_with(dataset, settings, &mut |_| {})
}

/// [`build_report`], telling `progress` as each case starts.
pub fn build_report_with(
    dataset: &Dataset,
    settings: &Settings,
    progress: &mut dyn FnMut(Progress<'_>),
) -> Result<Report, MergeError> {
    let mut settings = settings.validate()?;
    // A budget's percentile is computed with the others (see [`budget`]).
    if let Some(b) = &dataset.budget
        && !settings.percentiles.contains(&b.percentile)
    {
        settings.percentiles.push(b.percentile);
        settings.percentiles.sort_by(f64::total_cmp);
    }
    let settings = &settings;
    let mut cache = CalibrationCache::default();
    let cases = dataset.cases.len();
    let analyses: Vec<CaseAnalysis> = dataset
        .cases
        .iter()
        .enumerate()
        .map(|(index, c)| {
            progress(Progress::Case {
                index,
                cases,
                name: &c.info.name,
            });
            let mut a = analyse_case(c, settings, &mut cache);
            let (decenter, despace) =
                placement::analyse(c, settings, &mut cache, &a.report.caveats);
            a.report.decenter = decenter.as_ref().map(|q| q.report.clone());
            a.report.despace = despace.as_ref().map(|q| q.report.clone());
            a.decenter = decenter.map(|q| q.levels);
            a.despace = despace.map(|q| q.levels);
            a
        })
        .collect();
    let params: Vec<&BTreeMap<String, f64>> =
        dataset.cases.iter().map(|c| &c.info.parameters).collect();
    let sweep = sweep::sweep(&params, &analyses, settings);
    let budget = dataset
        .budget
        .as_ref()
        .map(|b| budget::budget_report(b, &params, &analyses, settings));
    let targets: Vec<report::Figure> = analyses.iter().map(|a| a.target.clone()).collect();
    let cases: Vec<report::CaseReport> = analyses.into_iter().map(|a| a.report).collect();
    let answer = answer::answer(&cases, &targets, &sweep, settings);
    let missing = dataset.missing();
    Ok(Report {
        format: report::REPORT_FORMAT,
        format_version: report::REPORT_VERSION,
        program: "mc-merge",
        program_version: env!("CARGO_PKG_VERSION"),
        job_id: dataset.job_id.clone(),
        job_samples: dataset.job_samples,
        coverage: report::Coverage {
            complete: missing.is_empty(),
            present: dataset.present(),
            expected: dataset.job_samples,
            missing_ranges: missing.len(),
            missing: missing.into_iter().take(100).collect(),
        },
        failed: report::FailedSummary {
            total: dataset.cases.iter().map(|c| c.failed).sum(),
            excluded: dataset.cases.iter().any(|c| c.failed > 0),
        },
        settings: settings.clone(),
        definitions: definitions::definitions(settings),
        cases,
        sweep,
        answer,
        budget,
    })
}

/// The report as pretty JSON with a final newline. Fails (a bug) if a number is not finite.
pub fn report_json(report: &Report) -> Result<String, MergeError> {
    let mut s = serde_json::to_string_pretty(report).map_err(|e| MergeError::Internal {
        message: format!("cannot serialise the report: {e}"),
    })?;
    s.push('\n');
    Ok(s)
}

/// Does what the command line asks, writing to `out`: a helper command, an export, or a
/// merge (the table and the files written, nothing with `--quiet`).
pub fn execute(args: Args, out: &mut dyn Write) -> Result<(), MergeError> {
    if let Some(helper) = &args.command {
        return helper.print(out);
    }
    let export = args.export.clone();
    let quiet = args.quiet;
    let options = args.validate()?;
    let mut sink = std::io::sink();
    let out: &mut dyn Write = if quiet { &mut sink } else { out };
    if let Some(to) = &export {
        export::run(&options, to, out)?;
        if options.out.is_none() {
            return Ok(());
        }
    }
    run(&options, out).map(|_| ())
}

/// Runs a merge as the command line asks: verify, compute, print the table to `out`, and with
/// a report directory write `report.json`, the plots, `report.md` and `report.html`
/// ([`readable`]) ([`report_dir`]: the directory is
/// locked, another job's report directory is refused, every file written atomically and
/// never through a link, only our own earlier files removed).
pub fn run(options: &Options, out: &mut dyn Write) -> Result<Report, MergeError> {
    // Progress on stderr: a large job's statistics and plots take some seconds each.
    let started = std::time::Instant::now();
    let say = |what: String| {
        if options.progress {
            eprintln!(
                "mc-merge: {what} ({:.1} s)",
                started.elapsed().as_secs_f64()
            );
        }
    };
    let merge = merge_with(&options.paths, &options.settings, &mut |p| match p {
        Progress::Verified { files, samples } => {
            say(format!("{samples} samples in {files} shard files verified"))
        }
        Progress::Case { index, cases, name } => say(format!(
            "case {} of {cases} ({name}): percentiles, bootstrap, Rayleigh test",
            index + 1
        )),
    })?;
    let json = report_json(&merge.report)?;
    let mut text = table::render(&merge.report, merge.dataset.files.len());
    if let Some(dir) = &options.out {
        let mut names = vec![report_dir::REPORT_FILE.to_string()];
        if options.plots {
            names.extend(plot::file_names(&merge.report));
        }
        names.extend([readable::MARKDOWN_FILE, readable::HTML_FILE].map(String::from));
        let mut files = report_dir::open(dir, &merge.report.job_id, &names)?;
        files.write(report_dir::REPORT_FILE, json.as_bytes())?;
        text.push('\n');
        let plots = if options.plots {
            say(format!("drawing the plots into {}", dir.display()));
            plot::draw_all(&mut files, &merge.dataset.cases, &merge.report)?
        } else {
            vec![]
        };
        say("writing report.md and report.html".to_string());
        let readable = readable::write(&mut files, &merge.report, &merge.dataset.writers, &plots)?;
        files.finish()?;
        // One line for the files (a report has dozens of plots), then the answer, then where
        // to read the rest: the last lines on the screen are what the user came for.
        text.push_str(&format!(
            "wrote {} files to {}: {}, {} plots, {}, {}\n",
            1 + plots.len() + readable.len(),
            dir.display(),
            report_dir::REPORT_FILE,
            plots.len(),
            readable::MARKDOWN_FILE,
            readable::HTML_FILE
        ));
    }
    text.push_str(&table::answer(&merge.report));
    if let Some(dir) = &options.out {
        text.push_str(&format!(
            "\nreport: {}\n",
            dir.join(readable::HTML_FILE).display()
        ));
    }
    out.write_all(text.as_bytes())
        .map_err(|source| MergeError::Io {
            path: PathBuf::from("<stdout>"),
            source,
        })?;
    Ok(merge.report)
}
