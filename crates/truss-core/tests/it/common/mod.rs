//! Shared helpers of the integration tests: the deterministic normal generator of
//! `truss-stats` (so the tests need nothing of mc-shard) and model builders.

#![allow(dead_code)]

use truss_core::model_file::{BehaviourSpec, MemberSpec, ModelFile, NodeSpec, SupportSpec};

/// SplitMix64 uniforms in (0, 1) and Box–Muller normals: deterministic test data, from
/// the statistics crate's one definition.
pub use truss_stats::rng::SplitMix64 as Normals;

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

/// The model of Fig. 16 (section 4.2.3): the 5-stage prism with pin joints of the default
/// clearance, its cables of ratio 0 solved at their limit.
pub fn fig16_model() -> truss_core::Model {
    truss_core::prism::PrismOptions {
        backlash: Some(truss_core::prism::BacklashOptions::default()),
        ..truss_core::prism::PrismOptions::with_stages(5)
    }
    .model()
    .unwrap()
}

/// One sample of the paper's Fig. 16 case (§4.2.3) for a prism with backlash joints:
/// battens and longerons N(0, σ²), diagonals U[−3σ, 0] (every member's numbers drawn in
/// model order), then each joint's clearance U[0.004, 0.017] mm: (length errors, clearances)
/// \[mm\].
pub fn fig16_draw(
    model: &truss_core::Model,
    sigma: f64,
    rng: &mut Normals,
) -> (Vec<f64>, Vec<f64>) {
    let errors = model
        .members()
        .iter()
        .map(|m| match m.group.as_str() {
            "diagonal" => -3.0 * sigma * rng.uniform(),
            _ => sigma * rng.normal(),
        })
        .collect();
    let clearances = (0..model.joints().len())
        .map(|_| 0.004 + 0.013 * rng.uniform())
        .collect();
    (errors, clearances)
}
