//! Unit tests of the record format: round trips, the partition contract, and the scanner's
//! verdicts on good, torn, incomplete and corrupt files.

use super::*;
use proptest::prelude::*;
use std::io::Write;

fn begin(range: ShardRange) -> Begin {
    Begin::new(
        "mc-shard",
        "0.1.0",
        &"ab".repeat(32),
        range,
        10,
        vec![
            CaseInfo {
                name: "a".into(),
                start: 0,
                samples: 4,
                parameters: [("sigma".to_string(), 0.0063)].into(),
            },
            CaseInfo {
                name: "b".into(),
                start: 4,
                samples: 6,
                parameters: Default::default(),
            },
        ],
    )
}

fn sample(index: u64, theta: f64) -> Sample {
    let (case, k) = if index < 4 {
        ("a", index)
    } else {
        ("b", index - 4)
    };
    Sample {
        index,
        case: case.into(),
        sample: k,
        status: Status::Converged,
        iterations: 3,
        theta_p: Some(theta),
        tan_theta_x: Some(-theta / 2.0),
        tan_theta_y: Some(theta / 3.0),
        decenter_x: Some(3.0 * theta),
        decenter_y: Some(-4.0 * theta),
        decenter: Some(5.0 * theta),
        despace: Some(-theta),
        residual: Some(1e-12),
        slack_cables: Some(2),
        loose_joints: None,
        floating: None,
        holding_force: None,
        limit_ratio: None,
        reason: None,
    }
}

/// Writes a shard of `range` and returns its bytes.
fn shard_bytes(range: ShardRange) -> Vec<u8> {
    let mut out = to_line(&Record::Begin(begin(range))).into_bytes();
    let mut digest = SampleDigest::new();
    for i in range.start..range.end {
        let line = sample(i, 1e-5 * (i as f64 + 0.1)).to_line();
        digest.add_line(line.as_bytes(), false);
        out.extend_from_slice(line.as_bytes());
    }
    out.extend_from_slice(to_line(&Record::End(digest.end())).as_bytes());
    out
}

fn write_temp(bytes: &[u8]) -> tempfile::NamedTempFile {
    let mut f = tempfile::NamedTempFile::new().unwrap();
    f.write_all(bytes).unwrap();
    f
}

#[test]
fn floats_round_trip_bit_exact() {
    for x in [
        1e-5,
        0.1 + 0.2,
        std::f64::consts::PI * 1e-7,
        f64::MIN_POSITIVE,
        9.690000000000001e-5,
        -3.3e-300,
    ] {
        let line = sample(0, x).to_line();
        let Record::Sample(back) = parse_record(line.as_bytes()).unwrap() else {
            panic!("not a sample")
        };
        assert_eq!(back.theta_p.unwrap().to_bits(), x.to_bits(), "{line}");
        assert_eq!(back.to_line(), line);
    }
}

#[test]
fn complete_shard_scans_and_reads() {
    let range = ShardRange::new(2, 7);
    let bytes = shard_bytes(range);
    let f = write_temp(&bytes);
    let mut seen = vec![];
    let scan = read_shard(f.path(), |_, s, _| {
        seen.push(s.index);
        Ok(())
    })
    .unwrap();
    assert_eq!(seen, vec![2, 3, 4, 5, 6]);
    assert!(scan.is_complete());
    assert_eq!(scan.valid_len, bytes.len() as u64);
}

#[test]
fn torn_last_line_is_reported_with_valid_prefix() {
    let bytes = shard_bytes(ShardRange::new(0, 5));
    let lines: Vec<&[u8]> = bytes.split_inclusive(|&b| b == b'\n').collect();
    // Header, two samples, and half of the third.
    let mut torn = [lines[0], lines[1], lines[2]].concat();
    let prefix = torn.len() as u64;
    torn.extend_from_slice(&lines[3][..lines[3].len() / 2]);
    let f = write_temp(&torn);
    let scan = scan_shard(f.path(), |_, _, _| Ok(())).unwrap();
    assert_eq!(scan.tail, Tail::Torn { line: 4 });
    assert_eq!(scan.valid_len, prefix);
    assert_eq!(scan.next_index(), 2);
    let err = read_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(matches!(err, ScanError::Torn { line: 4, .. }), "{err}");
}

