//! # shard-record: the JSON Lines format of one Monte Carlo shard
//!
//! One crate, used by both the writer (`mc-shard`) and the reader (`mc-merge`), so that the
//! two can never disagree about what a shard file holds.
//!
//! ## Overview
//!
//! A Monte Carlo job has `job_samples` samples, numbered by a *global index* `0..job_samples`
//! that runs over the job's cases in order (case 0's samples first). A *shard* is a contiguous
//! range `start..end` of that index, computed by one process and written to one file,
//! `shard-{start:010}-{end:010}.jsonl` (see [`ShardRange::file_name`]).
//!
//! ## Wire format (version 2)
//!
//! The file is [JSON Lines](https://jsonlines.org): UTF-8, one JSON object per line, each line
//! ended by `\n`. Every object has a `record` field naming its kind:
//!
//! 1. One `begin` line ([`Begin`]): `format` (always `"truss-mc-shard"`), `format_version`
//!    ([`FORMAT_VERSION`]), `program` and `program_version` (the writer), `job_id` (64 lower-case
//!    hex digits: the SHA-256 of the job's canonical form), `range` (`{"start": A, "end": B}`),
//!    `job_samples`, `cases`: every case of the job (not only those in this range) with its
//!    `name`, the global index of its first sample `start`, its `samples` count and `parameters`,
//!    named numbers that describe the case for sweeps (for example `sigma` in mm, `stages`),
//!    `checkpoint_every` (N, 1 ≤ N ≤ [`MAX_CHECKPOINT_EVERY`]; mc-shard writes
//!    [`CHECKPOINT_EVERY`]), and, when the job states an alignment budget, `budget`
//!    ([`Budget`]: `percentile` in %, and one or more of `theta_p` \[rad\], `decenter` \[mm\]
//!    and `despace` \[mm, of |despace|\], the limits each quantity's percentile must stay
//!    within).
//! 2. One `sample` line ([`Sample`]) for each global index of the range, in increasing order
//!    with no gaps: `index` (global), `case` (name), `sample` (index within the case),
//!    `status` (`"converged"` or `"failed"`), `iterations` (Newton iterations), and
//!    - when converged: `theta_p`, `tan_theta_x`, `tan_theta_y` (rad and dimensionless, paper
//!      eqs. 2, 8, 9), `decenter_x`, `decenter_y`, `decenter` and `despace` (mm: the top
//!      surface centroid's displacement relative to the bottom's, in the bottom's frame:
//!      its two components in the bottom plane, their magnitude, and its component along
//!      the bottom's normal, signed; `δ = (u₁ + u₂ + u₃)/3 − Σ s_k/m` over the top surface's
//!      nodes and the supported ones, `decenter_x = δ·e_x`, `decenter_y = δ·e_y`,
//!      `decenter = √(decenter_x² + decenter_y²)`, `despace = δ·n_b`: see
//!      `truss_core::measure`; written by numerics version 8 and later, absent from older
//!      shards), `residual` (final out-of-balance force, N), optionally `slack_cables`
//!      (how many tension-only members ended slack), `loose_joints` (backlash joints whose
//!      virtual cable ended slack) and `floating` (`true` when some stage's tilt is held by
//!      pretension alone, not by the members that bear; written for models whose bars do
//!      not frame the top surface's tilt, such as the prism with pin joints in free play)
//!      and, where `floating` is written, `holding_force` (N: the smallest force on one
//!      node of the top surface that moves θ_P by 1 %, in the linear response at the
//!      equilibrium; 0 where that equilibrium is not stable against some small load)
//!      and, only where the limit solver's last attempt at `ρ = 0` did not converge,
//!      `limit_ratio` (the compression ratio, > 0, of the one-sided members at the
//!      equilibrium reported instead: the last stage of the continuation, which stands
//!      for the limit; see the README, "Slack cables");
//!    - when failed: `reason`, a sentence saying why.
//!
//!    A failed solve is a line with its status, never a missing line.
//! 3. After every N-th sample line (N = `checkpoint_every`; after sample line N, 2N, …, the
//!    last one included when the range's length is a multiple of N), one `checkpoint` line
//!    ([`Checkpoint`]): `samples` (the sample lines so far), `sha256` (the SHA-256 of the
//!    exact bytes of those sample lines in file order, each with its `\n`) and `begin_sha256`
//!    (the SHA-256 of the begin line's bytes with its `\n`).
//!
//!    A writer that stops on purpose (SIGINT, SIGTERM) may end an incomplete file with one
//!    more checkpoint line off that schedule, a *stop checkpoint*, covering every sample
//!    line written. It is only valid as the file's last line; a writer resuming the file
//!    cuts it off (the finished file has only the scheduled checkpoints).
//! 4. One `end` line ([`End`]): `samples` (the number of sample lines), `failed` (how many of
//!    them failed), `sha256` (as a checkpoint's, over all sample lines; checkpoint lines are
//!    not hashed) and `begin_sha256`.
//!
//! Numbers are written in the shortest form that reads back to the same `f64` (serde_json with
//! `float_roundtrip`), so a reader recovers every bit the writer had.
//!
//! Units: lengths in mm, forces in N, angles in rad.
//!
//! ## Example
//!
//! ```text
//! {"record":"begin","format":"truss-mc-shard","format_version":2,"program":"mc-shard","program_version":"0.1.0","job_id":"6f1e…","range":{"start":0,"end":2},"job_samples":2,"cases":[{"name":"sigma-0.0063","start":0,"samples":2,"parameters":{"sigma":0.0063,"stages":5.0}}],"checkpoint_every":100}
//! {"record":"sample","index":0,"case":"sigma-0.0063","sample":0,"status":"converged","iterations":3,"theta_p":4.1e-5,"tan_theta_x":-2.2e-5,"tan_theta_y":3.5e-5,"decenter_x":0.0041,"decenter_y":-0.0023,"decenter":0.0047,"despace":0.0012,"residual":2.1e-11,"slack_cables":4}
//! {"record":"sample","index":1,"case":"sigma-0.0063","sample":1,"status":"failed","iterations":60,"reason":"Newton did not converge in 60 iterations (residual 3.2e-4 N)"}
//! {"record":"end","samples":2,"failed":1,"sha256":"9b0c…","begin_sha256":"41d7…"}
//! ```
//!
//! ## What is verified
//!
//! Every digest of a version-2 file covers the begin line as well as the sample lines, so a
//! changed header parameter (a case's `sigma`, say) breaks the first checkpoint or the end
//! line, exactly as a changed digit of θ_P does.
//!
//! - A complete file (one with its end line) is verified in full by [`scan_shard`] and
//!   [`read_shard`]: every line's shape and order, every checkpoint, the end line.
//! - An incomplete file is verified **up to its last checkpoint**: [`scan_shard`] reports
//!   that prefix ([`ShardScan::valid_len`], [`ShardScan::digest`]) and calls its `visit`
//!   only for lines so verified. The whole sample lines after the last checkpoint (at most
//!   N − 1, or N when the writer stopped just before the checkpoint line) cannot be told from
//!   edited ones; they are counted in [`ShardScan::unverified`] and a writer resuming the file
//!   cuts them off and solves them again. Resuming therefore costs one read of the file
//!   (SHA-256) and, after a crash, at most N samples' solves; after a stop on a signal
//!   (a stop checkpoint), none.
//! - Nothing checks that the numbers are the *right* ones for the job: a shard rewritten
//!   with fresh digests verifies. That is what `mc-shard audit` is for: it re-solves a seeded
//!   random sample of lines and compares them byte for byte.
//!
//! ## Torn and incomplete files
//!
//! A writer appends and flushes whole lines. A file whose last line lacks its `\n` was torn by
//! a crash: [`scan_shard`] reports the verified prefix so that a writer can truncate and
//! resume, and a reader can name the torn line. A file without an `end` line is incomplete.
//!
//! ## Versioning
//!
//! Readers accept `format_version` up to [`FORMAT_VERSION`] and ignore unknown fields, so a
//! later version may add optional fields; a change in meaning increments the version.
//! Version 1 (no `checkpoint_every`, no `checkpoint` lines, no `begin_sha256`: the begin
//! line and an incomplete file's lines were not covered by any digest) is still read, so
//! that older runs still merge; [`Begin::new`] writes it (plain files, test fixtures), and
//! [`Begin::with_checkpoints`] turns a header into version 2. mc-shard writes version 2, and
//! does not resume a version-1 file (its kept lines cannot be verified).

