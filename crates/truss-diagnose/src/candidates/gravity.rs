//! `gravity`: the self-weight of a ground test.
//!
//! Parameters `g_x`, `g_y`, `g_z` \[g\]: the self-weight vector in units of standard
//! gravity, \|g\| ≤ 1. It sets the case's `effects.gravity` with direction g/\|g\| and
//! acceleration 9.806 65·\|g\| m/s² (aluminium 2700 kg/m³, each member's weight lumped half
//! to each end). Its direction is the test orientation's gravity direction; \|g\| < 1 is a
//! partly off-loaded ground test.

use super::candidate::{Candidate, Registration, Trace};
use super::parameter::Parameter;
use crate::comparison::baseline::CaseEdit;
use crate::errors::DiagnoseError;
use truss_job::effects::{ALUMINIUM_DENSITY, GravitySpec, STANDARD_GRAVITY};

/// Self-weight of a ground test.
pub struct Gravity {
    parameters: Vec<Parameter>,
}

impl Gravity {
    /// The candidate's name.
    pub const NAME: &'static str = "gravity";

    /// Its registration: every baseline without gravity of its own.
    pub const REGISTRATION: Registration = Registration {
        name: Self::NAME,
        make: |baseline, _| {
            if baseline.case().effects.gravity.is_some() {
                Err("the baseline already has gravity".into())
            } else {
                Ok(Box::new(Gravity::new()))
            }
        },
    };

    pub(crate) fn new() -> Self {
        Self {
            parameters: ["g_x", "g_y", "g_z"]
                .iter()
                .map(|n| Parameter::linear(*n, "g", -1.0, 1.0, 0.0))
                .collect(),
        }
    }
}

impl Candidate for Gravity {
    fn name(&self) -> &'static str {
        Self::NAME
    }
    fn mechanism(&self) -> &'static str {
        "ground-test self-weight along the test orientation's gravity direction"
    }
    fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }
    fn apply(&self, v: &[f64], edit: &mut CaseEdit) -> Result<(), DiagnoseError> {
        let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let mut effects = edit.effects();
        effects.gravity = (norm > 0.0).then(|| GravitySpec {
            direction: [v[0] / norm, v[1] / norm, v[2] / norm],
            g: STANDARD_GRAVITY * norm,
            density: ALUMINIUM_DENSITY,
        });
        edit.set_effects(&effects);
        Ok(())
    }
    /// Scales g onto the unit ball; with a component held, scales the other two onto the
    /// disc that leaves (zero if the held one is already ±1).
    fn project(&self, v: &mut [f64], fixed: Option<usize>) {
        let norm2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if norm2 <= 1.0 {
            return;
        }
        match fixed {
            None => v.iter_mut().for_each(|x| *x /= norm2.sqrt()),
            Some(j) => {
                let room = (1.0 - v[j] * v[j]).max(0.0);
                let others = norm2 - v[j] * v[j];
                let r = if others > 0.0 {
                    (room / others).sqrt()
                } else {
                    0.0
                };
                for (i, x) in v.iter_mut().enumerate() {
                    if i != j {
                        *x *= r;
                    }
                }
            }
        }
    }
    fn reading(&self, j: usize, v: f64, _span: [f64; 3]) -> String {
        format!(
            "self-weight of {:.2} g along {}{} (a ground test's gravity direction)",
            v.abs(),
            if v >= 0.0 { "+" } else { "−" },
            ["x", "y", "z"][j]
        )
    }
    fn trace(&self) -> Trace {
        Trace::Orientation
    }
    /// Self-weight turns with the test orientation, whatever the rival.
    fn separated_from(&self, _rival: Trace) -> Option<&'static str> {
        Some("a test in another orientation (self-weight turns with it; the other effect does not)")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gravity's feasible set is the unit ball: a point outside is scaled onto it, and with a
    /// component held the other two are scaled onto the disc left (3-4-5 triangles by hand).
    #[test]
    fn gravity_projects_onto_the_ball_holding_a_component() {
        let g = Gravity::new();
        let mut v = [0.6, 0.8, 1.0];
        g.project(&mut v, None);
        let s = 2f64.sqrt();
        assert!((v[0] - 0.6 / s).abs() < 1e-12 && (v[2] - 1.0 / s).abs() < 1e-12);
        let mut v = [0.6, 0.8, 0.8];
        g.project(&mut v, Some(0));
        assert_eq!(v[0], 0.6);
        assert!((v[1] * v[1] + v[2] * v[2] - 0.64).abs() < 1e-12, "{v:?}");
        assert!((v[1] - v[2]).abs() < 1e-12);
        let mut v = [0.1, 1.0, 0.1];
        g.project(&mut v, Some(1));
        assert_eq!(v, [0.0, 1.0, 0.0]);
        let mut v = [0.3, 0.4, 0.0];
        g.project(&mut v, Some(2));
        assert_eq!(v, [0.3, 0.4, 0.0]);
    }
}
