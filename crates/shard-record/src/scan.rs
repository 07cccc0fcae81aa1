//! Reading a shard file line by line and checking it against the format's rules.
//!
//! [`scan_shard`] is lenient about the *tail* of a file (a torn last line, a missing end line)
//! and reports it, so a writer can resume; it is strict about everything else (a corrupt line
//! in the middle, an index out of order, a wrong digest), which no crash can produce.
//! [`read_shard`] is the strict reader used by merging: it also requires a complete file.
//!
//! In a version-2 file, sample lines are held back until the next checkpoint (or the end
//! line) verifies them: only then are they passed to `visit` and counted in the scan's
//! digest and valid prefix (see the crate doc, "What is verified").

use crate::{
    Begin, End, MAX_BEGIN_LINE_BYTES, MAX_LINE_BYTES, Record, Sample, SampleDigest, sha256_hex,
};
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// What went wrong reading a shard file. Every variant names the file, and the line where
/// there is one (lines count from 1).
#[derive(Debug, thiserror::Error)]
pub enum ScanError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: io::Error,
    },
    /// The file has no complete begin line (empty, or torn while writing the header).
    #[error("{}: no complete begin line (the file is empty or was torn while its header was written)", path.display())]
    NoHeader {
        /// The file.
        path: PathBuf,
    },
    /// A complete line breaks the format.
    #[error("{}:{line}: {message}", path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// Line number, from 1.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// The last line has no newline: the writer stopped mid-line.
    #[error("{}:{line}: torn line (no newline at the end of the file): the writer stopped while writing it", path.display())]
    Torn {
        /// The file.
        path: PathBuf,
        /// Line number of the torn line.
        line: u64,
    },
    /// The file ends without an end line.
    #[error("{}: incomplete: {samples} of the range's {expected} sample lines and no end line", path.display())]
    Incomplete {
        /// The file.
        path: PathBuf,
        /// Sample lines present.
        samples: u64,
        /// Sample lines the range calls for.
        expected: u64,
    },
}

/// How a scanned file ends.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Tail {
    /// A verified end line closes the file.
    Complete(End),
    /// The last line is complete but there is no end line yet.
    Open,
    /// The last line (number given) has no newline and was not counted.
    Torn {
        /// Line number of the torn line.
        line: u64,
    },
}

/// What a scan found: the header, the digest of the verified sample lines, and how the file
/// ends.
#[derive(Debug, Clone)]
pub struct ShardScan {
    /// The begin line.
    pub begin: Begin,
    /// SHA-256 (hex) of the begin line's bytes with its `\n`.
    pub begin_sha256: String,
    /// Digest (and count) of the verified sample lines (in a version-1 file: every whole one).
    pub digest: SampleDigest,
    /// Byte length of the verified prefix: header, verified sample lines with their
    /// checkpoints and, if complete, the end line.
    pub valid_len: u64,
    /// Whole sample lines after the last checkpoint of an incomplete version-2 file: not
    /// verified, not visited, not in `digest` (a resuming writer solves them again).
    pub unverified: u64,
    /// How the file ends.
    pub tail: Tail,
}

impl ShardScan {
    /// The global index the next sample line must have.
    pub fn next_index(&self) -> u64 {
        self.begin.range.start + self.digest.samples()
    }

    /// Whether the file is complete and verified.
    pub fn is_complete(&self) -> bool {
        matches!(self.tail, Tail::Complete(_))
    }
}

