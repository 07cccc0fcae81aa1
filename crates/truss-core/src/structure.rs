//! The compiled, immutable form of a model that solvers share: node numbering, per-member
//! constants, assembly targets, and the factorised all-taut material stiffness `K₀`.
//!
//! A [`Structure`] is built once per model and shared (behind an `Arc`) by every thread's
//! [`Solver`](crate::Solver). `K₀ = Σ k_m b_m b_mᵀ` (every cable taut, nominal geometry, no
//! geometric stiffness) is factorised here once: it proves the model is not a mechanism,
//! and with the Woodbury data over the cables it solves the linearised problem of every
//! sample (see the `linearised` module).
//!
//! Backlash joints are condensed here (see [`crate::joint`]): each hole node is dropped
//! (it gets no unknowns), its member is attached to the joint's shaft node instead, and a
//! member with joints at its ends becomes two one-sided members in parallel, its
//! tension-only half in the member's own place and its compression-only half after all the
//! model's members.

use crate::block::{Block, BlockBandMatrix};
use crate::element::{AxialMember, norm, sub};
use crate::linearised::{CableBasis, MAX_WOODBURY_CABLES};
use crate::model::{Behaviour, Model};
use crate::ordering::number_nodes;
use crate::{ModelError, TopSurface};

/// Marks a fixed direction in a node's DOF numbers.
pub(crate) const FIXED: u32 = u32::MAX;

/// Marks an assembly target that does not exist (a fully fixed node).
pub(crate) const NONE: usize = usize::MAX;

/// One member, compiled.
#[derive(Debug, Clone)]
pub(crate) struct CompiledMember {
    /// Where its stiffness and forces go.
    pub link: Link,
    /// Nominal vector `X_j − X_i` \[mm\].
    pub reference: [f64; 3],
    /// Nominal unit direction `(X_j − X_i)/L_r`.
    pub unit: [f64; 3],
    /// Nominal length `L_r = |X_j − X_i|` \[mm\].
    pub reference_length: f64,
    /// Nominal natural length \[mm\].
    pub natural_length: f64,
    /// Nominal `L_r − L₀` \[mm\].
    pub nominal_stretch: f64,
    /// `E·A` \[N\].
    pub rigidity: f64,
    /// Nominal axial stiffness `k = E·A/L₀` \[N/mm\].
    pub stiffness: f64,
    /// 1 for bars; the compression ratio for cables (and a half's slack-side ratio); for a
    /// cable of ratio 0, the working ratio that stands for the limit (see [`crate::limit`]).
    pub compression_ratio: f64,
    /// A cable of model ratio 0: the solver answers for the limit `r → 0`.
    pub limit: bool,
    /// Whether the member is one-sided: a cable, or a half of a member with a dead band.
    pub is_cable: bool,
    /// `σ`: +1 for bars and tension-only members, −1 for a compression-only half.
    pub sense: f64,
    /// The model member this stands for (itself, but for compression-only halves).
    pub model_member: usize,
    /// For a half of a member whose ends sit in clearance holes: its dead band.
    pub band: Option<Band>,
}

/// The dead band of a member whose ends sit in clearance holes (see [`crate::joint`]).
#[derive(Debug, Clone)]
pub(crate) struct Band {
    /// The joints (model order) at the member's first and second node, where there are.
    pub joints: [Option<usize>; 2],
    /// `Σ 1/k_t` over those joints \[mm/N\].
    pub compliance: f64,
    /// The member's own `E·A` \[N\].
    pub member_rigidity: f64,
    /// The other half's index among the structure's members.
    pub partner: usize,
}

