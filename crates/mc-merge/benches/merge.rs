//! `cargo bench -p mc-merge`: merging 50,000 samples (one case, 4 shards) with B = 2000
//! bootstrap replicates and 1000 goodness-of-fit null samples, the brief's yardstick (< 1 s),
//! and the bootstrap alone. The shards are written once into a temporary directory.

#[path = "../tests/it/common/mod.rs"]
mod common;

use common::{SynthCase, SynthJob};
use criterion::{Criterion, criterion_group, criterion_main};
use mc_merge::Settings;
use mc_merge::bootstrap::{BootstrapConfig, SortedSample, bootstrap_quantiles};
use std::time::Duration;

fn merge_50k(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let job = SynthJob::new(
        1,
        vec![SynthCase::rayleigh(
            "sigma-0.0063",
            50_000,
            3.96e-5,
            &[("sigma", 0.0063), ("stages", 5.0)],
        )],
    );
    job.write_split(dir.path(), 4);
    let paths = vec![dir.path().to_path_buf()];
    let settings = Settings::default();
    let mut g = c.benchmark_group("merge");
    g.sample_size(10).measurement_time(Duration::from_secs(15));
    g.bench_function("50k samples, B = 2000 (verify + statistics)", |b| {
        b.iter(|| mc_merge::merge(&paths, &settings).unwrap())
    });
    let data = mc_merge::merge(&paths, &settings).unwrap().dataset;
    let sample = SortedSample::new(data.cases[0].points().map(|p| (p.theta, p.index)).collect());
    let config = BootstrapConfig {
        replicates: 2000,
        seed: 1,
        threads: settings.threads,
    };
    g.bench_function("bootstrap only, 50k x 2000, 4 percentiles", |b| {
        b.iter(|| bootstrap_quantiles(&sample, &[0.5, 0.9, 0.95, 0.99], &config))
    });
    g.finish();
}

criterion_group!(benches, merge_50k);
criterion_main!(benches);
