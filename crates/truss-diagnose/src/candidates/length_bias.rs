//! `length_bias`: a systematic length offset per bar group.
//!
//! Parameters `bias.GROUP` \[mm\] in ±0.1, one for each bar group (a group with a member
//! that is not a cable). It adds the bias to the group's length-error mean (a constant if
//! the group has no distribution).

use super::candidate::{Candidate, MEMBER_LENGTHS, Registration, Trace, member_groups};
use super::parameter::Parameter;
use crate::comparison::baseline::CaseEdit;
use crate::errors::DiagnoseError;
use truss_job::distribution::{Constant, DistributionSpec};

/// A systematic length offset per bar group.
pub struct LengthBias {
    groups: Vec<String>,
    parameters: Vec<Parameter>,
}

impl LengthBias {
    /// The candidate's name.
    pub const NAME: &'static str = "length_bias";

    /// Its registration: every model with a bar group.
    pub const REGISTRATION: Registration = Registration {
        name: Self::NAME,
        make: |baseline, _| {
            let groups = member_groups(baseline, false);
            if groups.is_empty() {
                Err("the model has no bar group".into())
            } else {
                Ok(Box::new(LengthBias::new(groups)))
            }
        },
    };

    fn new(groups: Vec<String>) -> Self {
        let parameters = groups
            .iter()
            .map(|g| Parameter::linear(format!("bias.{g}"), "mm", -0.1, 0.1, 0.0))
            .collect();
        Self { groups, parameters }
    }
}

/// Adds `shift` to a distribution's values (a constant where there is none).
pub(crate) fn shifted(d: Option<DistributionSpec>, shift: f64) -> DistributionSpec {
    d.map_or(Constant { value: shift }.into(), |d| d.shifted(shift))
}

impl Candidate for LengthBias {
    fn name(&self) -> &'static str {
        Self::NAME
    }
    fn mechanism(&self) -> &'static str {
        "a systematic member-length offset per bar group (members made long or short on average)"
    }
    fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }
    fn apply(&self, v: &[f64], edit: &mut CaseEdit) -> Result<(), DiagnoseError> {
        for (g, &b) in self.groups.iter().zip(v) {
            if b != 0.0 {
                let d = shifted(edit.distribution(g), b);
                edit.set_distribution(g, d);
            }
        }
        Ok(())
    }
    fn reading(&self, j: usize, v: f64, _span: [f64; 3]) -> String {
        format!(
            "the {} members are on average {:.1} µm {} than nominal",
            self.groups[j],
            v.abs() * truss_units::MICROMETRE_PER_MM,
            if v >= 0.0 { "longer" } else { "shorter" }
        )
    }
    fn trace(&self) -> Trace {
        Trace::BarLengths
    }
    /// A uniform temperature change lengthens every member as a bias does; the diagonals'
    /// common error and joint free play differ from it in the members' own lengths.
    fn separated_from(&self, rival: Trace) -> Option<&'static str> {
        match rival {
            Trace::Temperature => Some(
                "the truss's temperature during the measurements (a uniform temperature change lengthens every member as a length bias does), or the member lengths measured one by one at a known temperature (`--measured-members`)",
            ),
            Trace::CableLengths | Trace::JointPlay => Some(MEMBER_LENGTHS),
            Trace::Orientation | Trace::BarLengths | Trace::LengthScatter => None,
        }
    }
}