/// Where a two-node element (a member or a joint, from node `i` to node `j`) puts its
/// stiffness blocks and forces.
#[derive(Debug, Clone)]
pub(crate) struct Link {
    /// Row numbers of (`i`x, `i`y, `i`z, `j`x, `j`y, `j`z); a fixed direction points at the
    /// zero slot (index `free`), whose value is always zero.
    pub dofs: [usize; 6],
    /// Block slots of (`i`,`i`), (`j`,`j`) and the coupling block, or [`NONE`].
    pub slots: [usize; 3],
    /// Whether the coupling block's rows belong to node `i` (else to node `j`).
    pub coupling_rows_i: bool,
    /// Whether this element is the first, in assembly order (members, then joints), to add
    /// to each of `slots`: it then writes the block instead of adding to it, so assembly
    /// needs no clearing.
    pub first: [bool; 3],
    /// 1 for a free direction, 0 for a fixed one, of node `i` then node `j`.
    pub masks: [[f64; 3]; 2],
    /// Blocks of node `i` and node `j` (rows `3b .. 3b + 3`), or [`NONE`] for a node with
    /// no free direction.
    pub ends: [usize; 2],
    /// Whether a node of the element has a block and a fixed direction, so that its rows
    /// need the masks (never for a node fixed in all or no directions).
    pub masked: bool,
}

/// One joint, compiled: condensed into its member's dead band.
#[derive(Debug, Clone)]
pub(crate) struct CompiledJoint {
    /// Its id, for messages.
    pub id: String,
    /// Its member's tension-only half (the model member's index).
    pub member: usize,
    /// Whether the hole is at the member's first node.
    pub at_start: bool,
    /// The shaft node.
    pub shaft: usize,
    /// Nominal clearance `g` \[mm\].
    pub clearance: f64,
    /// Contact stiffness `k_t` \[N/mm\].
    pub tension_stiffness: f64,
}

/// A model compiled for solving (see the module doc).
#[derive(Debug, Clone)]
pub struct Structure {
    pub(crate) node_ids: Vec<String>,
    pub(crate) node_xyz: Vec<[f64; 3]>,
    /// Row numbers of each node's directions, [`FIXED`] where held.
    pub(crate) node_dofs: Vec<[u32; 3]>,
    /// Node and direction of each row.
    pub(crate) dof_owner: Vec<(usize, u8)>,
    /// Number of rows (3 per active node); vectors have one more entry, the zero slot.
    pub(crate) free: usize,
    pub(crate) members: Vec<CompiledMember>,
    /// Number of the model's members (the first ones of `members`).
    pub(crate) model_members: usize,
    /// For each node that is a joint's hole, that joint: the node has no unknowns, and its
    /// position is its shaft's plus the joint's offset.
    pub(crate) hole_joint: Vec<Option<usize>>,
    /// The joints, in model order.
    pub(crate) joints: Vec<CompiledJoint>,
    /// Block slots and directions of fixed directions of active nodes (identity rows).
    pub(crate) identity_rows: Vec<(usize, usize)>,
    /// Slots of the band (within it, not its padding) that no member adds to: zeroed at
    /// the start of each assembly (a factorisation fills them in).
    pub(crate) untouched: Vec<usize>,
    /// External load per row (plus the zero slot) \[N\].
    pub(crate) loads: Vec<f64>,
    /// `K₀`, factorised.
    pub(crate) nominal: BlockBandMatrix,
    /// Woodbury data over the cables, for models with few enough cables.
    pub(crate) basis: Option<CableBasis>,
    pub(crate) top_surface: Option<TopSurface>,
    /// Whether the model's bars frame the top surface's tilt by themselves (see
    /// [`crate::limit::tilt_framed_by_bars`]): then no sample floats.
    pub(crate) tilt_framed: bool,
}

