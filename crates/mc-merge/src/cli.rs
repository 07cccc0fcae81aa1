//! The command line: raw flags ([`Args`], parsed by clap) validated into the library's
//! [`Options`] and [`Settings`], and the two helper commands `completions SHELL` and `man`.
//! What a command does is [`crate::execute`]'s.
//!
//! `mc-merge` takes its shard directories positionally, so the helper commands are clap
//! subcommands that conflict with every merge flag (`args_conflicts_with_subcommands`): a
//! merge is `mc-merge DIRS… [FLAGS]`, and `mc-merge completions bash` or `mc-merge man` print
//! to stdout and do nothing else. A shard directory literally named `man` or `completions` is
//! given as `./man`.
//!
//! Every numeric flag has a documented range ([`MAX_REPLICATES`], [`MAX_GOF_REPLICATES`],
//! [`MAX_PERCENTILES`], [`MAX_THREADS`], [`MAX_TARGET_ANGLE`]); a value outside it is refused
//! before anything is read, naming the flag, instead of exhausting memory.

use crate::errors::MergeError;
use crate::settings::{DEFAULT_SEED, DEFAULT_TARGET_ANGLE, Options, Settings};
#[cfg(doc)]
use crate::settings::{MAX_GOF_REPLICATES, MAX_PERCENTILES, MAX_REPLICATES, MAX_TARGET_ANGLE};
use clap::{CommandFactory, Parser, Subcommand};
use std::io::Write;
use std::path::PathBuf;

/// The most worker threads `--threads` accepts (every command's bound).
pub use truss_threads::MAX_THREADS;

const AFTER_HELP: &str = "\
Exit codes (the scheme every truss-mc binary shares):
  0  the shards verified and the report was written
  1  internal error (a bug)
  2  usage error (bad flag or value; an --export path among the shards)
  3  a file named on the command line is not a regular file (a FIFO, a device)
  4  I/O error reading shards or writing the report
  5  a file in the way: the report directory holds another job's report.json, another
     merge is writing it, or a symbolic link or a non-file stands at a name to be written
  6  verification failure: a torn, corrupt or incomplete shard, another job id, a wrong digest,
     a missing index range, or overlapping shards that disagree
  7  failed samples present (give --allow-failed to compute on the converged ones)

Every number is reproducible: the bootstrap weights are a function of (seed, replicate, global
sample index), so the report is byte-identical however the job was split and in whatever order
the shard files are given.";

/// Merges Monte Carlo shard files of one job into percentiles of the distortion angle θ_P with
/// bootstrap confidence intervals, the paper's Rayleigh law with goodness of fit, sweeps over
/// σ and the number of stages with the allowable σ, and SVG and PNG plots.
#[derive(Debug, Clone, Parser)]
#[command(
    name = "mc-merge",
    version,
    about,
    after_help = AFTER_HELP,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
pub struct Args {
    /// A helper command instead of a merge.
    #[command(subcommand)]
    pub command: Option<Helper>,

    /// Shard files, or directories whose *.jsonl files are read.
    #[arg(required = true, value_name = "DIR_OR_FILES")]
    pub paths: Vec<PathBuf>,

    /// Directory for report.json and the plots (created if needed). A directory holding
    /// another job's report is refused; our own earlier files in it are replaced. Without it
    /// only the table is printed.
    #[arg(short = 'o', long, value_name = "REPORT_DIR")]
    pub out: Option<PathBuf>,

    /// Print nothing on success (errors still go to stderr).
    #[arg(short = 'q', long)]
    pub quiet: bool,

    /// Percentiles of θ_P to estimate, in percent, comma separated, each strictly between 0 and 100.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "50,90,95,99",
        allow_negative_numbers = true
    )]
    pub percentiles: Vec<f64>,

    /// Confidence level of every interval, a fraction in (0, 1).
    #[arg(long, default_value_t = 0.95, allow_negative_numbers = true)]
    pub confidence: f64,

    /// Bootstrap replicates B, 10 to 100000.
    #[arg(long, default_value_t = 2000)]
    pub replicates: u32,

    /// Seed of the counter-based bootstrap generator.
    #[arg(long, default_value_t = DEFAULT_SEED)]
    pub bootstrap_seed: u64,

    /// Simulated null samples for the goodness-of-fit p-values, 19 to 100000.
    #[arg(long, default_value_t = 1000)]
    pub gof_replicates: u32,

    /// Significance level of the Rayleigh goodness-of-fit verdict.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub gof_level: f64,

    /// Target distortion angle in rad for the allowable σ (9.69e-5 rad: the paper's 20 arcsec, rounded; 19.99 arcsec).
    #[arg(long, default_value_t = DEFAULT_TARGET_ANGLE, allow_negative_numbers = true)]
    pub target_angle: f64,

    /// The percentile of θ_P that must meet the target angle (added to --percentiles if absent).
    #[arg(long, default_value_t = 95.0, allow_negative_numbers = true)]
    pub target_percentile: f64,

    /// Worker threads, 1 to 1024 (results do not depend on it; default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,

    /// Compute on the samples present when index ranges are missing; every figure is marked partial.
    #[arg(long)]
    pub allow_partial: bool,

    /// Compute on the converged samples when some failed; every affected figure says so.
    #[arg(long)]
    pub allow_failed: bool,

    /// Do not draw the plots.
    #[arg(long)]
    pub no_plots: bool,

    /// Verify, then write every sample as a row of FILE (.csv with a header row, or .jsonl),
    /// numbers as the shards hold them. Without --out no statistics are computed.
    #[arg(long, value_name = "FILE")]
    pub export: Option<PathBuf>,
}

