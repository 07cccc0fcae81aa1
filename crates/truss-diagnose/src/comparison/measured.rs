//! The measured files: parsed, checked row by row, and turned into per-specimen displacement
//! vectors of the measured coordinates.
//!
//! ## Node file (`--measured`)
//!
//! CSV with a header naming the columns `specimen`, `node`, `x`, `y`, `z` (any order, any
//! case, surrounding spaces ignored; other columns ignored), one row per measured node per
//! specimen, positions in mm in the model's frame with the bottom surface at nominal. Quoted
//! fields, CRLF line ends and a UTF-8 byte-order mark are accepted; node order does not
//! matter. A row with a missing or non-numeric field, a coordinate beyond the model's range
//! (|x| ≤ 10⁷ mm, `truss_core::model::MAX_COORDINATE`), more fields than the header (a
//! decimal comma shifts the columns), or a second row for the same specimen and node, is an
//! error naming its line.
//!
//! **Outliers.** A specimen with a coordinate more than [`OUTLIER_Z`] robust standard
//! deviations (1.4826 × the median absolute deviation over the specimens, at least
//! [`OUTLIER_FLOOR`]) from the coordinates' median is left out and listed with its line, node
//! and coordinate ([`Outlier`]): no candidate in the library moves one specimen that far
//! from the others (the scatter candidates scale every specimen's scatter alike, which the
//! robust deviation follows), while a typo (z × 10) or a shifted column does.
//!
//! **Copies.** A specimen whose compared coordinates repeat another's bit for bit is refused,
//! naming the copies grouped by the specimen they repeat (a run of consecutive copies as
//! one range, with its first lines): independent measurements never agree to the last
//! digit. Near-copies, and scatter below the stated noise, are checked against σ_m in
//! [`crate::comparison::checks`].
//!
//! Which coordinates enter the diagnosis: the nodes of the model that at least half of the
//! specimens measured (the top-surface nodes must be among them); node ids the model does not
//! know, and nodes measured by fewer than half of the specimens, are ignored and reported.
//! A specimen that lacks one of the chosen nodes is left out and counted. Fixed coordinates
//! (supports) are not compared: the model puts them at nominal by definition. The
//! displacement of a coordinate is the measured position minus the node's nominal position.
//!
//! ## Member file (`--measured-members`)
//!
//! CSV `specimen`, `member`, `length_error` (mm; natural length minus nominal, as in the
//! job's distributions), member ids of the model; unknown member ids are ignored and
//! reported. Specimen ids are those of the node file: a member row for a specimen the node
//! file does not have is refused, naming the ids; a length error beyond
//! [`MAX_MEMBER_ERROR_FRACTION`] of the member's nominal length is refused with its line.
//! A specimen's node positions and its own members' length errors come from the same truss,
//! and the intervals treat them as one independent unit ([`Measured::clusters`]); members of
//! a specimen left out of the node data (a missing node, an outlier) are one unit per
//! specimen.

use crate::errors::DiagnoseError;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use truss_core::Model;
use truss_core::measure::distortion;

/// Robust standard deviations beyond which a specimen is an outlier (module doc). For
/// normal data a specimen passes with probability 1 − 2e-23 per coordinate.
pub const OUTLIER_Z: f64 = 10.0;

/// Floor of the robust standard deviation in the outlier screen \[mm\] (0.1 µm).
pub const OUTLIER_FLOOR: f64 = 1e-4;

/// Largest measured member length error accepted, as a fraction of the member's nominal
/// length: 1 % (3.8 mm on a 380 mm member, a hundred times the loosest tolerance of the
/// paper).
pub const MAX_MEMBER_ERROR_FRACTION: f64 = 0.01;

/// A specimen left out as an outlier.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Outlier {
    /// The specimen.
    pub specimen: String,
    /// Line of the row furthest out.
    pub line: u64,
    /// Its node.
    pub node: String,
    /// Its coordinate (`x`, `y`, `z`).
    pub axis: &'static str,
    /// The measured displacement \[mm\].
    pub displacement: f64,
    /// Robust standard deviations from the median.
    pub robust_z: f64,
}

impl Outlier {
    /// In words, for the report and stderr.
    pub fn words(&self) -> String {
        format!(
            "specimen {} (line {}: node {} {} displaced {:.4} mm, {:.0} robust SD from the median)",
            self.specimen, self.line, self.node, self.axis, self.displacement, self.robust_z
        )
    }
}

/// A warning from a data check ([`crate::comparison::checks`]), in `diagnosis.json`'s
/// `data.checks[]`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DataCheck {
    /// `scatter_below_noise` or `specimens_closer_than_noise`.
    pub check: &'static str,
    /// How many coordinates (or pairs of specimens) are flagged.
    pub flagged: usize,
    /// The smallest p-value among them (module doc).
    pub p_value: f64,
    /// The warning in one sentence.
    pub words: String,
}

