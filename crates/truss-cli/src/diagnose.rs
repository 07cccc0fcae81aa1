//! `truss diagnose` and `truss synth-measured`: argument parsing over the `truss_diagnose`
//! library, which does the work.

use crate::CliError;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// Options of `truss diagnose`.
#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// The baseline job file.
    #[arg(long)]
    pub job: PathBuf,
    /// The case of the job the measurements are compared with.
    #[arg(long)]
    pub case: String,
    /// Measured node positions: CSV `specimen,node,x,y,z` (mm).
    #[arg(long)]
    pub measured: PathBuf,
    /// Measured member length errors: CSV `specimen,member,length_error` (mm).
    #[arg(long)]
    pub measured_members: Option<PathBuf>,
    /// The instrument's standard deviation per coordinate (mm).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub measurement_sigma: f64,
    /// Simulated samples per evaluation, 100 to 10 000 (default max(2000, 20 × specimens),
    /// at most 10 000).
    #[arg(long)]
    pub samples: Option<usize>,
    /// Output directory (diagnosis.json, diagnosis.md, updated-job.json, plots).
    #[arg(long)]
    pub out: PathBuf,
    /// Only these candidate effects, comma separated (default: every one that applies).
    #[arg(long, value_delimiter = ',')]
    pub candidates: Option<Vec<String>>,
    /// Worker threads (default: all cores; results do not depend on it).
    #[arg(long)]
    pub threads: Option<usize>,
    /// No SVG plots.
    #[arg(long)]
    pub no_plots: bool,
    /// No progress on stderr.
    #[arg(long)]
    pub quiet: bool,
}

/// Options of `truss synth-measured`.
#[derive(Debug, Args)]
pub struct SynthArgs {
    /// The baseline job file.
    #[arg(long)]
    pub job: PathBuf,
    /// The case to make specimens of.
    #[arg(long)]
    pub case: String,
    /// Number of specimens.
    #[arg(long)]
    pub specimens: usize,
    /// Seed of the specimens (independent of the job's seed).
    #[arg(long)]
    pub seed: u64,
    /// The hidden effect: `none`, or `NAME:PARAM=VALUE,…` (unnamed parameters at their
    /// baseline values), e.g. `thermal_gradient:gradient_x=0.002`; several separated by
    /// `;`.
    #[arg(long)]
    pub effect: String,
    /// The instrument's standard deviation per coordinate (mm).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub measurement_sigma: f64,
    /// Write every node, not only the top surface.
    #[arg(long)]
    pub all_nodes: bool,
    /// Also write measured member length errors to this CSV.
    #[arg(long)]
    pub members_out: Option<PathBuf>,
}

/// Runs `truss diagnose`; prints the verdict and the files written.
pub fn run_diagnose(args: &DiagnoseArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let options = truss_diagnose::DiagnoseOptions {
        job: args.job.clone(),
        case: args.case.clone(),
        measured: args.measured.clone(),
        measured_members: args.measured_members.clone(),
        out: args.out.clone(),
        settings: truss_diagnose::settings::Settings {
            samples: args.samples,
            measurement_sigma: args.measurement_sigma,
            quiet: args.quiet,
            candidates: args.candidates.clone(),
            threads: args.threads,
            ..Default::default()
        },
        plots: !args.no_plots,
    };
    let s = truss_diagnose::run(&options)?;
    writeln!(
        out,
        "named_effect: {}\nnamed_effects: {}\nverdict: {} ({})\nreason: {}\ndiscrepancy: {:.4} before, {:.4} after",
        s.named_effect,
        if s.named_effects.is_empty() {
            "none".to_string()
        } else {
            s.named_effects.join(", ")
        },
        s.verdict.as_str(),
        s.verdict.words(),
        s.reason,
        s.discrepancy.0,
        s.discrepancy.1
    )?;
    for line in &s.answer {
        writeln!(out, "{line}")?;
    }
    for f in &s.files {
        writeln!(out, "wrote {}", f.display())?;
    }
    Ok(())
}

/// Runs `truss synth-measured`, the CSV to `out`.
pub fn run_synth(args: &SynthArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let options = truss_diagnose::synth::SynthOptions {
        job: args.job.clone(),
        case: args.case.clone(),
        specimens: args.specimens,
        seed: args.seed,
        effect: args.effect.clone(),
        measurement_sigma: args.measurement_sigma,
        all_nodes: args.all_nodes,
        members_out: args.members_out.clone(),
    };
    if args.specimens == 0 {
        return Err(CliError::Usage("--specimens must be at least 1".into()));
    }
    let mut buf = std::io::BufWriter::new(out);
    truss_diagnose::synth::synth(&options, &mut buf)?;
    buf.flush()?;
    Ok(())
}
