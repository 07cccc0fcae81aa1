//! Progress of a run: an indicatif bar with samples/s and ETA on a terminal; otherwise (Slurm,
//! cron, CI) a plain line on stderr every few seconds.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// How often the plain progress line is printed.
const PLAIN_INTERVAL: Duration = Duration::from_secs(5);

/// A progress display for a shard of `total` samples.
pub enum Progress {
    /// Nothing shown.
    Quiet,
    /// A bar on a terminal.
    Bar(ProgressBar),
    /// Plain lines.
    Plain {
        /// What is running.
        label: String,
        /// Samples to do.
        total: u64,
        /// Samples done.
        done: u64,
        /// Samples done before this run (resumed).
        initial: u64,
        /// When the run started.
        start: Instant,
        /// When the last line was printed.
        last: Instant,
    },
}

impl Progress {
    /// A bar if stderr is a terminal, plain lines otherwise; `quiet` shows nothing.
    pub fn new(label: &str, total: u64, done: u64, quiet: bool) -> Self {
        if quiet {
            return Progress::Quiet;
        }
        if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(total);
            bar.set_style(
                ProgressStyle::with_template(
                    "{msg} [{bar:40}] {pos}/{len} samples, {per_sec}, ETA {eta}",
                )
                .expect("a valid template")
                .progress_chars("=> "),
            );
            bar.set_message(label.to_string());
            bar.set_position(done);
            Progress::Bar(bar)
        } else {
            let now = Instant::now();
            Progress::Plain {
                label: label.to_string(),
                total,
                done,
                initial: done,
                start: now,
                last: now,
            }
        }
    }

    /// `n` more samples are done.
    pub fn advance(&mut self, n: u64) {
        match self {
            Progress::Quiet => {}
            Progress::Bar(bar) => bar.inc(n),
            Progress::Plain {
                label,
                total,
                done,
                initial,
                start,
                last,
            } => {
                *done += n;
                if last.elapsed() >= PLAIN_INTERVAL {
                    *last = Instant::now();
                    let rate = (*done - *initial) as f64 / start.elapsed().as_secs_f64().max(1e-9);
                    let eta = (*total - *done) as f64 / rate.max(1e-9);
                    eprintln!(
                        "{label}: {done}/{total} samples, {rate:.0} samples/s, ETA {eta:.0} s"
                    );
                }
            }
        }
    }

    /// The run ended.
    pub fn finish(&self) {
        if let Progress::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}
