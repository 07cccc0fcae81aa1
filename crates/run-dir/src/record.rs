//! The manifest's format, and the proof of authorship it carries: whether a manifest is the
//! writer's own, and whether a file it lists is still the very file the writer wrote.
//!
//! A manifest names files that a rerun may remove or replace, so a manifest anyone could have
//! written would let anyone delete anyone's files. It is therefore trusted only when all of
//! these hold (else [`read`] says why, and the writer treats it as listing nothing):
//!
//! - it is a regular file, not a link (opened with `O_NOFOLLOW`);
//! - it is owned by the process's effective user, and neither its group nor others may
//!   write it (mode `& 0o022 == 0`): in a shared directory (sticky bit or not) another user
//!   can create a file of this name, but not one owned by us;
//! - it is whole and unedited: its first line is [`HEADER`], and its last line `end HEX` holds
//!   the SHA-256 of every byte before it, so an appended or removed line, a torn write or a
//!   manifest of an older format is refused.
//!
//! Each line between them is one file, its name last (a plain name may hold spaces):
//!
//! ```text
//! # truss-mc manifest 2 (the files one writer wrote here; a rerun removes or replaces a file only while it is the file listed)
//! file DEVICE INODE SIZE SHA256 NAME
//! claim NAME
//! end SHA256
//! ```
//!
//! A `file` line is the identity of a file the writer wrote: device and inode numbers, size in
//! bytes and the SHA-256 of its content. A file at that name is the writer's only while all
//! four match ([`Identity::matches`]); a file replaced, edited or moved in since is not. A
//! `claim` line is a name the writer was about to write when the manifest was saved (it lists
//! a name *before* writing it, so that a crash never leaves its file unlisted): a rerun may
//! write that name again, but never removes a file on a claim alone.

use crate::errors::RunDirError;
use crate::input::open_own;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::Read;
use std::os::unix::fs::MetadataExt;
use std::path::Path;

/// The first line of a manifest of this format.
pub const HEADER: &str = "# truss-mc manifest 2 (the files one writer wrote here; a rerun removes or replaces a file only while it is the file listed)";

/// The longest manifest read \[bytes\]: a million plot names.
pub const MAX_MANIFEST_BYTES: u64 = 64 << 20;

/// Whether `name` is a plain file name (no directory part, not `.` or `..`, no line break),
/// the only kind a manifest lists.
pub fn is_plain_name(name: &str) -> bool {
    !name.is_empty() && name != "." && name != ".." && !name.contains(['/', '\n', '\r', '\0'])
}

/// A file as its writer left it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    /// Device number of the file system.
    pub dev: u64,
    /// Inode number.
    pub ino: u64,
    /// Size \[bytes\].
    pub size: u64,
    /// SHA-256 of the content, lower-case hex.
    pub sha256: String,
}

impl Identity {
    /// The identity of the open `file` whose content is `bytes` (the writer's own bytes, so
    /// the digest is not read back).
    pub fn of_written(file: &File, bytes: &[u8]) -> std::io::Result<Self> {
        let meta = file.metadata()?;
        Ok(Self {
            dev: meta.dev(),
            ino: meta.ino(),
            size: meta.len(),
            sha256: hex(&Sha256::digest(bytes)),
        })
    }

    /// Whether the regular file at `path` (a link is never followed) is this file: same
    /// device, inode and size, then the same content. `Ok(false)` when it is not, or when
    /// nothing or something other than a regular file is there.
    pub fn matches(&self, path: &Path) -> Result<bool, RunDirError> {
        let file = match open_own(path, OpenOptions::new().read(true)) {
            Ok(f) => f,
            Err(RunDirError::Io { source, .. })
                if source.kind() == std::io::ErrorKind::NotFound =>
            {
                return Ok(false);
            }
            Err(RunDirError::Link { .. } | RunDirError::NotAFile { .. }) => return Ok(false),
            Err(e) => return Err(e),
        };
        let meta = file.metadata().map_err(|e| RunDirError::io(path, e))?;
        if (meta.dev(), meta.ino(), meta.len()) != (self.dev, self.ino, self.size) {
            return Ok(false);
        }
        let mut hasher = Sha256::new();
        let mut buf = vec![0u8; 1 << 16];
        let mut reader = file.take(self.size + 1);
        loop {
            let n = reader
                .read(&mut buf)
                .map_err(|e| RunDirError::io(path, e))?;
            if n == 0 {
                break;
            }
            hasher.update(&buf[..n]);
        }
        Ok(hex(&hasher.finalize()) == self.sha256)
    }
}

/// What a manifest says about one name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Entry {
    /// The writer wrote this file.
    File(Identity),
    /// The writer was about to write this name.
    Claim,
}

