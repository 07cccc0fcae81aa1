//! Unit tests of format version 2: checkpoints and the begin line's digest. A changed digit
//! of a sample line or of a header parameter is found in complete and in incomplete files;
//! an incomplete file is verified up to its last checkpoint, and what follows is reported as
//! unverified, never visited.

use super::*;
use std::io::Write;

const EVERY: u64 = 4;

fn begin(range: ShardRange) -> Begin {
    Begin::new(
        "mc-shard",
        "0.1.0",
        &"cd".repeat(32),
        range,
        30,
        vec![CaseInfo {
            name: "a".into(),
            start: 0,
            samples: 30,
            parameters: [("sigma".to_string(), 0.5)].into(),
        }],
    )
    .with_checkpoints(EVERY)
}

fn sample(index: u64) -> Sample {
    Sample {
        index,
        case: "a".into(),
        sample: index,
        status: if index == 3 {
            Status::Failed
        } else {
            Status::Converged
        },
        iterations: 3,
        theta_p: (index != 3).then_some(1e-5 * (index as f64 + 0.1)),
        tan_theta_x: (index != 3).then_some(-2e-6),
        tan_theta_y: (index != 3).then_some(3e-6),
        decenter_x: None,
        decenter_y: None,
        decenter: None,
        despace: None,
        residual: (index != 3).then_some(1e-12),
        slack_cables: None,
        loose_joints: None,
        floating: None,
        holding_force: None,
        limit_ratio: None,
        reason: (index == 3).then(|| "Newton did not converge".to_string()),
    }
}

/// A complete version-2 shard of `range`, written with the encoder.
fn shard_text(range: ShardRange) -> String {
    let (mut encoder, mut out) = ShardEncoder::new(&begin(range));
    for i in range.start..range.end {
        let s = sample(i);
        encoder.push(s.to_line().as_bytes(), s.status == Status::Failed, &mut out);
    }
    out.extend_from_slice(&encoder.end().1);
    String::from_utf8(out).unwrap()
}

fn write_temp(text: &str) -> tempfile::NamedTempFile {
    let mut f = tempfile::NamedTempFile::new().unwrap();
    f.write_all(text.as_bytes()).unwrap();
    f
}

/// The lines of `text`, each with its `\n`.
fn lines(text: &str) -> Vec<&str> {
    text.split_inclusive('\n').collect()
}

#[test]
fn checkpoints_follow_every_nth_sample_and_the_file_verifies() {
    let text = shard_text(ShardRange::new(0, 10));
    let kinds: Vec<&str> = lines(&text)
        .iter()
        .map(|l| match parse_record(l.as_bytes()).unwrap() {
            Record::Begin(_) => "b",
            Record::Sample(_) => "s",
            Record::Checkpoint(_) => "c",
            Record::End(_) => "e",
        })
        .collect();
    assert_eq!(kinds.concat(), "bsssscssssccsse".replace("cc", "c"));
    let f = write_temp(&text);
    let mut seen = vec![];
    let scan = read_shard(f.path(), |_, s, _| {
        seen.push(s.index);
        Ok(())
    })
    .unwrap();
    assert_eq!(seen, (0..10).collect::<Vec<_>>());
    assert_eq!(scan.valid_len, text.len() as u64);
    assert_eq!(scan.unverified, 0);
    let Tail::Complete(end) = &scan.tail else {
        panic!("not complete")
    };
    assert_eq!(end.failed, 1);
    assert_eq!(
        end.begin_sha256.as_deref(),
        Some(sha256_hex(lines(&text)[0].as_bytes()).as_str())
    );
    // A range whose length is a multiple of N ends with a checkpoint, then the end line.
    let text = shard_text(ShardRange::new(0, 8));
    let f = write_temp(&text);
    assert!(
        read_shard(f.path(), |_, _, _| Ok(()))
            .unwrap()
            .is_complete()
    );
    assert!(lines(&text)[lines(&text).len() - 2].contains("\"checkpoint\""));
}

#[test]
fn a_changed_header_parameter_breaks_complete_and_partial_files() {
    let text = shard_text(ShardRange::new(0, 10));
    let edited = text.replacen("\"sigma\":0.5", "\"sigma\":0.05", 1);
    assert_ne!(edited, text);
    let f = write_temp(&edited);
    let err = read_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    // The first checkpoint (line 6) already finds it.
    assert!(
        matches!(err, ScanError::Corrupt { line: 6, .. })
            && err.to_string().contains("header was changed"),
        "{err}"
    );
    // Cut after the first checkpoint and a few lines: still found.
    let partial: String = lines(&edited)[..8].concat();
    let f = write_temp(&partial);
    let err = scan_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(err.to_string().contains("header was changed"), "{err}");
}

