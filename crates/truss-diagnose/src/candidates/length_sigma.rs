//! `length_sigma`: a mis-stated manufacturing σ per group.
//!
//! Parameters `sigma.GROUP` \[mm\] from 1/5 to 5 times the stated σ (fitted on a log
//! scale), for each group with a stated spread. It scales the group's spread about its mean
//! to the new σ.

use super::candidate::{Candidate, Registration, Trace};
use super::parameter::Parameter;
use crate::comparison::baseline::CaseEdit;
use crate::errors::DiagnoseError;

/// A mis-stated manufacturing σ per group.
pub struct LengthSigma {
    groups: Vec<(String, f64)>,
    parameters: Vec<Parameter>,
}

impl LengthSigma {
    /// The candidate's name.
    pub const NAME: &'static str = "length_sigma";

    /// Its registration: every case that states a length-error spread.
    pub const REGISTRATION: Registration = Registration {
        name: Self::NAME,
        make: |baseline, _| {
            let spread: Vec<(String, f64)> = baseline
                .case()
                .length_errors
                .iter()
                .filter(|(_, d)| d.std_dev() > 0.0)
                .map(|(g, d)| (g.clone(), d.std_dev()))
                .collect();
            if spread.is_empty() {
                Err("the baseline states no length-error spread".into())
            } else {
                Ok(Box::new(LengthSigma::new(spread)))
            }
        },
    };

    fn new(groups: Vec<(String, f64)>) -> Self {
        let parameters = groups
            .iter()
            .map(|(g, s)| Parameter {
                name: format!("sigma.{g}"),
                unit: "mm",
                low: s / 5.0,
                high: s * 5.0,
                null: *s,
                log: true,
            })
            .collect();
        Self { groups, parameters }
    }
}

impl Candidate for LengthSigma {
    fn name(&self) -> &'static str {
        Self::NAME
    }
    fn mechanism(&self) -> &'static str {
        "a mis-stated manufacturing σ per group (the members scatter more or less than stated)"
    }
    fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }
    fn apply(&self, v: &[f64], edit: &mut CaseEdit) -> Result<(), DiagnoseError> {
        for ((g, s0), &s) in self.groups.iter().zip(v) {
            let d = edit.distribution(g).ok_or_else(|| {
                DiagnoseError::Usage(format!("length_sigma: group {g} has no spread to scale"))
            })?;
            let d = d.spread_scaled(s / s0);
            edit.set_distribution(g, d);
        }
        Ok(())
    }
    fn reading(&self, j: usize, v: f64, _span: [f64; 3]) -> String {
        let (group, stated) = (&self.groups[j].0, self.parameters[j].null);
        format!(
            "the {group} members' lengths scatter by {:.1} µm (1 SD), {:.2} times the stated {:.1} µm",
            v * truss_units::MICROMETRE_PER_MM,
            v / stated,
            stated * truss_units::MICROMETRE_PER_MM
        )
    }
    fn trace(&self) -> Trace {
        Trace::LengthScatter
    }
    /// The members' scatter is measured directly, whatever mean effect it competes with
    /// (self-weight excepted: a test in another orientation says more).
    fn separated_from(&self, rival: Trace) -> Option<&'static str> {
        (rival != Trace::Orientation).then_some(
            "the member lengths measured one by one (`--measured-members`): their scatter is measured directly",
        )
    }
}