mod encode;
mod range;
mod scan;

pub use encode::ShardEncoder;

pub use range::{ShardRange, ShardRangeError};

/// The keys of a case's `parameters` in a shard's begin record: what the merge's sweeps read
/// to put cases on a curve. The job crate writes them (a pipeline test checks that it writes
/// no other key).
pub mod parameters {
    /// The largest standard deviation of the case's length errors, a group's own and lot
    /// parts together \[mm\].
    pub const SIGMA: &str = "sigma";
    /// The prism's stage count.
    pub const STAGES: &str = "stages";
    /// 1 when any length-error distribution is uniform.
    pub const UNIFORM: &str = "uniform";
    /// The largest limit/σ of the case's truncated normal length errors, when it has any.
    pub const TRUNCATED_NORMAL: &str = "truncated_normal";
    /// 1 for a model with backlash joints.
    pub const BACKLASH: &str = "backlash";
    /// The joints' regularisation `k_c/k_t` (cases differing in it form their own series).
    pub const JOINT_COMPRESSION_RATIO: &str = "joint_compression_ratio";
    /// The cables' compression stiffness over their tension stiffness, written only where it
    /// is not the default 0 (the limit; cases differing in it form their own series).
    pub const CABLE_COMPRESSION_RATIO: &str = "cable_compression_ratio";
    /// The largest share of a member's length-error variance held by its production lot's
    /// shared part, `σ_lot²/(σ_lot² + σ_part²)`, written only for cases whose groups have
    /// lots (cases differing in it form their own series).
    pub const LOT_SHARE: &str = "lot_share";
    /// Every key, in the order above.
    pub const ALL: [&str; 8] = [
        SIGMA,
        STAGES,
        UNIFORM,
        TRUNCATED_NORMAL,
        BACKLASH,
        JOINT_COMPRESSION_RATIO,
        CABLE_COMPRESSION_RATIO,
        LOT_SHARE,
    ];
}
pub use scan::{ScanError, ShardScan, Tail, parse_record, read_line, read_shard, scan_shard};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;

