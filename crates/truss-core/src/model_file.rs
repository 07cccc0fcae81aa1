//! The JSON model file: the raw, unvalidated form of a [`Model`](crate::Model).
//!
//! ## Format
//!
//! ```json
//! {
//!   "nodes":   [{"id": "n0.0", "xyz": [0.0, 0.0, 0.0]}, …],
//!   "members": [{"id": "batten.0.0", "nodes": ["n0.0", "n0.1"], "group": "batten",
//!                "area": 14.9, "youngs_modulus": 70000.0, "natural_length": 380.0,
//!                "behaviour": "bar"},
//!               {"id": "diagonal.1.0.a", "nodes": ["n0.0", "n1.1"], "group": "diagonal",
//!                "area": 3.1, "youngs_modulus": 70000.0, "natural_length": 537.4,
//!                "behaviour": "cable"}, …],
//!   "supports": [{"node": "n0.0", "fixed": "xyz"}, …],
//!   "loads":    [{"node": "n5.0", "force": [0.0, 0.0, -1.0]}],
//!   "top_surface": {"nodes": ["n5.0", "n5.1", "n5.2"], "reference_normal": [0.0, 0.0, 1.0]},
//!   "joints":   [{"id": "joint.5.0.below", "shaft": "n5.0", "hole": "n5.0.below",
//!                 "axis": [-0.866, -0.5, 0.0], "clearance": 0.01,
//!                 "tension_stiffness": 2.745e8}]
//! }
//! ```
//!
//! | field | meaning | unit |
//! |---|---|---|
//! | `nodes[].id` | unique node name | |
//! | `nodes[].xyz` | nominal position | mm |
//! | `members[].id` | unique member name | |
//! | `members[].nodes` | the two node ids it joins | |
//! | `members[].group` | group name (`batten`, `longeron`, `diagonal`, …); length-error distributions are given per group | |
//! | `members[].area` | cross-sectional area, > 0 | mm² |
//! | `members[].youngs_modulus` | Young's modulus, > 0 | MPa |
//! | `members[].natural_length` | stress-free length, > 0; optional, defaults to the distance between its nodes; within [`MAX_LENGTH_ERROR_FRACTION`](crate::MAX_LENGTH_ERROR_FRACTION) of itself (plus the joints' clearances summed) of that distance ([`crate::model::initial_strain_fault`]) | mm |
//! | `members[].behaviour` | `"bar"` (tension and compression) or `"cable"` (tension only) | |
//! | `members[].compression_ratio` | cables only: compression stiffness / tension stiffness, in [0, 1); default 0, the paper's (slack cables carry nothing: solved as the limit `r → 0`, see [`crate::limit`]) | |
//! | `supports[].node`, `supports[].fixed` | a node and the directions held fixed, any of `"x"`, `"y"`, `"z"` (`"xyz"` = pinned) | |
//! | `loads[].node`, `loads[].force` | a nodal force | N |
//! | `top_surface.nodes` | three nodes whose plane is measured (paper Fig. 5 order 1, 2, 3); optional | |
//! | `top_surface.reference_normal` | the normal θ_P is measured against, default `[0, 0, 1]` | |
//! | `joints[].id` | unique joint name; optional section (see [`crate::joint`]) | |
//! | `joints[].shaft`, `joints[].hole` | the shaft-centre node (batten end) and hole-centre node (one member end); same `xyz`; the hole node carries exactly one member, perpendicular to the axis, and no support, load or top-surface place (one hole per member end) | |
//! | `joints[].axis` | the shaft's axis (any length, normalised); optional: without it the clearance acts in every direction | |
//! | `joints[].clearance` | nominal clearance `g` ≥ 0, the virtual cable's natural length; a job may draw it per sample | mm |
//! | `joints[].tension_stiffness` | contact stiffness `k_t` > 0; default 10⁵ × the largest `E·A/L₀` of the members at the joint's nodes | N/mm |
//! | `joints[].compression_ratio` | `k_c/k_t` in [0, 1e-5], a regularising stiffness of a loose joint; default 0 (none: a loose pin carries no force) | |
//! | `joints[].axial_stiffness` | `k_a` > 0 along the axis; default `k_t` (kept for the file format: the shoulders are taken as rigid along the axis) | N/mm |
//!
//! Unknown fields are refused, so a misspelt field name is an error rather than a silently
//! ignored value. Magnitudes must be plausible (coordinates and lengths within ±10⁷ mm,
//! areas up to 10⁸ mm², moduli up to 10⁷ MPa, load components up to 10¹² N, a clearance up
//! to a tenth of its member: see [`crate::model`]), and a file is read only if it is a
//! regular file of at most [`MAX_INPUT_BYTES`] in UTF-8 ([`read_input`]).