#[test]
fn missing_end_line_is_incomplete() {
    let bytes = shard_bytes(ShardRange::new(0, 3));
    let cut = bytes[..bytes.len() - 1]
        .iter()
        .rposition(|&b| b == b'\n')
        .unwrap()
        + 1;
    let f = write_temp(&bytes[..cut]);
    let scan = scan_shard(f.path(), |_, _, _| Ok(())).unwrap();
    assert_eq!(scan.tail, Tail::Open);
    let err = read_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(err.to_string().contains("3 of the range's 3"), "{err}");
}

#[test]
fn changed_number_breaks_the_digest() {
    let bytes = String::from_utf8(shard_bytes(ShardRange::new(0, 3))).unwrap();
    let tampered = bytes.replacen("\"iterations\":3", "\"iterations\":4", 1);
    let f = write_temp(tampered.as_bytes());
    let err = read_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(
        matches!(err, ScanError::Corrupt { line: 5, .. }) && err.to_string().contains("sha256"),
        "{err}"
    );
}

#[test]
fn out_of_order_and_corrupt_lines_name_their_line() {
    let bytes = String::from_utf8(shard_bytes(ShardRange::new(0, 3))).unwrap();
    let mut lines: Vec<&str> = bytes.split_inclusive('\n').collect();
    lines.swap(1, 2);
    let f = write_temp(lines.concat().as_bytes());
    let err = read_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(matches!(err, ScanError::Corrupt { line: 2, .. }), "{err}");

    let mut lines: Vec<&str> = bytes.split_inclusive('\n').collect();
    lines[2] = "{\"record\":\"sample\",\"index\":\n";
    let f = write_temp(lines.concat().as_bytes());
    let err = read_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(matches!(err, ScanError::Corrupt { line: 3, .. }), "{err}");
}

#[test]
fn converged_without_angles_is_refused() {
    let mut s = sample(0, 1e-5);
    s.theta_p = None;
    assert!(s.check().is_err());
    s.theta_p = Some(f64::NAN);
    assert!(s.check().is_err());
}

/// A holding force must be a finite number of newtons ≥ 0 where a sample has one.
#[test]
fn a_holding_force_that_is_no_force_is_refused() {
    let mut s = sample(0, 1e-5);
    for ok in [None, Some(0.0), Some(2.5e-9)] {
        s.holding_force = ok;
        assert!(s.check().is_ok(), "{ok:?}");
    }
    for bad in [-1e-9, f64::NAN, f64::INFINITY] {
        s.holding_force = Some(bad);
        let err = s.check().unwrap_err();
        assert!(err.contains("holding_force"), "{bad}: {err}");
    }
}

/// A limit ratio must be a finite compression ratio > 0 where a sample has one.
#[test]
fn a_limit_ratio_that_is_no_ratio_is_refused() {
    let mut s = sample(0, 1e-5);
    for ok in [None, Some(1e-12), Some(2.0e-7)] {
        s.limit_ratio = ok;
        assert!(s.check().is_ok(), "{ok:?}");
    }
    for bad in [0.0, -1e-9, f64::NAN, f64::INFINITY] {
        s.limit_ratio = Some(bad);
        let err = s.check().unwrap_err();
        assert!(err.contains("limit_ratio"), "{bad}: {err}");
    }
}

#[test]
fn header_checks_case_tiling() {
    let mut b = begin(ShardRange::new(0, 10));
    assert!(b.check().is_ok());
    b.cases[1].start = 5;
    assert!(b.check().unwrap_err().contains("starts at 5"));
    let mut b = begin(ShardRange::new(0, 11));
    b.job_samples = 10;
    assert!(b.check().is_err());
    assert_eq!(begin(ShardRange::new(0, 1)).case_of(4).unwrap().1, 0);
    assert_eq!(begin(ShardRange::new(0, 1)).case_of(9).unwrap().0.name, "b");
    assert!(begin(ShardRange::new(0, 1)).case_of(10).is_none());
}

