//! Opening files to read: only regular files, and, in our own directories, never through a
//! link.
//!
//! - [`check_regular`] is for a file a user names on the command line (a shard, measured
//!   data): links are followed (the user chose the path), but what they lead to must be a
//!   regular file. It is checked *before* the file is opened, because opening a FIFO waits
//!   for a writer that may never come, and a device such as `/dev/zero` never ends. Each
//!   reader bounds how much it reads (documented where it reads).
//! - [`open_own`] is for a file this program writes in its own directory (a shard being
//!   resumed, a manifest, a lock file): opened with `O_NOFOLLOW` (a link there is refused,
//!   [`RunDirError::Link`]) and `O_NONBLOCK` (a FIFO there does not block the open), and
//!   refused unless it is a regular file.

use crate::errors::{RunDirError, file_kind};
use std::fs::{File, OpenOptions};
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;

/// Checks that `path` leads to a regular file (links followed); returns its metadata.
pub fn check_regular(path: &Path) -> Result<std::fs::Metadata, RunDirError> {
    let meta = std::fs::metadata(path).map_err(|e| RunDirError::io(path, e))?;
    if meta.is_file() {
        Ok(meta)
    } else {
        Err(RunDirError::NotRegular {
            path: path.to_path_buf(),
            kind: file_kind(&meta.file_type()),
        })
    }
}

/// Opens `path` with `options` (read, append, create, …), without following a link at its
/// last component and without blocking on a FIFO; refuses anything but a regular file
/// ([`RunDirError::Link`], [`RunDirError::NotAFile`]).
pub fn open_own(path: &Path, options: &OpenOptions) -> Result<File, RunDirError> {
    use rustix::fs::OFlags;
    let mut options = options.clone();
    options.custom_flags((OFlags::NOFOLLOW | OFlags::NONBLOCK).bits() as i32);
    let file = match options.open(path) {
        Ok(f) => f,
        Err(e) => {
            // ELOOP: the last component is a link.
            let is_link = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
            return Err(if is_link {
                RunDirError::Link {
                    path: path.to_path_buf(),
                }
            } else {
                RunDirError::io(path, e)
            });
        }
    };
    let meta = file.metadata().map_err(|e| RunDirError::io(path, e))?;
    if meta.is_file() {
        Ok(file)
    } else {
        Err(RunDirError::NotAFile {
            path: path.to_path_buf(),
            kind: file_kind(&meta.file_type()),
        })
    }
}

/// Opens our own file `path` to append to it, as [`open_own`] does, and refuses it when it
/// has more than one name ([`RunDirError::HardLinked`]): appending through one name of a
/// hard-linked file (a shard linked from a user's backup) would change it under every name.
pub fn open_to_append(path: &Path, options: &OpenOptions) -> Result<File, RunDirError> {
    let file = open_own(path, options)?;
    check_single_name(&file, path)?;
    Ok(file)
}

/// Refuses the open `file` (at `path`) when it has more than one name
/// ([`RunDirError::HardLinked`]): to be called before it is appended to or truncated.
pub fn check_single_name(file: &File, path: &Path) -> Result<(), RunDirError> {
    use std::os::unix::fs::MetadataExt;
    let links = file
        .metadata()
        .map_err(|e| RunDirError::io(path, e))?
        .nlink();
    if links > 1 {
        return Err(RunDirError::HardLinked {
            path: path.to_path_buf(),
            links,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `/dev/zero`, a link to it and a FIFO are refused at once; a regular file (or a link
    /// to one) is not.
    #[test]
    fn only_regular_files_are_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        assert!(
            std::process::Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap()
                .success()
        );
        let zero = dir.path().join("zero");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        for p in [Path::new("/dev/zero"), &zero, &fifo] {
            let e = check_regular(p).unwrap_err();
            assert!(matches!(e, RunDirError::NotRegular { .. }), "{e}");
        }
        let file = dir.path().join("f");
        std::fs::write(&file, "x").unwrap();
        let link = dir.path().join("l");
        std::os::unix::fs::symlink(&file, &link).unwrap();
        check_regular(&file).unwrap();
        check_regular(&link).unwrap();
        // Our own files: a link is refused, a FIFO does not block and is refused.
        let read = OpenOptions::new().read(true).clone();
        assert!(matches!(
            open_own(&link, &read).unwrap_err(),
            RunDirError::Link { .. }
        ));
        assert!(matches!(
            open_own(&fifo, &read).unwrap_err(),
            RunDirError::NotAFile { .. }
        ));
        open_own(&file, &read).unwrap();
        // A file with a second name is not appended to.
        let append = OpenOptions::new().append(true).clone();
        open_to_append(&file, &append).unwrap();
        std::fs::hard_link(&file, dir.path().join("backup")).unwrap();
        let e = open_to_append(&file, &append).unwrap_err();
        assert!(matches!(e, RunDirError::HardLinked { links: 2, .. }), "{e}");
        assert!(e.to_string().contains("2 hard links"), "{e}");
    }
}