impl Structure {
    /// Compiles `model` and factorises `K₀`; fails if the model is a mechanism.
    pub fn new(model: &Model) -> Result<Self, ModelError> {
        let nodes = model.nodes();
        let mut hole_joint = vec![None; nodes.len()];
        for (k, j) in model.joints().iter().enumerate() {
            hole_joint[j.hole] = Some(k);
        }
        // A member end in a hole acts on the joint's shaft; the hole node has no unknowns.
        let attach = |node: usize| hole_joint[node].map_or(node, |k| model.joints()[k].shaft);
        let fixed: Vec<[bool; 3]> = (0..nodes.len())
            .map(|i| {
                if hole_joint[i].is_some() {
                    [true; 3]
                } else {
                    model.fixed(i)
                }
            })
            .collect();
        let edges: Vec<[usize; 2]> = model
            .members()
            .iter()
            .map(|m| m.nodes.map(attach))
            .collect();
        let numbering = number_nodes(&fixed, &edges);
        let free = 3 * numbering.blocks;
        let mut k = BlockBandMatrix::new(numbering.blocks, numbering.bandwidth);
        let mut node_dofs = vec![[FIXED; 3]; nodes.len()];
        let mut dof_owner = vec![(0, 0); free];
        let mut identity_rows = Vec::new();
        for (node, block) in numbering.block.iter().enumerate() {
            if let Some(b) = *block {
                for d in 0..3 {
                    dof_owner[3 * b + d] = (node, d as u8);
                    if fixed[node][d] {
                        identity_rows.push((k.slot(b, b), d));
                    } else {
                        node_dofs[node][d] = (3 * b + d) as u32;
                    }
                }
            }
        }
        let link = |i: usize, j: usize| {
            let mut dofs = [free; 6];
            for d in 0..3 {
                for (side, node) in [i, j].into_iter().enumerate() {
                    if node_dofs[node][d] != FIXED {
                        dofs[3 * side + d] = node_dofs[node][d] as usize;
                    }
                }
            }
            let (bi, bj) = (numbering.block[i], numbering.block[j]);
            let slot = |a: Option<usize>, b: Option<usize>| match (a, b) {
                (Some(a), Some(b)) => k.slot(a.max(b), a.min(b)),
                _ => NONE,
            };
            let mask = |node: usize| fixed[node].map(|f| if f { 0.0 } else { 1.0 });
            Link {
                dofs,
                slots: [slot(bi, bi), slot(bj, bj), slot(bi, bj)],
                coupling_rows_i: bi > bj,
                first: [false; 3],
                masks: [mask(i), mask(j)],
                ends: [bi.unwrap_or(NONE), bj.unwrap_or(NONE)],
                masked: (bi.is_some() && fixed[i].iter().any(|&f| f))
                    || (bj.is_some() && fixed[j].iter().any(|&f| f)),
            }
        };
        let model_members = model.members().len();
        let mut members = Vec::with_capacity(model_members);
        let mut halves = Vec::new();
        for (m, member) in model.members().iter().enumerate() {
            let [i, j] = member.nodes;
            let reference = sub(nodes[j].xyz, nodes[i].xyz);
            let length = norm(reference);
            let (is_cable, compression_ratio) = match member.behaviour {
                Behaviour::Bar => (false, 1.0),
                Behaviour::Cable { compression_ratio } => (true, compression_ratio),
            };
            // A cable of ratio 0 gets its working ratio once the model's framing is known.
            let limit = is_cable && compression_ratio == 0.0;
            let rigidity = member.youngs_modulus * member.area;
            let mut compiled = CompiledMember {
                link: link(attach(i), attach(j)),
                reference,
                unit: reference.map(|x| x / length),
                reference_length: length,
                natural_length: member.natural_length,
                nominal_stretch: model.nominal_length(m) - member.natural_length,
                rigidity,
                stiffness: rigidity / member.natural_length,
                compression_ratio,
                limit,
                is_cable,
                sense: 1.0,
                model_member: m,
                band: None,
            };
            let ends = [hole_joint[i], hole_joint[j]];
            if ends != [None, None] {
                let joints = ends.iter().flatten().map(|&k| &model.joints()[k]);
                let compliance: f64 = joints.clone().map(|j| 1.0 / j.tension_stiffness).sum();
                // The joints' regularisations in series (zero if any joint has none).
                let regularisation = 1.0
                    / joints
                        .clone()
                        .map(|j| 1.0 / (j.compression_ratio * j.tension_stiffness))
                        .sum::<f64>();
                let series = 1.0 / (member.natural_length / rigidity + compliance);
                let ratio = 0.5 * regularisation / series;
                if ratio >= 1.0 {
                    let first = ends.iter().flatten().next().expect("a joint at one end");
                    return Err(ModelError::Invalid {
                        item: format!("joint {:?}", model.joints()[*first].id),
                        message: format!(
                            "its regularisation compression_ratio·tension_stiffness holds the \
                             loose member {:?} more stiffly than the member itself (ratio \
                             {ratio:e}); use a smaller compression_ratio",
                            member.id
                        ),
                    });
                }
                compiled.natural_length = member.natural_length;
                compiled.rigidity = series * member.natural_length;
                compiled.stiffness = series;
                compiled.compression_ratio = ratio;
                compiled.limit = false;
                compiled.is_cable = true;
                compiled.band = Some(Band {
                    joints: ends,
                    compliance,
                    member_rigidity: rigidity,
                    partner: model_members + halves.len(),
                });
                let mut half = compiled.clone();
                half.sense = -1.0;
                half.band.as_mut().expect("just set").partner = m;
                halves.push(half);
            }
            members.push(compiled);
        }
        members.extend(halves);
        let joints: Vec<CompiledJoint> = model
            .joints()
            .iter()
            .map(|j| {
                let member = (0..model_members)
                    .find(|&m| model.members()[m].nodes.contains(&j.hole))
                    .expect("the model checks that a hole carries one member");
                CompiledJoint {
                    id: j.id.clone(),
                    member,
                    at_start: model.members()[member].nodes[0] == j.hole,
                    shaft: j.shaft,
                    clearance: j.clearance,
                    tension_stiffness: j.tension_stiffness,
                }
            })
            .collect();
        let mut touched = vec![false; k.blocks() * (k.bandwidth() + 1)];
        for link in members.iter_mut().map(|c| &mut c.link) {
            for (first, &slot) in link.first.iter_mut().zip(&link.slots) {
                if slot != NONE && !touched[slot] {
                    touched[slot] = true;
                    *first = true;
                }
            }
        }
        let untouched = (0..k.blocks())
            .flat_map(|i| (i.saturating_sub(k.bandwidth())..=i).map(move |j| (i, j)))
            .map(|(i, j)| k.slot(i, j))
            .filter(|&slot| !touched[slot])
            .collect();
        let mut loads = vec![0.0; free + 1];
        for (node, dofs) in node_dofs.iter().enumerate() {
            let f = model.load(node);
            for d in 0..3 {
                if dofs[d] != FIXED {
                    loads[dofs[d] as usize] = f[d];
                }
            }
        }
        let mut structure = Self {
            node_ids: nodes.iter().map(|n| n.id.clone()).collect(),
            node_xyz: nodes.iter().map(|n| n.xyz).collect(),
            node_dofs,
            dof_owner,
            free,
            members,
            model_members,
            hole_joint,
            joints,
            identity_rows,
            untouched,
            loads,
            nominal: BlockBandMatrix::new(0, 0),
            basis: None,
            top_surface: model.top_surface().cloned(),
            tilt_framed: false,
        };
        structure.assemble_material(&mut k, |_| 1.0);
        k.factor().map_err(|e| {
            let (node, dof) = structure.describe_dof(e.index);
            ModelError::Mechanism { node, dof }
        })?;
        structure.nominal = k;
        structure.tilt_framed = crate::limit::tilt_framed_by_bars(&structure);
        let working = if structure.tilt_framed {
            crate::limit::FRAMED_RATIO
        } else {
            crate::limit::LIMIT_RATIO
        };
        for c in structure.members.iter_mut().filter(|c| c.limit) {
            c.compression_ratio = working;
        }
        let cables = structure.members.iter().filter(|m| m.is_cable).count();
        if cables > 0 && cables <= MAX_WOODBURY_CABLES {
            structure.basis = Some(CableBasis::new(&structure));
        }
        Ok(structure)
    }