#[test]
fn shard_specs_parse() {
    assert_eq!(ShardRange::parse_shard_spec("3/8").unwrap(), (3, 8));
    assert!(ShardRange::parse_shard_spec("8/8").is_err());
    assert!(ShardRange::parse_shard_spec("x/8").is_err());
    assert_eq!(
        "10..20".parse::<ShardRange>().unwrap(),
        ShardRange::new(10, 20)
    );
    assert!("20..10".parse::<ShardRange>().is_err());
    assert_eq!(
        ShardRange::new(0, 50000).file_name(),
        "shard-0000000000-0000050000.jsonl"
    );
}

proptest! {
    /// The partition contract: contiguous, disjoint, covering, sizes within one.
    #[test]
    fn partition_tiles_the_job(samples in 0u64..1_000_000, count in 1u64..200) {
        let parts = ShardRange::partition(count, samples).unwrap();
        prop_assert_eq!(parts.len() as u64, count);
        prop_assert_eq!(parts[0].start, 0);
        prop_assert_eq!(parts.last().unwrap().end, samples);
        for w in parts.windows(2) {
            prop_assert_eq!(w[0].end, w[1].start);
        }
        let min = parts.iter().map(|r| r.len()).min().unwrap();
        let max = parts.iter().map(|r| r.len()).max().unwrap();
        prop_assert!(max - min <= 1);
    }
}

/// The four placement fields come all or none, finite, with decenter ≥ 0; a sample without
/// them (a shard of numerics 7 or earlier) still checks, with no placement.
#[test]
fn placement_fields_are_checked() {
    let good = sample(0, 1e-5);
    good.check().unwrap();
    assert_eq!(good.placement().unwrap().decenter, 5e-5);
    let without = Sample {
        decenter_x: None,
        decenter_y: None,
        decenter: None,
        despace: None,
        ..good.clone()
    };
    without.check().unwrap();
    assert!(without.placement().is_none());
    let partial = Sample {
        despace: None,
        ..good.clone()
    };
    assert!(partial.check().unwrap_err().contains("all four or none"));
    let negative = Sample {
        decenter: Some(-1e-5),
        ..good.clone()
    };
    assert!(negative.check().unwrap_err().contains("decenter ≥ 0"));
    let infinite = Sample {
        decenter_x: Some(f64::INFINITY),
        ..good
    };
    assert!(infinite.check().is_err());
}

/// A budget round-trips in the begin line, is checked with the header, and is part of what
/// makes two headers the same shard.
#[test]
fn budgets_ride_in_the_begin_line() {
    let budget = Budget {
        percentile: 95.0,
        theta_p: Some(9.6963e-5),
        decenter: Some(0.05),
        despace: None,
    };
    let b = begin(ShardRange::new(0, 8)).with_budget(Some(budget));
    b.check().unwrap();
    let line = to_line(&Record::Begin(b.clone()));
    assert!(
        line.contains(r#""budget":{"percentile":95.0,"theta_p":0.000096963,"decenter":0.05}"#),
        "{line}"
    );
    match parse_record(line.trim_end().as_bytes()).unwrap() {
        Record::Begin(back) => assert_eq!(back, b),
        other => panic!("{other:?}"),
    }
    assert!(!b.same_shard(&begin(ShardRange::new(0, 8))));
    assert_eq!(
        budget.lines(),
        vec![("theta_p", 9.6963e-5), ("decenter", 0.05)]
    );
    for bad in [
        Budget {
            percentile: 100.0,
            ..budget
        },
        Budget {
            decenter: Some(0.0),
            ..budget
        },
        Budget {
            theta_p: Some(f64::NAN),
            ..budget
        },
        Budget {
            theta_p: None,
            decenter: None,
            despace: None,
            ..budget
        },
    ] {
        assert!(
            begin(ShardRange::new(0, 8))
                .with_budget(Some(bad))
                .check()
                .is_err(),
            "{bad:?}"
        );
    }
}
