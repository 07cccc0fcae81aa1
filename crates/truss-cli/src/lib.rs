//! The `truss` command: generate the paper's prism, solve a model file, compare simulation
//! with measurements, and allocate member-length tolerances.
//!
//! ## Commands
//!
//! - `truss model prism --stages N [options]` writes the model file of the paper's N-stage
//!   truss to stdout (Table 1 defaults, every one overridable).
//! - `truss solve MODEL.json [--length-error ID=MM]...` solves the model's equilibrium and
//!   prints a JSON result (see [`solve::SolveOutput`]).
//! - `truss diagnose --job J --case NAME --measured M.csv --out DIR` compares measurements
//!   with the case's simulation, names the missing effect, writes the updated job and shows
//!   the gap shrink (the `truss_diagnose` crate; [`diagnose`]).
//! - `truss synth-measured --job J --case NAME --specimens N --seed S --effect NAME:P=V,…`
//!   writes measured data with a hidden effect to stdout ([`truss_diagnose::synth`]).
//! - `truss tolerance --job J --case NAME --target-arcsec A --out DIR` allocates per-group
//!   length tolerances for a θ_P budget and verifies them (the `truss_tolerance` crate;
//!   [`tolerance`]).
//! - `truss completions bash|zsh|fish|elvish|powershell` writes a shell completion script
//!   to stdout (`truss completions bash > ~/.local/share/bash-completion/completions/truss`),
//!   and `truss man` the roff manual page (`truss man > truss.1; man ./truss.1`).
//!
//! ## Limits
//!
//! `truss model prism` takes at most [`MAX_STAGES`](truss_core::prism::MAX_STAGES) stages
//! and plausible values only ([`PrismOptions::check`]), refusing others as usage errors
//! that name the flag. `truss solve` reads only a regular file of at most
//! [`MAX_INPUT_BYTES`](truss_core::model_file::MAX_INPUT_BYTES), in UTF-8, and refuses a
//! `--length-error` beyond [`MAX_LENGTH_ERROR_FRACTION`](truss_core::MAX_LENGTH_ERROR_FRACTION)
//! of its member's natural length, or given twice for one member.
//!
//! ## Exit codes
//!
//! The scheme every truss-mc binary shares (`truss-exit`), mapped from the errors in one
//! place ([`exit_code`]):
//!
//! | code | meaning |
//! |---|---|
//! | 0 | success |
//! | 1 | internal error (a bug) |
//! | 2 | usage error (bad arguments) |
//! | 3 | the model file, job or measured data is invalid (the message names the item or line), or a file named is not a regular file |
//! | 4 | a file could not be read or written |
//! | 5 | a file in the way: a symbolic link or a non-file at an output's name, or an output directory another process is writing |
//! | 6 | a tolerance allocation did not verify (its files are written) |
//! | 7 | the solve failed (not converged, mechanism; the JSON result says why), or a diagnosis's simulation failed |

pub mod diagnose;
pub mod errors;
pub mod solve;
pub mod tolerance;

pub use errors::{CliError, exit_code};

use clap::{Args, Parser, Subcommand};
use std::io::Write;
use truss_core::prism::{BacklashOptions, PrismOptions, TABLE1_DIAGONAL_LENGTH};

/// Generate, solve and diagnose truss models. Units: mm, N, MPa, rad.
#[derive(Debug, Parser)]
#[command(
    name = "truss",
    version,
    about,
    after_help = truss_exit::SUMMARY
)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Write a model file to stdout.
    Model {
        /// Which model.
        #[command(subcommand)]
        kind: ModelKind,
    },
    /// Solve a model file's equilibrium and print the result as JSON.
    Solve(solve::SolveArgs),
    /// Compare measured trusses with a job case's simulation: where they disagree, which
    /// effect is missing (fitted), the updated job, and the gap before and after.
    Diagnose(diagnose::DiagnoseArgs),
    /// Write measured data (CSV, stdout) made from a case with a hidden effect.
    SynthMeasured(diagnose::SynthArgs),
    /// Which members matter, and the cheapest per-group length tolerances that keep θ_P at
    /// a percentile within a budget; verified by Monte Carlo.
    Tolerance(tolerance::ToleranceArgs),
    /// Write a shell completion script to stdout.
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Write the manual page (roff) to stdout.
    Man,
}

/// Model generators.
#[derive(Debug, Subcommand)]
pub enum ModelKind {
    /// The paper's N-stage triangular prism (section 2.1, Table 1).
    Prism(PrismArgs),
}

/// Table 1's values, the one place they are written ([`PrismOptions::default`]).
fn table1() -> PrismOptions {
    PrismOptions::default()
}