    /// Assembles the linearised material stiffness `Σ f(m)·k_m·b_m b_mᵀ` (nominal `k_m`
    /// and directions, `f(m)` a per-member factor such as a slack cable's compression
    /// ratio) into `k`, identity rows included.
    pub(crate) fn assemble_material(&self, k: &mut BlockBandMatrix, factor: impl Fn(usize) -> f64) {
        self.begin_assembly(k);
        for (m, c) in self.members.iter().enumerate() {
            let kk = factor(m) * c.rigidity / c.natural_length;
            let n = c.unit;
            let block = [
                kk * n[0] * n[0],
                kk * n[1] * n[0],
                kk * n[1] * n[1],
                kk * n[2] * n[0],
                kk * n[2] * n[1],
                kk * n[2] * n[2],
            ];
            self.add_block(k, &c.link, &block);
        }
        self.set_identity_rows(k);
    }

    /// Prepares `k` for [`Structure::add_block`] of every member, in order: zeroes the blocks that none writes (the first to reach a block writes it).
    #[inline]
    pub(crate) fn begin_assembly(&self, k: &mut BlockBandMatrix) {
        let storage = k.storage_mut();
        for &slot in &self.untouched {
            storage[slot] = [[0.0; 3]; 3];
        }
    }

    /// Adds a member's or joint's contribution `[[K, −K], [−K, K]]` (from the six distinct
    /// entries of the symmetric 3×3 `K`, order `[xx, yx, yy, zx, zy, zz]`), fixed
    /// directions masked; called for every member then every joint, in order, after
    /// [`Structure::begin_assembly`]. Only the lower triangles of diagonal blocks are
    /// written (the only part read).
    #[inline]
    pub(crate) fn add_block(&self, k: &mut BlockBandMatrix, c: &Link, e: &[f64; 6]) {
        let [sii, sjj, sij] = c.slots;
        let storage = k.storage_mut();
        if !c.masked {
            // Masks of ones: `x·1·1` is `x` exactly, so this is the masked sum without the
            // multiplications; a block's first member writes it (`0 + x` is `x`).
            for (slot, first) in [(sii, c.first[0]), (sjj, c.first[1])] {
                if slot != NONE {
                    let b = &mut storage[slot];
                    if first {
                        b[0][0] = e[0];
                        b[1][0] = e[1];
                        b[1][1] = e[2];
                        b[2][0] = e[3];
                        b[2][1] = e[4];
                        b[2][2] = e[5];
                    } else {
                        b[0][0] += e[0];
                        b[1][0] += e[1];
                        b[1][1] += e[2];
                        b[2][0] += e[3];
                        b[2][1] += e[4];
                        b[2][2] += e[5];
                    }
                }
            }
            if sij != NONE {
                let b = &mut storage[sij];
                let full = [[e[0], e[1], e[3]], [e[1], e[2], e[4]], [e[3], e[4], e[5]]];
                if c.first[2] {
                    // Written out: `full.map(|row| row.map(|x| −x))` is not inlined, and
                    // its call cost a sixth of the assembly.
                    for (row, f) in b.iter_mut().zip(&full) {
                        for (x, y) in row.iter_mut().zip(f) {
                            *x = -y;
                        }
                    }
                } else {
                    for (row, f) in b.iter_mut().zip(&full) {
                        for (x, y) in row.iter_mut().zip(f) {
                            *x -= y;
                        }
                    }
                }
            }
            return;
        }
        let full: Block = [[e[0], e[1], e[3]], [e[1], e[2], e[4]], [e[3], e[4], e[5]]];
        let [mi, mj] = c.masks;
        for (&slot, &first) in c.slots.iter().zip(&c.first) {
            if slot != NONE && first {
                storage[slot] = [[0.0; 3]; 3];
            }
        }
        if sii != NONE {
            add_masked(&mut storage[sii], &full, &mi, &mi, 1.0);
        }
        if sjj != NONE {
            add_masked(&mut storage[sjj], &full, &mj, &mj, 1.0);
        }
        if sij != NONE {
            if c.coupling_rows_i {
                add_masked(&mut storage[sij], &full, &mi, &mj, -1.0);
            } else {
                add_masked(&mut storage[sij], &full, &mj, &mi, -1.0);
            }
        }
    }

