//! # truss-exit: one exit-code scheme for every truss-mc binary
//!
//! `truss`, `truss-mc`, `mc-shard` and `mc-merge` exit with these codes, so that a script or
//! a batch system can tell what happened whichever binary it ran:
//!
//! | code | constant | meaning |
//! |---|---|---|
//! | 0 | [`OK`] | success |
//! | 1 | [`INTERNAL`] | internal error (a bug) |
//! | 2 | [`USAGE`] | usage error: bad arguments, a range outside the job |
//! | 3 | [`INVALID_INPUT`] | invalid input: a job, model file or measured data (the message names the JSON path or line) |
//! | 4 | [`IO`] | a file or directory could not be read or written |
//! | 5 | [`IN_THE_WAY`] | a file in the way: a shard of another job, locked by another process, or damaged |
//! | 6 | [`VERIFICATION`] | verification failed: shards incomplete or not verifying at the merge; a shard process of `run-all` failed |
//! | 7 | [`FAILED_SAMPLES`] | failed samples: a solve did not converge (`truss solve`, a diagnosis's simulation), or the merge found failed samples without `--allow-failed` |
//! | 130 | [`INTERRUPTED_SIGINT`] | interrupted by SIGINT (Ctrl-C): the finished samples are kept; rerun the same command to resume |
//! | 143 | [`INTERRUPTED_SIGTERM`] | interrupted by SIGTERM (`kill`, a supervisor, a time limit): likewise |
//!
//! ## Ending a binary
//!
//! Every binary ends through [`finish`], so that all four speak alike:
//!
//! - an error is printed once, as `BINARY: error: MESSAGE` on stderr, where `MESSAGE` is the
//!   error and its causes joined by `: `, a cause left out when the text before already says
//!   it (a `thiserror` message such as `"{path}: cannot read: {source}"` both shows its
//!   source and returns it as the cause; printing both gave
//!   `cannot read: No such file or directory (os error 2): No such file or directory (os error 2)`);
//! - a *broken pipe* on stdout (the reader went away: `truss model prism | head -1`) ends
//!   the binary quietly with code 0, as `ripgrep` and other command-line tools do: the
//!   reader asked for no more, so nothing failed. stdout is wrapped in a [`Stdout`], which
//!   notes the broken pipe, so that only a broken pipe *on stdout* is quiet; one on any other
//!   file or child process is an error like any other;
//! - output that cannot be written (a full disk, `/dev/full`) is an I/O error ([`IO`]),
//!   also when it is found only as the binary ends: [`success`] flushes what stdout still
//!   buffers and reports a failure there, so a result that cannot be written is never a
//!   success. (A stdout *closed* when the binary starts, `>&-`, cannot be told from
//!   `/dev/null`: before `main` runs, Rust's runtime opens `/dev/null` in place of a closed
//!   standard descriptor, as `subprocess.DEVNULL` does in Python, so writes to it succeed.)

/// Success.
pub const OK: u8 = 0;
/// An internal error (a bug).
pub const INTERNAL: u8 = 1;
/// Bad arguments, or a range outside the job.
pub const USAGE: u8 = 2;
/// A job, model file or measured data is invalid.
pub const INVALID_INPUT: u8 = 3;
/// A file or directory could not be read or written.
pub const IO: u8 = 4;
/// A file is in the way: another job's shard, locked, or damaged.
pub const IN_THE_WAY: u8 = 5;
/// Shards do not verify, or a shard process failed.
pub const VERIFICATION: u8 = 6;
/// Samples failed: a solve did not converge.
pub const FAILED_SAMPLES: u8 = 7;
/// Interrupted by SIGINT (128 + 2, as a shell reports it); finished samples are kept.
pub const INTERRUPTED_SIGINT: u8 = 130;
/// Interrupted by SIGTERM (128 + 15); finished samples are kept.
pub const INTERRUPTED_SIGTERM: u8 = 143;

