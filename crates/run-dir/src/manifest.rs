//! A writer's output directory: locked while it writes, and a manifest of what it wrote, so
//! that a rerun removes only its own earlier files.
//!
//! [`OutputDir::open`] creates the directory the user named (links are followed there: the
//! user chose the path), takes the lock of `.truss-mc.lock` in it ([`LOCK_FILE`]: one writer
//! at a time, every writer of the workspace alike; a second is refused with
//! [`RunDirError::Locked`] rather than left to wait behind a run that may take long), and
//! reads the writer's manifest `.WRITER.manifest`: a comment line, then the name of each file
//! the writer wrote in the directory, one a line.
//!
//! [`OutputDir::write`] lists a new name in the manifest *before* it writes the file (so a
//! crash never leaves a file of ours unlisted), then writes it as [`crate::write_file`] does.
//! [`OutputDir::finish`] removes the files of the earlier manifest that this run did not
//! write again (a renamed case's plots, the plots of a run with plots when this one has
//! none), and the temporary files a killed run of ours left, and writes the manifest of
//! this run. Only regular files are removed: a link or a directory at a listed name is left
//! as it is. A directory without a manifest (written before manifests existed) loses
//! nothing: its files of the same names are replaced, and no other file is touched.

use crate::errors::RunDirError;
use crate::input::open_own;
use crate::lock::{Lock, try_lock};
use crate::output::{TEMP_INFIX, write_file};
use std::collections::BTreeSet;
use std::fs::{File, OpenOptions};
use std::io::Read;
use std::path::{Path, PathBuf};

/// The lock file of an output directory.
pub const LOCK_FILE: &str = ".truss-mc.lock";

/// The longest manifest read \[bytes\]: a million plot names.
pub const MAX_MANIFEST_BYTES: u64 = 64 << 20;

/// The manifest file of `writer`.
pub fn manifest_name(writer: &str) -> String {
    format!(".{writer}.manifest")
}

/// Whether `name` is a plain file name (no directory part, not `.` or `..`, no line break),
/// the only kind a manifest lists.
pub fn is_plain_name(name: &str) -> bool {
    !name.is_empty() && name != "." && name != ".." && !name.contains(['/', '\n', '\r', '\0'])
}

/// An output directory being written by one writer (see the module doc).
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    writer: String,
    /// Held until the writer is done.
    _lock: File,
    /// What the previous run listed.
    earlier: BTreeSet<String>,
    /// What the manifest on disk lists now.
    listed: BTreeSet<String>,
    /// What this run wrote, in order.
    written: Vec<String>,
}

impl OutputDir {
    /// Creates `dir` if needed, locks it, and reads `writer`'s manifest.
    pub fn open(dir: &Path, writer: &str) -> Result<Self, RunDirError> {
        std::fs::create_dir_all(dir).map_err(|e| RunDirError::io(dir, e))?;
        let lock_path = dir.join(LOCK_FILE);
        let lock = open_own(
            &lock_path,
            OpenOptions::new().read(true).write(true).create(true),
        )?;
        match try_lock(&lock).map_err(|e| RunDirError::io(&lock_path, e))? {
            Lock::Taken => {}
            Lock::Held { holder } => {
                return Err(RunDirError::Locked {
                    path: dir.to_path_buf(),
                    holder,
                });
            }
        }
        let earlier = read_manifest(&dir.join(manifest_name(writer)))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            writer: writer.to_string(),
            _lock: lock,
            listed: earlier.clone(),
            earlier,
            written: Vec::new(),
        })
    }

    /// Refuses, before any work and without creating anything, the names among `names` in
    /// `dir` that could not be written: a link or a non-file stands there.
    pub fn check(dir: &Path, names: &[&str]) -> Result<(), RunDirError> {
        names
            .iter()
            .try_for_each(|n| crate::output::check_final(&dir.join(n)))
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// The files the writer's previous run wrote here, by name.
    pub fn earlier(&self) -> &BTreeSet<String> {
        &self.earlier
    }

    /// Writes the file `name` (a plain file name) in the directory: listed in the manifest
    /// first, then written whole through a temporary file; refused at a link or a non-file.
    /// Returns its path.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, RunDirError> {
        let path = self.dir.join(name);
        if !is_plain_name(name) {
            return Err(RunDirError::io(
                path,
                std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a plain file name"),
            ));
        }
        if !self.listed.contains(name) {
            self.listed.insert(name.to_string());
            self.save(&self.listed)?;
        }
        write_file(&path, bytes)?;
        self.written.push(name.to_string());
        Ok(path)
    }

    /// Removes the earlier run's files this run did not write again and our stale
    /// temporary files, and writes the manifest of this run.
    pub fn finish(self) -> Result<(), RunDirError> {
        let written: BTreeSet<String> = self.written.iter().cloned().collect();
        for name in self.earlier.difference(&written) {
            remove_regular(&self.dir.join(name))?;
        }
        let entries = std::fs::read_dir(&self.dir).map_err(|e| RunDirError::io(&self.dir, e))?;
        for entry in entries {
            let entry = entry.map_err(|e| RunDirError::io(&self.dir, e))?;
            let name = entry.file_name();
            let Some(name) = name.to_str() else { continue };
            let stale = name
                .strip_prefix('.')
                .and_then(|n| n.rsplit_once(TEMP_INFIX))
                .is_some_and(|(base, _)| self.listed.contains(base));
            if stale {
                remove_regular(&entry.path())?;
            }
        }
        self.save(&written)
    }

    fn save(&self, names: &BTreeSet<String>) -> Result<(), RunDirError> {
        let mut text = format!(
            "# the files {} wrote in this directory; a rerun removes only these\n",
            self.writer
        );
        for n in names {
            text.push_str(n);
            text.push('\n');
        }
        write_file(&self.dir.join(manifest_name(&self.writer)), text.as_bytes())
    }
}

/// Removes `path` if it is a regular file (never a link's target, never a directory).
fn remove_regular(path: &Path) -> Result<(), RunDirError> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_file() => std::fs::remove_file(path).map_err(|e| RunDirError::io(path, e)),
        _ => Ok(()),
    }
}

/// The names a manifest lists (none if it does not exist); lines that are not plain names
/// are ignored.
fn read_manifest(path: &Path) -> Result<BTreeSet<String>, RunDirError> {
    let file = match open_own(path, OpenOptions::new().read(true)) {
        Ok(f) => f,
        Err(RunDirError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
            return Ok(BTreeSet::new());
        }
        Err(e) => return Err(e),
    };
    let mut bytes = Vec::new();
    file.take(MAX_MANIFEST_BYTES)
        .read_to_end(&mut bytes)
        .map_err(|e| RunDirError::io(path, e))?;
    Ok(String::from_utf8_lossy(&bytes)
        .lines()
        .filter(|l| !l.starts_with('#') && is_plain_name(l))
        .map(String::from)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