    /// Puts 1 on the diagonal of every fixed direction of an active node.
    #[inline]
    pub(crate) fn set_identity_rows(&self, k: &mut BlockBandMatrix) {
        let storage = k.storage_mut();
        for &(slot, d) in &self.identity_rows {
            storage[slot][d][d] = 1.0;
        }
    }

    /// The member's constants for a sample with length error `error` \[mm\] and, for a
    /// half of a member in clearance holes, total clearance `gap` \[mm\]: the tension-only
    /// half's natural length is `L₀ + G`, the compression-only half's `L₀ − G`, and both
    /// have the series stiffness `1/(L₀/(E·A) + Σ 1/k_t)` (see [`crate::joint`]).
    #[inline]
    pub(crate) fn nominal_member(&self, m: &CompiledMember, error: f64, gap: f64) -> AxialMember {
        // `AxialMember::new` with the nominal length computed once.
        let natural_length = m.natural_length + error;
        let (rigidity, initial_stretch) = match &m.band {
            None => (m.rigidity, m.nominal_stretch - error),
            Some(b) => (
                b.member_rigidity * natural_length
                    / (natural_length + b.compliance * b.member_rigidity),
                m.nominal_stretch - error - m.sense * gap,
            ),
        };
        AxialMember {
            reference: m.reference,
            reference_length: m.reference_length,
            natural_length,
            initial_stretch,
            rigidity,
            compression_ratio: m.compression_ratio,
            sense: m.sense,
        }
    }

