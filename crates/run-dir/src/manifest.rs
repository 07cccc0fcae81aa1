//! A writer's output directory: locked while it writes, and a manifest of what it wrote, so
//! that a rerun removes or replaces only files it can prove it wrote.
//!
//! [`OutputDir::open`] creates the directory the user named (links are followed there: the
//! user chose the path), takes the lock of `.truss-mc.lock` in it ([`LOCK_FILE`]: one writer
//! at a time, every writer of the workspace alike; a second is refused with
//! [`RunDirError::Locked`] rather than left to wait behind a run that may take long), and
//! reads the writer's manifest `.WRITER.manifest` ([`crate::record`]: trusted only when it is
//! the writer's own, whole and unedited; each file listed with its device, inode, size and
//! SHA-256).
//!
//! **Replacing.** [`OutputDir::write`] writes a name only when nothing is there, or the file
//! there is provably the writer's: its manifest lists it with the identity it still has, or
//! claims the name (below), or this run wrote it. Any other file at the name (a user's, another
//! writer's such as a diagnosis's `theta_p-ecdf-before.svg`, one edited since) is refused with
//! [`RunDirError::NotOurs`], naming it and, when another writer's manifest lists it, that
//! writer: the file is left as it is. [`OutputDir::check`] makes the same check for every name
//! before any work, so a refusal never leaves a half-updated directory. A new name is listed
//! as a `claim` *before* it is written, so a crash never leaves a file of ours unlisted.
//!
//! **Removing.** [`OutputDir::finish`] removes the files of the earlier manifest that this run
//! did not write again (a renamed case's plots, the plots of a run with plots when this one
//! has none), but only those that are still the very file listed; a listed file that changed,
//! a name only claimed, the lock file and any manifest are kept, and each kept file is named
//! in one line on stderr (`warning: …`; the run still succeeds). It removes the temporary
//! files a killed run of ours left (`.NAME.tmp-` and exactly 16 hex digits, NAME one of our
//! names, owned by this user), and writes the manifest of this run. An untrusted manifest
//! (another user's, writable by others, edited, or of an older format) lists nothing: it is
//! named in one line on stderr and replaced by this run's.

use crate::errors::RunDirError;
use crate::input::open_own;
use crate::lock::{Lock, try_lock};
use crate::output::OutputFile;
pub use crate::record::is_plain_name;
use crate::record::{self, Entry, Identity};
use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// The lock file of an output directory.
pub const LOCK_FILE: &str = ".truss-mc.lock";

/// The manifest file of `writer`.
pub fn manifest_name(writer: &str) -> String {
    format!(".{writer}.manifest")
}

/// Whether `name` is never removed by a writer: the lock file, or a manifest.
fn is_kept_always(name: &str) -> bool {
    name == LOCK_FILE || (name.starts_with('.') && name.ends_with(".manifest"))
}

/// What a writer's earlier manifest gives it: the entries, or why it is not trusted.
type Earlier = Result<BTreeMap<String, Entry>, String>;