/// One measured coordinate: a node of the model and an axis (0 = x, 1 = y, 2 = z).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Coordinate {
    /// Node index in the model.
    pub node: usize,
    /// Node id.
    pub node_id: String,
    /// Axis, 0 = x, 1 = y, 2 = z.
    pub axis: usize,
}

impl Coordinate {
    /// The x, y and z coordinates of each of `nodes` (indices into `model`), in order.
    pub fn of_nodes(model: &Model, nodes: &[usize]) -> Vec<Coordinate> {
        nodes
            .iter()
            .flat_map(|&node| {
                let id = model.nodes()[node].id.clone();
                (0..3).map(move |axis| Coordinate {
                    node,
                    node_id: id.clone(),
                    axis,
                })
            })
            .collect()
    }

    /// `n5.1 z`.
    pub fn label(&self) -> String {
        format!("{} {}", self.node_id, ["x", "y", "z"][self.axis])
    }
}

/// What reading the files found and left out, for the report.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct DataReport {
    /// The node file.
    pub file: String,
    /// Data rows read.
    pub rows: usize,
    /// Specimens in the file.
    pub specimens_in_file: usize,
    /// Specimens used.
    pub specimens_used: usize,
    /// Specimens left out because a chosen node is missing: (specimen, missing node ids);
    /// at most 50 listed.
    pub left_out: Vec<(String, Vec<String>)>,
    /// How many specimens were left out.
    pub left_out_count: usize,
    /// Specimens left out as outliers (module doc).
    pub outliers: Vec<Outlier>,
    /// The nodes compared, model order.
    pub nodes: Vec<String>,
    /// Node ids in the file that the model does not have.
    pub unknown_nodes: Vec<String>,
    /// Nodes measured by fewer than half of the specimens (ignored).
    pub rare_nodes: Vec<String>,
    /// Measured nodes that are supports (their fixed coordinates are not compared).
    pub supports: Vec<String>,
    /// Member observations used, if a member file was given.
    pub member_rows: Option<usize>,
    /// Member ids in the member file that the model does not have.
    pub unknown_members: Vec<String>,
    /// The warnings of the checks against the stated instrument noise
    /// ([`crate::comparison::checks`]).
    pub checks: Vec<DataCheck>,
}