/// The scheme in one line, for every binary's `--help`.
pub const SUMMARY: &str = "Exit codes: 0 success, 1 internal error, 2 usage error, 3 invalid input (job, model, measured data), 4 I/O error, 5 a file in the way (another job's shard, locked, damaged), 6 verification failed (shards incomplete or not verifying; a shard process failed), 7 failed samples (a solve did not converge), 130 interrupted by SIGINT, 143 interrupted by SIGTERM (finished samples kept; rerun to resume).";

/// stdout (or any writer) that notes whether a write failed with a broken pipe, so that
/// [`finish`] can tell "the reader of our output went away" from any other error.
#[derive(Debug)]
pub struct Stdout<W> {
    inner: W,
    broken_pipe: bool,
}

impl Stdout<std::io::StdoutLock<'static>> {
    /// The process's stdout, locked.
    pub fn lock() -> Self {
        Self::new(std::io::stdout().lock())
    }
}

impl<W: std::io::Write> Stdout<W> {
    /// Wraps a writer.
    pub fn new(inner: W) -> Self {
        Self {
            inner,
            broken_pipe: false,
        }
    }

    /// Whether a write or flush failed because the reader closed the pipe.
    pub fn broken_pipe(&self) -> bool {
        self.broken_pipe
    }

    fn note<T>(&mut self, r: std::io::Result<T>) -> std::io::Result<T> {
        if let Err(e) = &r
            && e.kind() == std::io::ErrorKind::BrokenPipe
        {
            self.broken_pipe = true;
        }
        r
    }
}

impl<W: std::io::Write> std::io::Write for Stdout<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let r = self.inner.write(buf);
        self.note(r)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        let r = self.inner.flush();
        self.note(r)
    }
}

/// Ends the binary `binary` after success: flushes `stdout` (what is still buffered), and
/// ends with [`OK`], or like [`finish`] with [`IO`] if the flush fails.
pub fn success<W: std::io::Write>(binary: &str, stdout: &mut Stdout<W>) -> std::process::ExitCode {
    use std::io::Write;
    match stdout.flush() {
        Ok(()) => std::process::ExitCode::from(OK),
        Err(e) => finish(binary, &e, IO, stdout),
    }
}

