//! The random draws: pinned bit for bit, and distributed as documented.

use mc_shard::distribution::{Constant, DistributionSpec, Normal, TruncatedNormal, Uniform};
use mc_shard::sampler::{sample_stream, stream_key};
use rand_core::Rng;

/// Golden values: the key of (seed 20210325, case "golden"), the first four words of stream 7,
/// and the normal, uniform and truncated normal values they give. An upgrade of sha2, rand_chacha or libm (or
/// a change of the documented contract) that changes any draw fails here instead of silently
/// changing results.
#[test]
fn draws_are_pinned_bit_for_bit() {
    let key = stream_key(20210325, "golden");
    assert_eq!(
        shard_record::hex(&key),
        "8cd48c5a7648e697718cfbe0e512cf430d06027d492e324d3b430429d919c7f7"
    );
    let mut rng = sample_stream(&key, 7);
    let w: Vec<u64> = (0..4).map(|_| rng.next_u64()).collect();
    assert_eq!(
        w,
        [
            0xd536346cfb345054,
            0xf88c8d0f5fcc696d,
            0xeb71c321aca5cbc2,
            0x73045f3dadb6bcc0
        ]
    );
    let normal = DistributionSpec::Normal(Normal {
        mean: 0.0,
        sigma: 0.0063,
    });
    assert_eq!(normal.from_words(w[0], w[1]).to_bits(), 0x3f6eb16993e8959c);
    let uniform = DistributionSpec::Uniform(Uniform {
        low: -0.2,
        high: 0.2,
    });
    assert_eq!(uniform.from_words(w[2], w[3]).to_bits(), 0xbf94c5ce03b6dba8);
    // −0.00798418591979574 and 0.009738818987858335 mm: Python's
    // `statistics.NormalDist().inv_cdf` gives the same from the module doc's formula.
    let truncated = DistributionSpec::TruncatedNormal(TruncatedNormal {
        mean: 0.0,
        sigma: 0.0063,
        limit: 0.0126,
    });
    assert_eq!(
        truncated.from_words(w[0], w[1]).to_bits(),
        0xbf805a034b492070
    );
    assert_eq!(
        truncated.from_words(w[2], w[3]).to_bits(),
        0x3f83f1f2286fa5c1
    );
}

/// The draws follow their distributions: 200,000 normals have mean 0 and variance σ²
/// within 4 standard errors, and the fractions below −1σ, 0 and +2σ match Φ; uniforms stay
/// in [low, high) with mean and variance of U(low, high).
#[test]
fn draws_follow_their_distributions() {
    let key = stream_key(1, "moments");
    let n = 200_000;
    let normal = DistributionSpec::Normal(Normal {
        mean: 0.5,
        sigma: 2.0,
    });
    let (mut s1, mut s2) = (0.0, 0.0);
    let mut below = [0u32; 3];
    for k in 0..n / 1000 {
        let mut rng = sample_stream(&key, k);
        for _ in 0..1000 {
            let x = rand_distr::Distribution::<f64>::sample(&normal, &mut rng);
            let z = (x - 0.5) / 2.0;
            s1 += z;
            s2 += z * z;
            for (b, t) in below.iter_mut().zip([-1.0, 0.0, 2.0]) {
                *b += u32::from(z < t);
            }
        }
    }
    let nf = n as f64;
    let mean = s1 / nf;
    let var = s2 / nf - mean * mean;
    assert!(mean.abs() < 4.0 / nf.sqrt(), "mean {mean}");
    assert!(
        (var - 1.0).abs() < 4.0 * (2.0 / nf).sqrt(),
        "variance {var}"
    );
    for (b, p) in below.iter().zip([0.158655, 0.5, 0.977250]) {
        let f = *b as f64 / nf;
        assert!(
            (f - p).abs() < 4.0 * (p * (1.0 - p) / nf).sqrt(),
            "{f} vs {p}"
        );
    }
    let uniform = DistributionSpec::Uniform(Uniform {
        low: -0.2,
        high: 0.1,
    });
    let mut rng = sample_stream(&key, 999_999);
    let xs: Vec<f64> = (0..100_000)
        .map(|_| rand_distr::Distribution::<f64>::sample(&uniform, &mut rng))
        .collect();
    assert!(xs.iter().all(|&x| (-0.2..0.1).contains(&x)));
    let m = xs.iter().sum::<f64>() / xs.len() as f64;
    let v = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / xs.len() as f64;
    assert!(
        (m + 0.05).abs() < 4.0 * (0.09f64 / 12.0 / 1e5).sqrt(),
        "{m}"
    );
    assert!((v - 0.09 / 12.0).abs() < 0.02 * 0.09 / 12.0, "{v}");
}

