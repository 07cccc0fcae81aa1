//! Writing an output file: never through a link, never over what is not ours, never torn.
//!
//! [`OutputFile::create`] first looks at the final name without following it: a symbolic
//! link there is refused ([`RunDirError::Link`]), and so is anything but a regular file
//! ([`RunDirError::NotAFile`]). It then creates `.NAME.tmp-XXXXXXXXXXXXXXXX` in the same
//! directory (16 hex digits from the process's random hash keys, so another user cannot
//! guess it) with `O_CREAT|O_EXCL`, which fails rather than follow a link or open a file
//! that exists. The caller writes; [`OutputFile::commit`] flushes, syncs the file to disk and
//! renames it over the final name (`rename` replaces a link planted meanwhile, never its
//! target), and [`OutputFile::commit_new`] links it in place only if the name is still free.
//! An output dropped before either is removed, so a failed write (a full disk, a file-size
//! limit) leaves the final name as it was.

use crate::errors::{RunDirError, file_kind};
use std::fs::File;
use std::hash::{BuildHasher, RandomState};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The infix of temporary files: `.NAME.tmp-` then 16 hex digits.
pub const TEMP_INFIX: &str = ".tmp-";

/// The NAME of a temporary file name `.NAME.tmp-` + exactly 16 lower-case hex digits (as
/// [`OutputFile::create`] makes them), or `None` for any other name.
pub fn temporary_base(file_name: &str) -> Option<&str> {
    let (base, suffix) = file_name.strip_prefix('.')?.rsplit_once(TEMP_INFIX)?;
    let hex = suffix.len() == 16
        && suffix
            .bytes()
            .all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'));
    (hex && !base.is_empty()).then_some(base)
}

/// Checks what is at an output's final name, without following it: nothing, or a regular
/// file, may be replaced; a link or anything else is refused.
pub fn check_final(path: &Path) -> Result<(), RunDirError> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => Err(RunDirError::Link {
            path: path.to_path_buf(),
        }),
        Ok(m) if !m.is_file() => Err(RunDirError::NotAFile {
            path: path.to_path_buf(),
            kind: file_kind(&m.file_type()),
        }),
        Ok(_) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(RunDirError::io(path, e)),
    }
}

/// Creates the directory `path` inside a directory that exists (one the user named), or
/// accepts it if it is already a directory; refuses it when it is a symbolic link (even to
/// a directory: what is written there would land wherever the link points) or not a
/// directory.
pub fn create_dir(path: &Path) -> Result<(), RunDirError> {
    let check = || match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => Err(RunDirError::Link {
            path: path.to_path_buf(),
        }),
        Ok(m) if m.is_dir() => Ok(()),
        Ok(m) => Err(RunDirError::NotAFile {
            path: path.to_path_buf(),
            kind: file_kind(&m.file_type()),
        }),
        Err(e) => Err(RunDirError::io(path, e)),
    };
    match std::fs::create_dir(path) {
        Ok(()) => Ok(()),
        // `mkdir` never follows a link at its last component: look at what is there.
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => check(),
        Err(e) => Err(RunDirError::io(path, e)),
    }
}

/// An unpredictable 64-bit number: the process's random hash keys (seeded from the
/// operating system) applied to a counter and the time.
fn unpredictable() -> u64 {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    RandomState::new().hash_one((n, t, std::process::id()))
}

/// An output being written to its temporary file (see the module doc).
#[derive(Debug)]
pub struct OutputFile {
    path: PathBuf,
    temp: PathBuf,
    file: Option<BufWriter<File>>,
}