    /// The total clearance of member `m`'s joints \[mm\], each joint's from `clearance`
    /// (per joint, model order) or, where that is empty, its nominal one.
    #[inline]
    pub(crate) fn band_clearance(&self, m: &CompiledMember, clearance: &[f64]) -> f64 {
        m.band.as_ref().map_or(0.0, |b| {
            b.joints
                .iter()
                .flatten()
                .map(|&j| {
                    clearance
                        .get(j)
                        .copied()
                        .unwrap_or(self.joints[j].clearance)
                })
                .sum()
        })
    }

    /// Whether the model's bars frame the top surface's tilt by themselves (see
    /// [`crate::limit`]): its samples never float, and a cable of ratio 0 works at
    /// [`crate::limit::FRAMED_RATIO`].
    pub fn tilt_framed(&self) -> bool {
        self.tilt_framed
    }

    /// Number of rows of the stiffness matrix (3 per node with a free direction).
    pub fn free_dofs(&self) -> usize {
        self.free
    }

    /// Block (node) half-bandwidth of the stiffness matrix in the chosen numbering.
    pub fn bandwidth(&self) -> usize {
        self.nominal.bandwidth()
    }

    /// Nominal length of the shortest member \[mm\].
    pub(crate) fn shortest_member(&self) -> f64 {
        self.members
            .iter()
            .map(|m| m.reference_length)
            .fold(f64::INFINITY, f64::min)
    }

    /// Number of the model's members.
    pub fn member_count(&self) -> usize {
        self.model_members
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.node_ids.len()
    }

    /// Node id and direction (`x`, `y`, `z`) of row `dof`, for messages.
    pub(crate) fn describe_dof(&self, dof: usize) -> (String, char) {
        let (node, dir) = self.dof_owner[dof];
        (self.node_ids[node].clone(), ['x', 'y', 'z'][dir as usize])
    }
}

/// `target += sign · (row mask) ∘ block ∘ (column mask)`.
#[inline(always)]
fn add_masked(target: &mut Block, block: &Block, rows: &[f64; 3], cols: &[f64; 3], sign: f64) {
    for r in 0..3 {
        for c in 0..3 {
            target[r][c] += sign * rows[r] * cols[c] * block[r][c];
        }
    }
}
