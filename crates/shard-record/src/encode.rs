//! Writing a shard's bytes: the begin line, sample lines with their checkpoint lines, and
//! the end line, exactly as the crate doc specifies. The writer (`mc-shard`) uses it, so the
//! checkpoint rule lives next to the scanner that checks it.

use crate::{Begin, Checkpoint, End, Record, SampleDigest, ShardScan, sha256_hex, to_line};

/// The running state of a shard being written: the digest of the sample lines so far and
/// the begin line's digest.
#[derive(Debug, Clone)]
pub struct ShardEncoder {
    every: Option<u64>,
    begin_sha256: String,
    digest: SampleDigest,
}

impl ShardEncoder {
    /// A new shard with header `begin`; returns the encoder and the begin line's bytes.
    pub fn new(begin: &Begin) -> (Self, Vec<u8>) {
        let line = to_line(&Record::Begin(begin.clone())).into_bytes();
        let encoder = Self {
            every: begin.checkpoint_every,
            begin_sha256: sha256_hex(&line),
            digest: SampleDigest::new(),
        };
        (encoder, line)
    }

    /// Carries on after the verified prefix of a scanned file (the writer truncates the
    /// file to [`ShardScan::valid_len`] first).
    pub fn resume(scan: &ShardScan) -> Self {
        Self {
            every: scan.begin.checkpoint_every,
            begin_sha256: scan.begin_sha256.clone(),
            digest: scan.digest.clone(),
        }
    }

    /// Sample lines so far.
    pub fn samples(&self) -> u64 {
        self.digest.samples()
    }

    /// Failed samples so far.
    pub fn failed(&self) -> u64 {
        self.digest.failed()
    }

    /// Appends one sample line (its bytes with `\n`) to `out`, followed by a checkpoint line
    /// when one is due.
    pub fn push(&mut self, line: &[u8], failed: bool, out: &mut Vec<u8>) {
        self.digest.add_line(line, failed);
        out.extend_from_slice(line);
        if let Some(every) = self.every
            && self.digest.samples().is_multiple_of(every)
        {
            let checkpoint = Checkpoint {
                samples: self.digest.samples(),
                sha256: self.digest.sha256(),
                begin_sha256: self.begin_sha256.clone(),
            };
            out.extend_from_slice(to_line(&Record::Checkpoint(checkpoint)).as_bytes());
        }
    }

    /// The bytes of a *stop checkpoint* for an incomplete file's last line, when lines
    /// follow the last scheduled checkpoint: it verifies them, so a resume keeps them (and
    /// cuts the stop checkpoint off). `None` when no line is unverified.
    pub fn stop_checkpoint(&self) -> Option<Vec<u8>> {
        let every = self.every?;
        let samples = self.digest.samples();
        if samples.is_multiple_of(every) {
            return None;
        }
        let checkpoint = Checkpoint {
            samples,
            sha256: self.digest.sha256(),
            begin_sha256: self.begin_sha256.clone(),
        };
        Some(to_line(&Record::Checkpoint(checkpoint)).into_bytes())
    }

    /// The end record and its line's bytes.
    pub fn end(&self) -> (End, Vec<u8>) {
        let mut end = self.digest.end();
        if self.every.is_some() {
            end.begin_sha256 = Some(self.begin_sha256.clone());
        }
        let line = to_line(&Record::End(end.clone())).into_bytes();
        (end, line)
    }
}