use crate::errors::InputRefusal;
use serde::{Deserialize, Serialize};
use std::io::Read;
use std::path::Path;

/// The largest input file (model file, job file) read, 64 MiB \[bytes\]: ten times the model
/// of the largest prism ([`crate::prism::MAX_STAGES`] stages with backlash joints, 6.1 MB as
/// `truss model prism` writes it), so the limit refuses only what no truss needs, or what
/// never ends, before it is read into memory.
pub const MAX_INPUT_BYTES: u64 = 64 << 20;

/// Why [`read_input`] failed: the file could not be read, or it was refused.
#[derive(Debug)]
pub enum ReadFailure {
    /// The operating system's error (a missing file, no permission): an I/O failure.
    Io(std::io::Error),
    /// Read, or readable, but not an input this program takes: an invalid input.
    Refused(InputRefusal),
}

/// Reads an input file's text, refusing before it reads far what cannot be an input: a
/// file that is not a regular file (a directory, `/dev/zero`, a FIFO), one larger than
/// [`MAX_INPUT_BYTES`] (checked on the open file, and again while reading, in case it
/// grows), or text that is not UTF-8. A leading UTF-8 byte-order mark, which some Windows
/// editors write, is accepted and dropped.
pub fn read_input(path: &Path) -> Result<String, ReadFailure> {
    let regular = |meta: std::fs::Metadata| {
        if meta.is_file() {
            Ok(meta)
        } else {
            Err(ReadFailure::Refused(InputRefusal::NotRegularFile {
                kind: file_kind(&meta.file_type()),
            }))
        }
    };
    // Before opening: opening a FIFO waits for a writer, which may never come.
    regular(std::fs::metadata(path).map_err(ReadFailure::Io)?)?;
    let file = std::fs::File::open(path).map_err(ReadFailure::Io)?;
    // Again on the open file, in case the path was replaced in between.
    let meta = regular(file.metadata().map_err(ReadFailure::Io)?)?;
    let too_large = |bytes| {
        ReadFailure::Refused(InputRefusal::TooLarge {
            bytes,
            limit: MAX_INPUT_BYTES,
        })
    };
    if meta.len() > MAX_INPUT_BYTES {
        return Err(too_large(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(ReadFailure::Io)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(too_large(bytes.len() as u64));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        let before = &e.as_bytes()[..offset];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = offset
            - before
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |p| p + 1)
            + 1;
        ReadFailure::Refused(InputRefusal::NotUtf8 {
            line,
            column,
            offset,
        })
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// What a file that is not a regular file is, in words.
#[cfg(not(unix))]
fn file_kind(t: &std::fs::FileType) -> &'static str {
    if t.is_dir() {
        "a directory"
    } else {
        "not a file"
    }
}

/// What a file that is not a regular file is, in words.
#[cfg(unix)]
fn file_kind(t: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if t.is_dir() {
        "a directory"
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

/// A model file as written: ids are strings, nothing is checked yet.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// The nodes.
    pub nodes: Vec<NodeSpec>,
    /// The members.
    pub members: Vec<MemberSpec>,
    /// Fixed degrees of freedom.
    #[serde(default)]
    pub supports: Vec<SupportSpec>,
    /// Nodal forces \[N\].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub loads: Vec<LoadSpec>,
    /// The surface whose tilt is measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub top_surface: Option<TopSurfaceSpec>,
    /// Pin joints with backlash.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub joints: Vec<JointSpec>,
}

/// A node as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSpec {
    /// Unique id.
    pub id: String,
    /// Nominal position \[mm\].
    pub xyz: [f64; 3],
}

/// How a member carries load, as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BehaviourSpec {
    /// Tension and compression.
    Bar,
    /// Tension only (with a small compression stiffness ratio).
    Cable,
}

/// A member as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MemberSpec {
    /// Unique id.
    pub id: String,
    /// The two node ids.
    pub nodes: [String; 2],
    /// Group name.
    pub group: String,
    /// Cross-sectional area \[mm²\].
    pub area: f64,
    /// Young's modulus \[MPa\].
    pub youngs_modulus: f64,
    /// Stress-free length \[mm\]; defaults to the distance between the nodes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub natural_length: Option<f64>,
    /// Bar or cable.
    pub behaviour: BehaviourSpec,
    /// Cables only: compression stiffness / tension stiffness.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compression_ratio: Option<f64>,
}