impl DataReport {
    /// The first five specimens left out for a missing node, in words: `s1 lacks n1 n2; …`.
    pub fn first_left_out(&self) -> String {
        self.left_out
            .iter()
            .take(5)
            .map(|(s, n)| format!("{s} lacks {}", n.join(" ")))
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// Measured member length errors.
#[derive(Debug, Clone, Default)]
pub struct MemberData {
    /// (member index, measured length error \[mm\]).
    pub observations: Vec<(usize, f64)>,
    /// For each observation, the truss it was measured on: its specimen's index among the
    /// node file's specimens used (then the observation and that specimen's node positions
    /// are not independent), or, for a specimen not among them, their number plus the
    /// specimen's index among such others in order of first appearance.
    pub truss: Vec<usize>,
}

/// The measured data as the diagnosis uses it.
#[derive(Debug, Clone)]
pub struct Measured {
    /// Specimen ids used, in the order of first appearance.
    pub specimens: Vec<String>,
    /// The compared coordinates, model order (node, then axis).
    pub coords: Vec<Coordinate>,
    /// `n × d` displacements of the compared coordinates, row per specimen \[mm\].
    pub y: Vec<f64>,
    /// tan θ_x of each specimen's top surface \[-\].
    pub tan_x: Vec<f64>,
    /// tan θ_y \[-\].
    pub tan_y: Vec<f64>,
    /// θ_P \[rad\].
    pub theta_p: Vec<f64>,
    /// Each specimen's first line in the node file.
    pub lines: Vec<u64>,
    /// Member measurements, if given.
    pub members: Option<MemberData>,
    /// What was read and left out.
    pub report: DataReport,
}

impl Measured {
    /// The cluster of each unit term of ℓ (each specimen's, then each member observation's,
    /// as [`crate::likelihood::score`] lists them): one per truss ([`MemberData::truss`]), a specimen's
    /// node positions with its own member observations.
    pub fn clusters(&self) -> Vec<usize> {
        let mut out: Vec<usize> = (0..self.n()).collect();
        if let Some(m) = &self.members {
            out.extend_from_slice(&m.truss);
        }
        out
    }

    /// Number of specimens `n`.
    pub fn n(&self) -> usize {
        self.specimens.len()
    }

    /// Number of compared coordinates `d`.
    pub fn d(&self) -> usize {
        self.coords.len()
    }
}

/// Data rows of a CSV file with the named columns, as (line, fields in the order asked).
fn read_table(path: &Path, columns: &[&str]) -> Result<Vec<(u64, Vec<String>)>, DiagnoseError> {
    // A regular file of at most 64 MiB in UTF-8 (a FIFO or /dev/zero is refused before it
    // is opened), as every input file is read; a byte-order mark is dropped.
    use truss_core::model_file::{ReadFailure, read_input};
    let text = read_input(path).map_err(|e| match e {
        ReadFailure::Io(e) => DiagnoseError::io(path, e),
        ReadFailure::Refused(reason) => DiagnoseError::Measured {
            path: path.to_path_buf(),
            message: reason.to_string(),
        },
    })?;
    let bytes = text.as_bytes();
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(true)
        .comment(Some(b'#'))
        .from_reader(bytes);
    let bad = |line: u64, message: String| DiagnoseError::BadRow {
        path: path.to_path_buf(),
        line,
        message,
    };
    let header = reader
        .headers()
        .map_err(|e| bad(1, format!("cannot read the header: {e}")))?
        .clone();
    let index: Vec<usize> = columns
        .iter()
        .map(|c| {
            header
                .iter()
                .position(|h| h.eq_ignore_ascii_case(c))
                .ok_or_else(|| {
                    bad(
                        1,
                        format!(
                            "the header has no column {c:?} (expected {}; found {})",
                            columns.join(","),
                            header.iter().collect::<Vec<_>>().join(",")
                        ),
                    )
                })
        })
        .collect::<Result<_, _>>()?;
    // Line numbers from byte offsets (the csv crate does not count blank lines), counted
    // incrementally since records come in file order.
    let (mut counted_to, mut lines_before) = (0usize, 0u64);
    let mut line_at = |byte: u64| {
        // A record's position may be that of blank lines before it.
        let mut byte = (byte as usize).min(bytes.len());
        while byte < bytes.len() && (bytes[byte] == b'\n' || bytes[byte] == b'\r') {
            byte += 1;
        }
        if byte >= counted_to {
            lines_before += bytes[counted_to..byte]
                .iter()
                .filter(|&&b| b == b'\n')
                .count() as u64;
            counted_to = byte;
        }
        lines_before + 1
    };
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                let line = e.position().map_or(0, |p| line_at(p.byte()));
                return Err(bad(line, format!("unreadable row: {e}")));
            }
        };
        let line = record.position().map_or(0, |p| line_at(p.byte()));
        if record.iter().all(str::is_empty) {
            continue;
        }
        if record.len() > header.len() {
            return Err(bad(
                line,
                format!(
                    "{} fields where the header has {} (a decimal comma, or a stray separator?)",
                    record.len(),
                    header.len()
                ),
            ));
        }
        let fields = index
            .iter()
            .zip(columns)
            .map(|(&i, c)| match record.get(i) {
                Some(v) if !v.is_empty() => Ok(v.to_string()),
                _ => Err(bad(line, format!("the {c} field is empty or missing"))),
            })
            .collect::<Result<Vec<_>, _>>()?;
        rows.push((line, fields));
    }
    Ok(rows)
}

fn number(path: &Path, line: u64, column: &str, text: &str) -> Result<f64, DiagnoseError> {
    text.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| DiagnoseError::BadRow {
            path: path.to_path_buf(),
            line,
            message: format!("{column} = {text:?} is not a finite number [mm]"),
        })
}

/// A measured coordinate: a finite number within the model's own coordinate range
/// (`truss_core::model::MAX_COORDINATE`, 10⁷ mm). A value beyond it (z = 1e300 in every
/// specimen, which the outlier screen cannot see) is no measurement of this truss.
fn coordinate(path: &Path, line: u64, column: &str, text: &str) -> Result<f64, DiagnoseError> {
    let v = number(path, line, column, text)?;
    let max = truss_core::model::MAX_COORDINATE;
    if v.abs() > max {
        return Err(DiagnoseError::BadRow {
            path: path.to_path_buf(),
            line,
            message: format!(
                "{column} = {text} mm is beyond the coordinates a model may have (|{column}| ≤ {} mm)",
                truss_core::readable(max)
            ),
        });
    }
    Ok(v)
}

