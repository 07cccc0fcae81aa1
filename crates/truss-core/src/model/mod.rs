//! The validated truss model: nodes, members, supports, loads, and the measured surface.
//!
//! A [`Model`] is built only by validating a [`ModelFile`]; from then on its invariants hold:
//! ids are unique, every reference resolves to an index, every number is finite and within
//! a plausible magnitude ([`MAX_COORDINATE`], [`MAX_AREA`], [`MAX_MODULUS`], [`MAX_FORCE`],
//! [`MAX_CLEARANCE_FRACTION`]), areas, moduli and natural lengths are positive, no member has zero length, a joint's two nodes
//! coincide, every hole node carries exactly one member, perpendicular to its shaft's axis,
//! and nothing else (one hole per member end: see [`crate::joint`]), and the nominal
//! structure is not a mechanism.

use crate::joint::{DEFAULT_JOINT_COMPRESSION_RATIO, DEFAULT_JOINT_TENSION_FACTOR};
use crate::model_file::{
    BehaviourSpec, JointSpec, LoadSpec, MemberSpec, ModelFile, NodeSpec, SupportSpec,
    TopSurfaceSpec,
};
use crate::{DEFAULT_COMPRESSION_RATIO, MAX_LENGTH_ERROR_FRACTION, ModelError};

/// The largest joint clearance, as a fraction of the length of the member in the hole:
/// `g ≤ 0.1·L₀`. A joint is a pin in a hole whose contact acts across a fixed shaft axis
/// (see [`crate::joint`]); free play of a tenth of the member is no longer a pin joint but a
/// loose linkage. The bound is wide on purpose: the paper's own Fig. 15 exaggerates the
/// clearance to 30 mm on 380 mm members (7.9 %) to show the mechanism, where the real
/// joints have about 0.01 mm.
pub const MAX_CLEARANCE_FRACTION: f64 = 0.1;
use std::collections::HashMap;

/// A node.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Unique id.
    pub id: String,
    /// Nominal position \[mm\].
    pub xyz: [f64; 3],
}

/// How a member carries axial load.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Behaviour {
    /// Carries tension and compression with the same stiffness `E·A/L₀`.
    Bar,
    /// Carries tension with stiffness `E·A/L₀`; in compression (shorter than its natural
    /// length, "slack") its stiffness is `compression_ratio·E·A/L₀`.
    Cable {
        /// Compression stiffness / tension stiffness, in [0, 1).
        compression_ratio: f64,
    },
}

impl Behaviour {
    /// Whether the member is tension-only.
    pub fn is_cable(self) -> bool {
        matches!(self, Behaviour::Cable { .. })
    }
}

/// A member: a straight two-force element between two nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct Member {
    /// Unique id.
    pub id: String,
    /// Indices of its two nodes in [`Model::nodes`].
    pub nodes: [usize; 2],
    /// Group name; length-error distributions are given per group.
    pub group: String,
    /// Cross-sectional area \[mm²\].
    pub area: f64,
    /// Young's modulus \[MPa\].
    pub youngs_modulus: f64,
    /// Stress-free length \[mm\].
    pub natural_length: f64,
    /// Bar or cable.
    pub behaviour: Behaviour,
}

impl Member {
    /// Axial stiffness `E·A/L₀` in tension \[N/mm\].
    pub fn axial_stiffness(&self) -> f64 {
        self.youngs_modulus * self.area / self.natural_length
    }
}

/// The surface whose tilt is measured.
#[derive(Debug, Clone, PartialEq)]
pub struct TopSurface {
    /// Indices of its three nodes, in the paper's Fig. 5 order (1, 2, 3).
    pub nodes: [usize; 3],
    /// The unit normal θ_P is measured against.
    pub reference_normal: [f64; 3],
}

