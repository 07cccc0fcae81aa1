//! Flat exports: every verified sample as one row of a CSV file (or one object of a JSON
//! Lines file), for spreadsheets, pandas or R.
//!
//! `mc-merge DIR… --export samples.csv` first verifies the shards exactly as a merge does
//! ([`crate::load::load`]: one job, every digest, every index once, the same
//! `--allow-partial` / `--allow-failed` rules and exit codes), and writes nothing if they do
//! not verify. The format follows the file's extension:
//!
//! - `.csv`: a header row, then one row per sample in global index order, with the columns
//!   [`COLUMNS`]: `index` (global sample index), `case` (case name), `sample` (index within
//!   the case), `status` (`converged` or `failed`), `theta_p` \[rad\], `tan_theta_x` \[-\],
//!   `tan_theta_y` \[-\], `decenter_x`, `decenter_y`, `decenter`, `despace` \[mm\] (where
//!   the top surface's centroid sits against the bottom's frame, `truss_core::measure`;
//!   empty in shards of numerics version 7 or earlier), `iterations` (Newton iterations),
//!   `slack_cables` (slack tension-only members), `loose_joints` (loose pin joints; empty for
//!   models without joints), `holding_force` \[N\] (the largest force on a top node that, to
//!   first order, moves θ_P by at most 1 % and lets no bearing member go; empty where not
//!   recorded). A field a sample does not have (the angles of a failed sample) is empty.
//!   Case names are quoted as RFC 4180 says when they hold a comma, a quote or a line break.
//! - `.jsonl`: one object per sample with the same keys, absent fields as `null`.
//!
//! Numbers are the bytes of the shard lines, copied, not reformatted: the shortest
//! round-trip form the runner wrote, so every value reads back to the same `f64`.
//!
//! pandas: read the `.jsonl` export with `pd.read_json(path, lines=True, precise_float=True)`.
//! Without `precise_float=True` its JSON float parser changes the last digits of most values
//! (294,611 of 300,000 θ_P values of a test export, pandas 3.1). `pd.read_csv(path)` is exact
//! from pandas 3 on; older versions need `float_precision="round_trip"`.
//!
//! The file is written to a temporary file with an unpredictable name beside its final path
//! and renamed into place when complete (crate `run-dir`), so a failed export leaves no
//! partial file, and a symbolic link at the final path is refused (exit 5), never followed.
//! An export path that is one of the shard files read, or lies in a directory scanned for
//! shards, is refused before anything is read (usage, exit 2): it would destroy a shard, or
//! (a `.jsonl` file) be taken for one by the next merge.

use crate::errors::MergeError;
use crate::load::{LoadOptions, load, shard_files};
use crate::settings::{Options, Settings};
use shard_record::Record;
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

/// The exported columns, in order.
pub const COLUMNS: [&str; 15] = [
    "index",
    "case",
    "sample",
    "status",
    "theta_p",
    "tan_theta_x",
    "tan_theta_y",
    "decenter_x",
    "decenter_y",
    "decenter",
    "despace",
    "iterations",
    "slack_cables",
    "loose_joints",
    "holding_force",
];

/// An export format, from the file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Comma-separated values with a header row.
    Csv,
    /// One JSON object per line.
    JsonLines,
}

impl Format {
    /// The format of `path` by its extension (`.csv`, `.jsonl`).
    pub fn of(path: &Path) -> Result<Format, MergeError> {
        match path.extension().and_then(|e| e.to_str()) {
            Some("csv") => Ok(Format::Csv),
            Some("jsonl") => Ok(Format::JsonLines),
            _ => Err(MergeError::Usage {
                message: format!(
                    "--export {}: the file must end in .csv or .jsonl",
                    path.display()
                ),
            }),
        }
    }
}

