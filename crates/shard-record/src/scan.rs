//! Reading a shard file line by line and checking it against the format's rules.
//!
//! [`scan_shard`] is lenient about the *tail* of a file (a torn last line, a missing end line)
//! and reports it, so a writer can resume; it is strict about everything else (a corrupt line
//! in the middle, an index out of order, a wrong digest), which no crash can produce.
//! [`read_shard`] is the strict reader used by merging: it also requires a complete file.

use crate::{Begin, End, Record, Sample, SampleDigest};
use std::fs::File;
use std::io::{self, BufRead, BufReader};
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

/// What a scan found: the header, the digest of the valid sample lines, and how the file ends.
#[derive(Debug, Clone)]
pub struct ShardScan {
    /// The begin line.
    pub begin: Begin,
    /// Digest (and count) of the valid sample lines.
    pub digest: SampleDigest,
    /// Byte length of the valid prefix: header, valid sample lines and, if complete, the end line.
    pub valid_len: u64,
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
    let mut reader = BufReader::with_capacity(1 << 16, File::open(path).map_err(io_err)?);
    let mut buf = Vec::with_capacity(256);

    // The header.
    let n = reader.read_until(b'\n', &mut buf).map_err(io_err)?;
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
    let mut valid_len = n as u64;
    let mut digest = SampleDigest::new();
    let mut line_no = 1;

    loop {
        buf.clear();
        let n = reader.read_until(b'\n', &mut buf).map_err(io_err)?;
        if n == 0 {
            return Ok(ShardScan {
                begin,
                digest,
                valid_len,
                tail: Tail::Open,
            });
        }
        line_no += 1;
        if buf.last() != Some(&b'\n') {
            return Ok(ShardScan {
                begin,
                digest,
                valid_len,
                tail: Tail::Torn { line: line_no },
            });
        }
        match parse_record(&buf).map_err(|m| corrupt(line_no, m))? {
            Record::Begin(_) => {
                return Err(corrupt(line_no, "a second begin record".into()));
            }
            Record::Sample(sample) => {
                let expected = begin.range.start + digest.samples();
                if expected >= begin.range.end {
                    return Err(corrupt(
                        line_no,
                        format!(
                            "sample line beyond the range {} (an end line was expected)",
                            begin.range
                        ),
                    ));
                }
                if sample.index != expected {
                    return Err(corrupt(
                        line_no,
                        format!("index {} where {expected} was expected", sample.index),
                    ));
                }
                match begin.case_of(sample.index) {
                    Some((case, k)) if case.name == sample.case && k == sample.sample => {}
                    Some((case, k)) => {
                        return Err(corrupt(
                            line_no,
                            format!(
                                "index {} is sample {k} of case {:?}, but the line says sample {} of case {:?}",
                                sample.index, case.name, sample.sample, sample.case
                            ),
                        ));
                    }
                    None => {
                        return Err(corrupt(
                            line_no,
                            format!("index {} belongs to no case", sample.index),
                        ));
                    }
                }
                sample.check().map_err(|m| corrupt(line_no, m))?;
                visit(line_no, &sample, &buf).map_err(|m| corrupt(line_no, m))?;
                digest.add_line(&buf, sample.angles().is_none());
                valid_len += n as u64;
            }
            Record::End(end) => {
                let ours = digest.end();
                if digest.samples() != begin.range.len() {
                    return Err(corrupt(
                        line_no,
                        format!(
                            "end line after {} sample lines; the range {} needs {}",
                            digest.samples(),
                            begin.range,
                            begin.range.len()
                        ),
                    ));
                }
                if end != ours {
                    return Err(corrupt(
                        line_no,
                        format!(
                            "end line says {} samples, {} failed, sha256 {}; the sample lines give {} samples, {} failed, sha256 {}",
                            end.samples,
                            end.failed,
                            end.sha256,
                            ours.samples,
                            ours.failed,
                            ours.sha256
                        ),
                    ));
                }
                valid_len += n as u64;
                buf.clear();
                if reader.read_until(b'\n', &mut buf).map_err(io_err)? != 0 {
                    return Err(corrupt(line_no + 1, "data after the end line".into()));
                }
                return Ok(ShardScan {
                    begin,
                    digest,
                    valid_len,
                    tail: Tail::Complete(end),
                });
            }
        }
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

/// Parses one line (with or without its `\n`) as a record.
pub fn parse_record(line: &[u8]) -> Result<Record, String> {
    let text = std::str::from_utf8(line).map_err(|e| format!("not UTF-8: {e}"))?;
    serde_json::from_str(text.trim_end_matches('\n'))
        .map_err(|e| format!("not a valid record: {e}"))
}
