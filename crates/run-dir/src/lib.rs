//! # run-dir: files in a shared run directory
//!
//! A run directory is shared: cron workers on several machines, a merge, a diagnosis and the
//! people who read the reports all write into it, often over NFS. Anyone in the pool can plant
//! a symbolic link or leave a file of their own under a name we would write. This crate holds
//! the rules every writer and reader of the workspace follows, in one place:
//!
//! - **Outputs never go through a link, nor over what is not ours** ([`output`]). A file is
//!   written to a temporary file with an unpredictable name in the same directory, created
//!   exclusively (`O_CREAT|O_EXCL`, which never follows a link), flushed to disk, and renamed
//!   over its final name: a reader, a crash or a full disk sees the old file or the new one,
//!   never a torn one. A final name that is a symbolic link, or anything but a regular file
//!   (a directory, a FIFO), is refused, naming it ([`RunDirError::Link`],
//!   [`RunDirError::NotAFile`]); so is a directory we create inside the one the user named
//!   ([`output::create_dir`]) when it is a link. Files we append to (shards) are opened with
//!   `O_NOFOLLOW` ([`input::open_own`]).
//! - **A writer removes or replaces only what it can prove it wrote** ([`manifest`],
//!   [`record`]). Each writer keeps a manifest of the files it wrote in its directory
//!   (`.WRITER.manifest`: each file's device, inode, size and SHA-256), trusted only when it
//!   is owned by the current user, not writable by group or others, and matches its own
//!   digest. A rerun removes a listed file it does not write again only while that file is
//!   still the one listed, and writes over an existing file only on the same proof; anything
//!   else (a user's `theta_p-annotated.svg`, another writer's plots, a file edited since) is
//!   kept and named on stderr, or, at a name to write, refused ([`RunDirError::NotOurs`]).
//! - **Never written through a second name.** A file appended to (a shard being resumed) that
//!   has another hard link is refused ([`RunDirError::HardLinked`]).
//! - **One writer per directory at a time** ([`lock`]). A report directory is locked with the
//!   same kind of OS advisory lock the shards use (`flock`, on the file `.truss-mc.lock`); a
//!   second writer is refused at once, with the holder's pid when this machine can see it
//!   ([`RunDirError::Locked`]).
//! - **Inputs a user names are regular files** ([`input`]). A FIFO blocks an open forever
//!   and a device (`/dev/zero`) never ends; both are refused before they are opened
//!   ([`RunDirError::NotRegular`]). Each reader documents its own size limit.
//!
//! Every error names the path and says what kind of failure it is ([`RunDirError`]): an I/O
//! failure, a file in the way (a link, a foreign file, a file not provably ours, a hard-linked
//! file, a locked directory), or an input that
//! is not a regular file. Each binary maps them to the workspace's exit codes (4, 5 and 3 of
//! `truss-exit`) in its one exit-code function.

pub mod errors;
pub mod input;
pub mod lock;
pub mod manifest;
pub mod output;
pub mod record;

pub use errors::RunDirError;
pub use manifest::OutputDir;
pub use output::{OutputFile, create_dir, write_file};