#[test]
fn a_changed_sample_before_the_last_checkpoint_is_found_after_it_is_not_kept() {
    let text = shard_text(ShardRange::new(0, 10));
    let ls = lines(&text);
    // Header, samples 0-3, checkpoint, samples 4-7, checkpoint, samples 8, 9: cut before the
    // end line, so the file is incomplete.
    let partial = ls[..ls.len() - 1].concat();
    let changed = partial.replacen("\"theta_p\":0.000051", "\"theta_p\":0.000052", 1);
    assert_ne!(changed, partial);
    let f = write_temp(&changed);
    let err = scan_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(
        matches!(err, ScanError::Corrupt { line: 11, .. }) && err.to_string().contains("sha256"),
        "{err}"
    );
    // Unchanged, the two lines after the last checkpoint are reported, not visited, and the
    // verified prefix ends at the checkpoint.
    let f = write_temp(&partial);
    let mut seen = 0;
    let scan = scan_shard(f.path(), |_, _, _| {
        seen += 1;
        Ok(())
    })
    .unwrap();
    assert_eq!((seen, scan.digest.samples(), scan.unverified), (8, 8, 2));
    assert_eq!(scan.valid_len, ls[..11].concat().len() as u64);
    assert_eq!(scan.next_index(), 8);
    // A changed line after the last checkpoint is not an error: it is not kept.
    let changed = partial.replacen("\"theta_p\":0.000081", "\"theta_p\":0.000082", 1);
    assert_ne!(changed, partial);
    let f = write_temp(&changed);
    let scan = scan_shard(f.path(), |_, _, _| Ok(())).unwrap();
    assert_eq!((scan.digest.samples(), scan.unverified), (8, 2));
    // Resuming from it with the encoder gives the uninterrupted file's bytes.
    let mut bytes = changed.as_bytes()[..scan.valid_len as usize].to_vec();
    let mut encoder = ShardEncoder::resume(&scan);
    for i in 8..10 {
        let s = sample(i);
        encoder.push(s.to_line().as_bytes(), false, &mut bytes);
    }
    bytes.extend_from_slice(&encoder.end().1);
    assert_eq!(String::from_utf8(bytes).unwrap(), text);
}

#[test]
fn missing_misplaced_or_forged_checkpoints_are_refused() {
    let text = shard_text(ShardRange::new(0, 10));
    let ls = lines(&text);
    // Drop the first checkpoint (line 6).
    let dropped = [&ls[..5], &ls[6..]].concat().concat();
    let f = write_temp(&dropped);
    let err = read_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(err.to_string().contains("checkpoint line was due"), "{err}");
    // A checkpoint where none is due.
    let extra = [&ls[..3], &ls[5..6], &ls[3..]].concat().concat();
    let f = write_temp(&extra);
    let err = read_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(matches!(err, ScanError::Corrupt { line: 4, .. }), "{err}");
    // An end line without the begin digest.
    let end = ls[ls.len() - 1];
    let cut = end.find(",\"begin_sha256\"").unwrap();
    let forged = format!("{}{}}}\n", ls[..ls.len() - 1].concat(), &end[..cut]);
    let f = write_temp(&forged);
    let err = read_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(err.to_string().contains("begin_sha256 is missing"), "{err}");
}

#[test]
fn version_checks_of_the_header() {
    let mut b = begin(ShardRange::new(0, 3));
    assert!(b.check().is_ok());
    b.checkpoint_every = None;
    assert!(b.check().unwrap_err().contains("needs checkpoint_every"));
    b.checkpoint_every = Some(0);
    assert!(b.check().is_err());
    b.checkpoint_every = Some(MAX_CHECKPOINT_EVERY + 1);
    assert!(b.check().is_err());
    let mut v1 = b.clone();
    v1.format_version = 1;
    assert!(
        v1.check().is_err(),
        "checkpoint_every in a version-1 header"
    );
    v1.checkpoint_every = None;
    assert!(v1.check().is_ok());
    assert!(b.same_shard(&v1));
}

#[test]
fn a_stop_checkpoint_verifies_every_line_and_is_cut_off_on_resume() {
    let range = ShardRange::new(0, 10);
    let (mut encoder, mut bytes) = ShardEncoder::new(&begin(range));
    for i in 0..6 {
        let s = sample(i);
        encoder.push(
            s.to_line().as_bytes(),
            s.status == Status::Failed,
            &mut bytes,
        );
    }
    let kept = bytes.len() as u64;
    bytes.extend_from_slice(&encoder.stop_checkpoint().unwrap());
    let f = write_temp(std::str::from_utf8(&bytes).unwrap());
    let scan = scan_shard(f.path(), |_, _, _| Ok(())).unwrap();
    assert_eq!((scan.digest.samples(), scan.unverified), (6, 0));
    assert_eq!(scan.valid_len, kept, "the stop checkpoint is not kept");
    // Resumed from there, the file is the uninterrupted one.
    let mut resumed = bytes[..kept as usize].to_vec();
    let mut encoder = ShardEncoder::resume(&scan);
    for i in 6..10 {
        let s = sample(i);
        encoder.push(s.to_line().as_bytes(), false, &mut resumed);
    }
    resumed.extend_from_slice(&encoder.end().1);
    assert_eq!(String::from_utf8(resumed).unwrap(), shard_text(range));
    // Anywhere but last, an off-schedule checkpoint is refused; a stale one is too.
    let mut more = bytes.clone();
    more.extend_from_slice(sample(6).to_line().as_bytes());
    let f = write_temp(std::str::from_utf8(&more).unwrap());
    let err = scan_shard(f.path(), |_, _, _| Ok(())).unwrap_err();
    assert!(err.to_string().contains("nor the last line"), "{err}");
    let text = String::from_utf8(bytes).unwrap();
    let edited = text.replacen("\"iterations\":3", "\"iterations\":4", 1);
    let f = write_temp(&edited);
    assert!(scan_shard(f.path(), |_, _, _| Ok(())).is_err());
}
