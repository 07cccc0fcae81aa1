//! Stopping cleanly on SIGINT or SIGTERM (Ctrl-C, `kill PID`, a supervisor, Slurm's time
//! limit).
//!
//! [`install`] replaces the default action of both signals by setting a process-wide flag
//! ([`requested`]). The runner checks it before each sample: the samples in flight finish,
//! every finished line that is next in index order is appended, and the shard file is left
//! without its end line, as after a crash, so that running the same command again resumes
//! it. The command then prints [`message`] and exits with [`Signal::exit_code`] (128 + the
//! signal's number, as a shell reports a process killed by it).
//!
//! Without [`install`] (a library user, a test) the flag is never set and runs are never
//! interrupted.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// The signal number received (0: none).
fn flag() -> &'static Arc<AtomicUsize> {
    static FLAG: OnceLock<Arc<AtomicUsize>> = OnceLock::new();
    FLAG.get_or_init(|| Arc::new(AtomicUsize::new(0)))
}

/// A signal that asks the process to stop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Signal {
    /// SIGINT (2): Ctrl-C.
    Interrupt,
    /// SIGTERM (15): `kill PID`, a supervisor, a batch system's time limit.
    Terminate,
}

impl Signal {
    /// The exit code after this signal: 130 for SIGINT, 143 for SIGTERM (see `truss-exit`).
    pub fn exit_code(self) -> u8 {
        match self {
            Signal::Interrupt => truss_exit::INTERRUPTED_SIGINT,
            Signal::Terminate => truss_exit::INTERRUPTED_SIGTERM,
        }
    }

    /// The signal's name.
    pub fn name(self) -> &'static str {
        match self {
            Signal::Interrupt => "SIGINT",
            Signal::Terminate => "SIGTERM",
        }
    }
}

/// Sets the flag on SIGINT and SIGTERM from now on (idempotent).
pub fn install() -> std::io::Result<()> {
    static INSTALLED: OnceLock<()> = OnceLock::new();
    if INSTALLED.get().is_some() {
        return Ok(());
    }
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register_usize(sig, Arc::clone(flag()), sig as usize)?;
    }
    let _ = INSTALLED.set(());
    Ok(())
}

/// The signal received since [`install`], if any.
pub fn requested() -> Option<Signal> {
    match flag().load(Ordering::Relaxed) {
        0 => None,
        n if n == signal_hook::consts::SIGINT as usize => Some(Signal::Interrupt),
        _ => Some(Signal::Terminate),
    }
}

/// The line printed after an interrupt, `kept` being the sample lines in the shard files.
pub fn message(kept: u64) -> String {
    format!("interrupted: {kept} samples kept; rerun the same command to resume")
}

#[cfg(test)]
mod tests {
    /// The codes are the shell's 128 + signal number.
    #[test]
    fn exit_codes_are_128_plus_the_signal() {
        assert_eq!(super::Signal::Interrupt.exit_code(), 128 + 2);
        assert_eq!(super::Signal::Terminate.exit_code(), 128 + 15);
        assert_eq!(
            super::message(12),
            "interrupted: 12 samples kept; rerun the same command to resume"
        );
    }
}
