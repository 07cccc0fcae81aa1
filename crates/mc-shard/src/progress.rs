//! Progress of a run: a one-line bar on a terminal, sized to the terminal's width; otherwise
//! (Slurm, cron, CI) a plain line on stderr every few seconds, stamped with the UTC time.
//!
//! The rate (samples/s, an integer) and the ETA count only samples computed by this run:
//! samples kept from an interrupted run (`done` at the start) are shown in the count but
//! neither speed up the rate nor shorten the ETA.
//!
//! Plain lines read `2026-01-02T03:04:05Z shard 0..5000: 1200/5000 samples, 240 samples/s,
//! ETA 16 s`: the timestamp is RFC 3339 in UTC, to the second.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant, SystemTime};

/// How often the plain progress line is printed.
const PLAIN_INTERVAL: Duration = Duration::from_secs(5);

/// How often the bar's text is recomposed.
const BAR_INTERVAL: Duration = Duration::from_millis(100);

/// A progress display for a run of `total` samples.
pub enum Progress {
    /// Nothing shown.
    Quiet,
    /// A bar on a terminal.
    Bar {
        /// The bar (its template is the line composed by [`bar_line`]).
        bar: ProgressBar,
        /// The counts.
        counts: Counts,
        /// When the line was last composed.
        last: Instant,
    },
    /// Plain lines.
    Plain {
        /// The counts.
        counts: Counts,
        /// When the last line was printed.
        last: Instant,
    },
}

/// What a progress line shows.
#[derive(Debug, Clone)]
pub struct Counts {
    /// What is running.
    pub label: String,
    /// Samples to do.
    pub total: u64,
    /// Samples done (kept and computed).
    pub done: u64,
    /// Samples done before this run (kept from an interrupted one).
    pub initial: u64,
    /// When this run started.
    pub start: Instant,
}

impl Counts {
    /// Samples per second computed by this run (kept samples not counted), rounded down.
    pub fn rate(&self, elapsed: Duration) -> u64 {
        let secs = elapsed.as_secs_f64();
        if secs <= 0.0 {
            return 0;
        }
        ((self.done - self.initial) as f64 / secs) as u64
    }

    /// Seconds left at this run's rate; `None` before anything was computed.
    pub fn eta(&self, elapsed: Duration) -> Option<u64> {
        let computed = self.done - self.initial;
        if computed == 0 {
            return None;
        }
        let left = self.total.saturating_sub(self.done) as f64;
        Some((left * elapsed.as_secs_f64() / computed as f64).ceil() as u64)
    }

    /// The text after the bar: `1200/5000, 240/s, ETA 16 s`.
    fn figures(&self, elapsed: Duration) -> String {
        let eta = self
            .eta(elapsed)
            .map_or_else(|| "?".to_string(), format_seconds);
        format!(
            "{}/{}, {}/s, ETA {eta}",
            self.done,
            self.total,
            self.rate(elapsed)
        )
    }
}

/// `75 s`, `12m 05s`, `3h 02m`.
fn format_seconds(s: u64) -> String {
    match s {
        0..=99 => format!("{s} s"),
        100..=5999 => format!("{}m {:02}s", s / 60, s % 60),
        _ => format!("{}h {:02}m", s / 3600, s / 60 % 60),
    }
}

/// The bar's line for a terminal `width` columns wide: label, bar, counts, rate and ETA, in
/// fewer than `width` characters (the bar takes what is left, at most 40; the label is
/// shortened if even that does not fit).
pub fn bar_line(counts: &Counts, elapsed: Duration, width: usize) -> String {
    let figures = counts.figures(elapsed);
    let budget = width.saturating_sub(1);
    let fixed = figures.chars().count() + 4; // " [" + "] " around the bar
    let mut label: String = counts.label.clone();
    let room = budget.saturating_sub(fixed);
    let bar_len = room.saturating_sub(label.chars().count()).min(40);
    if bar_len < 10 {
        // Narrow: shorten the label to leave a 10-column bar, or drop both.
        let keep = room.saturating_sub(10);
        if keep == 0 {
            let plain = format!("{} {figures}", counts.label);
            return plain.chars().take(budget).collect();
        }
        label = label.chars().take(keep).collect();
    }
    let bar_len = room.saturating_sub(label.chars().count()).min(40);
    let filled = if counts.total == 0 {
        bar_len
    } else {
        (bar_len as u128 * counts.done as u128 / counts.total as u128) as usize
    };
    let mut bar = "=".repeat(filled);
    if filled < bar_len {
        bar.push('>');
        bar.push_str(&" ".repeat(bar_len - filled - 1));
    }
    format!("{label} [{bar}] {figures}")
}