/// The value of the `format` field of every begin line.
pub const FORMAT: &str = "truss-mc-shard";

/// The format version this crate writes and the highest it reads. Version 2 added
/// checkpoints and the begin line's digest (see the crate doc).
pub const FORMAT_VERSION: u32 = 2;

/// The checkpoint interval mc-shard writes: a `checkpoint` line after every 100 sample lines
/// (about 0.3 % of the file), so a resume re-solves at most 100 samples.
pub const CHECKPOINT_EVERY: u64 = 100;

/// The largest `checkpoint_every` a reader accepts (it holds that many lines while it
/// verifies them).
pub const MAX_CHECKPOINT_EVERY: u64 = 100_000;

/// The longest sample, checkpoint or end line a reader takes, 1 MiB \[bytes\]: a sample line
/// is a few hundred bytes. A longer line (a file that is not a shard, a sparse file of
/// zeros) is refused as corrupt before it is read into memory.
pub const MAX_LINE_BYTES: u64 = 1 << 20;

/// The longest begin line a reader takes, 256 MiB \[bytes\]: it lists every case of the job
/// with its parameters, about a hundred bytes a case, so four times the largest job file
/// (64 MiB) holds any job's.
pub const MAX_BEGIN_LINE_BYTES: u64 = 256 << 20;

/// One line of a shard file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "record", rename_all = "snake_case")]
pub enum Record {
    /// The first line.
    Begin(Begin),
    /// One line per sample.
    Sample(Sample),
    /// After every `checkpoint_every` sample lines (format version 2).
    Checkpoint(Checkpoint),
    /// The last line.
    End(End),
}

/// A sample record borrowed for writing: serialises exactly as `Record::Sample`.
#[derive(Serialize)]
#[serde(tag = "record", rename_all = "snake_case")]
enum RecordRef<'a> {
    Sample(&'a Sample),
}

