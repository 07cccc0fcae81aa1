//! A manifest is no proof of authorship unless the merge can check it (crate `run-dir`): a
//! manifest planted in a fresh `--out`, or one line appended to mc-merge's own, deletes
//! nothing; a case whose plot name is another writer's file is refused before anything is
//! written; the sweep of stale temporary files takes only the writers' own names; the lock
//! file is never removed.

use crate::hostile::code;
use crate::report_dir::{job, merge};
use std::path::Path;

fn read(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// A `.mc-merge.manifest` planted in a fresh `--out` listing the user's files deletes
/// neither; the merge succeeds and names the manifest on stderr.
#[test]
fn a_planted_manifest_deletes_nothing() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(11, &["a"]).write_split(shards.path(), 1);
    std::fs::write(out.path().join("notes.txt"), "notes").unwrap();
    std::fs::write(out.path().join("data.csv"), "1,2").unwrap();
    std::fs::write(
        out.path().join(".mc-merge.manifest"),
        "# the files mc-merge wrote\nnotes.txt\ndata.csv\n.truss-mc.lock\n",
    )
    .unwrap();
    let (status, stderr) = code(&merge(shards.path(), out.path(), &[]));
    assert_eq!(status, Some(0), "{stderr}");
    assert!(
        stderr.contains(".mc-merge.manifest: not trusted"),
        "{stderr}"
    );
    assert_eq!(read(out.path(), "notes.txt"), "notes");
    assert_eq!(read(out.path(), "data.csv"), "1,2");
    assert!(out.path().join(".truss-mc.lock").exists());
}

/// One line appended to mc-merge's own manifest in a same-job report directory deletes
/// nothing: the manifest is no longer proof, so the merge cannot show that `report.json` is
/// its own either, and refuses (exit 5) with every file left as it was.
#[test]
fn an_appended_line_deletes_nothing() {
    use std::os::unix::fs::MetadataExt;
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(12, &["a"]).write_split(shards.path(), 1);
    assert_eq!(code(&merge(shards.path(), out.path(), &[])).0, Some(0));
    std::fs::write(out.path().join("notes.txt"), "notes").unwrap();
    let manifest = out.path().join(".mc-merge.manifest");
    let mut text = read(out.path(), ".mc-merge.manifest");
    text.push_str("notes.txt\n");
    std::fs::write(&manifest, text).unwrap();
    let inode = std::fs::metadata(out.path().join("report.json"))
        .unwrap()
        .ino();
    let (status, stderr) = code(&merge(shards.path(), out.path(), &["--no-plots"]));
    assert_eq!(status, Some(5), "{stderr}");
    assert!(stderr.contains("not trusted"), "{stderr}");
    assert!(stderr.contains("report.json: not replaced"), "{stderr}");
    assert_eq!(read(out.path(), "notes.txt"), "notes");
    assert!(out.path().join("theta_p-a.svg").exists());
    let after = std::fs::metadata(out.path().join("report.json"))
        .unwrap()
        .ino();
    assert_eq!(after, inode, "report.json was replaced");
}

/// A case named `ecdf-before` would write `theta_p-ecdf-before.svg`, a diagnosis's plot in
/// the same directory: refused (exit 5) naming it, before anything is written.
#[test]
fn another_writers_file_is_not_replaced() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(13, &["ecdf-before"]).write_split(shards.path(), 1);
    std::fs::write(
        out.path().join("theta_p-ecdf-before.svg"),
        "the diagnosis's",
    )
    .unwrap();
    let (status, stderr) = code(&merge(shards.path(), out.path(), &[]));
    assert_eq!(status, Some(5), "{stderr}");
    assert!(stderr.contains("theta_p-ecdf-before.svg"), "{stderr}");
    assert_eq!(
        read(out.path(), "theta_p-ecdf-before.svg"),
        "the diagnosis's"
    );
    assert!(!out.path().join("report.json").exists());
}

/// A user's `.report.md.tmp-mynotes` is not a stale temporary file of ours.
#[test]
fn the_sweep_leaves_names_not_ours() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(14, &["a"]).write_split(shards.path(), 1);
    assert_eq!(code(&merge(shards.path(), out.path(), &[])).0, Some(0));
    std::fs::write(out.path().join(".report.md.tmp-mynotes"), "mine").unwrap();
    std::fs::write(out.path().join(".report.md.tmp-0123456789abcdef"), "stale").unwrap();
    let (status, stderr) = code(&merge(shards.path(), out.path(), &[]));
    assert_eq!(status, Some(0), "{stderr}");
    assert_eq!(read(out.path(), ".report.md.tmp-mynotes"), "mine");
    assert!(!out.path().join(".report.md.tmp-0123456789abcdef").exists());
}

/// A directory at `report.html` is refused before `report.json` is replaced.
#[test]
fn a_name_in_the_way_leaves_the_report_whole() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(15, &["a"]).write_split(shards.path(), 1);
    assert_eq!(code(&merge(shards.path(), out.path(), &[])).0, Some(0));
    use std::os::unix::fs::MetadataExt;
    let inode = |p: &Path| std::fs::metadata(p.join("report.json")).unwrap().ino();
    let before = inode(out.path());
    std::fs::remove_file(out.path().join("report.html")).unwrap();
    std::fs::create_dir(out.path().join("report.html")).unwrap();
    let (status, stderr) = code(&merge(shards.path(), out.path(), &[]));
    assert_eq!(status, Some(5), "{stderr}");
    assert!(stderr.contains("report.html"), "{stderr}");
    assert_eq!(inode(out.path()), before, "report.json was replaced");
}