/// A support as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportSpec {
    /// The node id.
    pub node: String,
    /// Fixed directions: a string of the letters `x`, `y`, `z`.
    pub fixed: String,
}

/// A nodal load as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// The node id.
    pub node: String,
    /// Force \[N\].
    pub force: [f64; 3],
}

/// The measured surface as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopSurfaceSpec {
    /// Three node ids, in the paper's Fig. 5 order.
    pub nodes: [String; 3],
    /// Reference normal; default +z.
    #[serde(default = "default_normal")]
    pub reference_normal: [f64; 3],
}

/// A pin joint with backlash as written (see [`crate::joint`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSpec {
    /// Unique id.
    pub id: String,
    /// The shaft-centre node id (batten end).
    pub shaft: String,
    /// The hole-centre node id (longeron end).
    pub hole: String,
    /// The shaft's axis; none for backlash in every direction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<[f64; 3]>,
    /// Nominal clearance \[mm\].
    pub clearance: f64,
    /// Contact stiffness \[N/mm\]; default 10⁵ × the stiffest member at the joint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tension_stiffness: Option<f64>,
    /// Centring stiffness of a loose joint / contact stiffness; default 1e-5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compression_ratio: Option<f64>,
    /// Stiffness along the axis \[N/mm\]; default the contact stiffness.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axial_stiffness: Option<f64>,
}

fn default_normal() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

impl ModelFile {
    /// Parses a model file's text; `origin` names it in errors (a path, or `<string>`).
    pub fn from_json(text: &str, origin: &str) -> Result<Self, crate::ModelError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        serde_json::from_str(text).map_err(|e| crate::ModelError::Syntax {
            origin: origin.to_string(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        })
    }

    /// Pretty JSON text of the file, ending with a newline.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("model files always serialise");
        s.push('\n');
        s
    }
}

#[cfg(test)]
mod tests {
    use super::{MAX_INPUT_BYTES, ReadFailure, read_input};
    use crate::InputRefusal;

    fn refusal(path: &std::path::Path) -> InputRefusal {
        match read_input(path) {
            Err(ReadFailure::Refused(r)) => r,
            other => panic!("{}: expected a refusal, got {other:?}", path.display()),
        }
    }

    /// Devices, directories and pipes are refused at once, before a byte is read:
    /// `/dev/zero` would otherwise fill the memory, and opening a FIFO would wait for a
    /// writer.
    #[test]
    fn only_regular_files_are_read() {
        assert_eq!(
            refusal(std::path::Path::new("/dev/zero")),
            InputRefusal::NotRegularFile {
                kind: "a character device"
            }
        );
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(
            refusal(dir.path()),
            InputRefusal::NotRegularFile {
                kind: "a directory"
            }
        );
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        assert_eq!(
            refusal(&fifo),
            InputRefusal::NotRegularFile { kind: "a pipe" }
        );
        let missing = read_input(&dir.path().join("missing.json"));
        assert!(matches!(missing, Err(ReadFailure::Io(_))), "{missing:?}");
    }

    /// A file over the limit is refused from its size (a sparse file: nothing is written).
    #[test]
    fn files_over_the_limit_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.json");
        let file = std::fs::File::create(&path).unwrap();
        file.set_len(MAX_INPUT_BYTES + 1).unwrap();
        assert_eq!(
            refusal(&path),
            InputRefusal::TooLarge {
                bytes: MAX_INPUT_BYTES + 1,
                limit: MAX_INPUT_BYTES
            }
        );
    }

    /// Invalid UTF-8 is refused with its line and column; a UTF-8 byte-order mark is
    /// dropped, and the text after it is read unchanged.
    #[test]
    fn text_must_be_utf8_and_a_bom_is_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("latin1.json");
        std::fs::write(&path, b"{\n  \"id\": \"n\xe90\"\n}").unwrap();
        assert_eq!(
            refusal(&path),
            InputRefusal::NotUtf8 {
                line: 2,
                column: 11,
                offset: 12
            }
        );
        std::fs::write(&path, "\u{feff}{\"a\": 1}").unwrap();
        assert_eq!(read_input(&path).unwrap(), "{\"a\": 1}");
    }
}
