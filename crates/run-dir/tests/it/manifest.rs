//! A writer's output directory (`run_dir::manifest`, `run_dir::record`): a rerun removes and
//! replaces only files it can prove it wrote; an untrusted or edited manifest, another
//! writer's files, a user's temporary-looking names and the lock file are left alone.
use run_dir::RunDirError;
use run_dir::manifest::{LOCK_FILE, OutputDir, manifest_name};
use run_dir::record::{self, Entry, Identity};
use std::collections::BTreeMap;
use std::fs::File;
use std::path::Path;

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| !n.starts_with('.'))
        .collect();
    v.sort();
    v
}

/// A rerun removes its own files it does not write again, and nothing else; a second
/// writer on a locked directory is refused.
#[test]
fn reruns_remove_only_their_own_files() {
    let dir = tempfile::tempdir().unwrap();
    let mut out = OutputDir::open(dir.path(), "w").unwrap();
    out.write("a.svg", b"a").unwrap();
    out.write("b.svg", b"b").unwrap();
    let e = OutputDir::open(dir.path(), "w").unwrap_err();
    assert!(matches!(e, RunDirError::Locked { .. }), "{e}");
    assert!(e.to_string().contains("wait for it or stop it"), "{e}");
    out.finish().unwrap();
    std::fs::write(dir.path().join("mine.svg"), "mine").unwrap();
    std::fs::write(dir.path().join(".b.svg.tmp-0123456789abcdef"), "stale").unwrap();
    let mut out = OutputDir::open(dir.path(), "w").unwrap();
    assert_eq!(out.earlier().len(), 2);
    out.write("a.svg", b"a2").unwrap();
    out.finish().unwrap();
    assert_eq!(names(dir.path()), ["a.svg", "mine.svg"]);
    assert!(!dir.path().join(".b.svg.tmp-0123456789abcdef").exists());
    // Another writer's manifest is its own.
    let other = OutputDir::open(dir.path(), "v").unwrap();
    assert!(other.earlier().is_empty());
    other.finish().unwrap();
    assert_eq!(names(dir.path()), ["a.svg", "mine.svg"]);
}

/// A planted link at a listed name is left alone (not followed, not removed) and
/// writing that name again is refused.
#[test]
fn listed_links_are_neither_followed_nor_removed() {
    let dir = tempfile::tempdir().unwrap();
    let elsewhere = tempfile::tempdir().unwrap();
    let target = elsewhere.path().join("precious");
    std::fs::write(&target, "precious").unwrap();
    let mut out = OutputDir::open(dir.path(), "w").unwrap();
    out.write("p.png", b"p").unwrap();
    out.finish().unwrap();
    std::fs::remove_file(dir.path().join("p.png")).unwrap();
    std::os::unix::fs::symlink(&target, dir.path().join("p.png")).unwrap();
    let mut out = OutputDir::open(dir.path(), "w").unwrap();
    assert!(matches!(
        out.write("p.png", b"x").unwrap_err(),
        RunDirError::Link { .. }
    ));
    out.finish().unwrap();
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "precious");
    assert!(dir.path().join("p.png").is_symlink());
}

/// A manifest of identity for `name` in `dir` as the writer would record it.
fn identity(dir: &Path, name: &str) -> Identity {
    let path = dir.join(name);
    let bytes = std::fs::read(&path).unwrap();
    Identity::of_written(&File::open(&path).unwrap(), &bytes).unwrap()
}

fn plant(dir: &Path, writer: &str, text: &str) {
    std::fs::write(dir.join(manifest_name(writer)), text).unwrap();
}

/// A manifest the writer did not write removes nothing: one of an older format (names
/// only), one with a line appended, one others may write; the run succeeds and names it.
#[test]
fn untrusted_manifests_remove_nothing() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    for n in ["notes.txt", "data.csv"] {
        std::fs::write(dir.path().join(n), n).unwrap();
    }
    plant(
        dir.path(),
        "w",
        "# the files w wrote\nnotes.txt\ndata.csv\n",
    );
    let mut out = OutputDir::open(dir.path(), "w").unwrap();
    assert!(out.earlier().is_empty());
    out.write("a.svg", b"a").unwrap();
    let warnings = out.finish().unwrap();
    assert_eq!(names(dir.path()), ["a.svg", "data.csv", "notes.txt"]);
    assert!(
        warnings[0].contains(".w.manifest: not trusted"),
        "{warnings:?}"
    );
    // One appended line in a real manifest.
    let manifest = dir.path().join(manifest_name("w"));
    let mut text = std::fs::read_to_string(&manifest).unwrap();
    text.push_str("claim notes.txt\n");
    std::fs::write(&manifest, &text).unwrap();
    let out = OutputDir::open(dir.path(), "w").unwrap();
    let warnings = out.finish().unwrap();
    assert!(
        warnings[0].contains("do not match its own digest"),
        "{warnings:?}"
    );
    assert_eq!(names(dir.path()), ["a.svg", "data.csv", "notes.txt"]);
    // A whole manifest that others may write, listing a.svg as it is.
    let whole = record::render(
        &[(
            "a.svg".to_string(),
            Entry::File(identity(dir.path(), "a.svg")),
        )]
        .into(),
    );
    std::fs::write(&manifest, whole).unwrap();
    std::fs::set_permissions(&manifest, std::fs::Permissions::from_mode(0o666)).unwrap();
    let out = OutputDir::open(dir.path(), "w").unwrap();
    assert!(
        out.warnings()[0].contains("mode 666"),
        "{:?}",
        out.warnings()
    );
    out.finish().unwrap();
    assert_eq!(names(dir.path()), ["a.svg", "data.csv", "notes.txt"]);
}