impl OutputFile {
    /// Starts the output `path`: refuses a link or a non-file at `path`, and creates the
    /// temporary file beside it.
    pub fn create(path: &Path) -> Result<Self, RunDirError> {
        check_final(path)?;
        let name = path
            .file_name()
            .ok_or_else(|| {
                RunDirError::io(
                    path,
                    std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name"),
                )
            })?
            .to_string_lossy()
            .into_owned();
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        loop {
            let temp = dir.join(format!(".{name}{TEMP_INFIX}{:016x}", unpredictable()));
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&temp)
            {
                Ok(file) => {
                    return Ok(Self {
                        path: path.to_path_buf(),
                        temp,
                        file: Some(BufWriter::new(file)),
                    });
                }
                // Someone took the name (a guess, or a planted link): draw another.
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(RunDirError::io(path, e)),
            }
        }
    }

    /// The final name.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes and syncs the temporary file; returns it, still open.
    fn seal(&mut self) -> Result<File, RunDirError> {
        let writer = self.file.take().expect("an output is sealed once");
        let file = writer
            .into_inner()
            .map_err(|e| RunDirError::io(&self.path, e.into_error()))?;
        file.sync_all()
            .map_err(|e| RunDirError::io(&self.path, e))?;
        Ok(file)
    }

    /// Syncs the file to disk and renames it over the final name (refused if a link or a
    /// non-file has appeared there).
    pub fn commit(self) -> Result<(), RunDirError> {
        self.commit_then(|_| Ok(()))
    }

    /// Like [`OutputFile::commit`], and returns the identity of the file committed, whose
    /// content was `bytes` (the device and inode are read from the open file before the
    /// rename, so a file swapped in afterwards is not mistaken for it).
    pub fn commit_identity(self, bytes: &[u8]) -> Result<crate::record::Identity, RunDirError> {
        let path = self.path.clone();
        self.commit_then(|file| {
            crate::record::Identity::of_written(file, bytes).map_err(|e| RunDirError::io(&path, e))
        })
    }

    fn commit_then<T>(
        mut self,
        before: impl FnOnce(&File) -> Result<T, RunDirError>,
    ) -> Result<T, RunDirError> {
        let done = self.seal().and_then(|file| {
            let value = before(&file)?;
            check_final(&self.path)?;
            std::fs::rename(&self.temp, &self.path).map_err(|e| RunDirError::io(&self.path, e))?;
            Ok(value)
        });
        if done.is_err() {
            let _ = std::fs::remove_file(&self.temp);
        }
        done
    }

    /// Syncs the file to disk and puts it at the final name only if nothing is there (a hard
    /// link, which never replaces): `Ok(false)` if the name was taken meanwhile. The
    /// temporary file is removed either way.
    pub fn commit_new(mut self) -> Result<bool, RunDirError> {
        let done = self
            .seal()
            .and_then(|_| match std::fs::hard_link(&self.temp, &self.path) {
                Ok(()) => Ok(true),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
                Err(e) => Err(RunDirError::io(&self.path, e)),
            });
        let _ = std::fs::remove_file(&self.temp);
        done
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.file
            .as_mut()
            .expect("an output is written before it is sealed")
            .write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file
            .as_mut()
            .expect("an output is flushed before it is sealed")
            .flush()
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        if self.file.is_some() {
            // Not committed: the final name keeps what it had.
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

/// Writes `bytes` as the file `path` (see the module doc): refused at a link or a non-file,
/// written whole or not at all.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), RunDirError> {
    let mut out = OutputFile::create(path)?;
    out.write_all(bytes).map_err(|e| RunDirError::io(path, e))?;
    out.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A link at the final name is refused and its target untouched; a regular file is
    /// replaced whole; no temporary file is left.
    #[test]
    fn links_are_refused_and_files_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("theirs.txt");
        std::fs::write(&target, "theirs").unwrap();
        let link = dir.path().join("out.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let e = write_file(&link, b"ours").unwrap_err();
        assert!(matches!(e, RunDirError::Link { .. }), "{e}");
        assert!(e.to_string().contains("out.txt"), "{e}");
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "theirs");
        let file = dir.path().join("file.txt");
        std::fs::write(&file, "old").unwrap();
        write_file(&file, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "new");
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(names.len(), 3, "{names:?}");
    }

    /// A directory at the final name is not ours; a link where a directory is to be created
    /// is refused.
    #[test]
    fn non_files_and_linked_directories_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let e = write_file(&sub, b"x").unwrap_err();
        assert!(matches!(e, RunDirError::NotAFile { .. }), "{e}");
        create_dir(&sub).unwrap();
        let link = dir.path().join("quarantine");
        std::os::unix::fs::symlink(&sub, &link).unwrap();
        assert!(matches!(
            create_dir(&link).unwrap_err(),
            RunDirError::Link { .. }
        ));
        create_dir(&dir.path().join("new")).unwrap();
        assert!(dir.path().join("new").is_dir());
    }

    /// An output dropped before its commit leaves nothing; `commit_new` never replaces.
    #[test]
    fn uncommitted_outputs_vanish_and_new_ones_never_replace() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.csv");
        std::fs::write(&path, "old").unwrap();
        let mut out = OutputFile::create(&path).unwrap();
        out.write_all(b"half").unwrap();
        drop(out);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let out = OutputFile::create(&path).unwrap();
        assert!(!out.commit_new().unwrap());
        let fresh = dir.path().join("b.csv");
        let mut out = OutputFile::create(&fresh).unwrap();
        out.write_all(b"b").unwrap();
        assert!(out.commit_new().unwrap());
        assert_eq!(std::fs::read_to_string(&fresh).unwrap(), "b");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }
}
