//! Advisory file locks (`flock`, std's [`File::try_lock`]), the mechanism shards are locked
//! with, and who holds one.
//!
//! A lock is held by an open file and released when the holder closes it or dies, so a
//! lock is never stale. When a lock is busy, the holder's pid is looked up in
//! `/proc/locks` (Linux) by the file's device and inode; a holder on another machine
//! (over NFS) is not listed there, and is reported as not visible.

use std::fs::File;

/// What trying a lock found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lock {
    /// The lock is ours until the file is closed.
    Taken,
    /// Another open file holds it; its process, when visible here.
    Held {
        /// The holder's pid.
        holder: Option<u32>,
    },
}

/// Takes `file`'s exclusive lock without waiting.
pub fn try_lock(file: &File) -> std::io::Result<Lock> {
    match file.try_lock() {
        Ok(()) => Ok(Lock::Taken),
        Err(std::fs::TryLockError::WouldBlock) => Ok(Lock::Held {
            holder: holder(file),
        }),
        Err(std::fs::TryLockError::Error(e)) => Err(e),
    }
}

/// The pid of the process holding a `flock` lock on `file`, from `/proc/locks` (read up to
/// three times, see below).
pub fn holder(file: &File) -> Option<u32> {
    use std::os::unix::fs::MetadataExt;
    let meta = file.metadata().ok()?;
    let dev = meta.dev();
    let key = format!(
        "{:02x}:{:02x}:{}",
        rustix::fs::major(dev),
        rustix::fs::minor(dev),
        meta.ino()
    );
    // The kernel writes /proc/locks a page at a time: a lock taken or released by another
    // thread between two reads can shift the lines so that one is skipped. Read it again
    // before saying the holder is not visible.
    (0..3).find_map(|_| holder_in(&std::fs::read_to_string("/proc/locks").ok()?, &key))
}

/// The pid of the `FLOCK` lock on `key` (`MAJOR:MINOR:INODE`, as `/proc/locks` writes it) in
/// the text of `/proc/locks`; waiting requests (`->`) are not holders.
fn holder_in(table: &str, key: &str) -> Option<u32> {
    table.lines().find_map(|line| {
        let fields: Vec<&str> = line.split_whitespace().collect();
        match fields.as_slice() {
            [_, "FLOCK", _, _, pid, dev, ..] if *dev == key => pid.parse().ok(),
            _ => None,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_holder_is_found_in_proc_locks() {
        let table = "1: POSIX  ADVISORY  WRITE 77 fe:00:12 0 EOF\n\
                     2: FLOCK  ADVISORY  WRITE 4242 fe:00:5529825 0 EOF\n\
                     2: -> FLOCK  ADVISORY  WRITE 99 fe:00:5529825 0 EOF\n";
        assert_eq!(holder_in(table, "fe:00:5529825"), Some(4242));
        assert_eq!(holder_in(table, "fe:00:12"), None);
    }

    /// A second open file of the same path finds the lock held, by this process.
    #[test]
    fn a_held_lock_names_its_holder() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("lock");
        let first = File::create(&path).unwrap();
        assert_eq!(try_lock(&first).unwrap(), Lock::Taken);
        let second = File::open(&path).unwrap();
        let found = try_lock(&second).unwrap();
        if std::path::Path::new("/proc/locks").exists() {
            assert_eq!(
                found,
                Lock::Held {
                    holder: Some(std::process::id())
                }
            );
        } else {
            assert!(matches!(found, Lock::Held { .. }));
        }
        drop(first);
        // Another test of this binary may fork a child between our open and its exec: the
        // child holds a copy of `first` (close-on-exec closes it at the exec), so the lock is
        // released when that copy closes, within moments.
        let released = (0..200).any(|_| {
            let taken = try_lock(&second).unwrap() == Lock::Taken;
            if !taken {
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
            taken
        });
        assert!(released, "the lock outlived its file by 2 s");
    }
}