/// The error and its causes joined by `: `, each cause left out whose text the message
/// already contains (see the crate doc).
pub fn message(error: &(dyn std::error::Error + 'static)) -> String {
    let mut text = error.to_string();
    let mut cause = error.source();
    while let Some(c) = cause {
        let more = c.to_string();
        if !more.is_empty() && !text.contains(&more) {
            text.push_str(": ");
            text.push_str(&more);
        }
        cause = c.source();
    }
    text
}

/// Whether the error or one of its causes is an I/O error of kind broken pipe.
pub fn is_broken_pipe(error: &(dyn std::error::Error + 'static)) -> bool {
    let mut cause = Some(error);
    while let Some(c) = cause {
        if c.downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
        {
            return true;
        }
        cause = c.source();
    }
    false
}

/// Ends the binary `binary` after an error whose exit code is `code`: quietly with [`OK`]
/// when the error is a broken pipe on `stdout` (see the crate doc), else after printing
/// `BINARY: error: MESSAGE` ([`message`]) to stderr.
pub fn finish<W>(
    binary: &str,
    error: &(dyn std::error::Error + 'static),
    code: u8,
    stdout: &Stdout<W>,
) -> std::process::ExitCode {
    if stdout.broken_pipe && is_broken_pipe(error) {
        return std::process::ExitCode::from(OK);
    }
    report(binary, error);
    std::process::ExitCode::from(code)
}

/// Prints `BINARY: error: MESSAGE` ([`message`]) to stderr; a closed stderr is ignored (there
/// is nowhere left to say so).
pub fn report(binary: &str, error: &(dyn std::error::Error + 'static)) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{binary}: error: {}", message(error));
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    /// An error whose message shows its source, as `thiserror`'s `"{path}: {source}"` does.
    #[derive(Debug)]
    struct Shows(std::io::Error);
    impl std::fmt::Display for Shows {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "job.json: cannot read: {}", self.0)
        }
    }
    impl std::error::Error for Shows {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    /// An error whose message does not show its source.
    #[derive(Debug)]
    struct Hides(Shows);
    impl std::fmt::Display for Hides {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "the run failed")
        }
    }
    impl std::error::Error for Hides {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    /// A cause the message already shows is printed once; one it does not show is added.
    #[test]
    fn message_prints_each_cause_once() {
        let missing = || std::io::Error::from(std::io::ErrorKind::NotFound);
        let once = super::message(&Shows(missing()));
        assert_eq!(once, format!("job.json: cannot read: {}", missing()));
        let chained = super::message(&Hides(Shows(missing())));
        assert_eq!(chained, format!("the run failed: {once}"));
        assert_eq!(chained.matches(&missing().to_string()).count(), 1);
    }

    /// A broken pipe is found anywhere in the chain, and only a broken pipe.
    #[test]
    fn broken_pipes_are_found_in_the_chain() {
        let pipe = || std::io::Error::from(std::io::ErrorKind::BrokenPipe);
        assert!(super::is_broken_pipe(&Hides(Shows(pipe()))));
        let other = std::io::Error::from(std::io::ErrorKind::PermissionDenied);
        assert!(!super::is_broken_pipe(&Hides(Shows(other))));
    }

    /// A writer whose reader has gone: the wrapper notes the broken pipe, and `finish` then
    /// ends with 0; the same error from elsewhere keeps its code.
    #[test]
    fn a_broken_pipe_on_stdout_ends_quietly() {
        struct Closed;
        impl Write for Closed {
            fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
                Err(std::io::ErrorKind::BrokenPipe.into())
            }
            fn flush(&mut self) -> std::io::Result<()> {
                Ok(())
            }
        }
        let fresh = super::Stdout::new(Closed);
        let mut out = super::Stdout::new(Closed);
        let e = out.write_all(b"x").unwrap_err();
        assert!(out.broken_pipe() && !fresh.broken_pipe());
        let quiet = super::finish("t", &e, super::IO, &out);
        assert_eq!(quiet, std::process::ExitCode::from(super::OK));
        let loud = super::finish("t", &e, super::IO, &fresh);
        assert_eq!(loud, std::process::ExitCode::from(super::IO));
    }

    /// A flush that fails at the end is an I/O error, not a success.
    #[test]
    fn a_failed_final_flush_is_an_io_error() {
        struct Full;
        impl Write for Full {
            fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
                Ok(buf.len())
            }
            fn flush(&mut self) -> std::io::Result<()> {
                Err(std::io::ErrorKind::StorageFull.into())
            }
        }
        let mut full = super::Stdout::new(Full);
        let code = super::success("t", &mut full);
        assert_eq!(code, std::process::ExitCode::from(super::IO));
        let mut fine = super::Stdout::new(Vec::new());
        assert_eq!(
            super::success("t", &mut fine),
            std::process::ExitCode::from(super::OK)
        );
    }

    /// The codes are distinct, and the summary states each.
    #[test]
    fn codes_are_distinct_and_summarised() {
        let codes = [
            super::OK,
            super::INTERNAL,
            super::USAGE,
            super::INVALID_INPUT,
            super::IO,
            super::IN_THE_WAY,
            super::VERIFICATION,
            super::FAILED_SAMPLES,
        ];
        for (i, c) in codes.iter().enumerate() {
            assert_eq!(*c as usize, i);
            assert!(super::SUMMARY.contains(&format!("{c} ")), "{c}");
        }
        for c in [super::INTERRUPTED_SIGINT, super::INTERRUPTED_SIGTERM] {
            assert!(super::SUMMARY.contains(&format!("{c} ")), "{c}");
        }
    }
}
