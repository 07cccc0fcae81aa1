//! `backlash`: clearance at pin joints, the nodes of a prism made pin joints with backlash.
//!
//! Parameters `clearance` \[mm\] in \[0, 0.05\], the joints' mean radial clearance, and, with
//! the members measured one by one, `spread` \[mm\] in \[0, 0.05\] (held ≤ `clearance`), the
//! half-width h of their uniform scatter among joints, the paper's U\[mean − h, mean + h\]
//! (section 4.2.3). The prism gets pin joints at every node (`"backlash": true`:
//! truss-core's virtual cable joints at their default stiffnesses) and the case's
//! `backlash.clearance` the fitted distribution ([`clearance_distribution`]: a constant at
//! h = 0); the members' and the joints' draws are those of the baseline (common random
//! numbers: each joint's clearance is mean + h·(2u − 1), its u fixed).

use super::candidate::{Candidate, MEMBER_LENGTHS, Registration, Trace};
use super::parameter::Parameter;
use crate::comparison::baseline::{Baseline, CaseEdit};
use crate::errors::DiagnoseError;
use truss_core::prism::BacklashOptions;
use truss_job::distribution::{Constant, DistributionSpec, Uniform};
use truss_job::job::{CaseBacklash, ModelSpec};

/// Clearance at pin joints: the nodes of a prism become pin joints with backlash.
///
/// Two parameters: the joints' mean clearance and the half-width h of its uniform scatter
/// among joints (each joint of each specimen its own clearance, U\[mean − h, mean + h\], as
/// the paper draws them). The scatter is resolved only with the members measured one by one
/// (per-specimen conditioning, [`crate::likelihood::conditional`]); from node positions
/// alone h is not resolved and its extra parameter's penalty lets a length effect win the
/// BIC, so there the candidate keeps the one parameter, the clearance, which then stands
/// for the joints' mean. Where h's interval reaches 0 the report says the spread is not
/// resolved by the data.
pub struct Backlash {
    parameters: Vec<Parameter>,
}

impl Backlash {
    /// The candidate's name.
    pub const NAME: &'static str = "backlash";

    /// Its registration: a prism the job generates without joints; the spread only with
    /// the members measured.
    pub const REGISTRATION: Registration = Registration {
        name: Self::NAME,
        make: |baseline, with_members| {
            Backlash::applicable(baseline)?;
            Ok(Box::new(Backlash::new(with_members)))
        },
    };

    fn new(spread: bool) -> Self {
        let mut parameters = vec![Parameter::linear("clearance", "mm", 0.0, 0.05, 0.0)];
        if spread {
            parameters.push(Parameter::linear("spread", "mm", 0.0, 0.05, 0.0));
        }
        Self { parameters }
    }

    /// Whether the baseline can take joint clearances: its model must be a prism the job
    /// generates without backlash (the candidate makes its nodes pin joints); a model that
    /// already has joints has backlash already, a model file without them has no joints to
    /// loosen.
    fn applicable(baseline: &Baseline) -> Result<(), String> {
        if !baseline.model().joints().is_empty() {
            return Err("the baseline's model already has pin joints with clearance".into());
        }
        match baseline.derived_case().model {
            ModelSpec::Prism(_) => Ok(()),
            ModelSpec::File(_) => Err(
                "the baseline's model is a model file without joints[]: there is no pin joint to loosen (give the model joints, or use a prism job)"
                    .into(),
            ),
        }
    }
}

impl Candidate for Backlash {
    fn name(&self) -> &'static str {
        Self::NAME
    }
    fn mechanism(&self) -> &'static str {
        "clearance at the pin joints (every node a shaft in a hole; radial clearances uniform about their mean, U[mean − h, mean + h])"
    }
    fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }
    /// Keeps 0 ≤ h ≤ mean (no negative clearance): with h held (a profile over it) the
    /// mean is raised to h, otherwise h is lowered to the mean.
    fn project(&self, v: &mut [f64], fixed: Option<usize>) {
        if v.len() > 1 && v[1] > v[0] {
            match fixed {
                Some(1) => v[0] = v[1],
                _ => v[1] = v[0],
            }
        }
    }
    /// At the null (no clearance) the case is left as it is; otherwise the prism gets pin
    /// joints (truss-core's defaults) and the case the clearances U\[mean − h, mean + h\]
    /// (a constant at h = 0; h above the mean is held to it). A one-value `values` is h = 0.
    fn apply(&self, v: &[f64], edit: &mut CaseEdit) -> Result<(), DiagnoseError> {
        let clearance = v[0];
        if clearance <= 0.0 {
            return Ok(());
        }
        let spread = v.get(1).copied().unwrap_or(0.0).min(clearance);
        let ModelSpec::Prism(prism) = &mut edit.model else {
            return Err(DiagnoseError::Usage(
                "backlash: the case's model is not a prism the job generates".into(),
            ));
        };
        prism.backlash.get_or_insert_with(BacklashOptions::default);
        edit.model_edited = true;
        edit.case.backlash = Some(CaseBacklash {
            clearance: clearance_distribution(clearance, spread),
        });
        Ok(())
    }
    fn reading(&self, j: usize, v: f64, _span: [f64; 3]) -> String {
        if j == 1 {
            return format!(
                "the joints' clearances scatter uniformly within ±{:.1} µm of their mean (some joints tighter, some looser)",
                v * truss_units::MICROMETRE_PER_MM
            );
        }
        format!(
            "each pin joint has on average about {:.1} µm of radial clearance (free play of its shaft in the hole)",
            v * truss_units::MICROMETRE_PER_MM
        )
    }
    /// The spread reaching 0: the joints may all have one clearance.
    fn unresolved(&self, j: usize) -> Option<&'static str> {
        (j == 1).then_some(
            " — spread: not resolved by these data (its interval reaches 0: the joints may all have the same clearance, which the fitted `clearance` then stands for)",
        )
    }
    fn trace(&self) -> Trace {
        Trace::JointPlay
    }
    fn separated_from(&self, rival: Trace) -> Option<&'static str> {
        matches!(rival, Trace::BarLengths | Trace::CableLengths).then_some(MEMBER_LENGTHS)
    }
    /// Joint free play shortens the truss much as a member-length error does.
    fn mistaken_without_members(&self, rival: Trace) -> bool {
        matches!(rival, Trace::BarLengths | Trace::CableLengths)
    }
}

/// The joints' clearance distribution \[mm\] of mean `mean` and half-width `spread` (h):
/// U\[mean − h, mean + h\], the paper's form (section 4.2.3: U\[0.004, 0.017\] mm), a
/// constant when h = 0. The job's sampler draws a joint's clearance as low + (high − low)·u
/// from the joint's own random word u, so c = mean + h·(2u − 1): with common random numbers
/// every joint's clearance is linear in (mean, h), and the likelihood smooth in both.
pub fn clearance_distribution(mean: f64, spread: f64) -> DistributionSpec {
    if spread > 0.0 {
        Uniform {
            low: mean - spread,
            high: mean + spread,
        }
        .into()
    } else {
        Constant { value: mean }.into()
    }
}
