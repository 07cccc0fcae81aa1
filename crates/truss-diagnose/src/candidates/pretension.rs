//! `diagonal_pretension`: a common length error of the diagonals (cables).
//!
//! Parameter `length_error` \[mm\] in \[−0.2, 0\], added to every cable group's length
//! error: diagonals made short, so pretensioned (lengthening them instead would make them
//! slack, a different mechanism whose likelihood is not smooth at the null). The null is the
//! end of the range, where P(χ²₁ ≥ Λ) is conservative: the null distribution is
//! ½χ²₀ + ½χ²₁.

use super::backlash::Backlash;
use super::candidate::{Candidate, MEMBER_LENGTHS, Registration, Trace, member_groups};
use super::length_bias::shifted;
use super::parameter::Parameter;
use crate::comparison::baseline::CaseEdit;
use crate::errors::DiagnoseError;

/// A common length error of the diagonals (cables).
pub struct DiagonalPretension {
    groups: Vec<String>,
    parameters: Vec<Parameter>,
}

impl DiagonalPretension {
    /// The candidate's name.
    pub const NAME: &'static str = "diagonal_pretension";

    /// Its registration: every model with a cable group.
    pub const REGISTRATION: Registration = Registration {
        name: Self::NAME,
        make: |baseline, _| {
            let groups = member_groups(baseline, true);
            if groups.is_empty() {
                Err("the model has no cable group".into())
            } else {
                Ok(Box::new(DiagonalPretension::new(groups)))
            }
        },
    };

    fn new(groups: Vec<String>) -> Self {
        Self {
            groups,
            parameters: vec![Parameter::linear("length_error", "mm", -0.2, 0.0, 0.0)],
        }
    }
}

impl Candidate for DiagonalPretension {
    fn name(&self) -> &'static str {
        Self::NAME
    }
    fn mechanism(&self) -> &'static str {
        "a common length error of the diagonals (negative: made short, pretensioning the frame)"
    }
    fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }
    fn apply(&self, v: &[f64], edit: &mut CaseEdit) -> Result<(), DiagnoseError> {
        if v[0] != 0.0 {
            for g in &self.groups {
                let d = shifted(edit.distribution(g), v[0]);
                edit.set_distribution(g, d);
            }
        }
        Ok(())
    }
    fn reading(&self, _j: usize, v: f64, _span: [f64; 3]) -> String {
        format!(
            "the diagonals are on average {:.1} µm shorter than nominal, pretensioning the frame",
            v.abs() * truss_units::MICROMETRE_PER_MM
        )
    }
    fn trace(&self) -> Trace {
        Trace::CableLengths
    }
    fn separated_from(&self, rival: Trace) -> Option<&'static str> {
        match rival {
            Trace::Temperature => Some(
                "the diagonals' lengths measured one by one (`--measured-members`), or the truss's temperature",
            ),
            Trace::BarLengths | Trace::JointPlay => Some(MEMBER_LENGTHS),
            Trace::Orientation | Trace::CableLengths | Trace::LengthScatter => None,
        }
    }
    /// The pretension sets how far pin joints with free play ([`Backlash`]) are pulled into
    /// contact: with the diagonals short the shafts bear on their holes and the play closes;
    /// with them slack the stages float within it. Alone against slack diagonals the
    /// clearance loosens what the data show tight, and alone against free play a
    /// pretension stiffens what floats. (Declared here only: this module already names
    /// backlash's, and the other way round the two files would import each other.)
    fn interacts_with(&self) -> &'static [&'static str] {
        &[Backlash::NAME]
    }
}
