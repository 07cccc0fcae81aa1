//! Bad model files are refused with an error naming the item.

use crate::common::*;
use truss_core::{Model, ModelError};

fn triangle() -> truss_core::ModelFile {
    file(
        vec![
            node("a", [0.0, 0.0, 0.0]),
            node("b", [100.0, 0.0, 0.0]),
            node("c", [0.0, 100.0, 0.0]),
        ],
        vec![
            member("ab", "a", "b", 1.0, None, None),
            member("bc", "b", "c", 1.0, None, None),
            member("ca", "c", "a", 1.0, None, None),
        ],
        vec![support("a", "xyz"), support("b", "yz"), support("c", "z")],
    )
}

fn message(f: truss_core::ModelFile) -> String {
    Model::new(f).unwrap_err().to_string()
}

#[test]
fn the_valid_triangle_is_accepted() {
    Model::new(triangle()).unwrap();
}

#[test]
fn unknown_node_is_named() {
    let mut f = triangle();
    f.members[1].nodes[1] = "q".into();
    let m = message(f);
    assert!(
        m.contains("members[1]") && m.contains("\"bc\"") && m.contains("\"q\""),
        "{m}"
    );
}

#[test]
fn duplicate_ids_are_named() {
    let mut f = triangle();
    f.members[2].id = "ab".into();
    assert!(message(f).contains("member id \"ab\" is used twice"));
    let mut f = triangle();
    f.nodes[2].id = "a".into();
    assert!(message(f).contains("node id \"a\""));
}

#[test]
fn zero_length_member_is_named() {
    let mut f = triangle();
    f.nodes[1].xyz = [0.0, 0.0, 0.0];
    let m = message(f);
    assert!(m.contains("zero-length") && m.contains("\"ab\""), "{m}");
}

#[test]
fn non_positive_area_and_modulus_are_named() {
    let mut f = triangle();
    f.members[0].area = 0.0;
    assert!(message(f).contains("area must be positive"));
    let mut f = triangle();
    f.members[2].youngs_modulus = -70_000.0;
    let m = message(f);
    assert!(
        m.contains("members[2]") && m.contains("youngs_modulus"),
        "{m}"
    );
    let mut f = triangle();
    f.members[0].natural_length = Some(0.0);
    assert!(message(f).contains("natural_length"));
}

#[test]
fn non_finite_numbers_are_named() {
    let mut f = triangle();
    f.nodes[2].xyz[1] = f64::NAN;
    let m = message(f);
    assert!(
        m.contains("nodes[2]") && m.contains("xyz") && m.contains("not a finite"),
        "{m}"
    );
    let mut f = triangle();
    f.members[1].area = f64::INFINITY;
    assert!(message(f).contains("not a finite"));
}

#[test]
fn a_mechanism_is_refused_naming_the_free_node() {
    let mut f = triangle();
    f.supports[2].fixed = "".into();
    let m = message(f);
    assert!(
        m.contains("mechanism") && m.contains("\"c\"") && m.contains("z"),
        "{m}"
    );
}

#[test]
fn bad_json_and_misspelt_fields_name_the_line() {
    let text = triangle_json().replace("\"youngs_modulus\"", "\"youngs_modulous\"");
    let err = Model::from_json(&text, "m.json").unwrap_err();
    assert!(matches!(err, ModelError::Syntax { .. }), "{err}");
    let m = err.to_string();
    assert!(
        m.starts_with("m.json: line ") && m.contains("youngs_modulous"),
        "{m}"
    );
}

#[test]
fn cable_fields_are_checked() {
    let mut f = triangle();
    f.members[0].compression_ratio = Some(0.5);
    assert!(message(f).contains("cables only"));
    // Negative, above 1, or not finite: refused, naming the member.
    for bad in [1.5, -1e-9, f64::NAN, f64::INFINITY] {
        let mut f = triangle();
        f.members[0] = member("ab", "a", "b", 1.0, None, Some(bad));
        let m = message(f);
        assert!(
            m.contains("\"ab\"") && m.contains("compression_ratio"),
            "{bad}: {m}"
        );
    }
    // 0 is the paper's: slack cables carry nothing (solved as the limit r → 0).
    let mut f = triangle();
    f.members[0] = member("ab", "a", "b", 1.0, None, Some(0.0));
    assert!(Model::new(f).is_ok());
}

fn triangle_json() -> String {
    triangle().to_json()
}