/// Each draw takes exactly two words, whatever the distribution.
#[test]
fn every_draw_takes_two_words() {
    let key = stream_key(3, "words");
    for dist in [
        DistributionSpec::Normal(Normal {
            mean: 0.0,
            sigma: 1.0,
        }),
        DistributionSpec::Uniform(Uniform {
            low: 0.0,
            high: 1.0,
        }),
        DistributionSpec::Constant(Constant { value: 2.0 }),
        DistributionSpec::TruncatedNormal(TruncatedNormal {
            mean: 0.0,
            sigma: 1.0,
            limit: 2.0,
        }),
    ] {
        let mut a = sample_stream(&key, 0);
        let mut b = sample_stream(&key, 0);
        rand_distr::Distribution::<f64>::sample(&dist, &mut a);
        b.next_u64();
        b.next_u64();
        assert_eq!(a.next_u64(), b.next_u64(), "{dist:?}");
    }
}

/// A job with truncated normal length errors runs end to end: `inputs` writes the sampler's
/// own draws, each within ±limit, and `run` converges every sample and marks the case's
/// shape in the shard's header.
#[test]
fn truncated_normal_jobs_draw_and_run() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"{"model": {"prism": {"stages": 2}}, "seed": 5, "cases": [
        {"name": "scrapped", "samples": 20, "length_errors": {
            "batten": {"truncated_normal": {"sigma": 0.0063, "limit": 0.0126}},
            "longeron": {"truncated_normal": {"sigma": 0.0063, "limit": 0.0063}}}}]}"#;
    let path = crate::common::write(dir.path(), "job.json", text);
    let csv = dir.path().join("inputs.csv");
    let o = crate::binary::mc_shard(&[
        "inputs",
        "--job",
        path.to_str().unwrap(),
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let job = mc_shard::Job::read(&path).unwrap();
    let case = &job.cases[0];
    let key = stream_key(job.seed, &case.name);
    let table = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = table.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 21);
    let mut errors = Vec::new();
    for (k, row) in rows[1..].iter().enumerate() {
        mc_shard::sampler::draw_length_errors(&key, case, k as u64, &mut errors);
        for (h, cell) in rows[0][3..].iter().zip(&row[3..]) {
            let id = h.strip_prefix("length_error:").unwrap();
            let m = case
                .model
                .members()
                .iter()
                .position(|m| m.id == id)
                .unwrap();
            let v: f64 = cell.parse().unwrap();
            assert_eq!(v.to_bits(), errors[m].to_bits(), "{id}");
            let limit = if id.starts_with("batten") {
                0.0126
            } else {
                0.0063
            };
            assert!(v.abs() <= limit, "{id}: {v}");
        }
    }
    let out = dir.path().join("out");
    let o = crate::binary::mc_shard(&[
        "run",
        "--job",
        path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--threads",
        "2",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lines = crate::common::sample_lines(&out);
    assert_eq!(lines.len(), 20);
    assert!(lines.iter().all(|l| l.contains(r#""status":"converged""#)));
    let shard = crate::common::only_shard(&out);
    let begin = std::fs::read_to_string(shard).unwrap();
    assert!(begin.contains(r#""truncated_normal":2.0"#), "{begin}");
}

/// A job with lot-shared length errors: `inputs` writes the summed errors, so the battens of
/// one level, which have no scatter of their own (σ_part = 0), share one value per sample,
/// different from the next level's, and those are the sampler's draws bit for bit.
#[test]
fn inputs_write_the_lots_shared_errors() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"{"model": {"prism": {"stages": 2}}, "seed": 5, "cases": [
        {"name": "lots", "samples": 10, "length_errors": {
            "batten": {"normal": {"sigma": 0}, "lot": {"by": "level", "normal": {"sigma": 0.003}}},
            "longeron": {"normal": {"sigma": 0.0063}}}}]}"#;
    let path = crate::common::write(dir.path(), "job.json", text);
    let csv = dir.path().join("inputs.csv");
    let o = crate::binary::mc_shard(&[
        "inputs",
        "--job",
        path.to_str().unwrap(),
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let job = mc_shard::Job::read(&path).unwrap();
    let case = &job.cases[0];
    let key = stream_key(job.seed, &case.name);
    let table = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = table.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 11);
    let column = |id: &str| {
        rows[0]
            .iter()
            .position(|h| *h == format!("length_error:{id}"))
            .unwrap()
    };
    let mut errors = Vec::new();
    for (k, row) in rows[1..].iter().enumerate() {
        mc_shard::sampler::draw_length_errors(&key, case, k as u64, &mut errors);
        for level in 0..3 {
            let first = row[column(&format!("batten.{level}.0"))];
            for j in 1..3 {
                assert_eq!(row[column(&format!("batten.{level}.{j}"))], first);
            }
            let m = case
                .model
                .member_index(&format!("batten.{level}.0"))
                .unwrap();
            assert_eq!(first.parse::<f64>().unwrap().to_bits(), errors[m].to_bits());
        }
        assert_ne!(row[column("batten.0.0")], row[column("batten.1.0")]);
    }
}
