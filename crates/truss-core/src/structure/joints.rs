//! The second stage of compiling a structure: the members, with the backlash joints condensed
//! into them (see [`crate::joint`]). A member end in a clearance hole acts on the joint's
//! shaft node, and a member with joints at its ends becomes two one-sided members in
//! parallel with a dead band of the joints' total clearance: its tension-only half in the
//! member's own place, its compression-only half after all the model's members. Both halves
//! have the series stiffness `1/(L₀/(E·A) + Σ 1/k_t)`.

use super::numbering::Numbering;
use super::parts::{Band, CompiledJoint, CompiledMember};
use crate::ModelError;
use crate::element::{norm, sub};
use crate::model::{Behaviour, Model};

/// The model's members compiled, in model order, then the compression-only halves of the
/// members in clearance holes. Fails where a joint's regularisation would hold its loose
/// member more stiffly than the member itself.
pub(super) fn compile_members(
    model: &Model,
    numbering: &Numbering,
) -> Result<Vec<CompiledMember>, ModelError> {
    let nodes = model.nodes();
    let hole_joint = &numbering.hole_joint;
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
            link: numbering.link(numbering.attach(model, i), numbering.attach(model, j)),
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
    Ok(members)
}

/// The model's joints compiled, in model order: each with its member's tension-only half.
pub(super) fn compile_joints(model: &Model) -> Vec<CompiledJoint> {
    let model_members = model.members().len();
    model
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
        .collect()
}