/// The header line of a shard.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Begin {
    /// Always [`FORMAT`].
    pub format: String,
    /// The format version the file was written in.
    pub format_version: u32,
    /// The writing program's name.
    pub program: String,
    /// The writing program's version.
    pub program_version: String,
    /// SHA-256 (hex) of the job's canonical form.
    pub job_id: String,
    /// The global sample indices this shard holds.
    pub range: ShardRange,
    /// The total number of samples of the job, over all cases.
    pub job_samples: u64,
    /// Every case of the job, in order.
    pub cases: Vec<CaseInfo>,
    /// A checkpoint line after every this many sample lines (format version 2; absent in
    /// version 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint_every: Option<u64>,
    /// The job's alignment budget, if it states one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub budget: Option<Budget>,
}

/// A job's alignment budget: each quantity's `percentile`-th percentile must stay within its
/// limit (a line per quantity; at least one).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Budget {
    /// The percentile every line is read at, in % (0 < p < 100).
    pub percentile: f64,
    /// θ_P's limit \[rad\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub theta_p: Option<f64>,
    /// `decenter`'s limit \[mm\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decenter: Option<f64>,
    /// The limit of `|despace|` \[mm\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub despace: Option<f64>,
}

impl Budget {
    /// The lines in the order θ_P, decenter, despace: (quantity name, limit).
    pub fn lines(&self) -> Vec<(&'static str, f64)> {
        [
            ("theta_p", self.theta_p),
            ("decenter", self.decenter),
            ("despace", self.despace),
        ]
        .into_iter()
        .filter_map(|(q, l)| Some((q, l?)))
        .collect()
    }

    /// Checks the budget: a percentile in (0, 100), at least one line, every limit finite
    /// and positive (θ_P's below π/2 rad).
    pub fn check(&self) -> Result<(), String> {
        if !(self.percentile > 0.0 && self.percentile < 100.0) {
            return Err(format!(
                "budget percentile {} is not in (0, 100)",
                self.percentile
            ));
        }
        if self.lines().is_empty() {
            return Err("a budget needs at least one line".into());
        }
        for (q, l) in self.lines() {
            let most = if q == "theta_p" {
                std::f64::consts::FRAC_PI_2
            } else {
                f64::INFINITY
            };
            if !(l > 0.0 && l < most) {
                return Err(format!(
                    "budget line {q}: limit {l} is not a positive number"
                ));
            }
        }
        Ok(())
    }
}

/// One case of a job, as the header describes it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseInfo {
    /// The case's unique name.
    pub name: String,
    /// The global index of the case's first sample.
    pub start: u64,
    /// How many samples the case has.
    pub samples: u64,
    /// Named numbers describing the case (`sigma` in mm, `stages`, …), for sweeps.
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
}

impl CaseInfo {
    /// The global index range of the case's samples.
    pub fn range(&self) -> ShardRange {
        ShardRange {
            start: self.start,
            end: self.start + self.samples,
        }
    }
}

/// Whether a sample's solve converged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// The equilibrium was found; the angles are present.
    Converged,
    /// The solve failed; `reason` says why.
    Failed,
}

/// One sample line. Optional fields are present or absent according to `status`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Global sample index.
    pub index: u64,
    /// Case name.
    pub case: String,
    /// Index of the sample within its case.
    pub sample: u64,
    /// Converged or failed.
    pub status: Status,
    /// Newton iterations taken.
    pub iterations: u32,
    /// Distortion angle θ_P between top and bottom normals \[rad\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub theta_p: Option<f64>,
    /// tan θ_x of the top surface (paper eq. 8) \[-\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tan_theta_x: Option<f64>,
    /// tan θ_y of the top surface (paper eq. 9) \[-\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tan_theta_y: Option<f64>,
    /// The top centroid's shift along the bottom frame's first in-plane axis \[mm\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decenter_x: Option<f64>,
    /// The top centroid's shift along the bottom frame's second in-plane axis \[mm\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decenter_y: Option<f64>,
    /// `√(decenter_x² + decenter_y²)` \[mm\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decenter: Option<f64>,
    /// The top centroid's displacement along the bottom's normal, signed \[mm\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub despace: Option<f64>,
    /// Final out-of-balance force, max norm over free DOFs \[N\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub residual: Option<f64>,
    /// Number of tension-only members that ended slack.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slack_cables: Option<u32>,
    /// Number of backlash joints whose virtual cable ended slack (the joint is loose).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loose_joints: Option<u32>,
    /// Whether some stage's tilt is held by pretension alone, not by the members that bear
    /// (a floating stage); written for models whose bars do not frame the tilt.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floating: Option<bool>,
    /// The holding force \[N\]: the smallest force on one node of the top surface that moves
    /// θ_P by 1 % (linear response at the equilibrium; 0 where the equilibrium is not
    /// stable against some small load); written where `floating` is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub holding_force: Option<f64>,
    /// Where the limit solver's last attempt at `ρ = 0` did not converge: the compression
    /// ratio (dimensionless, > 0) of the one-sided members at the equilibrium reported,
    /// the continuation's last converged stage, which stands for the limit. Absent where
    /// the equilibrium is the limit's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit_ratio: Option<f64>,
    /// Why the solve failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// Where a converged sample's top surface sits against the bottom (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// `decenter_x` \[mm\].
    pub decenter_x: f64,
    /// `decenter_y` \[mm\].
    pub decenter_y: f64,
    /// `decenter` \[mm\].
    pub decenter: f64,
    /// `despace` \[mm\].
    pub despace: f64,
}