/// Reads the node file (and the member file, if given) against `model`; `min_specimens` is
/// the fewest usable specimens accepted.
pub fn read(
    model: &Model,
    nodes_path: &Path,
    members_path: Option<&Path>,
    min_specimens: usize,
) -> Result<Measured, DiagnoseError> {
    let rows = read_table(nodes_path, &["specimen", "node", "x", "y", "z"])?;
    let mut report = DataReport {
        file: nodes_path.display().to_string(),
        rows: rows.len(),
        ..DataReport::default()
    };
    // specimen -> node index -> (position, line)
    let mut order: Vec<String> = Vec::new();
    let mut by_specimen: HashMap<String, BTreeMap<usize, ([f64; 3], u64)>> = HashMap::new();
    let mut unknown: BTreeMap<String, ()> = BTreeMap::new();
    for (line, f) in &rows {
        let xyz = [
            coordinate(nodes_path, *line, "x", &f[2])?,
            coordinate(nodes_path, *line, "y", &f[3])?,
            coordinate(nodes_path, *line, "z", &f[4])?,
        ];
        let entry = by_specimen.entry(f[0].clone()).or_insert_with(|| {
            order.push(f[0].clone());
            BTreeMap::new()
        });
        let Some(node) = model.node_index(&f[1]) else {
            unknown.insert(f[1].clone(), ());
            continue;
        };
        if let Some((_, first)) = entry.insert(node, (xyz, *line)) {
            return Err(DiagnoseError::BadRow {
                path: nodes_path.to_path_buf(),
                line: *line,
                message: format!(
                    "specimen {:?} node {:?} was already measured on line {first}",
                    f[0], f[1]
                ),
            });
        }
    }
    report.unknown_nodes = unknown.into_keys().collect();
    report.specimens_in_file = order.len();
    let measured_err = |message: String| DiagnoseError::Measured {
        path: nodes_path.to_path_buf(),
        message,
    };
    // Nodes measured by at least half of the specimens.
    let mut counts = vec![0usize; model.nodes().len()];
    for nodes in by_specimen.values() {
        for &node in nodes.keys() {
            counts[node] += 1;
        }
    }
    let half = order.len().div_ceil(2).max(1);
    let chosen: Vec<usize> = (0..counts.len()).filter(|&i| counts[i] >= half).collect();
    report.rare_nodes = (0..counts.len())
        .filter(|&i| counts[i] > 0 && counts[i] < half)
        .map(|i| model.nodes()[i].id.clone())
        .collect();
    let top = model
        .top_surface()
        .ok_or_else(|| measured_err("the model names no top surface".into()))?
        .clone();
    for &t in &top.nodes {
        if !chosen.contains(&t) {
            return Err(measured_err(format!(
                "top-surface node {} is measured for {} of {} specimens; it must be measured for all",
                model.nodes()[t].id,
                counts[t],
                order.len()
            )));
        }
    }
    report.nodes = chosen
        .iter()
        .map(|&i| model.nodes()[i].id.clone())
        .collect();
    let coords: Vec<Coordinate> = chosen
        .iter()
        .flat_map(|&node| {
            let fixed = model.fixed(node);
            (0..3)
                .filter(move |&a| !fixed[a])
                .map(move |axis| Coordinate {
                    node,
                    node_id: model.nodes()[node].id.clone(),
                    axis,
                })
        })
        .collect();
    report.supports = chosen
        .iter()
        .filter(|&&i| model.fixed(i).iter().any(|&f| f))
        .map(|&i| model.nodes()[i].id.clone())
        .collect();
    let (mut specimens, mut y) = (Vec::new(), Vec::new());
    let (mut tan_x, mut tan_y, mut theta_p) = (Vec::new(), Vec::new(), Vec::new());
    let nominal = |i: usize| model.nodes()[i].xyz;
    let complete: Vec<&String> = order
        .iter()
        .filter(|s| chosen.iter().all(|i| by_specimen[*s].contains_key(i)))
        .collect();
    let disp_of =
        |s: &String, c: &Coordinate| by_specimen[s][&c.node].0[c.axis] - nominal(c.node)[c.axis];
    report.outliers = outliers(&complete, &coords, &disp_of, &|s, c| {
        by_specimen[s][&c.node].1
    });
    for s in &order {
        if report.outliers.iter().any(|o| &o.specimen == s) {
            continue;
        }
        let nodes = &by_specimen[s];
        let missing: Vec<String> = chosen
            .iter()
            .filter(|i| !nodes.contains_key(i))
            .map(|&i| model.nodes()[i].id.clone())
            .collect();
        if !missing.is_empty() {
            report.left_out_count += 1;
            if report.left_out.len() < 50 {
                report.left_out.push((s.clone(), missing));
            }
            continue;
        }
        let disp = |i: usize| {
            let p = nodes[&i].0;
            let x = nominal(i);
            [p[0] - x[0], p[1] - x[1], p[2] - x[2]]
        };
        y.extend(coords.iter().map(|c| disp(c.node)[c.axis]));
        let d = distortion(
            top.nodes.map(nominal),
            top.nodes.map(disp),
            top.reference_normal,
        );
        tan_x.push(d.tan_theta_x);
        tan_y.push(d.tan_theta_y);
        theta_p.push(d.theta_p);
        specimens.push(s.clone());
    }
    let first_line = |s: &String| {
        by_specimen[s]
            .values()
            .map(|(_, line)| *line)
            .min()
            .unwrap_or(0)
    };
    repeated_specimens(&specimens, &y, coords.len(), &first_line).map_err(measured_err)?;
    let lines = specimens.iter().map(first_line).collect();
    report.specimens_used = specimens.len();
    if specimens.len() < min_specimens {
        return Err(measured_err(format!(
            "{} usable specimens ({} left out for missing nodes, {} as outliers); at least {min_specimens} are needed",
            specimens.len(),
            report.left_out_count,
            report.outliers.len()
        )));
    }
    let members = match members_path {
        None => None,
        Some(p) => Some(read_members(model, p, &specimens, &order, &mut report)?),
    };
    Ok(Measured {
        specimens,
        coords,
        y,
        tan_x,
        tan_y,
        theta_p,
        lines,
        members,
        report,
    })
}