/// Options of `truss model prism`; defaults are the paper's Table 1.
#[derive(Debug, Args)]
pub struct PrismArgs {
    /// Number of stages N, from 1 to 1000.
    #[arg(long, default_value_t = table1().stages)]
    pub stages: usize,
    /// Batten length l, the triangle's side (mm).
    #[arg(long, default_value_t = table1().side, allow_negative_numbers = true)]
    pub side: f64,
    /// Stage height h, the longeron length (mm).
    #[arg(long, default_value_t = table1().height, allow_negative_numbers = true)]
    pub height: f64,
    /// Batten cross-section (mm²).
    #[arg(long, default_value_t = table1().batten_area, allow_negative_numbers = true)]
    pub batten_area: f64,
    /// Batten Young's modulus (MPa).
    #[arg(long, default_value_t = table1().batten_modulus, allow_negative_numbers = true)]
    pub batten_modulus: f64,
    /// Longeron cross-section (mm²).
    #[arg(long, default_value_t = table1().longeron_area, allow_negative_numbers = true)]
    pub longeron_area: f64,
    /// Longeron Young's modulus (MPa).
    #[arg(long, default_value_t = table1().longeron_modulus, allow_negative_numbers = true)]
    pub longeron_modulus: f64,
    /// Diagonal cable cross-section (mm²).
    #[arg(long, default_value_t = table1().diagonal_area, allow_negative_numbers = true)]
    pub diagonal_area: f64,
    /// Diagonal cable Young's modulus (MPa).
    #[arg(long, default_value_t = table1().diagonal_modulus, allow_negative_numbers = true)]
    pub diagonal_modulus: f64,
    /// Diagonal natural length (mm; Table 1: 537.4).
    #[arg(long, default_value_t = TABLE1_DIAGONAL_LENGTH, conflicts_with = "exact_diagonals", allow_negative_numbers = true)]
    pub diagonal_length: f64,
    /// Give the diagonals the exact face-diagonal length √(l² + h²) instead.
    #[arg(long)]
    pub exact_diagonals: bool,
    /// Cables' compression stiffness / tension stiffness: 0, the paper's, carries nothing
    /// when slack (solved as the limit r → 0).
    #[arg(long, default_value_t = truss_core::DEFAULT_COMPRESSION_RATIO, allow_negative_numbers = true)]
    pub compression_ratio: f64,
    /// Model the batten–longeron pin joints with backlash (paper section 4): each longeron
    /// end gets its own hole on the batten's shaft, with free play.
    #[arg(long)]
    pub backlash: bool,
    /// Clearance of every joint (mm; with `--backlash`).
    #[arg(long, default_value_t = truss_core::prism::PAPER_CLEARANCE, requires = "backlash", allow_negative_numbers = true)]
    pub clearance: f64,
    /// Joint contact stiffness over a longeron's axial stiffness E·A/h (with `--backlash`).
    #[arg(long, default_value_t = truss_core::joint::DEFAULT_JOINT_TENSION_FACTOR, requires = "backlash", allow_negative_numbers = true)]
    pub joint_tension_factor: f64,
    /// Loose joint's regularising stiffness over its contact stiffness, in [0, 1e-5]; 0 for
    /// none, the physical limit (with `--backlash`).
    #[arg(long, default_value_t = truss_core::joint::DEFAULT_JOINT_COMPRESSION_RATIO, requires = "backlash", allow_negative_numbers = true)]
    pub joint_compression_ratio: f64,
}

impl PrismArgs {
    /// The flag that sets a field of [`PrismOptions`] (as [`PrismOptions::check`] names it).
    pub fn flag(field: &str) -> String {
        match field {
            "backlash.clearance" => "--clearance".into(),
            "backlash.tension_factor" => "--joint-tension-factor".into(),
            "backlash.compression_ratio" => "--joint-compression-ratio".into(),
            f => format!("--{}", f.replace('_', "-")),
        }
    }

    /// The generator options.
    pub fn options(&self) -> PrismOptions {
        PrismOptions {
            stages: self.stages,
            side: self.side,
            height: self.height,
            batten_area: self.batten_area,
            batten_modulus: self.batten_modulus,
            longeron_area: self.longeron_area,
            longeron_modulus: self.longeron_modulus,
            diagonal_area: self.diagonal_area,
            diagonal_modulus: self.diagonal_modulus,
            diagonal_length: (!self.exact_diagonals).then_some(self.diagonal_length),
            compression_ratio: self.compression_ratio,
            backlash: self.backlash.then_some(BacklashOptions {
                clearance: self.clearance,
                tension_factor: self.joint_tension_factor,
                compression_ratio: self.joint_compression_ratio,
            }),
        }
    }
}

/// Runs a command, writing its output to `out`.
pub fn run(cli: Cli, out: &mut dyn Write) -> anyhow::Result<()> {
    match cli.command {
        Command::Model {
            kind: ModelKind::Prism(args),
        } => {
            let options = args.options();
            options.check().map_err(|(field, message)| {
                CliError::Usage(format!("{}: {message}", PrismArgs::flag(field)))
            })?;
            let model = options.model().map_err(CliError::from)?;
            out.write_all(model.to_file().to_json().as_bytes())
                .map_err(CliError::from)?;
        }
        Command::Solve(args) => solve::run(&args, out)?,
        Command::Diagnose(args) => diagnose::run_diagnose(&args, out)?,
        Command::SynthMeasured(args) => diagnose::run_synth(&args, out)?,
        Command::Tolerance(args) => tolerance::run(&args, out)?,
        Command::Completions { shell } => {
            // Into memory first: clap_complete panics on a failed write (a closed pipe).
            let mut script = Vec::new();
            let mut command = <Cli as clap::CommandFactory>::command();
            clap_complete::generate(shell, &mut command, "truss", &mut script);
            out.write_all(&script).map_err(CliError::from)?;
        }
        Command::Man => {
            let mut page = Vec::new();
            truss_man::pages(<Cli as clap::CommandFactory>::command(), &mut page)
                .map_err(CliError::from)?;
            out.write_all(&page).map_err(CliError::from)?;
        }
    }
    Ok(())
}