/// Verifies the shards at `paths` as a merge does, then writes every sample to `to`;
/// returns the number of rows written.
pub fn export(paths: &[PathBuf], settings: &Settings, to: &Path) -> Result<u64, MergeError> {
    let format = Format::of(to)?;
    let settings = settings.validate()?;
    let files = shard_files(paths)?;
    check_destination(paths, &files, to)?;
    let dataset = load(
        &files,
        LoadOptions {
            allow_partial: settings.allow_partial,
            allow_failed: settings.allow_failed,
            threads: settings.threads,
        },
    )?;
    // The verified files, by the start of their range; overlaps are identical (verified),
    // so each index is taken from the first file that holds it.
    let mut ordered = Vec::new();
    for f in &dataset.files {
        ordered.push((range_start(f)?, f.clone()));
    }
    ordered.sort();
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| MergeError::Io { path, source }
    };
    let mut out = run_dir::OutputFile::create(to)?;
    if format == Format::Csv {
        writeln!(out, "{}", COLUMNS.join(",")).map_err(io(to))?;
    }
    let mut next = 0u64;
    let mut rows = 0u64;
    let mut row = Vec::new();
    for (_, file) in &ordered {
        let reader = std::io::BufReader::new(std::fs::File::open(file).map_err(io(file))?);
        for line in reader.split(b'\n') {
            let line = line.map_err(io(file))?;
            if !line.starts_with(br#"{"record":"sample""#) {
                continue;
            }
            let fields = flat_fields(&line).ok_or_else(|| MergeError::Internal {
                message: format!("{}: a verified sample line did not scan", file.display()),
            })?;
            let index = field(&fields, "index")
                .and_then(|v| std::str::from_utf8(v).ok()?.parse::<u64>().ok())
                .ok_or_else(|| MergeError::Internal {
                    message: format!("{}: a sample line without an index", file.display()),
                })?;
            if index < next {
                continue;
            }
            next = index + 1;
            row.clear();
            match format {
                Format::Csv => csv_row(&fields, &mut row),
                Format::JsonLines => json_row(&fields, &mut row),
            }
            out.write_all(&row).map_err(io(to))?;
            rows += 1;
        }
    }
    out.commit()?;
    Ok(rows)
}

/// Refuses an export path `to` that is one of the shard `files` read, or lies in one of the
/// directories among `paths` (scanned for shards). Paths are compared with links resolved,
/// and files also by their device and inode (a hard link).
fn check_destination(paths: &[PathBuf], files: &[PathBuf], to: &Path) -> Result<(), MergeError> {
    use std::os::unix::fs::MetadataExt;
    let parent = match to.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    // A missing directory: the write will say so.
    let Ok(parent) = parent.canonicalize() else {
        return Ok(());
    };
    let refuse = |why: String| MergeError::Usage {
        message: format!(
            "--export {}: {why}; give a path outside the shards' directories",
            to.display()
        ),
    };
    for dir in paths.iter().filter(|p| p.is_dir()) {
        if dir.canonicalize().is_ok_and(|d| d == parent) {
            return Err(refuse(format!(
                "lies in {}, a directory read for shards (the next merge would take a .jsonl export for a shard)",
                dir.display()
            )));
        }
    }
    let target = to.file_name().map(|name| parent.join(name));
    let inode = std::fs::symlink_metadata(to)
        .ok()
        .map(|m| (m.dev(), m.ino()));
    for file in files {
        let same_path = file.canonicalize().ok() == target;
        let same_inode =
            inode.is_some() && std::fs::metadata(file).ok().map(|m| (m.dev(), m.ino())) == inode;
        if same_path || same_inode {
            return Err(refuse(format!(
                "is the shard file {}, which this merge reads",
                file.display()
            )));
        }
    }
    Ok(())
}

/// `mc-merge … --export FILE`: verifies and exports, printing the row count to `out` (the
/// command line then merges as usual when `--out` is given as well).
pub fn run(options: &Options, to: &Path, out: &mut dyn Write) -> Result<(), MergeError> {
    let rows = export(&options.paths, &options.settings, to)?;
    writeln!(out, "exported {rows} samples to {}", to.display()).map_err(|source| MergeError::Io {
        path: PathBuf::from("<stdout>"),
        source,
    })
}

/// The start of the range in a shard's header line.
fn range_start(file: &Path) -> Result<u64, MergeError> {
    let f = std::fs::File::open(file).map_err(|source| MergeError::Io {
        path: file.to_path_buf(),
        source,
    })?;
    let mut first = String::new();
    std::io::BufReader::new(f)
        .read_line(&mut first)
        .map_err(|source| MergeError::Io {
            path: file.to_path_buf(),
            source,
        })?;
    match serde_json::from_str::<Record>(&first) {
        Ok(Record::Begin(b)) => Ok(b.range.start),
        _ => Err(MergeError::Internal {
            message: format!("{}: a verified shard without a header", file.display()),
        }),
    }
}

/// The value bytes of `key` among `fields`.
fn field<'a>(fields: &[(&[u8], &'a [u8])], key: &str) -> Option<&'a [u8]> {
    fields
        .iter()
        .find(|(k, _)| *k == key.as_bytes())
        .map(|(_, v)| *v)
}