/// The angles of a converged sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Angles {
    /// θ_P \[rad\].
    pub theta_p: f64,
    /// tan θ_x \[-\].
    pub tan_theta_x: f64,
    /// tan θ_y \[-\].
    pub tan_theta_y: f64,
}

impl Sample {
    /// The angles, if the sample converged and all three are present and finite.
    pub fn angles(&self) -> Option<Angles> {
        match (
            self.status,
            self.theta_p,
            self.tan_theta_x,
            self.tan_theta_y,
        ) {
            (Status::Converged, Some(theta_p), Some(tan_theta_x), Some(tan_theta_y))
                if theta_p.is_finite() && tan_theta_x.is_finite() && tan_theta_y.is_finite() =>
            {
                Some(Angles {
                    theta_p,
                    tan_theta_x,
                    tan_theta_y,
                })
            }
            _ => None,
        }
    }

    /// The placement, if the sample converged and all four fields are present and finite
    /// (absent from the lines of numerics versions before 8).
    pub fn placement(&self) -> Option<Placement> {
        match (
            self.status,
            self.decenter_x,
            self.decenter_y,
            self.decenter,
            self.despace,
        ) {
            (Status::Converged, Some(x), Some(y), Some(d), Some(z))
                if x.is_finite() && y.is_finite() && d.is_finite() && z.is_finite() =>
            {
                Some(Placement {
                    decenter_x: x,
                    decenter_y: y,
                    decenter: d,
                    despace: z,
                })
            }
            _ => None,
        }
    }

    /// Refuses a converged sample whose θ_P is not an angle between the surfaces, in
    /// \[0, π/2\] rad (the tangents are finite: [`Sample::angles`]). Its digests may well
    /// verify (a line rewritten with fresh ones): a θ_P of 1e308 would otherwise wreck every
    /// statistic. Every reader that verifies shards applies it (the merge, the Python
    /// package).
    pub fn check_angles(&self) -> Result<(), String> {
        match self.angles() {
            Some(a) if !(0.0..=std::f64::consts::FRAC_PI_2).contains(&a.theta_p) => Err(format!(
                "theta_p {} rad is not a distortion angle (it lies in [0, π/2])",
                a.theta_p
            )),
            _ => Ok(()),
        }
    }