/// Scans the shard file at `path`, checking every complete line, and calls `visit` with each
/// valid sample, its line number and the line's bytes (with its `\n`). `visit` may refuse a
/// sample with a message, which becomes a [`ScanError::Corrupt`] at that line.
///
/// A torn last line or a missing end line is reported in [`ShardScan::tail`], not as an
/// error; everything else that breaks the format is an error.
pub fn scan_shard(
    path: &Path,
    mut visit: impl FnMut(u64, &Sample, &[u8]) -> Result<(), String>,
) -> Result<ShardScan, ScanError> {
    let io_err = |source| ScanError::Io {
        path: path.to_path_buf(),
        source,
    };
    let corrupt = |line: u64, message: String| ScanError::Corrupt {
        path: path.to_path_buf(),
        line,
        message,
    };
    // Only a regular file: opening a FIFO would wait for a writer, a device never ends.
    let meta = std::fs::metadata(path).map_err(io_err)?;
    if !meta.is_file() {
        return Err(io_err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a regular file",
        )));
    }
    let mut reader = BufReader::with_capacity(1 << 16, File::open(path).map_err(io_err)?);
    let mut buf = Vec::with_capacity(256);
    let too_long = |line: u64, max: u64| {
        corrupt(
            line,
            format!("a line longer than {max} bytes: not a shard line"),
        )
    };

    // The header.
    let n = read_line(&mut reader, &mut buf, MAX_BEGIN_LINE_BYTES)
        .map_err(io_err)?
        .ok_or_else(|| too_long(1, MAX_BEGIN_LINE_BYTES))?;
    if n == 0 || buf.last() != Some(&b'\n') {
        return Err(ScanError::NoHeader {
            path: path.to_path_buf(),
        });
    }
    let begin = match parse_record(&buf) {
        Ok(Record::Begin(b)) => b,
        Ok(_) => return Err(corrupt(1, "the first line is not a begin record".into())),
        Err(e) => return Err(corrupt(1, e)),
    };
    begin.check().map_err(|m| corrupt(1, m))?;
    let begin_sha256 = sha256_hex(&buf);
    let every = begin.checkpoint_every;
    // The verified prefix, and the lines read since (held back until a checkpoint).
    let mut valid_len = n as u64;
    let mut digest = SampleDigest::new();
    let mut pending_digest = SampleDigest::new();
    let mut pending_len = 0u64;
    let mut pending: Vec<(u64, Sample, Vec<u8>)> = Vec::new();
    let mut last_checkpoint = 0;
    let mut line_no = 1;
    let open = |begin: Begin, digest, valid_len, pending: usize, tail| ShardScan {
        begin,
        begin_sha256: begin_sha256.clone(),
        digest,
        valid_len,
        unverified: pending as u64,
        tail,
    };

    loop {
        buf.clear();
        line_no += 1;
        let n = read_line(&mut reader, &mut buf, MAX_LINE_BYTES)
            .map_err(io_err)?
            .ok_or_else(|| too_long(line_no, MAX_LINE_BYTES))?;
        if n == 0 {
            return Ok(open(begin, digest, valid_len, pending.len(), Tail::Open));
        }
        if buf.last() != Some(&b'\n') {
            let tail = Tail::Torn { line: line_no };
            return Ok(open(begin, digest, valid_len, pending.len(), tail));
        }
        let read = pending_digest.samples();
        let due = every.is_some_and(|k| read > last_checkpoint && read.is_multiple_of(k));
        let record = parse_record(&buf).map_err(|m| corrupt(line_no, m))?;
        if due && !matches!(record, Record::Checkpoint(_)) {
            return Err(corrupt(
                line_no,
                format!(
                    "a checkpoint line was due after sample line {} (checkpoint_every {})",
                    pending_digest.samples(),
                    every.unwrap_or(0)
                ),
            ));
        }
        match record {
            Record::Begin(_) => {
                return Err(corrupt(line_no, "a second begin record".into()));
            }
            Record::Sample(sample) => {
                let expected = begin.range.start + pending_digest.samples();
                check_sample(&begin, &sample, expected).map_err(|m| corrupt(line_no, m))?;
                pending_digest.add_line(&buf, sample.angles().is_none());
                pending_len += n as u64;
                if every.is_none() {
                    visit(line_no, &sample, &buf).map_err(|m| corrupt(line_no, m))?;
                    digest = pending_digest.clone();
                    valid_len += pending_len;
                    pending_len = 0;
                } else {
                    pending.push((line_no, sample, buf.clone()));
                }
            }
            Record::Checkpoint(checkpoint) => {
                // Off schedule, a checkpoint may only be the last line: a stop checkpoint.
                let stop = !due && every.is_some() && read > last_checkpoint;
                if !due && !stop {
                    return Err(corrupt(
                        line_no,
                        format!(
                            "a checkpoint line after sample line {} (checkpoint_every {})",
                            pending_digest.samples(),
                            every.map_or("absent: format_version 1".into(), |k| k.to_string())
                        ),
                    ));
                }
                check_digests(
                    &pending_digest,
                    &begin_sha256,
                    checkpoint.samples,
                    &checkpoint.sha256,
                    Some(&checkpoint.begin_sha256),
                    true,
                )
                .map_err(|m| corrupt(line_no, format!("checkpoint: {m}")))?;
                for (at, sample, bytes) in pending.drain(..) {
                    visit(at, &sample, &bytes).map_err(|m| corrupt(at, m))?;
                }
                digest = pending_digest.clone();
                if stop {
                    // The verified prefix ends before the stop checkpoint, which a resuming
                    // writer cuts off so the finished file has only scheduled checkpoints.
                    valid_len += pending_len;
                    buf.clear();
                    if read_line(&mut reader, &mut buf, MAX_LINE_BYTES)
                        .map_err(io_err)?
                        .is_none_or(|n| n != 0)
                    {
                        return Err(corrupt(
                            line_no,
                            format!(
                                "a checkpoint line after sample line {read} is neither due (checkpoint_every {}) nor the last line",
                                every.unwrap_or(0)
                            ),
                        ));
                    }
                    return Ok(open(begin, digest, valid_len, 0, Tail::Open));
                }
                valid_len += pending_len + n as u64;
                pending_len = 0;
                last_checkpoint = read;
            }
            Record::End(end) => {
                if pending_digest.samples() != begin.range.len() {
                    return Err(corrupt(
                        line_no,
                        format!(
                            "end line after {} sample lines; the range {} needs {}",
                            pending_digest.samples(),
                            begin.range,
                            begin.range.len()
                        ),
                    ));
                }
                if end.failed != pending_digest.failed() {
                    return Err(corrupt(
                        line_no,
                        format!(
                            "end line says {} failed; the sample lines have {}",
                            end.failed,
                            pending_digest.failed()
                        ),
                    ));
                }
                check_digests(
                    &pending_digest,
                    &begin_sha256,
                    end.samples,
                    &end.sha256,
                    end.begin_sha256.as_deref(),
                    every.is_some(),
                )
                .map_err(|m| corrupt(line_no, format!("end line: {m}")))?;
                for (at, sample, bytes) in pending.drain(..) {
                    visit(at, &sample, &bytes).map_err(|m| corrupt(at, m))?;
                }
                digest = pending_digest;
                valid_len += pending_len + n as u64;
                buf.clear();
                if read_line(&mut reader, &mut buf, MAX_LINE_BYTES)
                    .map_err(io_err)?
                    .is_none_or(|n| n != 0)
                {
                    return Err(corrupt(line_no + 1, "data after the end line".into()));
                }
                return Ok(open(begin, digest, valid_len, 0, Tail::Complete(end)));
            }
        }
    }
}