/// A plain progress line (without the time stamp).
pub fn plain_line(counts: &Counts, elapsed: Duration) -> String {
    let eta = counts
        .eta(elapsed)
        .map_or_else(|| "?".to_string(), |s| format!("{s} s"));
    format!(
        "{}: {}/{} samples, {} samples/s, ETA {eta}",
        counts.label,
        counts.done,
        counts.total,
        counts.rate(elapsed)
    )
}

/// `time` as RFC 3339 in UTC to the second: `2026-01-02T03:04:05Z`.
pub fn rfc3339_utc(time: SystemTime) -> String {
    let secs = time
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm, proleptic Gregorian).
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

/// The terminal's width in columns (80 when unknown).
fn terminal_width() -> usize {
    match console::Term::stderr().size() {
        (_, 0) => 80,
        (_, w) => w as usize,
    }
}

impl Progress {
    /// A bar if stderr is a terminal, plain lines otherwise; `quiet` shows nothing. `done`
    /// samples were kept from an earlier run.
    pub fn new(label: &str, total: u64, done: u64, quiet: bool) -> Self {
        if quiet {
            return Progress::Quiet;
        }
        let now = Instant::now();
        let counts = Counts {
            label: label.to_string(),
            total,
            done,
            initial: done,
            start: now,
        };
        if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(total);
            bar.set_style(ProgressStyle::with_template("{msg}").expect("a valid template"));
            bar.set_message(bar_line(&counts, Duration::ZERO, terminal_width()));
            Progress::Bar {
                bar,
                counts,
                last: now,
            }
        } else {
            Progress::Plain { counts, last: now }
        }
    }

    /// `n` more samples are done.
    pub fn advance(&mut self, n: u64) {
        match self {
            Progress::Quiet => {}
            Progress::Bar { bar, counts, last } => {
                counts.done += n;
                if last.elapsed() >= BAR_INTERVAL {
                    *last = Instant::now();
                    let line = bar_line(counts, counts.start.elapsed(), terminal_width());
                    bar.set_message(line);
                }
            }
            Progress::Plain { counts, last } => {
                counts.done += n;
                if last.elapsed() >= PLAIN_INTERVAL {
                    *last = Instant::now();
                    eprintln!(
                        "{} {}",
                        rfc3339_utc(SystemTime::now()),
                        plain_line(counts, counts.start.elapsed())
                    );
                }
            }
        }
    }

    /// The run ended.
    pub fn finish(&self) {
        if let Progress::Bar { bar, .. } = self {
            bar.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts(label: &str, total: u64, initial: u64, done: u64) -> Counts {
        Counts {
            label: label.into(),
            total,
            done,
            initial,
            start: Instant::now(),
        }
    }

    /// After a resume the rate and ETA count only this run's samples: 1,558,557 kept, 600
    /// computed in 6 s is 100/s, not 259,859/s, and the ETA is the rest at 100/s.
    #[test]
    fn rate_and_eta_ignore_kept_samples() {
        let c = counts("run-all", 1_600_000, 1_558_557, 1_558_557 + 600);
        let six = Duration::from_secs(6);
        assert_eq!(c.rate(six), 100);
        assert_eq!(c.eta(six), Some((1_600_000 - 1_559_157) / 100 + 1));
        let line = plain_line(&c, six);
        assert!(line.contains(", 100 samples/s,"), "{line}");
        // Nothing computed yet: no rate, no ETA, not a division by zero.
        let fresh = counts("x", 10, 4, 4);
        assert_eq!(fresh.rate(six), 0);
        assert_eq!(fresh.eta(six), None);
    }

    /// The bar line is shorter than the terminal at any width, keeps the figures whenever
    /// they fit, and shows the rate as an integer.
    #[test]
    fn bar_line_fits_the_terminal() {
        let c = counts("shard 0000000000..0000050000", 300_000, 0, 123_457);
        let elapsed = Duration::from_millis(7_300);
        for width in [20, 40, 60, 80, 100, 165, 300] {
            let line = bar_line(&c, elapsed, width);
            assert!(line.chars().count() < width, "{width}: {line:?}");
        }
        let line = bar_line(&c, elapsed, 80);
        assert!(line.contains("123457/300000, 16911/s, ETA 11 s"), "{line}");
        assert!(line.contains('['), "{line}");
        let wide = bar_line(&c, elapsed, 300);
        assert!(wide.starts_with("shard 0000000000..0000050000 ["), "{wide}");
    }

    /// RFC 3339 UTC stamps of known instants.
    #[test]
    fn timestamps_are_rfc3339_utc() {
        let at = |s: u64| rfc3339_utc(SystemTime::UNIX_EPOCH + Duration::from_secs(s));
        assert_eq!(at(0), "1970-01-01T00:00:00Z");
        assert_eq!(at(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(at(1_798_761_599), "2026-12-31T23:59:59Z");
        assert_eq!(at(4_107_542_400), "2100-03-01T00:00:00Z");
    }
}