    /// Checks that the fields present agree with `status`: a converged sample carries three
    /// finite angles with θ_P ≥ 0, a holding force, where it has one, finite and ≥ 0, and
    /// the four placement fields all or none, finite, with `decenter` ≥ 0; a failed one
    /// carries a reason.
    pub fn check(&self) -> Result<(), String> {
        let placement_fields = [
            self.decenter_x,
            self.decenter_y,
            self.decenter,
            self.despace,
        ]
        .iter()
        .filter(|f| f.is_some())
        .count();
        match self.status {
            Status::Converged => match self.angles() {
                Some(_)
                    if self
                        .holding_force
                        .is_some_and(|f| !(f.is_finite() && f >= 0.0)) =>
                {
                    Err("holding_force must be a finite number of newtons ≥ 0".into())
                }
                Some(_)
                    if self
                        .limit_ratio
                        .is_some_and(|r| !(r.is_finite() && r > 0.0)) =>
                {
                    Err("limit_ratio must be a finite compression ratio > 0".into())
                }
                Some(_) if placement_fields != 0 && placement_fields != 4 => {
                    Err("decenter_x, decenter_y, decenter and despace come all four or none".into())
                }
                Some(_)
                    if placement_fields == 4
                        && self.placement().is_none_or(|p| p.decenter < 0.0) =>
                {
                    Err("decenter_x, decenter_y, despace must be finite mm and decenter ≥ 0".into())
                }
                Some(a) if a.theta_p >= 0.0 => Ok(()),
                Some(_) => Err("theta_p is negative".into()),
                None => Err(
                    "a converged sample needs finite theta_p, tan_theta_x and tan_theta_y".into(),
                ),
            },
            Status::Failed => match &self.reason {
                Some(_) => Ok(()),
                None => Err("a failed sample needs a reason".into()),
            },
        }
    }

    /// The line this sample is written as, with its terminating `\n`.
    pub fn to_line(&self) -> String {
        let mut out = Vec::with_capacity(256);
        self.write_line(&mut out);
        String::from_utf8(out).expect("serde_json writes UTF-8")
    }

    /// Appends the line this sample is written as (the bytes of [`Sample::to_line`]) to
    /// `out`, without copying the sample.
    pub fn write_line(&self, out: &mut Vec<u8>) {
        serde_json::to_writer(&mut *out, &RecordRef::Sample(self))
            .expect("records always serialise");
        out.push(b'\n');
    }
}

/// The closing line of a shard.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct End {
    /// Number of sample lines.
    pub samples: u64,
    /// Number of failed samples among them.
    pub failed: u64,
    /// SHA-256 (hex) of all sample lines' bytes, each with its `\n`.
    pub sha256: String,
    /// SHA-256 (hex) of the begin line's bytes with its `\n` (format version 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub begin_sha256: Option<String>,
}

/// A checkpoint line (format version 2): the digest of the sample lines so far and of the
/// begin line, so that an incomplete file is verified up to it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Number of sample lines before this checkpoint.
    pub samples: u64,
    /// SHA-256 (hex) of those sample lines' bytes, each with its `\n`.
    pub sha256: String,
    /// SHA-256 (hex) of the begin line's bytes with its `\n`.
    pub begin_sha256: String,
}

/// Serialises a record as one line with its terminating `\n`.
pub fn to_line(record: &Record) -> String {
    // Serialising these plain types cannot fail: no maps with non-string keys, no I/O.
    let mut line = serde_json::to_string(record).expect("records always serialise");
    line.push('\n');
    line
}

/// Running SHA-256 over sample lines, for the `end` record.
#[derive(Clone, Default)]
pub struct SampleDigest {
    hasher: Sha256,
    samples: u64,
    failed: u64,
}

impl std::fmt::Debug for SampleDigest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SampleDigest")
            .field("samples", &self.samples)
            .field("failed", &self.failed)
            .finish_non_exhaustive()
    }
}

impl SampleDigest {
    /// An empty digest.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one sample line (its bytes including `\n`) and whether it failed.
    pub fn add_line(&mut self, line: &[u8], failed: bool) {
        self.hasher.update(line);
        self.samples += 1;
        self.failed += u64::from(failed);
    }

    /// Number of lines added so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Number of failed lines added so far.
    pub fn failed(&self) -> u64 {
        self.failed
    }

    /// The SHA-256 (hex) of the lines added so far.
    pub fn sha256(&self) -> String {
        hex(&self.hasher.clone().finalize())
    }

    /// The end record of a version-1 file (no begin digest) for the lines added so far.
    pub fn end(&self) -> End {
        End {
            samples: self.samples,
            failed: self.failed,
            sha256: self.sha256(),
            begin_sha256: None,
        }
    }
}

/// SHA-256 (lower-case hex) of `bytes`: of a begin line, for `begin_sha256`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// Lower-case hex of bytes.
pub fn hex(bytes: &[u8]) -> String {
    use std::fmt::Write;
    bytes
        .iter()
        .fold(String::with_capacity(2 * bytes.len()), |mut s, b| {
            let _ = write!(s, "{b:02x}");
            s
        })
}

