//! Hostile and meaningless inputs, refused at once by name with the right exit code (usage
//! 2, invalid input 3, I/O 4), and the command-line conventions every binary shares: one
//! error prefix, each cause printed once, a quiet end on a broken pipe, completions and a
//! man page.

use crate::{json, truss};
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

/// stderr as text.
fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A 1-stage prism model file in a fresh directory.
fn prism_file(dir: &std::path::Path) -> std::path::PathBuf {
    let path = dir.join("p.json");
    std::fs::write(&path, truss(&["model", "prism", "--stages", "1"]).stdout).unwrap();
    path
}

/// Stage counts past the limit, 2⁶⁴ − 1 included, are usage errors naming `--stages`
/// (they used to fill the memory); the limit itself is accepted.
#[test]
fn stage_counts_beyond_the_limit_are_refused() {
    for stages in ["18446744073709551615", "100000", "1001", "0"] {
        let out = truss(&["model", "prism", "--stages", stages]);
        assert_eq!(out.status.code(), Some(2), "{stages}: {}", stderr(&out));
        let err = stderr(&out);
        assert!(
            err.starts_with("truss: error: --stages: must be from 1 to 1000"),
            "{err}"
        );
        assert!(out.stdout.is_empty());
    }
    let out = truss(&["model", "prism", "--stages", "1000"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        json(&out)["members"].as_array().unwrap().len(),
        12 * 1000 + 3
    );
}

/// Implausible prism values are usage errors naming their flag.
#[test]
fn implausible_prism_values_name_their_flag() {
    for (flag, value) in [
        ("--side", "1e308"),
        ("--height", "-380"),
        ("--batten-modulus", "NaN"),
        ("--diagonal-area", "inf"),
    ] {
        let out = truss(&["model", "prism", &format!("{flag}={value}")]);
        assert_eq!(out.status.code(), Some(2), "{flag} {value}");
        assert!(
            stderr(&out).starts_with(&format!("truss: error: {flag}: ")),
            "{}",
            stderr(&out)
        );
    }
    let out = truss(&["model", "prism", "--backlash", "--clearance", "1e308"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--clearance: must be from 0 to 38 mm"));
}

/// Not a regular file, too large, not UTF-8: invalid input (3), naming the file, at once;
/// a missing file is an I/O error (4) whose cause is printed once.
#[test]
fn model_files_that_cannot_be_models_are_refused_by_name() {
    let out = truss(&["solve", "/dev/zero"]);
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    assert_eq!(
        stderr(&out),
        "truss: error: /dev/zero: not a regular file (a character device); give the path of a file\n"
    );
    let dir = tempfile::tempdir().unwrap();
    let out = truss(&["solve", dir.path().to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(3));
    assert!(stderr(&out).contains("(a directory)"));

    let big = dir.path().join("big.json");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(truss_core::model_file::MAX_INPUT_BYTES + 1)
        .unwrap();
    let out = truss(&["solve", big.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(3));
    assert!(
        stderr(&out).contains("big.json: 67108865 bytes is more than the 67108864 bytes"),
        "{}",
        stderr(&out)
    );

    let latin1 = dir.path().join("latin1.json");
    let mut text = truss(&["model", "prism", "--stages", "1"]).stdout;
    let at = text.windows(4).position(|w| w == b"n0.0").unwrap();
    text[at] = 0xe9;
    std::fs::write(&latin1, &text).unwrap();
    let out = truss(&["solve", latin1.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(3), "invalid UTF-8 is invalid input");
    assert!(stderr(&out).contains("latin1.json: not UTF-8 text: invalid bytes at line 4"));

    let missing = dir.path().join("nope.json");
    let out = truss(&["solve", missing.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(4));
    let err = stderr(&out);
    let cause = std::io::Error::from(std::io::ErrorKind::NotFound).to_string();
    assert!(err.starts_with("truss: error: "), "{err}");
    assert_eq!(
        err.matches("No such file or directory").count(),
        1,
        "{err} ({cause})"
    );
}

/// A model file starting with a UTF-8 byte-order mark (as some Windows editors write) is
/// read as if it had none.
#[test]
fn a_byte_order_mark_is_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let path = prism_file(dir.path());
    let mut text = "\u{feff}".as_bytes().to_vec();
    text.extend(std::fs::read(&path).unwrap());
    std::fs::write(&path, text).unwrap();
    let out = truss(&["solve", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(json(&out)["converged"], true);
}

/// A length error beyond 1 % of the member's natural length (3.8 mm of 380 mm) is a usage
/// error, as is a member given twice; 1 % itself is solved.
#[test]
fn meaningless_length_errors_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = prism_file(dir.path());
    let p = path.to_str().unwrap();
    for value in ["100", "-3.81", "1e308"] {
        let arg = format!("longeron.1.0={value}");
        let out = truss(&["solve", p, "--length-error", &arg]);
        assert_eq!(out.status.code(), Some(2), "{value}");
        let err = stderr(&out);
        assert!(
            err.contains("more than 1% of the member's natural length 380 mm (3.8 mm)"),
            "{err}"
        );
        assert!(out.stdout.is_empty(), "nothing solved");
    }
    let out = truss(&["solve", p, "--length-error", "longeron.1.0=3.8"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = truss(&[
        "solve",
        p,
        "--length-error",
        "longeron.1.0=0.01",
        "--length-error",
        "batten.0.0=0.01",
        "--length-error",
        "longeron.1.0=0.02",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("member \"longeron.1.0\" already has a length error"),
        "{}",
        stderr(&out)
    );
}

/// `truss model prism --stages 30 | head -1`: the reader leaves after one line, and
/// `truss` ends quietly with 0 (no "I/O error").
#[test]
fn a_broken_pipe_ends_quietly() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_truss"))
        .args(["model", "prism", "--stages", "30"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    let mut reader = BufReader::new(child.stdout.take().unwrap());
    reader.read_line(&mut first).unwrap();
    assert_eq!(first, "{\n");
    // The model (about 100 kB) is more than a pipe holds: truss is still writing.
    drop(reader);
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(stderr(&out), "");
}

/// Completion scripts for bash, zsh and fish, and a man page, all from the same flags.
#[test]
fn completions_and_man_page_are_generated() {
    for (shell, sign) in [
        ("bash", "complete -F"),
        ("zsh", "#compdef truss"),
        ("fish", "complete -c truss"),
    ] {
        let out = truss(&["completions", shell]);
        assert!(out.status.success(), "{shell}");
        let script = String::from_utf8(out.stdout).unwrap();
        assert!(script.contains(sign), "{shell}: {script}");
        assert!(script.contains("length-error"), "{shell}");
    }
    assert_eq!(truss(&["completions", "tcsh"]).status.code(), Some(2));
    let out = truss(&["man"]);
    assert!(out.status.success());
    let page = String::from_utf8(out.stdout).unwrap();
    assert!(page.contains(".TH truss 1"), "{page}");
    assert!(page.contains("completions"));
}

/// No help text shows rustdoc's escapes (`\[mm\]`).
#[test]
fn help_has_no_escaped_brackets() {
    for args in [
        &["--help"][..],
        &["model", "prism", "--help"],
        &["solve", "--help"],
        &["completions", "--help"],
        &["man", "--help"],
        &["diagnose", "--help"],
        &["synth-measured", "--help"],
        &["tolerance", "--help"],
    ] {
        let out = truss(args);
        let help = String::from_utf8(out.stdout).unwrap();
        assert!(!help.contains("\\["), "{args:?}: {help}");
    }
}

/// A model file whose natural length sets an initial strain beyond 1 % (480 mm on a 380 mm
/// longeron), or a prism whose diagonals would (400 mm on a 537.4 mm face diagonal), is
/// refused before any solve, naming the member or the flag.
#[test]
fn natural_lengths_beyond_the_strain_rule_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = prism_file(dir.path());
    let mut model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let longeron = model["members"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|m| m["id"] == "longeron.1.0")
        .unwrap();
    longeron["natural_length"] = serde_json::json!(480.0);
    std::fs::write(&path, model.to_string()).unwrap();
    let out = truss(&["solve", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("longeron.1.0") && err.contains("natural_length 480 mm"),
        "{err}"
    );
    assert!(out.stdout.is_empty(), "nothing solved");
    let out = truss(&["model", "prism", "--diagonal-length", "400"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).starts_with("truss: error: --diagonal-length: 400 mm is more than 1%"),
        "{}",
        stderr(&out)
    );
}

/// `--cost` or `--fix` given twice for one group is refused naming the flag (usage, 2), as
/// `--length-error` twice for one member is; not "the last one wins".
#[test]
fn repeated_costs_and_fixes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let job = crate::one_stage_job(dir.path());
    for (flag, first, second) in [
        ("--cost", "batten=1", "batten=2"),
        ("--fix", "batten=0.01", "batten=0.05"),
    ] {
        let out = truss(&[
            "tolerance",
            "--job",
            job.to_str().unwrap(),
            "--case",
            "c",
            "--target-arcsec",
            "20",
            "--out",
            dir.path().join("t").to_str().unwrap(),
            flag,
            first,
            flag,
            second,
        ]);
        assert_eq!(out.status.code(), Some(2), "{flag}: {}", stderr(&out));
        let err = stderr(&out);
        assert!(
            err.contains(&format!("{flag} {second}")) && err.contains("given twice"),
            "{err}"
        );
    }
}

/// `--measurement-sigma -0.001` reaches the command, which refuses it with the flag's own
/// message (usage, 2), not clap's "unexpected argument '-0'"; other numeric flags take a
/// negative value to refuse it themselves too.
#[test]
fn negative_numbers_reach_their_flags_check() {
    let dir = tempfile::tempdir().unwrap();
    let job = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../jobs/diagnose-baseline.json"
    );
    let measured = dir.path().join("m.csv");
    std::fs::write(&measured, "specimen,node,x,y,z\n").unwrap();
    let out = truss(&[
        "diagnose",
        "--job",
        job,
        "--case",
        "as-built",
        "--measured",
        measured.to_str().unwrap(),
        "--measurement-sigma",
        "-0.001",
        "--out",
        dir.path().join("d").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("--measurement-sigma must be a non-negative number of mm"),
        "{}",
        stderr(&out)
    );
    let out = truss(&[
        "tolerance",
        "--job",
        job,
        "--case",
        "as-built",
        "--target-arcsec",
        "-20",
        "--out",
        dir.path().join("t").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("--target-arcsec: -20"),
        "{}",
        stderr(&out)
    );
    let out = truss(&["model", "prism", "--side", "-380"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).starts_with("truss: error: --side: "),
        "{}",
        stderr(&out)
    );
}