/// The triangle with node `c` split into a shaft `c` and a hole `c.h` (member `ca` on the
/// hole), joined by a joint with clearance 0.01 mm.
fn jointed() -> truss_core::ModelFile {
    let mut f = triangle();
    f.nodes.push(node("c.h", [0.0, 100.0, 0.0]));
    f.members[2].nodes[0] = "c.h".into();
    f.joints.push(truss_core::model_file::JointSpec {
        id: "joint.c".into(),
        shaft: "c".into(),
        hole: "c.h".into(),
        axis: Some([0.0, 0.0, 1.0]),
        clearance: 0.01,
        tension_stiffness: None,
        compression_ratio: None,
        axial_stiffness: None,
    });
    f
}

#[test]
fn joint_faults_are_named() {
    Model::new(jointed()).unwrap();
    type Change = fn(&mut truss_core::model_file::JointSpec);
    let cases: Vec<(Change, &str)> = vec![
        (|j| j.hole = "nowhere".into(), "\"nowhere\""),
        (|j| j.hole = "c".into(), "two different nodes"),
        (|j| j.hole = "b".into(), "same xyz"),
        (|j| j.axis = Some([0.0; 3]), "axis must not be zero"),
        (|j| j.clearance = -0.001, "clearance"),
        (|j| j.clearance = f64::NAN, "clearance"),
        (|j| j.tension_stiffness = Some(0.0), "tension_stiffness"),
        (|j| j.compression_ratio = Some(2.0), "compression_ratio"),
        (|j| j.compression_ratio = Some(-1e-9), "compression_ratio"),
    ];
    for (change, expected) in cases {
        let mut f = jointed();
        change(&mut f.joints[0]);
        let m = message(f);
        assert!(
            m.contains("joints[0]") && m.contains("\"joint.c\"") && m.contains(expected),
            "{expected}: {m}"
        );
    }
    let mut f = jointed();
    let mut twin = f.joints[0].clone();
    twin.shaft = "c".into();
    f.joints.push(twin);
    let m = message(f);
    assert!(m.contains("\"joint.c\" is used twice"), "{m}");
}

/// A hole is one member end's (see `truss_core::joint`): a hole node with two members, a
/// support or a load, a hole shared by two joints, and a member not perpendicular to its
/// pin are refused, naming the joint and the reason.
#[test]
fn joint_layout_faults_are_named() {
    type Change = fn(&mut truss_core::ModelFile);
    let cases: Vec<(Change, &str)> = vec![
        (
            |f| f.members[1].nodes[1] = "c.h".into(),
            "carries 2 members",
        ),
        (|f| f.supports.push(support("c.h", "z")), "no support"),
        (
            |f| {
                f.loads.push(truss_core::model_file::LoadSpec {
                    node: "c.h".into(),
                    force: [0.0, 0.0, 1.0],
                })
            },
            "no load",
        ),
        (
            |f| f.joints[0].axis = Some([0.0, 1.0, 1.0]),
            "not perpendicular",
        ),
        (
            |f| f.members[2] = member("ca", "c.h", "a", 1.0, None, Some(1e-4)),
            "is a cable",
        ),
        (
            |f| {
                let mut twin = f.joints[0].clone();
                twin.id = "joint.twin".into();
                f.joints.push(twin);
            },
            "a hole belongs to one member end",
        ),
    ];
    for (change, expected) in cases {
        let mut f = jointed();
        change(&mut f);
        let m = message(f);
        assert!(
            m.contains("joint") && m.contains(expected),
            "{expected}: {m}"
        );
    }
}

/// A natural length further than 1 % of itself from the distance between its nodes sets an
/// initial strain beyond the elastic range, as a length error that large would
/// (`truss_core::MAX_LENGTH_ERROR_FRACTION`): refused naming the member and the field,
/// before any solve. Within 1 % it is a pretension, and accepted.
#[test]
fn natural_lengths_beyond_the_strain_rule_are_named() {
    let mut f = triangle();
    f.members[0].natural_length = Some(126.0);
    let m = message(f);
    assert!(
        m.contains("members[0]") && m.contains("\"ab\"") && m.contains("natural_length"),
        "{m}"
    );
    assert!(m.contains("1%"), "{m}");
    let mut f = triangle();
    f.members[0].natural_length = Some(99.2);
    Model::new(f).unwrap();
}