/// A well-formed manifest whose identities do not match (a forged one, a file replaced
/// or edited since) removes nothing and names what it kept; the lock file and manifests
/// are never removed, even listed with their true identity.
#[test]
fn only_the_very_files_written_are_removed() {
    let dir = tempfile::tempdir().unwrap();
    let mut out = OutputDir::open(dir.path(), "w").unwrap();
    out.write("a.svg", b"a").unwrap();
    out.write("b.svg", b"b").unwrap();
    out.finish().unwrap();
    std::fs::write(dir.path().join("b.svg"), "the user's edit").unwrap();
    std::fs::write(dir.path().join("notes.txt"), "notes").unwrap();
    let forged = Identity {
        sha256: "0".repeat(64),
        ..identity(dir.path(), "notes.txt")
    };
    let mut entries: BTreeMap<String, Entry> = record::read(&dir.path().join(".w.manifest"))
        .unwrap()
        .unwrap();
    entries.insert("notes.txt".into(), Entry::File(forged));
    for n in [LOCK_FILE, ".v.manifest"] {
        std::fs::write(dir.path().join(n), "x").unwrap();
        entries.insert(n.into(), Entry::File(identity(dir.path(), n)));
    }
    plant(dir.path(), "w", &record::render(&entries));
    let out = OutputDir::open(dir.path(), "w").unwrap();
    let warnings = out.finish().unwrap();
    assert_eq!(names(dir.path()), ["b.svg", "notes.txt"]);
    assert!(dir.path().join(LOCK_FILE).exists());
    assert!(dir.path().join(".v.manifest").exists());
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(warnings.iter().all(|w| w.contains("kept")), "{warnings:?}");
}

/// A file at a name to write that the writer cannot prove it wrote is refused and left
/// as it is: a user's file, another writer's (named), one edited since.
#[test]
fn files_not_provably_ours_are_not_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let mut diagnosis = OutputDir::open(dir.path(), "truss-diagnose").unwrap();
    diagnosis
        .write("theta_p-ecdf-before.svg", b"diagnosis")
        .unwrap();
    diagnosis.finish().unwrap();
    std::fs::write(dir.path().join("notes.md"), "mine").unwrap();
    let e = OutputDir::check(dir.path(), "mc-merge", &["theta_p-ecdf-before.svg"]).unwrap_err();
    assert!(e.to_string().contains("listed by truss-diagnose"), "{e}");
    let mut merge = OutputDir::open(dir.path(), "mc-merge").unwrap();
    for name in ["theta_p-ecdf-before.svg", "notes.md"] {
        let e = merge.write(name, b"merge").unwrap_err();
        assert!(matches!(e, RunDirError::NotOurs { .. }), "{e}");
        assert!(e.to_string().contains("left as it is"), "{e}");
    }
    merge.write("report.md", b"r").unwrap();
    merge.write("report.md", b"r2").unwrap();
    merge.finish().unwrap();
    let read = |n: &str| std::fs::read_to_string(dir.path().join(n)).unwrap();
    assert_eq!(read("theta_p-ecdf-before.svg"), "diagnosis");
    assert_eq!(read("notes.md"), "mine");
    std::fs::write(dir.path().join("report.md"), "edited").unwrap();
    let mut merge = OutputDir::open(dir.path(), "mc-merge").unwrap();
    let e = merge.write("report.md", b"r3").unwrap_err();
    assert!(
        e.to_string().contains("changed since mc-merge wrote it"),
        "{e}"
    );
    assert_eq!(read("report.md"), "edited");
}

/// The sweep removes only temporary files of our names with the writers' 16-hex-digit
/// suffix.
#[test]
fn the_sweep_matches_only_our_temporary_names() {
    let dir = tempfile::tempdir().unwrap();
    let mut out = OutputDir::open(dir.path(), "w").unwrap();
    out.write("report.md", b"r").unwrap();
    out.finish().unwrap();
    let kept = [
        ".report.md.tmp-mynotes",
        ".report.md.tmp-0123456789ABCDEF",
        ".other.tmp-0123456789abcdef",
    ];
    for n in kept.iter().chain(&[".report.md.tmp-0123456789abcdef"]) {
        std::fs::write(dir.path().join(n), "x").unwrap();
    }
    let mut out = OutputDir::open(dir.path(), "w").unwrap();
    out.write("report.md", b"r").unwrap();
    out.finish().unwrap();
    for n in kept {
        assert!(dir.path().join(n).exists(), "{n} was removed");
    }
    assert!(!dir.path().join(".report.md.tmp-0123456789abcdef").exists());
}

/// A whole, well-formed manifest owned by another user (who may create files in a shared
/// directory) lists nothing, even with every identity right. Needs root to give a file
/// away; skipped otherwise.
#[test]
fn another_users_manifest_lists_nothing() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("notes.txt"), "notes").unwrap();
    let entries = [(
        "notes.txt".to_string(),
        Entry::File(identity(dir.path(), "notes.txt")),
    )]
    .into();
    plant(dir.path(), "w", &record::render(&entries));
    let manifest = dir.path().join(manifest_name("w"));
    if std::os::unix::fs::chown(&manifest, Some(65534), None).is_err() {
        eprintln!("skipped: cannot give a file to another user here");
        return;
    }
    let out = OutputDir::open(dir.path(), "w").unwrap();
    assert!(
        out.warnings()[0].contains("owned by user 65534"),
        "{:?}",
        out.warnings()
    );
    let _ = out.finish();
    assert_eq!(names(dir.path()), ["notes.txt"]);
}
