//! `mc-shard plan`: a job's cases timed on this machine, its estimated CPU time, and a
//! suggested split: this machine, and a cluster only for a job that would take this machine
//! more than [`CLUSTER_WORTHWHILE_SECONDS`].

use crate::job::Job;
use crate::worker::Worker;
use std::fmt::Write;
use std::time::Instant;

/// A job timed on this machine, and what it suggests.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The measured time of one sample of each case, in the job's order \[s\].
    pub seconds_per_sample: Vec<f64>,
    /// The advice, from the estimated CPU time of the whole job.
    pub advice: Advice,
}

impl Plan {
    /// Times a few samples of each case of `job` (at most 50, at most about half a second
    /// in all) and advises a split for this machine's cores.
    pub fn time(job: &Job) -> Plan {
        let mut cpu_seconds = 0.0;
        let mut per_case = Vec::new();
        let mut worker = Worker::new(job);
        for c in &job.cases {
            let n = c.samples.min(50);
            let t = Instant::now();
            let mut done = 0;
            for k in 0..n {
                worker.sample(c.start + k);
                done += 1;
                if t.elapsed().as_secs_f64() > 0.5 / job.cases.len() as f64 {
                    break;
                }
            }
            let each = t.elapsed().as_secs_f64() / done as f64;
            cpu_seconds += each * c.samples as f64;
            per_case.push(each);
        }
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
        Plan {
            seconds_per_sample: per_case,
            advice: Advice::new(cpu_seconds, cores, job.samples()),
        }
    }

    /// The plan as JSON (`plan --json`): the job id, its cases with their timing, the
    /// estimated CPU time and the suggested split.
    pub fn json(&self, job: &Job) -> serde_json::Value {
        serde_json::json!({
            "job_id": job.id,
            "samples": job.samples(),
            "cases": job.cases.iter().zip(&self.seconds_per_sample).map(|(c, t)| serde_json::json!({
                "name": c.name, "start": c.start, "samples": c.samples,
                "parameters": c.parameters, "seconds_per_sample": t,
            })).collect::<Vec<_>>(),
            "estimated_cpu_seconds": self.advice.cpu_seconds,
            "suggested": {"local_threads": self.advice.cores,
                          "cluster_shards": self.advice.cluster_shards.unwrap_or(1),
                          "cluster_advised": self.advice.cluster_shards.is_some()},
        })
    }

    /// The plan as text, for the job file `job_file`: the job id, a line per case, the
    /// estimated CPU time and the suggestion.
    pub fn text(&self, job: &Job, job_file: &str) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "job id   {}", job.id);
        let _ = writeln!(
            s,
            "samples  {} in {} case(s)",
            job.samples(),
            job.cases.len()
        );
        for (c, t) in job.cases.iter().zip(&self.seconds_per_sample) {
            let params: Vec<String> = c
                .parameters
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            let _ = writeln!(
                s,
                "  {:<24} {:>9} samples  indices {}..{}  ~{:.0} µs/sample  {}",
                c.name,
                c.samples,
                c.start,
                c.start + c.samples,
                t * 1e6,
                params.join(" ")
            );
        }
        let _ = writeln!(s, "estimated {:.1} CPU-seconds", self.advice.cpu_seconds);
        let _ = writeln!(s, "{}", self.advice.text(job_file));
        s
    }
}

/// A cluster task's work: about five minutes of one core \[s\].
pub const CLUSTER_TASK_SECONDS: f64 = 300.0;

/// Below this wall time on this machine a job is not worth a cluster \[s\].
pub const CLUSTER_WORTHWHILE_SECONDS: f64 = 600.0;

/// `mc-shard plan`'s suggestion: this machine, and a cluster split only for a job that
/// would take this machine more than [`CLUSTER_WORTHWHILE_SECONDS`].
#[derive(Debug, Clone, PartialEq)]
pub struct Advice {
    /// The job's estimated CPU time \[s\].
    pub cpu_seconds: f64,
    /// This machine's cores.
    pub cores: u64,
    /// Shards of about [`CLUSTER_TASK_SECONDS`] each, when a cluster is worth it.
    pub cluster_shards: Option<u64>,
}

impl Advice {
    /// The advice for a job of `cpu_seconds` CPU time and `samples` samples on `cores` cores.
    pub fn new(cpu_seconds: f64, cores: u64, samples: u64) -> Self {
        let cores = cores.max(1);
        let local = cpu_seconds / cores as f64;
        let cluster_shards = (local > CLUSTER_WORTHWHILE_SECONDS)
            .then(|| ((cpu_seconds / CLUSTER_TASK_SECONDS).ceil() as u64).clamp(2, samples.max(2)));
        Advice {
            cpu_seconds,
            cores,
            cluster_shards,
        }
    }

    /// The line `plan` prints for the job file `job`.
    pub fn text(&self, job: &str) -> String {
        let local = self.cpu_seconds / self.cores as f64;
        let here = format!(
            "suggested: this machine, about {} on {} (truss-mc run-all --job {job} --out DIR)",
            duration(local),
            plural(self.cores, "core", "cores"),
        );
        match self.cluster_shards {
            None => format!("{here}; no cluster needed"),
            Some(k) => format!(
                "{here}; or a cluster, {} of about {} each (--shard I/{k})",
                plural(k, "shard", "shards"),
                duration(self.cpu_seconds / k as f64),
            ),
        }
    }
}

/// `1 shard`, `2 shards`.
fn plural(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// A duration for people: `9.5 s`, `4 min`, `2.5 h`.
fn duration(seconds: f64) -> String {
    if seconds < 60.0 {
        format!("{seconds:.1} s")
    } else if seconds < 5400.0 {
        format!("{:.0} min", seconds / 60.0)
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}

#[cfg(test)]
mod tests {
    use super::Advice;

    /// A job of seconds gets no cluster advice; a long one gets a split with the right
    /// grammar, never "1 shards".
    #[test]
    fn plan_advises_a_cluster_only_for_long_jobs() {
        let short = Advice::new(9.5, 2, 1000).text("job.json");
        assert_eq!(
            short,
            "suggested: this machine, about 4.8 s on 2 cores \
             (truss-mc run-all --job job.json --out DIR); no cluster needed"
        );
        assert!(Advice::new(0.2, 1, 10).text("j").contains("on 1 core "));
        // 20 CPU-hours on 8 cores: 2.5 h here, or 240 shards of 5 min.
        let long = Advice::new(72_000.0, 8, 300_000).text("j");
        assert!(long.contains("about 2.5 h on 8 cores"), "{long}");
        assert!(long.contains("a cluster, 240 shards of about 5 min each (--shard I/240)"));
        // Just over the threshold: at least two shards.
        let edge = Advice::new(700.0, 1, 50).cluster_shards;
        assert_eq!(edge, Some(3));
        assert_eq!(Advice::new(601.0, 1, 50).cluster_shards, Some(3));
        assert_eq!(Advice::new(599.0, 1, 50).cluster_shards, None);
        for cpu in [0.0, 1.0, 650.0, 1e4, 1e6] {
            assert!(!Advice::new(cpu, 1, 100).text("j").contains("1 shards"));
        }
    }
}
