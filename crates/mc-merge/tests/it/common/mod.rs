//! Synthetic shard files for tests and benchmarks, written with `shard_record`'s own types so
//! that they are valid by construction (digests included).
//!
//! A sample's angles are a pure function of (seed, global index): tan θ_x and tan θ_y are
//! N(0, σ_t²) by Box–Muller from the counter-based generator, and θ_P = atan √(tan²θ_x + tan²θ_y)
//! (paper eq. 7), Rayleigh(σ_t) to first order (eq. 26). So any split of a job writes the same
//! samples.

#![allow(dead_code)]

use mc_merge::rng::{self, Stream};
use shard_record::{Begin, CaseInfo, Record, Sample, SampleDigest, ShardRange, Status, to_line};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// How a case's angles are drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// tan θ_x, tan θ_y ~ N(0, σ_t²): θ_P Rayleigh.
    Rayleigh,
    /// θ_P uniform on [0, 3σ_t] (clearly not Rayleigh), tan components split at a random angle.
    Uniform,
}

/// One synthetic case.
#[derive(Debug, Clone)]
pub struct SynthCase {
    /// Name.
    pub name: String,
    /// Samples.
    pub samples: u64,
    /// Parameters (sigma in mm, stages, ...).
    pub parameters: BTreeMap<String, f64>,
    /// σ_t of the slopes \[-\].
    pub sigma_t: f64,
    /// The law.
    pub law: Law,
    /// Every k-th sample (within the case) fails, if set.
    pub fail_every: Option<u64>,
    /// Whether samples record loose_joints (sample k has k % 4 loose joints).
    pub loose: bool,
    /// If set, samples record `floating`, true for every n-th sample within the case.
    pub floating_every: Option<u64>,
    /// If set, every n-th converged sample within the case records a `limit_ratio` (its
    /// equilibrium a stage of the limit's continuation: 1e-12 times 1 to 7).
    pub limit_stage_every: Option<u64>,
}

impl SynthCase {
    /// A Rayleigh case.
    pub fn rayleigh(name: &str, samples: u64, sigma_t: f64, params: &[(&str, f64)]) -> Self {
        Self {
            name: name.into(),
            samples,
            parameters: params.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
            sigma_t,
            law: Law::Rayleigh,
            fail_every: None,
            loose: false,
            floating_every: None,
            limit_stage_every: None,
        }
    }
}

/// A synthetic job.
#[derive(Debug, Clone)]
pub struct SynthJob {
    /// 64 hex digits.
    pub job_id: String,
    /// Seed of the angles.
    pub seed: u64,
    /// The cases.
    pub cases: Vec<SynthCase>,
    /// The alignment budget the begin lines carry, if any.
    pub budget: Option<shard_record::Budget>,
}

impl SynthJob {
    /// A job with the given cases.
    pub fn new(seed: u64, cases: Vec<SynthCase>) -> Self {
        Self {
            job_id: format!("{:016x}", rng::mix64(seed)).repeat(4),
            seed,
            cases,
            budget: None,
        }
    }

    /// Total samples.
    pub fn samples(&self) -> u64 {
        self.cases.iter().map(|c| c.samples).sum()
    }

    /// The header's case list.
    pub fn case_infos(&self) -> Vec<CaseInfo> {
        let mut start = 0;
        self.cases
            .iter()
            .map(|c| {
                let info = CaseInfo {
                    name: c.name.clone(),
                    start,
                    samples: c.samples,
                    parameters: c.parameters.clone(),
                };
                start += c.samples;
                info
            })
            .collect()
    }