impl Begin {
    /// A header for `range` of job `job_id`, written by this program version, in format
    /// version 1 (no checkpoints, the begin line not covered by a digest): the plain form
    /// for fixtures. Writers chain [`Begin::with_checkpoints`] to write version 2.
    pub fn new(
        program: &str,
        program_version: &str,
        job_id: &str,
        range: ShardRange,
        job_samples: u64,
        cases: Vec<CaseInfo>,
    ) -> Self {
        Self {
            format: FORMAT.to_string(),
            format_version: 1,
            program: program.to_string(),
            program_version: program_version.to_string(),
            job_id: job_id.to_string(),
            range,
            job_samples,
            cases,
            checkpoint_every: None,
            budget: None,
        }
    }

    /// This header with the job's alignment budget.
    pub fn with_budget(mut self, budget: Option<Budget>) -> Self {
        self.budget = budget;
        self
    }

    /// This header in the current format version ([`FORMAT_VERSION`]) with a checkpoint
    /// line after every `every` sample lines.
    pub fn with_checkpoints(mut self, every: u64) -> Self {
        self.format_version = FORMAT_VERSION;
        self.checkpoint_every = Some(every);
        self
    }

    /// Whether `self` describes the same job and shard as `other`: job id, range, sample
    /// count, cases with their parameters and the budget (not the writer, its version, or
    /// the format).
    pub fn same_shard(&self, other: &Begin) -> bool {
        self.job_id == other.job_id
            && self.range == other.range
            && self.job_samples == other.job_samples
            && self.cases == other.cases
            && self.budget == other.budget
    }

    /// Checks the header's own consistency: format name and version, job id shape, the
    /// range inside the job, and the cases tiling `0..job_samples` in order.
    pub fn check(&self) -> Result<(), String> {
        if self.format != FORMAT {
            return Err(format!("format is {:?}, expected {FORMAT:?}", self.format));
        }
        if self.format_version == 0 || self.format_version > FORMAT_VERSION {
            return Err(format!(
                "format_version {} is not supported (this reader knows 1..={FORMAT_VERSION})",
                self.format_version
            ));
        }
        match (self.format_version, self.checkpoint_every) {
            (1, None) => {}
            (1, Some(_)) => {
                return Err("checkpoint_every in a format_version 1 header".into());
            }
            (_, Some(n)) if (1..=MAX_CHECKPOINT_EVERY).contains(&n) => {}
            (v, Some(n)) => {
                return Err(format!(
                    "checkpoint_every {n} is outside 1..={MAX_CHECKPOINT_EVERY} (format_version {v})"
                ));
            }
            (v, None) => {
                return Err(format!("format_version {v} needs checkpoint_every"));
            }
        }
        if self.job_id.len() != 64
            || !self
                .job_id
                .bytes()
                .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
        {
            return Err(format!(
                "job_id {:?} is not 64 lower-case hex digits",
                self.job_id
            ));
        }
        if let Some(b) = &self.budget {
            b.check()?;
        }
        if self.range.start > self.range.end || self.range.end > self.job_samples {
            return Err(format!(
                "range {} is not inside the job's 0..{}",
                self.range, self.job_samples
            ));
        }
        let mut next = 0;
        for case in &self.cases {
            if case.start != next {
                return Err(format!(
                    "case {:?} starts at {} where {} was expected",
                    case.name, case.start, next
                ));
            }
            next = next
                .checked_add(case.samples)
                .ok_or_else(|| format!("case {:?}: sample counts overflow", case.name))?;
        }
        if next != self.job_samples {
            return Err(format!(
                "cases cover 0..{next} but job_samples is {}",
                self.job_samples
            ));
        }
        Ok(())
    }

    /// The case that global index `index` belongs to, with the index within that case.
    pub fn case_of(&self, index: u64) -> Option<(&CaseInfo, u64)> {
        let pos = self.cases.partition_point(|c| c.start + c.samples <= index);
        self.cases
            .get(pos)
            .filter(|c| c.range().contains(index))
            .map(|c| (c, index - c.start))
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod tests_v2;