/// Lower-case hex of `bytes`.
fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The text of a manifest listing `entries` (see the module doc).
pub fn render(entries: &BTreeMap<String, Entry>) -> String {
    let mut text = format!("{HEADER}\n");
    for (name, entry) in entries {
        match entry {
            Entry::File(id) => text.push_str(&format!(
                "file {} {} {} {} {name}\n",
                id.dev, id.ino, id.size, id.sha256
            )),
            Entry::Claim => text.push_str(&format!("claim {name}\n")),
        }
    }
    let end = hex(&Sha256::digest(text.as_bytes()));
    text.push_str(&format!("end {end}\n"));
    text
}

/// Reads the manifest at `path`: `Ok(Ok(entries))` when it is trusted (none when there is no
/// manifest), `Ok(Err(why))` when it is not (see the module doc; `why` in words), `Err` on an
/// I/O failure.
pub fn read(path: &Path) -> Result<Result<BTreeMap<String, Entry>, String>, RunDirError> {
    let file = match open_own(path, OpenOptions::new().read(true)) {
        Ok(f) => f,
        Err(RunDirError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
            return Ok(Ok(BTreeMap::new()));
        }
        Err(e @ (RunDirError::Link { .. } | RunDirError::NotAFile { .. })) => {
            return Ok(Err(e.to_string()));
        }
        Err(e) => return Err(e),
    };
    let meta = file.metadata().map_err(|e| RunDirError::io(path, e))?;
    let me = rustix::process::geteuid().as_raw();
    if meta.uid() != me {
        return Ok(Err(format!(
            "it is owned by user {}, not by this process's user {me}",
            meta.uid()
        )));
    }
    if meta.mode() & 0o022 != 0 {
        return Ok(Err(format!(
            "its group or others may write it (mode {:o})",
            meta.mode() & 0o7777
        )));
    }
    let mut bytes = Vec::new();
    file.take(MAX_MANIFEST_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| RunDirError::io(path, e))?;
    if bytes.len() as u64 > MAX_MANIFEST_BYTES {
        return Ok(Err(format!("it is longer than {MAX_MANIFEST_BYTES} bytes")));
    }
    Ok(parse(&bytes))
}

/// The entries of a manifest's bytes, or why they are not a whole manifest of this format.
fn parse(bytes: &[u8]) -> Result<BTreeMap<String, Entry>, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "it is not UTF-8".to_string())?;
    let body_end = text
        .trim_end_matches('\n')
        .rfind('\n')
        .map(|i| i + 1)
        .ok_or("it is not a manifest of this format")?;
    let (body, end) = text.split_at(body_end);
    if !body.starts_with(&format!("{HEADER}\n")) {
        return Err("it is not a manifest of this format (or of an older one)".into());
    }
    if end != format!("end {}\n", hex(&Sha256::digest(body.as_bytes()))) {
        return Err("its lines do not match its own digest (edited, appended to or torn)".into());
    }
    let mut entries = BTreeMap::new();
    for line in body.lines().skip(1) {
        let (name, entry) = parse_line(line).ok_or_else(|| format!("unreadable line {line:?}"))?;
        if !is_plain_name(name) {
            return Err(format!("line {line:?} does not name a plain file"));
        }
        entries.insert(name.to_string(), entry);
    }
    Ok(entries)
}

fn parse_line(line: &str) -> Option<(&str, Entry)> {
    if let Some(name) = line.strip_prefix("claim ") {
        return Some((name, Entry::Claim));
    }
    let mut parts = line.strip_prefix("file ")?.splitn(5, ' ');
    let mut number = || parts.next()?.parse::<u64>().ok();
    let (dev, ino, size) = (number()?, number()?, number()?);
    let sha256 = parts.next()?;
    let name = parts.next()?;
    let hex_digits = sha256.len() == 64 && sha256.bytes().all(|b| b.is_ascii_hexdigit());
    hex_digits.then(|| {
        let id = Identity {
            dev,
            ino,
            size,
            sha256: sha256.to_ascii_lowercase(),
        };
        (name, Entry::File(id))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rendered manifest reads back; one appended line, an edited digest or the old
    /// format (names only) is not trusted.
    #[test]
    fn manifests_read_back_and_edits_are_refused() {
        let id = Identity {
            dev: 1,
            ino: 2,
            size: 3,
            sha256: "a".repeat(64),
        };
        let entries: BTreeMap<String, Entry> = [
            ("a b.svg".to_string(), Entry::File(id)),
            ("c.md".to_string(), Entry::Claim),
        ]
        .into();
        let text = render(&entries);
        assert_eq!(parse(text.as_bytes()).unwrap(), entries);
        let appended = format!("{text}notes.txt\n");
        assert!(parse(appended.as_bytes()).is_err());
        let inserted = text.replacen("claim c.md\n", "claim c.md\nclaim notes.txt\n", 1);
        assert!(parse(inserted.as_bytes()).is_err());
        let old = "# the files mc-merge wrote in this directory\nnotes.txt\n";
        assert!(parse(old.as_bytes()).is_err());
        assert!(parse(b"").is_err());
    }
}