/// An output directory being written by one writer (see the module doc).
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    writer: String,
    /// Held until the writer is done.
    _lock: File,
    /// What the previous run's trusted manifest listed, or why it is not trusted.
    earlier: Earlier,
    /// What the manifest on disk lists now.
    listed: BTreeMap<String, Entry>,
    /// What this run wrote.
    written: BTreeMap<String, Identity>,
    /// The warnings printed, one line each.
    warnings: Vec<String>,
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
        let manifest = dir.join(manifest_name(writer));
        let earlier = record::read(&manifest)?;
        let mut out = Self {
            dir: dir.to_path_buf(),
            writer: writer.to_string(),
            _lock: lock,
            listed: earlier.clone().unwrap_or_default(),
            earlier,
            written: BTreeMap::new(),
            warnings: Vec::new(),
        };
        if let Err(why) = &out.earlier {
            out.warn(format!(
                "{}: not trusted ({why}); no file it lists is removed or replaced",
                manifest.display()
            ));
        }
        Ok(out)
    }

    /// Refuses, before any work and without creating anything, the names among `names` in
    /// `dir` that `writer` could not write: a link or a non-file stands there, or a file
    /// it cannot prove it wrote (see the module doc).
    pub fn check(dir: &Path, writer: &str, names: &[&str]) -> Result<(), RunDirError> {
        // A directory not made yet has no manifest: nothing there to prove.
        let earlier = record::read(&dir.join(manifest_name(writer)))?;
        names
            .iter()
            .try_for_each(|n| provable(dir, writer, &earlier, &BTreeMap::new(), n))
    }

    /// Like [`OutputDir::check`], under the lock: refuses the first of `names` this writer
    /// could not write.
    pub fn check_names<S: AsRef<str>>(&self, names: &[S]) -> Result<(), RunDirError> {
        names.iter().try_for_each(|n| {
            provable(
                &self.dir,
                &self.writer,
                &self.earlier,
                &self.written,
                n.as_ref(),
            )
        })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// The files the writer's previous run wrote here, by name, as its trusted manifest
    /// lists them (none when it is not trusted).
    pub fn earlier(&self) -> BTreeMap<String, Entry> {
        self.earlier.clone().unwrap_or_default()
    }

    /// The warnings this writer printed so far, one line each.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Writes the file `name` (a plain file name) in the directory: refused at a link, a
    /// non-file or a file not provably ours; listed in the manifest first, then written whole
    /// through a temporary file. Returns its path.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, RunDirError> {
        let path = self.dir.join(name);
        if !is_plain_name(name) || is_kept_always(name) {
            return Err(RunDirError::io(
                path,
                std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a plain file name"),
            ));
        }
        provable(&self.dir, &self.writer, &self.earlier, &self.written, name)?;
        if !self.listed.contains_key(name) {
            self.listed.insert(name.to_string(), Entry::Claim);
            self.save(&self.listed)?;
        }
        let mut out = OutputFile::create(&path)?;
        out.write_all(bytes)
            .map_err(|e| RunDirError::io(&path, e))?;
        let id = out.commit_identity(bytes)?;
        self.listed
            .insert(name.to_string(), Entry::File(id.clone()));
        self.written.insert(name.to_string(), id);
        Ok(path)
    }

    /// Removes the earlier run's files this run did not write again, when each is still the
    /// file listed (else it is kept and named on stderr), and our stale temporary files; writes
    /// the manifest of this run. Returns the warnings printed.
    pub fn finish(mut self) -> Result<Vec<String>, RunDirError> {
        let earlier = self.earlier.clone().unwrap_or_default();
        for (name, entry) in &earlier {
            if self.written.contains_key(name) || is_kept_always(name) {
                continue;
            }
            let path = self.dir.join(name);
            let there = std::fs::symlink_metadata(&path).is_ok();
            match entry {
                Entry::File(id) if id.matches(&path)? => {
                    std::fs::remove_file(&path).map_err(|e| RunDirError::io(&path, e))?;
                }
                Entry::File(_) if there => self.warn(format!(
                    "{}: kept: it is not the file {} wrote here (changed or replaced since)",
                    path.display(),
                    self.writer
                )),
                Entry::Claim if there => self.warn(format!(
                    "{}: kept: an earlier {} run was stopped before it could record this file",
                    path.display(),
                    self.writer
                )),
                Entry::File(_) | Entry::Claim => {}
            }
        }
        self.remove_stale_temporaries()?;
        let mine: BTreeMap<String, Entry> = self
            .written
            .iter()
            .map(|(n, id)| (n.clone(), Entry::File(id.clone())))
            .collect();
        self.save(&mine)?;
        Ok(self.warnings)
    }

    /// Removes `.NAME.tmp-` + 16 hex digits where NAME is one of ours, owned by this user.
    fn remove_stale_temporaries(&self) -> Result<(), RunDirError> {
        let me = rustix::process::geteuid().as_raw();
        let entries = std::fs::read_dir(&self.dir).map_err(|e| RunDirError::io(&self.dir, e))?;
        for entry in entries {
            let entry = entry.map_err(|e| RunDirError::io(&self.dir, e))?;
            let name = entry.file_name();
            let Some(name) = name.to_str() else { continue };
            let ours = crate::output::temporary_base(name)
                .is_some_and(|base| self.listed.contains_key(base) && !is_kept_always(base));
            if !ours {
                continue;
            }
            let path = entry.path();
            match std::fs::symlink_metadata(&path) {
                Ok(m) if m.is_file() && m.uid() == me && m.nlink() == 1 => {
                    std::fs::remove_file(&path).map_err(|e| RunDirError::io(&path, e))?;
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn warn(&mut self, line: String) {
        eprintln!("warning: {line}");
        self.warnings.push(line);
    }

    fn save(&self, entries: &BTreeMap<String, Entry>) -> Result<(), RunDirError> {
        let path = self.dir.join(manifest_name(&self.writer));
        crate::write_file(&path, record::render(entries).as_bytes())
    }
}

/// Refuses `name` in `dir` unless `writer` may write it: nothing there, or a regular file
/// this run wrote, or one its trusted earlier manifest lists with the identity it has (or
/// claims). A link or a non-file is refused as [`crate::output::check_final`] does.
fn provable(
    dir: &Path,
    writer: &str,
    earlier: &Earlier,
    written: &BTreeMap<String, Identity>,
    name: &str,
) -> Result<(), RunDirError> {
    let path = dir.join(name);
    crate::output::check_final(&path)?;
    if std::fs::symlink_metadata(&path).is_err() {
        return Ok(());
    }
    let listed = match earlier {
        Ok(entries) => entries.get(name),
        Err(_) => None,
    };
    let ours = match (written.get(name), listed) {
        (Some(id), _) => id.matches(&path)?,
        (None, Some(Entry::Claim)) => true,
        (None, Some(Entry::File(id))) => id.matches(&path)?,
        (None, None) => false,
    };
    if ours {
        return Ok(());
    }
    let why = match (earlier, listed) {
        (Err(why), _) => format!("{writer}'s manifest is not trusted: {why}"),
        (Ok(_), Some(_)) => format!("it changed since {writer} wrote it"),
        (Ok(_), None) => match other_writer(dir, writer, name) {
            Some(other) => format!("it is listed by {other}, another writer in this directory"),
            None => format!("{writer}'s manifest does not list it"),
        },
    };
    Err(RunDirError::NotOurs {
        path,
        writer: writer.to_string(),
        why,
    })
}

/// Another writer whose manifest in `dir` (trusted or not: this only names it) lists `name`.
fn other_writer(dir: &Path, writer: &str, name: &str) -> Option<String> {
    let mine = manifest_name(writer);
    std::fs::read_dir(dir).ok()?.find_map(|entry| {
        let file_name = entry.ok()?.file_name().into_string().ok()?;
        let other = file_name.strip_prefix('.')?.strip_suffix(".manifest")?;
        if file_name == mine {
            return None;
        }
        let file = open_own(&dir.join(&file_name), OpenOptions::new().read(true)).ok()?;
        let mut text = String::new();
        file.take(record::MAX_MANIFEST_BYTES)
            .read_to_string(&mut text)
            .ok()?;
        let suffix = format!(" {name}");
        text.lines()
            .any(|l| l == name || l.ends_with(&suffix))
            .then(|| other.to_string())
    })
}
