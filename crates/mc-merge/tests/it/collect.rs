//! Samples from memory ([`mc_merge::load::Collector`]: a run in-process, shards the Python
//! package read back) give the report `mc-merge` writes for shard files of the same lines,
//! byte for byte, in whatever order they are added; and they meet the merge's refusals: an
//! index outside the job, a second copy that differs, a θ_P that is no angle, missing samples
//! unless partial results are asked for.

use crate::common::{SynthCase, SynthJob};
use mc_merge::load::{Collector, LoadOptions, ShardWriter};
use mc_merge::{MergeError, Settings};
use shard_record::ShardRange;

fn job() -> SynthJob {
    SynthJob::new(
        11,
        vec![
            SynthCase::rayleigh("a", 400, 2e-5, &[("sigma", 0.0033), ("stages", 5.0)]),
            SynthCase::rayleigh("b", 300, 4e-5, &[("sigma", 0.0066), ("stages", 5.0)]),
        ],
    )
}

fn settings() -> Settings {
    Settings {
        replicates: 200,
        gof_replicates: 99,
        ..Default::default()
    }
}

fn collector(j: &SynthJob) -> Collector {
    let writer = ShardWriter {
        program: "test".into(),
        program_version: "0".into(),
        format_version: shard_record::FORMAT_VERSION,
        files: 0,
    };
    Collector::new(j.job_id.clone(), j.samples(), &j.case_infos(), writer)
}

fn options(allow_partial: bool) -> LoadOptions {
    LoadOptions {
        allow_partial,
        ..Default::default()
    }
}

#[test]
fn samples_from_memory_give_the_merges_report_byte_for_byte() {
    let j = job();
    let dir = tempfile::tempdir().unwrap();
    j.write_split(dir.path(), 3);
    let merged = mc_merge::merge(&[dir.path().to_path_buf()], &settings()).unwrap();
    let from_files = mc_merge::report_json(&merged.report).unwrap();
    // Added backwards, one index twice with the same line.
    let mut c = collector(&j);
    for index in (0..j.samples()).rev().chain([5]) {
        let s = j.sample(index);
        c.add(&s, s.to_line().as_bytes()).unwrap();
    }
    let data = c.finish(options(false)).unwrap();
    let report = mc_merge::build_report(&data, &settings()).unwrap();
    assert_eq!(mc_merge::report_json(&report).unwrap(), from_files);
    assert_eq!(
        mc_merge::table::answer(&report),
        mc_merge::table::answer(&merged.report)
    );
}

#[test]
fn samples_from_memory_meet_the_merges_refusals() {
    let j = job();
    let mut c = collector(&j);
    let s = j.sample(700);
    let e = c.add(&s, s.to_line().as_bytes()).err().unwrap();
    assert!(
        matches!(e, MergeError::Sample { index: 700, .. }),
        "{e}: index 700 is outside a job of 700"
    );
    let mut s = j.sample(3);
    c.add(&s, s.to_line().as_bytes()).unwrap();
    s.theta_p = Some(s.theta_p.unwrap() * 1.5);
    let e = c.add(&s, s.to_line().as_bytes()).err().unwrap();
    assert!(e.to_string().contains("different lines"), "{e}");
    s.theta_p = Some(2.0);
    s.index = 4;
    s.sample = 4;
    let e = c.add(&s, s.to_line().as_bytes()).err().unwrap();
    assert!(e.to_string().contains("not a distortion angle"), "{e}");
    assert_eq!(e.exit_code(), truss_exit::VERIFICATION);
    // One case only: missing samples refused, as the merge refuses them, unless allowed,
    // and then every figure says partial, as `--allow-partial` makes them.
    let fill = |c: &mut Collector| {
        for index in 400..700 {
            let s = j.sample(index);
            c.add(&s, s.to_line().as_bytes()).unwrap();
        }
    };
    let mut c = collector(&j);
    fill(&mut c);
    let e = c.finish(options(false)).err().unwrap();
    assert!(matches!(e, MergeError::Missing { present: 300, .. }), "{e}");
    let mut c = collector(&j);
    fill(&mut c);
    let data = c.finish(options(true)).unwrap();
    let partial = Settings {
        allow_partial: true,
        ..settings()
    };
    let report = mc_merge::build_report(&data, &partial).unwrap();
    assert!(!report.coverage.complete);
    assert_eq!(report.cases[1].n, 300);
    assert_eq!(report.cases[0].n, 0);
    let dir = tempfile::tempdir().unwrap();
    j.write_shard(dir.path(), ShardRange::new(400, 700));
    let merged = mc_merge::merge(&[dir.path().to_path_buf()], &partial).unwrap();
    assert_eq!(
        mc_merge::report_json(&report).unwrap(),
        mc_merge::report_json(&merged.report).unwrap()
    );
}