/// A pin joint with backlash between a shaft node and a hole node (see [`crate::joint`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Unique id.
    pub id: String,
    /// Index of the shaft-centre node (batten end).
    pub shaft: usize,
    /// Index of the hole-centre node (longeron end).
    pub hole: usize,
    /// Unit shaft axis, or `None` for backlash in every direction.
    pub axis: Option<[f64; 3]>,
    /// Nominal clearance `g` \[mm\].
    pub clearance: f64,
    /// Contact stiffness `k_t` \[N/mm\].
    pub tension_stiffness: f64,
    /// `k_c/k_t` ≥ 0, a loose joint's regularising stiffness over the contact stiffness
    /// (0, the default, for none: the physical limit).
    pub compression_ratio: f64,
    /// Stiffness along the axis `k_a` \[N/mm\].
    pub axial_stiffness: f64,
}

/// A validated truss model (see the module doc for its invariants).
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    nodes: Vec<Node>,
    members: Vec<Member>,
    fixed: Vec<[bool; 3]>,
    loads: Vec<[f64; 3]>,
    top_surface: Option<TopSurface>,
    joints: Vec<Joint>,
    node_index: HashMap<String, usize>,
}

impl Model {
    /// Validates everything but the mechanism check (which needs the solver's structure;
    /// [`Model::new`] does both).
    pub(crate) fn check(file: ModelFile) -> Result<Self, ModelError> {
        if file.nodes.is_empty() {
            return Err(ModelError::Empty { what: "nodes" });
        }
        if file.members.is_empty() {
            return Err(ModelError::Empty { what: "members" });
        }
        let node_index = unique_ids("node", file.nodes.iter().map(|n| n.id.as_str()))?;
        unique_ids("member", file.members.iter().map(|m| m.id.as_str()))?;
        let nodes = file
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| check_node(i, n))
            .collect::<Result<Vec<_>, _>>()?;
        let lookup = |item: &dyn Fn() -> String, id: &str| {
            node_index
                .get(id)
                .copied()
                .ok_or_else(|| ModelError::UnknownNode {
                    item: item(),
                    node: id.to_string(),
                })
        };
        let members = file
            .members
            .iter()
            .enumerate()
            .map(|(i, m)| check_member(i, m, &nodes, &lookup))
            .collect::<Result<Vec<_>, _>>()?;
        let mut fixed = vec![[false; 3]; nodes.len()];
        for (i, s) in file.supports.iter().enumerate() {
            let item = || format!("supports[{i}]");
            let node = lookup(&item, &s.node)?;
            for dof in parse_fixed(&item(), s)? {
                fixed[node][dof] = true;
            }
        }
        let mut loads = vec![[0.0; 3]; nodes.len()];
        for (i, l) in file.loads.iter().enumerate() {
            let item = || format!("loads[{i}]");
            let node = lookup(&item, &l.node)?;
            at_most(&item(), "force", &l.force, MAX_FORCE, "N")?;
            for (acc, f) in loads[node].iter_mut().zip(l.force) {
                *acc += f;
            }
        }
        let top_surface = file
            .top_surface
            .as_ref()
            .map(|t| check_top_surface(t, &nodes, &lookup))
            .transpose()?;
        unique_ids("joint", file.joints.iter().map(|j| j.id.as_str()))?;
        let joints = file
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| check_joint(i, j, &nodes, &members, &lookup))
            .collect::<Result<Vec<_>, _>>()?;
        check_joint_layout(
            &joints,
            &nodes,
            &members,
            &fixed,
            &loads,
            top_surface.as_ref(),
        )?;
        let play: f64 = joints.iter().map(|j| j.clearance).sum();
        for (i, m) in members.iter().enumerate() {
            let length = distance(nodes[m.nodes[0]].xyz, nodes[m.nodes[1]].xyz);
            let what = "the distance between its nodes";
            if let Some(fault) = initial_strain_fault(m.natural_length, length, play, what) {
                return Err(ModelError::Invalid {
                    item: format!("members[{i}] (id {:?})", m.id),
                    message: format!(
                        "natural_length {fault}; a member that long is another design, to be \
                         drawn with its own node positions"
                    ),
                });
            }
        }
        Ok(Self {
            nodes,
            members,
            fixed,
            loads,
            top_surface,
            joints,
            node_index,
        })
    }

    /// The largest length error member `m` may be given \[mm\]:
    /// [`MAX_LENGTH_ERROR_FRACTION`] of its natural length.
    pub fn max_length_error(&self, m: usize) -> f64 {
        // L₀/100 rather than 0.01·L₀, which is 3.8000000000000003 for 380 mm.
        self.members[m].natural_length / MAX_LENGTH_ERROR_FRACTION.recip()
    }

    /// Checks a length error `value` \[mm\] for member `m`: finite and within
    /// [`Model::max_length_error`]; the message says why not (the tools prefix the flag or
    /// key that gave it).
    pub fn check_length_error(&self, m: usize, value: f64) -> Result<(), String> {
        if !value.is_finite() {
            return Err(format!("{value} is not a finite number of mm"));
        }
        let max = self.max_length_error(m);
        if value.abs() > max {
            return Err(format!(
                "{value} mm is more than {}% of the member's natural length {} mm ({max} mm), \
                 beyond the elastic range where the model means anything",
                100.0 * MAX_LENGTH_ERROR_FRACTION,
                self.members[m].natural_length
            ));
        }
        Ok(())
    }

    /// The nodes.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The members.
    pub fn members(&self) -> &[Member] {
        &self.members
    }

    /// Which directions (x, y, z) of node `node` are fixed.
    pub fn fixed(&self, node: usize) -> [bool; 3] {
        self.fixed[node]
    }

    /// The total nodal load on node `node` \[N\].
    pub fn load(&self, node: usize) -> [f64; 3] {
        self.loads[node]
    }

    /// The measured surface, if the model has one.
    pub fn top_surface(&self) -> Option<&TopSurface> {
        self.top_surface.as_ref()
    }

    /// The pin joints with backlash.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Index of the node with id `id`.
    pub fn node_index(&self, id: &str) -> Option<usize> {
        self.node_index.get(id).copied()
    }

    /// Index of the member with id `id`.
    pub fn member_index(&self, id: &str) -> Option<usize> {
        self.members.iter().position(|m| m.id == id)
    }

    /// The distinct group names, in order of first appearance.
    pub fn groups(&self) -> Vec<&str> {
        let mut groups: Vec<&str> = Vec::new();
        for m in &self.members {
            if !groups.contains(&m.group.as_str()) {
                groups.push(&m.group);
            }
        }
        groups
    }

    /// Nominal length of member `m` (distance between its nodes' nominal positions) \[mm\].
    pub fn nominal_length(&self, m: usize) -> f64 {
        let [a, b] = self.members[m].nodes;
        distance(self.nodes[a].xyz, self.nodes[b].xyz)
    }

    /// The model as a file, with every default written out.
    pub fn to_file(&self) -> ModelFile {
        let axes = |f: [bool; 3]| -> String {
            "xyz"
                .chars()
                .zip(f)
                .filter(|(_, fixed)| *fixed)
                .map(|(c, _)| c)
                .collect()
        };
        ModelFile {
            nodes: self
                .nodes
                .iter()
                .map(|n| NodeSpec {
                    id: n.id.clone(),
                    xyz: n.xyz,
                })
                .collect(),
            members: self
                .members
                .iter()
                .map(|m| MemberSpec {
                    id: m.id.clone(),
                    nodes: m.nodes.map(|n| self.nodes[n].id.clone()),
                    group: m.group.clone(),
                    area: m.area,
                    youngs_modulus: m.youngs_modulus,
                    natural_length: Some(m.natural_length),
                    behaviour: match m.behaviour {
                        Behaviour::Bar => BehaviourSpec::Bar,
                        Behaviour::Cable { .. } => BehaviourSpec::Cable,
                    },
                    compression_ratio: match m.behaviour {
                        Behaviour::Bar => None,
                        Behaviour::Cable { compression_ratio } => Some(compression_ratio),
                    },
                })
                .collect(),
            supports: self
                .fixed
                .iter()
                .enumerate()
                .filter(|(_, f)| f.iter().any(|&x| x))
                .map(|(i, &f)| SupportSpec {
                    node: self.nodes[i].id.clone(),
                    fixed: axes(f),
                })
                .collect(),
            loads: self
                .loads
                .iter()
                .enumerate()
                .filter(|(_, f)| f.iter().any(|&x| x != 0.0))
                .map(|(i, &force)| LoadSpec {
                    node: self.nodes[i].id.clone(),
                    force,
                })
                .collect(),
            top_surface: self.top_surface.as_ref().map(|t| TopSurfaceSpec {
                nodes: t.nodes.map(|n| self.nodes[n].id.clone()),
                reference_normal: t.reference_normal,
            }),
            joints: self
                .joints
                .iter()
                .map(|j| JointSpec {
                    id: j.id.clone(),
                    shaft: self.nodes[j.shaft].id.clone(),
                    hole: self.nodes[j.hole].id.clone(),
                    axis: j.axis,
                    clearance: j.clearance,
                    tension_stiffness: Some(j.tension_stiffness),
                    compression_ratio: Some(j.compression_ratio),
                    axial_stiffness: Some(j.axial_stiffness),
                })
                .collect(),
        }
    }
}

