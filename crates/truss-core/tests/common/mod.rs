//! Shared helpers of the integration tests: a small deterministic normal generator (so the
//! tests need nothing of mc-shard) and model builders.

#![allow(dead_code)]

use truss_core::model_file::{BehaviourSpec, MemberSpec, ModelFile, NodeSpec, SupportSpec};

/// SplitMix64 uniforms in (0, 1) and Box–Muller normals: deterministic test data.
pub struct Normals(u64);

impl Normals {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    pub fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
    }
}

/// Length errors \[mm\] with standard deviation `sigma` on the members whose group is in
/// `groups`, zero elsewhere.
pub fn errors(
    model: &truss_core::Model,
    groups: &[&str],
    sigma: f64,
    rng: &mut Normals,
) -> Vec<f64> {
    model
        .members()
        .iter()
        .map(|m| {
            let z = rng.normal();
            if groups.contains(&m.group.as_str()) {
                sigma * z
            } else {
                0.0
            }
        })
        .collect()
}

pub fn node(id: &str, xyz: [f64; 3]) -> NodeSpec {
    NodeSpec { id: id.into(), xyz }
}

pub fn member(
    id: &str,
    a: &str,
    b: &str,
    area: f64,
    natural: Option<f64>,
    cable: Option<f64>,
) -> MemberSpec {
    MemberSpec {
        id: id.into(),
        nodes: [a.into(), b.into()],
        group: if cable.is_some() {
            "cable".into()
        } else {
            "bar".into()
        },
        area,
        youngs_modulus: 70_000.0,
        natural_length: natural,
        behaviour: if cable.is_some() {
            BehaviourSpec::Cable
        } else {
            BehaviourSpec::Bar
        },
        compression_ratio: cable,
    }
}

pub fn support(node: &str, fixed: &str) -> SupportSpec {
    SupportSpec {
        node: node.into(),
        fixed: fixed.into(),
    }
}

pub fn file(
    nodes: Vec<NodeSpec>,
    members: Vec<MemberSpec>,
    supports: Vec<SupportSpec>,
) -> ModelFile {
    ModelFile {
        nodes,
        members,
        supports,
        loads: vec![],
        top_surface: None,
        joints: vec![],
    }
}