/// Checks a sample line against its place: the `expected` global index, inside the range,
/// the case and within-case index the header gives it, and its fields against its status.
fn check_sample(begin: &Begin, sample: &Sample, expected: u64) -> Result<(), String> {
    if expected >= begin.range.end {
        return Err(format!(
            "sample line beyond the range {} (an end line was expected)",
            begin.range
        ));
    }
    if sample.index != expected {
        return Err(format!(
            "index {} where {expected} was expected",
            sample.index
        ));
    }
    match begin.case_of(sample.index) {
        Some((case, k)) if case.name == sample.case && k == sample.sample => {}
        Some((case, k)) => {
            return Err(format!(
                "index {} is sample {k} of case {:?}, but the line says sample {} of case {:?}",
                sample.index, case.name, sample.sample, sample.case
            ));
        }
        None => return Err(format!("index {} belongs to no case", sample.index)),
    }
    sample.check()
}

/// Checks a checkpoint's or end line's count and digests against the lines read.
/// `need_begin`: the format requires the begin line's digest.
fn check_digests(
    lines: &SampleDigest,
    begin_sha256: &str,
    samples: u64,
    sha256: &str,
    claimed_begin: Option<&str>,
    need_begin: bool,
) -> Result<(), String> {
    if samples != lines.samples() {
        return Err(format!(
            "says {samples} sample lines; {} were read",
            lines.samples()
        ));
    }
    let ours = lines.sha256();
    if sha256 != ours {
        return Err(format!(
            "sha256 {sha256} does not match the sample lines' {ours} (a sample line was changed)"
        ));
    }
    match (claimed_begin, need_begin) {
        (Some(b), _) if b != begin_sha256 => Err(format!(
            "begin_sha256 {b} does not match the begin line's {begin_sha256} (the header was changed)"
        )),
        (None, true) => Err("begin_sha256 is missing (format_version 2)".into()),
        _ => Ok(()),
    }
}

/// Reads a shard strictly: like [`scan_shard`], but a torn or incomplete file is an error.
pub fn read_shard(
    path: &Path,
    visit: impl FnMut(u64, &Sample, &[u8]) -> Result<(), String>,
) -> Result<ShardScan, ScanError> {
    let scan = scan_shard(path, visit)?;
    match scan.tail {
        Tail::Complete(_) => Ok(scan),
        Tail::Torn { line } => Err(ScanError::Torn {
            path: path.to_path_buf(),
            line,
        }),
        Tail::Open => Err(ScanError::Incomplete {
            path: path.to_path_buf(),
            samples: scan.digest.samples(),
            expected: scan.begin.range.len(),
        }),
    }
}

/// Reads one line, with its `\n` if it has one, into `buf`: its length (0 at the end of the
/// file), or `None` if the line is longer than `max` bytes (then more than `max` bytes of it
/// are in `buf`, and no more).
pub fn read_line(
    reader: &mut impl BufRead,
    buf: &mut Vec<u8>,
    max: u64,
) -> io::Result<Option<usize>> {
    let n = reader.by_ref().take(max + 1).read_until(b'\n', buf)?;
    Ok((n as u64 <= max).then_some(n))
}

/// Parses one line (with or without its `\n`) as a record.
pub fn parse_record(line: &[u8]) -> Result<Record, String> {
    let text = std::str::from_utf8(line).map_err(|e| format!("not UTF-8: {e}"))?;
    serde_json::from_str(text.trim_end_matches('\n'))
        .map_err(|e| format!("not a valid record: {e}"))
}