/// Euclidean distance \[mm\].
pub(crate) fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// Resolves a node id for an item (described lazily, for the error message).
type NodeLookup<'a> = dyn Fn(&dyn Fn() -> String, &str) -> Result<usize, ModelError> + 'a;

fn unique_ids<'a>(
    kind: &'static str,
    ids: impl Iterator<Item = &'a str>,
) -> Result<HashMap<String, usize>, ModelError> {
    let mut seen = HashMap::new();
    for (i, id) in ids.enumerate() {
        if let Some(&first) = seen.get(id) {
            return Err(ModelError::DuplicateId {
                kind,
                id: id.to_string(),
                first,
                second: i,
            });
        }
        seen.insert(id.to_string(), i);
    }
    Ok(seen)
}

fn finite(item: &str, field: &'static str, values: &[f64]) -> Result<(), ModelError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(ModelError::NotFinite {
            item: item.to_string(),
            field,
        })
    }
}

fn positive(item: &str, field: &'static str, value: f64) -> Result<f64, ModelError> {
    finite(item, field, &[value])?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(ModelError::NotPositive {
            item: item.to_string(),
            field,
            value,
        })
    }
}

fn check_node(i: usize, n: &NodeSpec) -> Result<Node, ModelError> {
    at_most(
        &format!("nodes[{i}] (id {:?})", n.id),
        "xyz",
        &n.xyz,
        MAX_COORDINATE,
        "mm",
    )?;
    Ok(Node {
        id: n.id.clone(),
        xyz: n.xyz,
    })
}

