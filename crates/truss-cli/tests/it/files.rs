//! Files in a shared run directory (crate `run-dir`): `truss diagnose` and `truss tolerance`
//! never write through a planted link, and refuse it before any work; files named on the
//! command line are read only if they are regular files; output that cannot be written is
//! an I/O error.

use crate::hostile::{assert_untouched, code, fifo, precious, run_bounded};
use crate::truss;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

fn job_path() -> &'static str {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../jobs/diagnose-baseline.json"
    )
}

/// Measured data of 30 specimens, as `synth-measured` writes it.
fn measured(dir: &Path) -> std::path::PathBuf {
    let out = truss(&[
        "synth-measured",
        "--job",
        job_path(),
        "--case",
        "as-built",
        "--specimens",
        "30",
        "--seed",
        "3",
        "--effect",
        "none",
        "--measurement-sigma",
        "0.001",
    ]);
    assert!(out.status.success(), "{}", code(&out).1);
    let path = dir.join("m.csv");
    std::fs::write(&path, out.stdout).unwrap();
    path
}

/// Runs `truss` with `args`, bounded (see `hostile::run_bounded`).
fn truss_bounded(args: &[&str]) -> (Option<i32>, String) {
    run_bounded(Path::new(env!("CARGO_BIN_EXE_truss")), args)
}

/// A link at `diagnosis.md` or at a diagnosis plot's name is refused (exit 5), naming it,
/// before the diagnosis runs; what it points at keeps its bytes.
#[test]
fn diagnose_never_writes_through_a_link() {
    let dir = tempfile::tempdir().unwrap();
    let target = precious(dir.path());
    let m = measured(dir.path());
    for name in ["diagnosis.md", "theta_p-ecdf-before.svg"] {
        let out = dir.path().join(format!("out-{name}"));
        std::fs::create_dir(&out).unwrap();
        std::os::unix::fs::symlink(&target, out.join(name)).unwrap();
        let started = Instant::now();
        let o = truss(&[
            "diagnose",
            "--job",
            job_path(),
            "--case",
            "as-built",
            "--measured",
            m.to_str().unwrap(),
            "--measurement-sigma",
            "0.001",
            "--samples",
            "400",
            "--out",
            out.to_str().unwrap(),
        ]);
        let (status, stderr) = code(&o);
        assert_eq!(status, Some(5), "{name}: {stderr}");
        assert!(
            stderr.contains(name) && stderr.contains("symbolic link"),
            "{stderr}"
        );
        assert!(
            started.elapsed() < Duration::from_secs(5),
            "refused before the work"
        );
        assert_untouched(&target);
    }
}

/// `--measured` and `--measured-members` as a FIFO, `/dev/zero` or a link to it are refused
/// at once (invalid input, exit 3), naming the file.
#[test]
fn diagnose_reads_only_regular_files() {
    let dir = tempfile::tempdir().unwrap();
    let m = measured(dir.path());
    let fifo = fifo(dir.path(), "fifo.csv");
    let zero = dir.path().join("zero.csv");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let out = dir.path().join("d");
    for bad in [fifo.as_path(), Path::new("/dev/zero"), zero.as_path()] {
        for (flag, measured) in [("--measured", bad), ("--measured-members", bad)] {
            let measured_arg = if flag == "--measured" {
                bad
            } else {
                m.as_path()
            };
            let mut args = vec![
                "diagnose",
                "--job",
                job_path(),
                "--case",
                "as-built",
                "--measured",
                measured_arg.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ];
            if flag == "--measured-members" {
                args.extend(["--measured-members", measured.to_str().unwrap()]);
            }
            let (status, stderr) = truss_bounded(&args);
            assert_eq!(status, Some(3), "{flag} {}: {stderr}", bad.display());
            assert!(
                stderr.contains(&bad.display().to_string())
                    && stderr.contains("not a regular file"),
                "{stderr}"
            );
        }
    }
}