fn read_members(
    model: &Model,
    path: &Path,
    specimens: &[String],
    all_specimens: &[String],
    report: &mut DataReport,
) -> Result<MemberData, DiagnoseError> {
    let rows = read_table(path, &["specimen", "member", "length_error"])?;
    let mut truss: HashMap<String, usize> = specimens
        .iter()
        .enumerate()
        .map(|(i, s)| (s.clone(), i))
        .collect();
    let mut seen: HashMap<(String, usize), u64> = HashMap::new();
    let mut unknown: BTreeMap<String, ()> = BTreeMap::new();
    let mut data = MemberData::default();
    let strangers: BTreeMap<&str, u64> = rows
        .iter()
        .filter(|(_, f)| !all_specimens.contains(&f[0]))
        .map(|(line, f)| (f[0].as_str(), *line))
        .rev()
        .collect();
    if !strangers.is_empty() {
        return Err(DiagnoseError::Measured {
            path: path.to_path_buf(),
            message: format!(
                "member rows for {} specimen(s) the node file does not have: {} (the specimen ids of the two files must match)",
                strangers.len(),
                strangers
                    .iter()
                    .take(20)
                    .map(|(s, line)| format!("{s:?} (line {line})"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        });
    }
    for (line, f) in &rows {
        let value = number(path, *line, "length_error", &f[2])?;
        let Some(m) = model.member_index(&f[1]) else {
            unknown.insert(f[1].clone(), ());
            continue;
        };
        let length = model.nominal_length(m);
        if value.abs() > MAX_MEMBER_ERROR_FRACTION * length {
            return Err(DiagnoseError::BadRow {
                path: path.to_path_buf(),
                line: *line,
                message: format!(
                    "member {:?} length_error = {value} mm is beyond {} % of its {length:.1} mm length: not a manufacturing error (a unit or sign slip?)",
                    f[1],
                    MAX_MEMBER_ERROR_FRACTION * 100.0
                ),
            });
        }
        if let Some(first) = seen.insert((f[0].clone(), m), *line) {
            return Err(DiagnoseError::BadRow {
                path: PathBuf::from(path),
                line: *line,
                message: format!(
                    "specimen {:?} member {:?} was already measured on line {first}",
                    f[0], f[1]
                ),
            });
        }
        data.observations.push((m, value));
        let next = truss.len();
        data.truss.push(*truss.entry(f[0].clone()).or_insert(next));
    }
    report.member_rows = Some(data.observations.len());
    report.unknown_members = unknown.into_keys().collect();
    Ok(data)
}

/// The specimens (among `complete`) with a coordinate beyond [`OUTLIER_Z`] robust standard
/// deviations of the median; `disp` gives a specimen's displacement at a coordinate, `line`
/// the line of its row.
fn outliers(
    complete: &[&String],
    coords: &[Coordinate],
    disp: &dyn Fn(&String, &Coordinate) -> f64,
    line: &dyn Fn(&String, &Coordinate) -> u64,
) -> Vec<Outlier> {
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    };
    if complete.len() < 3 {
        return Vec::new();
    }
    let centre: Vec<(f64, f64)> = coords
        .iter()
        .map(|c| {
            let mut v: Vec<f64> = complete.iter().map(|s| disp(s, c)).collect();
            let m = median(&mut v);
            let mut dev: Vec<f64> = v.iter().map(|x| (x - m).abs()).collect();
            (m, (1.4826 * median(&mut dev)).max(OUTLIER_FLOOR))
        })
        .collect();
    let mut out = Vec::new();
    for s in complete {
        let worst = coords
            .iter()
            .zip(&centre)
            .map(|(c, &(m, sd))| (c, disp(s, c), (disp(s, c) - m).abs() / sd))
            .max_by(|a, b| a.2.total_cmp(&b.2));
        if let Some((c, value, z)) = worst
            && z > OUTLIER_Z
        {
            out.push(Outlier {
                specimen: (*s).clone(),
                line: line(s, c),
                node: c.node_id.clone(),
                axis: ["x", "y", "z"][c.axis],
                displacement: value,
                robust_z: z,
            });
        }
    }
    out
}

/// Refuses specimens whose `d` compared coordinates (`y`, a row per specimen) repeat an
/// earlier specimen's bit for bit. Independent measurements never agree to the last digit
/// in every coordinate: an exact repeat is a copy (a copy-paste slip, a file joined twice),
/// and fitted as data its missing scatter reads as an effect (30 copies of one specimen
/// were once diagnosed as gravity at p < 1e-16). `line` gives a specimen's first row. The
/// copies are named grouped by the specimen they repeat, runs of consecutive copies as one
/// range (`"s2" to "s31" (30 specimens, first lines 5 to 92) repeat "s1" (line 2)`), at
/// most [`NAMED_GROUPS`] groups.
fn repeated_specimens(
    specimens: &[String],
    y: &[f64],
    d: usize,
    line: &dyn Fn(&String) -> u64,
) -> Result<(), String> {
    if d == 0 {
        return Ok(());
    }
    let mut first: HashMap<Vec<u64>, usize> = HashMap::new();
    // For each original (in order of first appearance), its copies in file order.
    let mut groups: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (k, row) in y.chunks(d).enumerate() {
        let key: Vec<u64> = row.iter().map(|v| v.to_bits()).collect();
        match first.get(&key) {
            Some(&original) => groups.entry(original).or_default().push(k),
            None => {
                first.insert(key, k);
            }
        }
    }
    if groups.is_empty() {
        return Ok(());
    }
    let copies: usize = groups.values().map(Vec::len).sum();
    let named: Vec<String> = groups
        .iter()
        .take(NAMED_GROUPS)
        .map(|(&o, c)| {
            let o = &specimens[o];
            format!(
                "{} {} {o:?} (line {})",
                runs(c)
                    .iter()
                    .map(|&(i, j)| {
                        let (a, b) = (&specimens[i], &specimens[j]);
                        if i == j {
                            format!("{a:?} (line {})", line(a))
                        } else {
                            format!(
                                "{a:?} to {b:?} ({} specimens, first lines {} to {})",
                                j - i + 1,
                                line(a),
                                line(b)
                            )
                        }
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
                if c.len() == 1 { "repeats" } else { "repeat" },
                line(o)
            )
        })
        .collect();
    Err(format!(
        "{copies} specimen(s) repeat another's measurements exactly, in all {d} compared coordinates, \
         which independent measurements never do: {}{}; remove the copies (a copy-paste slip \
         or a file joined twice?) or give each specimen its own measurements",
        named.join("; "),
        if groups.len() > named.len() {
            format!("; and {} more group(s)", groups.len() - named.len())
        } else {
            String::new()
        }
    ))
}

/// Most groups of copies named in the refusal of repeated specimens (module doc).
pub const NAMED_GROUPS: usize = 5;

/// The runs of consecutive indices in `k` (increasing), as (first, last).
fn runs(k: &[usize]) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = Vec::new();
    for &i in k {
        match out.last_mut() {
            Some((_, last)) if *last + 1 == i => *last = i,
            _ => out.push((i, i)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use truss_core::prism::PrismOptions;

    /// A specimen that repeats another's rows exactly is refused before anything is fitted,
    /// naming both and their first lines; the same values in another order of rows are the
    /// same measurements; a difference in the last digit of one coordinate is data.
    #[test]
    fn a_repeated_specimen_is_refused_naming_both() {
        let model = PrismOptions::with_stages(2).model().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let h = 380.0 * 3f64.sqrt() / 2.0;
        let rows = |s: &str, z: &str| {
            format!("{s},n2.0,0,0,760.001\n{s},n2.1,380,0,{z}\n{s},n2.2,190,{h},759.999\n")
        };
        let mut text = "specimen,node,x,y,z\n".to_string();
        text += &rows("s1", "760.002");
        text += &rows("s2", "760.004");
        text += &rows("s3", "760.002");
        let p = write(dir.path(), "m.csv", &text);
        let e = read(&model, &p, None, 1).unwrap_err().to_string();
        assert!(
            e.contains("1 specimen(s) repeat another's measurements exactly")
                && e.contains("\"s3\" (line 8) repeats \"s1\" (line 2)"),
            "{e}"
        );
        let text = text.replace("s3,n2.1,380,0,760.002", "s3,n2.1,380,0,760.0020000000001");
        let p = write(dir.path(), "m2.csv", &text);
        assert!(read(&model, &p, None, 1).is_ok());
    }

    /// The slip: specimen c0 then 30 copies of it (c1–c30), among distinct ones,
    /// and a second group (a copy of d2 at the end): refused in one message that names the
    /// 30 as one range with their first lines, and the lone copy apart.
    #[test]
    fn thirty_copies_are_named_as_one_range() {
        let model = PrismOptions::with_stages(2).model().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let h = 380.0 * 3f64.sqrt() / 2.0;
        let rows = |s: &str, z: f64| {
            format!("{s},n2.0,0,0,760.001\n{s},n2.1,380,0,{z}\n{s},n2.2,190,{h},759.999\n")
        };
        let mut text = "specimen,node,x,y,z\n".to_string();
        for k in 0..5 {
            text += &rows(&format!("d{k}"), 760.0 + 1e-4 * k as f64);
        }
        for k in 0..31 {
            text += &rows(&format!("c{k}"), 760.00005);
        }
        text += &rows("d9", 760.0 + 1e-4 * 2.0);
        let p = write(dir.path(), "m.csv", &text);
        let e = read(&model, &p, None, 1).unwrap_err().to_string();
        // d0–d4 take lines 2–16, c0 lines 17–19, c1 from line 20, …, c30 from 107, d9 from 110.
        assert!(
            e.contains(
                "31 specimen(s) repeat another's measurements exactly, in all 9 compared coordinates"
            ) && e.contains(
                "\"c1\" to \"c30\" (30 specimens, first lines 20 to 107) repeat \"c0\" (line 17)"
            ) && e.contains("\"d9\" (line 110) repeats \"d2\" (line 8)"),
            "{e}"
        );
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    /// Quoted fields, CRLF, a BOM, shuffled columns and node order, an extra unknown node and
    /// a specimen missing a node: read as the module doc says.
    #[test]
    fn robust_to_csv_details_and_reports_what_it_leaves_out() {
        let model = PrismOptions::with_stages(2).model().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let h = 380.0 * 3f64.sqrt() / 2.0;
        let text = format!(
            "\u{feff}Node , specimen,z,x,y,comment\r\n\
             \"n2.1\",s1,760.001,380,0,\r\n\
             n2.0,s1,760,0,0,\"a, quoted\"\r\n\
             n2.2,s1,760,190,{h},\r\n\
             marker,s1,1,2,3,\r\n\
             n2.0,\"s2\",759.999,0.0005,0,\r\n\
             n2.1,s2,760,380,0,\r\n\
             n2.2,s2,760,190,{h},\r\n\
             n2.0,s3,760,0,0,\r\n\
             n2.1,s3,760,380,0,\r\n"
        );
        let p = write(dir.path(), "m.csv", &text);
        let m = read(&model, &p, None, 1).unwrap();
        assert_eq!(m.specimens, vec!["s1", "s2"]);
        assert_eq!(m.report.left_out_count, 1);
        assert_eq!(
            m.report.left_out[0],
            ("s3".to_string(), vec!["n2.2".into()])
        );
        assert_eq!(m.report.unknown_nodes, vec!["marker"]);
        assert_eq!(m.d(), 9);
        // s1: n2.1 z displaced by +0.001; s2: n2.0 z by -0.001 and x by +0.0005.
        let z21 = m.coords.iter().position(|c| c.label() == "n2.1 z").unwrap();
        assert!((m.y[z21] - 0.001).abs() < 1e-12);
        let x20 = m.coords.iter().position(|c| c.label() == "n2.0 x").unwrap();
        assert!((m.y[9 + x20] - 0.0005).abs() < 1e-12);
        // tan θ_x = (z₂ − z₁)/l (paper eq. 17) for s1.
        assert!((m.tan_x[0] - 0.001 / 380.0).abs() < 1e-12);
        // Members: s2's and s1's join their node terms (clusters 1 and 0); s3 (left out of
        // the node data) is one cluster after them; an unknown member id is reported.
        let members = write(
            dir.path(),
            "mm.csv",
            "specimen,member,length_error\n\
             s2,longeron.1.0,0.001\n\
             s3,longeron.1.0,0.002\n\
             s1,longeron.1.1,-0.001\n\
             s3,longeron.1.1,0.0\n\
             s1,strut.9,0.1\n",
        );
        let m = read(&model, &p, Some(&members), 1).unwrap();
        let data = m.members.as_ref().unwrap();
        assert_eq!(data.observations.len(), 4);
        assert_eq!(data.truss, vec![1, 2, 0, 2]);
        assert_eq!(m.clusters(), vec![0, 1, 1, 2, 0, 2]);
        assert_eq!(m.report.member_rows, Some(4));
        assert_eq!(m.report.unknown_members, vec!["strut.9"]);
        // Member rows for specimens the node file lacks are refused, naming them.
        let strangers = write(
            dir.path(),
            "ms.csv",
            "specimen,member,length_error\ns2,longeron.1.0,0.001\ns4,batten.1.0,0.003\ns9,batten.1.0,0\n",
        );
        let e = read(&model, &p, Some(&strangers), 1)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(
                "2 specimen(s) the node file does not have: \"s4\" (line 3), \"s9\" (line 4)"
            ),
            "{e}"
        );
        // −500 mm on a 380 mm member is refused with its line.
        let absurd = write(
            dir.path(),
            "ma.csv",
            "specimen,member,length_error\ns2,longeron.1.0,0.001\ns1,batten.1.0,-500\n",
        );
        let e = read(&model, &p, Some(&absurd), 1).unwrap_err().to_string();
        assert!(e.contains("ma.csv:3: member \"batten.1.0\" length_error = -500 mm is beyond 1 % of its 380.0 mm length"), "{e}");
    }

    #[test]
    fn bad_rows_name_their_line() {
        let model = PrismOptions::with_stages(1).model().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = write(
            dir.path(),
            "m.csv",
            "specimen,node,x,y,z\ns1,n1.0,0,0,380\ns1,n1.1,abc,0,380\n",
        );
        let e = read(&model, &p, None, 1).unwrap_err().to_string();
        assert!(
            e.ends_with("m.csv:3: x = \"abc\" is not a finite number [mm]"),
            "{e}"
        );
        let p = write(
            dir.path(),
            "d.csv",
            "specimen,node,x,y,z\ns1,n1.0,0,0,380\n\ns1,n1.0,0,0,380\n",
        );
        let e = read(&model, &p, None, 1).unwrap_err().to_string();
        assert!(
            e.contains("d.csv:4: specimen \"s1\" node \"n1.0\" was already measured on line 2"),
            "{e}"
        );
        let p = write(dir.path(), "h.csv", "specimen,node,x,y\ns1,n1.0,0,0\n");
        let e = read(&model, &p, None, 1).unwrap_err().to_string();
        assert!(e.contains("h.csv:1: the header has no column \"z\""), "{e}");
        let p = write(dir.path(), "e.csv", "specimen,node,x,y,z\ns1,n1.0,0,,380\n");
        let e = read(&model, &p, None, 1).unwrap_err().to_string();
        assert!(e.contains("e.csv:2: the y field is empty"), "{e}");
        // A decimal comma shifts the columns: an extra field, refused with its line.
        let p = write(
            dir.path(),
            "c.csv",
            "specimen,node,x,y,z\ns1,n1.0,0,0,380\ns1,n1.1,380,0,380,001\n",
        );
        let e = read(&model, &p, None, 1).unwrap_err().to_string();
        assert!(
            e.contains("c.csv:3: 6 fields where the header has 5"),
            "{e}"
        );
    }

    /// Twenty specimens scattered by a few µm, one of them with z typed ten times too large:
    /// that one is left out and listed by specimen, line, node and coordinate; the others stay.
    #[test]
    fn a_typo_row_is_an_outlier_left_out() {
        let model = PrismOptions::with_stages(1).model().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let h = 380.0 * 3f64.sqrt() / 2.0;
        let mut text = String::from("specimen,node,x,y,z\n");
        for s in 0..20 {
            let dz = 0.001 * ((s * 7 % 5) as f64 - 2.0);
            let z = if s == 13 { 3800.0 + dz } else { 380.0 + dz };
            // (n1.2 z differs by 0.1 µm from specimen to specimen: no two are copies.)
            text += &format!(
                "s{s},n1.0,0,0,{z}\ns{s},n1.1,380,0,{}\ns{s},n1.2,190,{h},{}\n",
                380.0 - dz,
                380.0 + 1e-4 * s as f64
            );
        }
        let p = write(dir.path(), "o.csv", &text);
        let m = read(&model, &p, None, 1).unwrap();
        assert_eq!(m.n(), 19);
        assert!(!m.specimens.contains(&"s13".to_string()));
        let o = &m.report.outliers;
        assert_eq!(o.len(), 1, "{o:?}");
        assert_eq!((o[0].specimen.as_str(), o[0].line), ("s13", 2 + 3 * 13));
        assert_eq!((o[0].node.as_str(), o[0].axis), ("n1.0", "z"));
        // s13: dz = 0.001·(91 mod 5 − 2) = −0.001 mm.
        assert!((o[0].displacement - 3419.999).abs() < 1e-6);
    }

    /// z = 1e300 mm in every specimen moves no specimen from the others (the outlier screen
    /// cannot see it) and is no measurement: refused naming its line and the range.
    #[test]
    fn coordinates_beyond_the_models_range_are_refused() {
        let model = PrismOptions::with_stages(1).model().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let h = 380.0 * 3f64.sqrt() / 2.0;
        let mut text = String::from("specimen,node,x,y,z\n");
        for s in 0..6 {
            text += &format!("s{s},n1.0,0,0,1e300\ns{s},n1.1,380,0,380\ns{s},n1.2,190,{h},380\n");
        }
        let p = write(dir.path(), "far.csv", &text);
        let e = read(&model, &p, None, 1).err().unwrap().to_string();
        assert!(e.contains("far.csv:2: z = 1e300 mm is beyond"), "{e}");
    }
}