fn check_member(
    i: usize,
    m: &MemberSpec,
    nodes: &[Node],
    lookup: &NodeLookup<'_>,
) -> Result<Member, ModelError> {
    let item = || format!("members[{i}] (id {:?})", m.id);
    let a = lookup(&item, &m.nodes[0])?;
    let b = lookup(&item, &m.nodes[1])?;
    let length = distance(nodes[a].xyz, nodes[b].xyz);
    if a == b || length == 0.0 {
        return Err(ModelError::ZeroLength {
            item: item(),
            a: m.nodes[0].clone(),
            b: m.nodes[1].clone(),
        });
    }
    let area = positive(&item(), "area", m.area)?;
    at_most(&item(), "area", &[area], MAX_AREA, "mm²")?;
    let youngs_modulus = positive(&item(), "youngs_modulus", m.youngs_modulus)?;
    at_most(
        &item(),
        "youngs_modulus",
        &[youngs_modulus],
        MAX_MODULUS,
        "MPa",
    )?;
    let natural_length = positive(
        &item(),
        "natural_length",
        m.natural_length.unwrap_or(length),
    )?;
    at_most(
        &item(),
        "natural_length",
        &[natural_length],
        MAX_COORDINATE,
        "mm",
    )?;
    let behaviour = match (m.behaviour, m.compression_ratio) {
        (BehaviourSpec::Bar, None) => Behaviour::Bar,
        (BehaviourSpec::Bar, Some(_)) => {
            return Err(ModelError::Invalid {
                item: item(),
                message: "compression_ratio applies to cables only".into(),
            });
        }
        (BehaviourSpec::Cable, ratio) => {
            let r = ratio.unwrap_or(DEFAULT_COMPRESSION_RATIO);
            finite(&item(), "compression_ratio", &[r])?;
            if !(0.0..1.0).contains(&r) {
                return Err(ModelError::Invalid {
                    item: item(),
                    message: format!("compression_ratio must be in [0, 1), got {r}"),
                });
            }
            Behaviour::Cable {
                compression_ratio: r,
            }
        }
    };
    if m.group.is_empty() {
        return Err(ModelError::Invalid {
            item: item(),
            message: "group must not be empty".into(),
        });
    }
    Ok(Member {
        id: m.id.clone(),
        nodes: [a, b],
        group: m.group.clone(),
        area,
        youngs_modulus,
        natural_length,
        behaviour,
    })
}

