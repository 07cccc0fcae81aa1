//! `thermal_gradient`: a linear temperature field.
//!
//! Parameters `gradient_x`, `gradient_y`, `gradient_z` \[K/mm\] in ±0.01 and `offset` \[K\]
//! in ±20. It sets the case's `effects.thermal_gradient`: ΔT(x) = offset + gradient·(x − c),
//! c the centroid of the model's nodes, α = 23e-6 /K; each member lengthens by
//! α·ΔT(midpoint)·L.

use super::candidate::{Candidate, Registration, Trace};
use super::parameter::Parameter;
use crate::comparison::baseline::CaseEdit;
use crate::errors::DiagnoseError;
use truss_job::effects::{ALUMINIUM_ALPHA, ThermalSpec};

/// A linear temperature field.
pub struct Thermal {
    parameters: Vec<Parameter>,
    reference: [f64; 3],
}

impl Thermal {
    /// The candidate's name.
    pub const NAME: &'static str = "thermal_gradient";

    /// Its registration: every baseline without a temperature field of its own, the field
    /// about the centroid of the model's nodes.
    pub const REGISTRATION: Registration = Registration {
        name: Self::NAME,
        make: |baseline, _| {
            if baseline.case().effects.thermal_gradient.is_some() {
                return Err("the baseline already has a temperature field".into());
            }
            let model = baseline.model();
            let n = model.nodes().len() as f64;
            let mut c = [0.0; 3];
            for node in model.nodes() {
                for (ck, x) in c.iter_mut().zip(node.xyz) {
                    *ck += x / n;
                }
            }
            Ok(Box::new(Thermal::new(c)))
        },
    };

    fn new(reference: [f64; 3]) -> Self {
        let mut parameters: Vec<Parameter> = ["gradient_x", "gradient_y", "gradient_z"]
            .iter()
            .map(|n| Parameter::linear(*n, "K/mm", -0.01, 0.01, 0.0))
            .collect();
        parameters.push(Parameter::linear("offset", "K", -20.0, 20.0, 0.0));
        Self {
            parameters,
            reference,
        }
    }
}

impl Candidate for Thermal {
    fn name(&self) -> &'static str {
        Self::NAME
    }
    fn mechanism(&self) -> &'static str {
        "a linear temperature field (gradient and uniform offset about the model's centroid), aluminium α = 23e-6 /K"
    }
    fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }
    fn apply(&self, v: &[f64], edit: &mut CaseEdit) -> Result<(), DiagnoseError> {
        let mut effects = edit.effects();
        effects.thermal_gradient = v.iter().any(|&x| x != 0.0).then(|| ThermalSpec {
            gradient: [v[0], v[1], v[2]],
            offset: v[3],
            alpha: ALUMINIUM_ALPHA,
            reference: self.reference,
        });
        edit.set_effects(&effects);
        Ok(())
    }
    /// The offset as the truss warmer or cooler than stated; a gradient as the temperature
    /// difference across the span along its axis.
    fn reading(&self, j: usize, v: f64, span: [f64; 3]) -> String {
        if j == 3 {
            return format!(
                "the whole truss about {:.2} K {} than the stated conditions",
                v.abs(),
                if v >= 0.0 { "warmer" } else { "cooler" }
            );
        }
        format!(
            "about {:.2} K of temperature difference across the {:.0} mm the truss spans along {}",
            (v * span[j]).abs(),
            span[j],
            ["x", "y", "z"][j]
        )
    }
    fn trace(&self) -> Trace {
        Trace::Temperature
    }
}