/// One CSV row of a sample's fields: numbers copied, strings unescaped and quoted if needed.
fn csv_row(fields: &[(&[u8], &[u8])], row: &mut Vec<u8>) {
    for (i, column) in COLUMNS.iter().enumerate() {
        if i > 0 {
            row.push(b',');
        }
        match field(fields, column) {
            None | Some(b"null") => {}
            Some(v) if v.first() == Some(&b'"') => {
                let text: String = serde_json::from_slice(v).unwrap_or_default();
                if text.contains([',', '"', '\n', '\r']) {
                    row.push(b'"');
                    row.extend_from_slice(text.replace('"', "\"\"").as_bytes());
                    row.push(b'"');
                } else {
                    row.extend_from_slice(text.as_bytes());
                }
            }
            Some(v) => row.extend_from_slice(v),
        }
    }
    row.push(b'\n');
}

/// One JSON object of a sample's fields, values copied as they are.
fn json_row(fields: &[(&[u8], &[u8])], row: &mut Vec<u8>) {
    row.push(b'{');
    for (i, column) in COLUMNS.iter().enumerate() {
        if i > 0 {
            row.push(b',');
        }
        row.push(b'"');
        row.extend_from_slice(column.as_bytes());
        row.extend_from_slice(b"\":");
        row.extend_from_slice(field(fields, column).unwrap_or(b"null"));
    }
    row.extend_from_slice(b"}\n");
}

/// The keys (without quotes) and raw value bytes of a flat JSON object (values: strings,
/// numbers, literals; no nesting), as a sample line is. `None` if it is not one.
fn flat_fields(line: &[u8]) -> Option<Vec<(&[u8], &[u8])>> {
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    let inner = line.strip_prefix(b"{")?.strip_suffix(b"}")?;
    let mut fields = Vec::new();
    let mut at = 0;
    while at < inner.len() {
        let key_end = string_end(inner, at)?;
        let key = &inner[at + 1..key_end - 1];
        if inner.get(key_end) != Some(&b':') {
            return None;
        }
        let start = key_end + 1;
        let end = if inner.get(start) == Some(&b'"') {
            string_end(inner, start)?
        } else {
            let len = inner[start..]
                .iter()
                .position(|&b| b == b',')
                .unwrap_or(inner.len() - start);
            if inner[start..start + len].contains(&b'{')
                || inner[start..start + len].contains(&b'[')
            {
                return None;
            }
            start + len
        };
        fields.push((key, &inner[start..end]));
        at = end;
        match inner.get(at) {
            Some(b',') => at += 1,
            None => {}
            Some(_) => return None,
        }
    }
    Some(fields)
}

/// The position just after the JSON string starting at `start` (its opening quote).
fn string_end(bytes: &[u8], start: usize) -> Option<usize> {
    if bytes.get(start) != Some(&b'"') {
        return None;
    }
    let mut i = start + 1;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' => i += 2,
            b'"' => return Some(i + 1),
            _ => i += 1,
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A converged line: numbers are copied byte for byte; a failed one has empty angles; a
    /// case name with a comma and a quote is quoted.
    #[test]
    fn rows_copy_the_bytes() {
        let line = br#"{"record":"sample","index":12,"case":"a,\"b\"","sample":2,"status":"converged","iterations":3,"theta_p":0.000015191290325887272,"tan_theta_x":-9.12659139265723e-6,"tan_theta_y":1e-5,"decenter_x":0.0041,"decenter_y":-0.0023,"decenter":0.0047,"despace":0.0012,"residual":7.5e-15,"slack_cables":6,"floating":false,"holding_force":2.5e-9}"#;
        let fields = flat_fields(line).unwrap();
        let mut row = Vec::new();
        csv_row(&fields, &mut row);
        assert_eq!(
            String::from_utf8(row).unwrap(),
            "12,\"a,\"\"b\"\"\",2,converged,0.000015191290325887272,-9.12659139265723e-6,1e-5,0.0041,-0.0023,0.0047,0.0012,3,6,,2.5e-9\n"
        );
        let failed = br#"{"record":"sample","index":1,"case":"c","sample":1,"status":"failed","iterations":60,"reason":"Newton did not converge, {really}"}"#;
        let mut row = Vec::new();
        csv_row(&flat_fields(failed).unwrap(), &mut row);
        assert_eq!(
            String::from_utf8(row).unwrap(),
            "1,c,1,failed,,,,,,,,60,,,\n"
        );
        let mut row = Vec::new();
        json_row(&flat_fields(failed).unwrap(), &mut row);
        let v: serde_json::Value = serde_json::from_slice(&row).unwrap();
        assert_eq!(v["status"], "failed");
        assert!(v["theta_p"].is_null() && v["holding_force"].is_null());
        assert!(flat_fields(br#"{"a":{"b":1}}"#).is_none());
    }
}