/// A link at `tolerance.md` is refused (exit 5) before the study runs; a FIFO given as the
/// job is refused at once (exit 3), as every job reader refuses it.
#[test]
fn tolerance_never_writes_through_a_link_nor_reads_a_fifo() {
    let dir = tempfile::tempdir().unwrap();
    let target = precious(dir.path());
    let job = crate::one_stage_job(dir.path());
    let out = dir.path().join("t");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&target, out.join("tolerance.md")).unwrap();
    let args = |job: &Path| {
        vec![
            "tolerance".to_string(),
            "--job".into(),
            job.display().to_string(),
            "--case".into(),
            "c".into(),
            "--target-arcsec".into(),
            "20".into(),
            "--samples".into(),
            "1000".into(),
            "--sensitivity-samples".into(),
            "1000".into(),
            "--out".into(),
            out.display().to_string(),
        ]
    };
    let started = Instant::now();
    let a = args(&job);
    let (status, stderr) = truss_bounded(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(status, Some(5), "{stderr}");
    assert!(
        stderr.contains("tolerance.md") && stderr.contains("symbolic link"),
        "{stderr}"
    );
    assert!(
        started.elapsed() < Duration::from_secs(5),
        "refused before the work"
    );
    assert_untouched(&target);
    std::fs::remove_file(out.join("tolerance.md")).unwrap();
    let fifo = fifo(dir.path(), "job.fifo");
    let a = args(&fifo);
    let (status, stderr) = truss_bounded(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(status, Some(3), "{stderr}");
    assert!(stderr.contains("not a regular file"), "{stderr}");
}

/// A manifest planted in the output directory (`.truss-diagnose.manifest`,
/// `.truss-tolerance.manifest`) listing the merge's `report.json` deletes nothing: it is not
/// the writer's own (an older format, unchecked); the run succeeds and names it on stderr.
#[test]
fn planted_manifests_delete_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let m = measured(dir.path());
    let job = crate::one_stage_job(dir.path());
    let plant = |out: &Path, writer: &str| {
        std::fs::create_dir(out).unwrap();
        std::fs::write(out.join("report.json"), "the merge's report").unwrap();
        std::fs::write(
            out.join(format!(".{writer}.manifest")),
            "# the files wrote\nreport.json\n",
        )
        .unwrap();
    };
    let d = dir.path().join("d");
    plant(&d, "truss-diagnose");
    let o = truss(&[
        "diagnose",
        "--job",
        job_path(),
        "--case",
        "as-built",
        "--measured",
        m.to_str().unwrap(),
        "--measurement-sigma",
        "0.001",
        "--samples",
        "100",
        "--no-plots",
        "--quiet",
        "--out",
        d.to_str().unwrap(),
    ]);
    let t = dir.path().join("t");
    plant(&t, "truss-tolerance");
    let o2 = crate::small_tolerance(&job, &t, &[]);
    for (o, out, writer) in [(o, d, "truss-diagnose"), (o2, t, "truss-tolerance")] {
        let (status, stderr) = code(&o);
        assert!(matches!(status, Some(0 | 6)), "{writer}: {stderr}");
        assert!(
            stderr.contains(&format!(".{writer}.manifest: not trusted")),
            "{writer}: {stderr}"
        );
        let report = std::fs::read_to_string(out.join("report.json")).unwrap();
        assert_eq!(report, "the merge's report", "{writer}");
    }
}

/// Output that cannot be written (`/dev/full`) is an I/O error (exit 4) for a result and
/// for a completion script alike (clap's generator used to panic, 101, in the other
/// binaries: see their tests).
#[test]
fn unwritable_output_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("p.json");
    std::fs::write(&model, truss(&["model", "prism", "--stages", "1"]).stdout).unwrap();
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    for args in [
        vec!["solve", model.to_str().unwrap()],
        vec!["completions", "bash"],
        vec!["man"],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_truss"))
            .args(&args)
            .stdout(full())
            .output()
            .unwrap();
        let (status, stderr) = code(&o);
        assert_eq!(status, Some(4), "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("truss: error: cannot write output"),
            "{stderr}"
        );
    }
}
