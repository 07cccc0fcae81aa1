//! Why a file in a run directory was not written or read, naming the path.

use std::path::PathBuf;

/// A file that could not be written or read, or that was refused.
#[derive(Debug, thiserror::Error)]
pub enum RunDirError {
    /// The operating system's error (a full disk, no permission, a missing directory).
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The name to write is a symbolic link: writing would change the file it points to.
    #[error("{}: is a symbolic link; outputs are never written through a link (remove the link, or use another directory)", path.display())]
    Link {
        /// The link.
        path: PathBuf,
    },
    /// The name to write holds something other than a regular file.
    #[error("{}: is {kind}, not a file this program writes; it is left as it is (move it away, or use another directory)", path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// What it is: `a directory`, `a pipe`, …
        kind: &'static str,
    },
    /// Another process holds the directory's lock: it is writing there now.
    #[error("{}: another process is writing this directory ({}): wait for it or stop it", path.display(), holder_words(*holder))]
    Locked {
        /// The directory.
        path: PathBuf,
        /// The lock holder's pid, when this machine can see it.
        holder: Option<u32>,
    },
    /// A regular file stands at a name to write, and the writer cannot prove it wrote it (its
    /// manifest does not list it as it is now): replacing it could destroy someone's file.
    #[error("{}: not replaced: {why}; it is left as it is (move it away, or use another directory)", path.display())]
    NotOurs {
        /// The file.
        path: PathBuf,
        /// The writer (`mc-merge`, …).
        writer: String,
        /// Why it is not provably the writer's, in words.
        why: String,
    },
    /// A file to append to has more than one name (a hard link): appending would change the
    /// other names' file too.
    #[error("{}: has {links} hard links; appending would also change the file at its other names (copy it to a file of its own, or remove the other links)", path.display())]
    HardLinked {
        /// The file.
        path: PathBuf,
        /// Its number of links.
        links: u64,
    },
    /// A file a user named is not a regular file (a FIFO, a device, a directory).
    #[error("{}: not a regular file ({kind}); give the path of a file", path.display())]
    NotRegular {
        /// The path.
        path: PathBuf,
        /// What it is.
        kind: &'static str,
    },
}

impl RunDirError {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        RunDirError::Io {
            path: path.into(),
            source,
        }
    }
}

/// A lock holder in words: `pid 1234`, or why the pid is not known.
pub fn holder_words(holder: Option<u32>) -> String {
    match holder {
        Some(pid) => format!("pid {pid}"),
        None => "its pid is not visible here: it may run on another machine".into(),
    }
}

/// What a file that is not a regular file is, in words.
pub fn file_kind(t: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if t.is_dir() {
        "a directory"
    } else if t.is_symlink() {
        "a symbolic link"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_fifo() {
        "a pipe"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}