/// Why a natural length `natural` \[mm\] cannot start within the elastic range between
/// points `length` \[mm\] apart (`what` says which: `the distance between its nodes`), or
/// `None` if it can: it can when `|length − natural| ≤ natural ×`
/// [`MAX_LENGTH_ERROR_FRACTION`] `+ play`, the bound a length error has
/// ([`Model::max_length_error`]) widened by `play` \[mm\], the model's joint clearances
/// summed. Free play moves each hole by at most its clearance from its shaft, so the
/// distance between any two nodes once it is taken up is within that sum of the nominal one
/// (0 without joints: the bound is then exact). Beyond it the initial strain
/// `(length − natural)/natural` could only be taken up by yielding, which the model does not
/// represent.
pub fn initial_strain_fault(natural: f64, length: f64, play: f64, what: &str) -> Option<String> {
    let max = natural / MAX_LENGTH_ERROR_FRACTION.recip() + play;
    if (natural - length).abs() <= max {
        return None;
    }
    let free_play = if play > 0.0 {
        format!(
            " and the joints' summed clearance {} mm",
            crate::readable(play)
        )
    } else {
        String::new()
    };
    Some(format!(
        "{} mm is more than {}% of itself{free_play} ({} mm) from {what}, {} mm: an initial \
         strain beyond the elastic range, where the model means nothing (see \
         truss_core::MAX_LENGTH_ERROR_FRACTION)",
        crate::readable(natural),
        100.0 * MAX_LENGTH_ERROR_FRACTION,
        crate::readable(max),
        crate::readable(length)
    ))
}

fn parse_fixed(item: &str, s: &SupportSpec) -> Result<Vec<usize>, ModelError> {
    let mut dofs = Vec::new();
    for c in s.fixed.chars() {
        let dof = match c {
            'x' => 0,
            'y' => 1,
            'z' => 2,
            _ => {
                return Err(ModelError::Invalid {
                    item: item.to_string(),
                    message: format!(
                        "fixed must be made of the letters x, y, z; got {:?}",
                        s.fixed
                    ),
                });
            }
        };
        dofs.push(dof);
    }
    Ok(dofs)
}

fn check_top_surface(
    t: &TopSurfaceSpec,
    nodes: &[Node],
    lookup: &NodeLookup<'_>,
) -> Result<TopSurface, ModelError> {
    let item = || "top_surface".to_string();
    let mut idx = [0; 3];
    for (k, id) in t.nodes.iter().enumerate() {
        idx[k] = lookup(&item, id)?;
    }
    finite(&item(), "reference_normal", &t.reference_normal)?;
    let r = t.reference_normal;
    let norm = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
    if norm == 0.0 {
        return Err(ModelError::Invalid {
            item: item(),
            message: "reference_normal must not be zero".into(),
        });
    }
    let p = idx.map(|i| nodes[i].xyz);
    let n = crate::measure::cross(
        [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]],
        [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]],
    );
    if n == [0.0; 3] {
        return Err(ModelError::Invalid {
            item: item(),
            message: "its three nodes are on one line and define no plane".into(),
        });
    }
    Ok(TopSurface {
        nodes: idx,
        reference_normal: r.map(|x| x / norm),
    })
}