/// The helper commands: they print to stdout and merge nothing.
#[derive(Debug, Clone, Subcommand)]
pub enum Helper {
    /// Print a shell completion script (bash, zsh, fish, elvish or powershell) to stdout.
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the man page (roff) to stdout.
    Man,
}

impl Helper {
    /// Writes the completion script or the man page to `out`.
    pub fn print(&self, out: &mut dyn Write) -> Result<(), MergeError> {
        let mut command = Args::command();
        let stdout = |source| MergeError::Io {
            path: PathBuf::from("<stdout>"),
            source,
        };
        match self {
            Helper::Completions { shell } => {
                // Through memory: clap_complete panics when its writer fails.
                let mut script = Vec::new();
                clap_complete::generate(*shell, &mut command, "mc-merge", &mut script);
                out.write_all(&script).map_err(stdout)
            }
            Helper::Man => truss_man::pages(command, out).map_err(stdout),
        }
    }
}

impl Args {
    /// Checks every value and builds the options.
    pub fn validate(self) -> Result<Options, MergeError> {
        if let Some(t) = self.threads
            && !truss_threads::accepted(t)
        {
            return Err(MergeError::Usage {
                message: format!("--threads {t}: must be between 1 and {MAX_THREADS}"),
            });
        }
        let settings = Settings {
            percentiles: self.percentiles.clone(),
            confidence: self.confidence,
            replicates: self.replicates,
            bootstrap_seed: self.bootstrap_seed,
            gof_replicates: self.gof_replicates,
            gof_level: self.gof_level,
            target_angle: self.target_angle,
            target_percentile: self.target_percentile,
            allow_partial: self.allow_partial,
            allow_failed: self.allow_failed,
            threads: truss_threads::or_available(self.threads),
        }
        .validate()?;
        Ok(Options {
            paths: self.paths,
            plots: !self.no_plots,
            progress: !self.quiet,
            out: self.out,
            settings,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::{MAX_PERCENTILES, MAX_REPLICATES};

    fn parse(args: &[&str]) -> Result<Options, MergeError> {
        let mut v = vec!["mc-merge"];
        v.extend_from_slice(args);
        Args::try_parse_from(v).unwrap().validate()
    }

    #[test]
    fn defaults_and_target_added() {
        let o = parse(&["d", "--percentiles", "50,99", "--target-percentile", "90"]).unwrap();
        assert_eq!(o.settings.percentiles, vec![50.0, 90.0, 99.0]);
        assert_eq!(o.settings.replicates, 2000);
        assert!(o.plots && o.out.is_none());
    }

    #[test]
    fn bad_values_are_usage_errors() {
        for bad in [
            &["d", "--percentiles", "0,95"][..],
            &["d", "--percentiles", "100"],
            &["d", "--confidence", "95"],
            &["d", "--target-angle=-1"],
            &["d", "--target-angle", "0"],
            &["d", "--replicates", "3"],
            &["d", "--threads", "0"],
        ] {
            let e = parse(bad).unwrap_err();
            assert_eq!(e.exit_code(), truss_exit::USAGE, "{bad:?}: {e}");
        }
    }

    #[test]
    fn absurd_numbers_are_refused_naming_the_flag() {
        let many = vec!["50"; MAX_PERCENTILES + 1].join(",");
        for (flag, bad) in [
            ("--replicates", &["d", "--replicates", "4000000000"][..]),
            ("--replicates", &["d", "--replicates", "100001"]),
            ("--gof-replicates", &["d", "--gof-replicates", "4000000000"]),
            ("--threads", &["d", "--threads", "100000"]),
            ("--target-angle", &["d", "--target-angle", "1e300"]),
            ("--target-angle", &["d", "--target-angle", "inf"]),
            ("--percentiles", &["d", "--percentiles", &many]),
        ] {
            let e = parse(bad).unwrap_err();
            assert_eq!(e.exit_code(), truss_exit::USAGE, "{bad:?}");
            assert!(e.to_string().contains(flag), "{bad:?}: {e}");
        }
        // The caps themselves are accepted.
        let cap = MAX_REPLICATES.to_string();
        assert_eq!(
            parse(&["d", "--replicates", &cap])
                .unwrap()
                .settings
                .replicates,
            MAX_REPLICATES
        );
    }

    #[test]
    fn helper_commands_and_short_flags() {
        let a = Args::try_parse_from(["mc-merge", "completions", "bash"]).unwrap();
        assert!(matches!(a.command, Some(Helper::Completions { .. })));
        let a = Args::try_parse_from(["mc-merge", "d", "-o", "r", "-q"]).unwrap();
        assert_eq!(a.out, Some(PathBuf::from("r")));
        assert!(a.quiet && a.command.is_none());
        // A helper command takes no merge flags, and a merge needs its directories.
        assert!(Args::try_parse_from(["mc-merge", "man", "--out", "r"]).is_err());
        assert!(Args::try_parse_from(["mc-merge", "--out", "r"]).is_err());
        // A directory called `man` is given as a path.
        let a = Args::try_parse_from(["mc-merge", "./man"]).unwrap();
        assert_eq!(a.paths, vec![PathBuf::from("./man")]);
    }
}