    /// The sample at global `index`.
    pub fn sample(&self, index: u64) -> Sample {
        let mut start = 0;
        let mut case = &self.cases[0];
        for c in &self.cases {
            if index < start + c.samples {
                case = c;
                break;
            }
            start += c.samples;
        }
        let k = index - start;
        let key = rng::replicate_key(self.seed, Stream::Synthetic, 0);
        let u1 = rng::open01(rng::bits(key, 2 * index));
        let u2 = rng::open01(rng::bits(key, 2 * index + 1));
        let failed = case.fail_every.is_some_and(|e| k % e == e - 1);
        let (tx, ty) = match case.law {
            Law::Rayleigh => {
                let r = case.sigma_t * (-2.0 * u1.ln()).sqrt();
                let a = 2.0 * std::f64::consts::PI * u2;
                (r * a.cos(), r * a.sin())
            }
            Law::Uniform => {
                let r = 3.0 * case.sigma_t * u1;
                let a = 2.0 * std::f64::consts::PI * u2;
                (r * a.cos(), r * a.sin())
            }
        };
        // Decenter from the same draws, 1000 mm per unit tangent (so Rayleigh where θ_P
        // is), and a despace N(0, (700 σ_t mm)²) from a stream of its own.
        let zkey = rng::replicate_key(self.seed, Stream::Synthetic, 1);
        let z = rng::box_muller(
            rng::open01(rng::bits(zkey, 2 * index)),
            rng::open01(rng::bits(zkey, 2 * index + 1)),
        );
        let (dx, dy) = (1000.0 * tx, 1000.0 * ty);
        Sample {
            index,
            case: case.name.clone(),
            sample: k,
            status: if failed {
                Status::Failed
            } else {
                Status::Converged
            },
            iterations: if failed { 60 } else { 3 + (index % 3) as u32 },
            theta_p: (!failed).then(|| (tx * tx + ty * ty).sqrt().atan()),
            tan_theta_x: (!failed).then_some(tx),
            tan_theta_y: (!failed).then_some(ty),
            decenter_x: (!failed).then_some(dx),
            decenter_y: (!failed).then_some(dy),
            decenter: (!failed).then_some(dx.hypot(dy)),
            despace: (!failed).then_some(700.0 * case.sigma_t * z),
            residual: (!failed).then_some(1e-11),
            slack_cables: (!failed).then_some((index % 5) as u32),
            loose_joints: (case.loose && !failed).then_some((k % 4) as u32),
            floating: case
                .floating_every
                .filter(|_| !failed)
                .map(|n| k.is_multiple_of(n)),
            // Where `floating` is recorded: a floating sample held by nanonewtons, the
            // others by millinewtons, each times 1 to 7.
            holding_force: case.floating_every.filter(|_| !failed).map(|n| {
                let scale = if k.is_multiple_of(n) { 1e-9 } else { 1e-3 };
                scale * (1 + k % 7) as f64
            }),
            limit_ratio: case
                .limit_stage_every
                .filter(|n| !failed && k.is_multiple_of(*n))
                .map(|_| 1e-12 * (1 + k % 7) as f64),
            reason: failed
                .then(|| format!("Newton did not converge in 60 iterations (sample {k})")),
        }
    }

    /// The begin line of a shard of `range`.
    pub fn begin(&self, range: ShardRange) -> Begin {
        Begin::new(
            "mc-shard",
            "0.1.0",
            &self.job_id,
            range,
            self.samples(),
            self.case_infos(),
        )
        .with_budget(self.budget)
    }

    /// The bytes of a complete shard of `range`.
    pub fn shard_bytes(&self, range: ShardRange) -> Vec<u8> {
        self.shard_bytes_with(range, |_| {})
    }

    /// The bytes of a complete, valid shard of `range` whose samples pass through `edit`
    /// (the digest is computed after the edit, so the file verifies on its own).
    pub fn shard_bytes_with(&self, range: ShardRange, edit: impl Fn(&mut Sample)) -> Vec<u8> {
        let mut out = to_line(&Record::Begin(self.begin(range))).into_bytes();
        let mut digest = SampleDigest::new();
        for i in range.start..range.end {
            let mut s = self.sample(i);
            edit(&mut s);
            let line = s.to_line();
            digest.add_line(line.as_bytes(), s.status == Status::Failed);
            out.extend_from_slice(line.as_bytes());
        }
        out.extend_from_slice(to_line(&Record::End(digest.end())).as_bytes());
        out
    }

    /// Writes a shard of `range` into `dir` (streaming, for large shards) and returns its path.
    pub fn write_shard(&self, dir: &Path, range: ShardRange) -> PathBuf {
        let path = dir.join(range.file_name());
        let file = std::fs::File::create(&path).unwrap();
        let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
        w.write_all(to_line(&Record::Begin(self.begin(range))).as_bytes())
            .unwrap();
        let mut digest = SampleDigest::new();
        for i in range.start..range.end {
            let s = self.sample(i);
            let line = s.to_line();
            digest.add_line(line.as_bytes(), s.status == Status::Failed);
            w.write_all(line.as_bytes()).unwrap();
        }
        w.write_all(to_line(&Record::End(digest.end())).as_bytes())
            .unwrap();
        w.flush().unwrap();
        path
    }

    /// Writes `bytes` as the shard file of `range` in `dir` under an optional name suffix.
    pub fn write_bytes(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    /// Writes the job split into `k` shards (the shard-record partition) into `dir`.
    pub fn write_split(&self, dir: &Path, k: u64) -> Vec<PathBuf> {
        ShardRange::partition(k, self.samples())
            .unwrap()
            .into_iter()
            .map(|r| self.write_shard(dir, r))
            .collect()
    }
}