fn check_joint(
    i: usize,
    j: &JointSpec,
    nodes: &[Node],
    members: &[Member],
    lookup: &NodeLookup<'_>,
) -> Result<Joint, ModelError> {
    let item = || format!("joints[{i}] (id {:?})", j.id);
    let shaft = lookup(&item, &j.shaft)?;
    let hole = lookup(&item, &j.hole)?;
    if shaft == hole {
        return Err(ModelError::Invalid {
            item: item(),
            message: "shaft and hole must be two different nodes".into(),
        });
    }
    if nodes[shaft].xyz != nodes[hole].xyz {
        return Err(ModelError::Invalid {
            item: item(),
            message: format!(
                "shaft {:?} at {:?} and hole {:?} at {:?} must have the same xyz (a joint's \
                 nodes coincide nominally)",
                j.shaft, nodes[shaft].xyz, j.hole, nodes[hole].xyz
            ),
        });
    }
    let axis = match j.axis {
        None => None,
        Some(a) => {
            finite(&item(), "axis", &a)?;
            let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            if n == 0.0 {
                return Err(ModelError::Invalid {
                    item: item(),
                    message: "axis must not be zero".into(),
                });
            }
            Some(a.map(|x| x / n))
        }
    };
    finite(&item(), "clearance", &[j.clearance])?;
    if j.clearance < 0.0 {
        return Err(ModelError::Invalid {
            item: item(),
            message: format!("clearance must be at least 0 mm, got {}", j.clearance),
        });
    }
    let shortest = members
        .iter()
        .filter(|m| m.nodes.contains(&hole))
        .map(|m| m.natural_length)
        .fold(f64::INFINITY, f64::min);
    if j.clearance > MAX_CLEARANCE_FRACTION * shortest {
        return Err(ModelError::Invalid {
            item: item(),
            message: format!(
                "clearance {} mm is more than {}% of its member's length {shortest} mm: \
                 free play that large is not a pin joint (see \
                 truss_core::model::MAX_CLEARANCE_FRACTION)",
                j.clearance,
                100.0 * MAX_CLEARANCE_FRACTION
            ),
        });
    }
    let tension_stiffness = match j.tension_stiffness {
        Some(k) => positive(&item(), "tension_stiffness", k)?,
        None => {
            let stiffest = members
                .iter()
                .filter(|m| m.nodes.iter().any(|&n| n == shaft || n == hole))
                .map(Member::axial_stiffness)
                .fold(0.0, f64::max);
            if stiffest == 0.0 {
                return Err(ModelError::Invalid {
                    item: item(),
                    message: "no member meets its nodes: give tension_stiffness".into(),
                });
            }
            DEFAULT_JOINT_TENSION_FACTOR * stiffest
        }
    };
    let compression_ratio = j
        .compression_ratio
        .unwrap_or(DEFAULT_JOINT_COMPRESSION_RATIO);
    finite(&item(), "compression_ratio", &[compression_ratio])?;
    if !(0.0..=MAX_JOINT_COMPRESSION_RATIO).contains(&compression_ratio) {
        return Err(ModelError::Invalid {
            item: item(),
            message: format!(
                "compression_ratio must be in [0, {MAX_JOINT_COMPRESSION_RATIO:e}] (0, the \
                 default, is a loose pin that carries no force; a larger regularisation \
                 would hold a loose joint more stiffly than its member), got \
                 {compression_ratio}"
            ),
        });
    }
    let axial_stiffness = match j.axial_stiffness {
        Some(k) => positive(&item(), "axial_stiffness", k)?,
        None => tension_stiffness,
    };
    Ok(Joint {
        id: j.id.clone(),
        shaft,
        hole,
        axis,
        clearance: j.clearance,
        tension_stiffness,
        compression_ratio,
        axial_stiffness,
    })
}

/// Largest coordinate, `|x|`, `|y|`, `|z|` ≤ 10⁷ mm (10 km) \[mm\]: a plausible bound that
/// keeps every product of the solver far from overflow (a coordinate of 1e308 would pass
/// `is_finite` and make every length infinite).
pub const MAX_COORDINATE: f64 = 1e7;
/// Largest member cross-section, 10⁸ mm² (100 m²) \[mm²\].
pub const MAX_AREA: f64 = 1e8;
/// Largest Young's modulus, 10⁷ MPa (10 TPa, ten times diamond's) \[MPa\].
pub const MAX_MODULUS: f64 = 1e7;
/// Largest component of a nodal load, 10¹² N \[N\].
pub const MAX_FORCE: f64 = 1e12;

/// Refuses a value beyond ±`max` (after [`finite`]), naming its item and field.
fn at_most(
    item: &str,
    field: &'static str,
    values: &[f64],
    max: f64,
    unit: &str,
) -> Result<(), ModelError> {
    finite(item, field, values)?;
    match values.iter().find(|v| v.abs() > max) {
        None => Ok(()),
        Some(v) => Err(ModelError::Invalid {
            item: item.to_string(),
            message: format!(
                "{field} {} is beyond the plausible ±{max:e} {unit}",
                crate::readable(*v)
            ),
        }),
    }
}

/// Largest accepted `compression_ratio` of a joint: with the default contact stiffness
/// (10⁵ × the member's), a loose joint's regularisation is then at most the member's own
/// stiffness.
pub const MAX_JOINT_COMPRESSION_RATIO: f64 = 1e-5;

/// The layout that makes a joint's hole part of one member end (see [`crate::joint`]): each
/// hole node is the hole of one joint and the shaft of none, carries exactly one member,
/// perpendicular to the shaft's axis, and has no support, load or place in the top surface.
fn check_joint_layout(
    joints: &[Joint],
    nodes: &[Node],
    members: &[Member],
    fixed: &[[bool; 3]],
    loads: &[[f64; 3]],
    top: Option<&TopSurface>,
) -> Result<(), ModelError> {
    let invalid = |j: &Joint, message: String| ModelError::Invalid {
        item: format!("joint {:?}", j.id),
        message,
    };
    for (i, j) in joints.iter().enumerate() {
        let h = j.hole;
        if let Some(other) = joints
            .iter()
            .enumerate()
            .find(|(k, o)| (*k != i && o.hole == h) || o.shaft == h)
        {
            return Err(invalid(
                j,
                format!(
                    "its hole node is also in joint {:?}: a hole belongs to one member end",
                    other.1.id
                ),
            ));
        }
        let at: Vec<&Member> = members.iter().filter(|m| m.nodes.contains(&h)).collect();
        if at.len() != 1 {
            return Err(invalid(
                j,
                format!(
                    "its hole node carries {} members ({}); a hole is one member end's, so \
                     give each member end its own hole node and joint (a node between two \
                     stages holds two joints on one shaft)",
                    at.len(),
                    at.iter()
                        .map(|m| format!("{:?}", m.id))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        if at[0].behaviour != Behaviour::Bar {
            return Err(invalid(
                j,
                format!(
                    "member {:?} in its hole is a cable: only bars sit on pins",
                    at[0].id
                ),
            ));
        }
        if fixed[h].iter().any(|&f| f) || loads[h] != [0.0; 3] {
            return Err(invalid(
                j,
                "its hole node must have no support and no load: support or load the shaft".into(),
            ));
        }
        if top.is_some_and(|t| t.nodes.contains(&h)) {
            return Err(invalid(
                j,
                "its hole node is in the top surface: measure the shaft nodes".into(),
            ));
        }
        if let Some(a) = j.axis {
            let m = at[0];
            let [p, q] = m.nodes.map(|n| nodes[n].xyz);
            let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
            let cos = (a[0] * d[0] + a[1] * d[1] + a[2] * d[2]).abs() / distance(p, q);
            if cos > 1e-6 {
                return Err(invalid(
                    j,
                    format!(
                        "member {:?} is not perpendicular to the shaft's axis (cosine {cos:.3e}); \
                         a pin's axis is perpendicular to the member it holds",
                        m.id
                    ),
                ));
            }
        }
    }
    Ok(())
}
