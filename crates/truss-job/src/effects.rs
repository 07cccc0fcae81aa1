//! Deterministic physical effects a case can add to its model: the ground test's self-weight
//! and a linear temperature field. Both are the same for every sample of the case.
//!
//! ## `gravity`
//!
//! ```json
//! "effects": {"gravity": {"direction": [0, 0, -1], "g": 9.80665, "density": 2.7e-6}}
//! ```
//!
//! Each member's weight `W = ρ·A·L·g` \[N\] (ρ in kg/mm³, A in mm², L its nominal length in mm,
//! g in m/s²: kg·m/s² = N) is lumped half to each of its two nodes, along `direction`
//! (normalised; it need not be vertical, since the truss may be tested on its side). Defaults:
//! aluminium, ρ = 2700 kg/m³ = 2.7e-6 kg/mm³; standard gravity g = 9.80665 m/s².
//!
//! ## `thermal_gradient`
//!
//! ```json
//! "effects": {"thermal_gradient": {"gradient": [0, 0, 0.002], "offset": 0.5, "alpha": 23e-6}}
//! ```
//!
//! A temperature change `ΔT(x) = offset + gradient·(x − reference)` \[K\] (gradient in K/mm,
//! `reference` a point in mm, default the origin) lengthens each member by
//! `α·ΔT(x_mid)·L` \[mm\], its midpoint's temperature times its nominal length, added to its
//! length error. Default α = 23e-6 /K (aluminium).

use serde::{Deserialize, Serialize};
use truss_core::Model;

/// Standard gravity \[m/s²\].
pub const STANDARD_GRAVITY: f64 = 9.80665;
/// Density of aluminium \[kg/mm³\] (2700 kg/m³).
pub const ALUMINIUM_DENSITY: f64 = 2.7e-6;
/// Thermal expansion coefficient of aluminium \[1/K\].
pub const ALUMINIUM_ALPHA: f64 = 23e-6;

/// The effects of a case, as a job writes them.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectsSpec {
    /// Self-weight.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<GravitySpec>,
    /// A linear temperature field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal_gradient: Option<ThermalSpec>,
}

/// Self-weight (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GravitySpec {
    /// Direction of gravity in the model's frame (normalised).
    pub direction: [f64; 3],
    /// Acceleration \[m/s²\].
    #[serde(default = "standard_gravity")]
    pub g: f64,
    /// Density \[kg/mm³\].
    #[serde(default = "aluminium_density")]
    pub density: f64,
}

/// A linear temperature field (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalSpec {
    /// Temperature gradient \[K/mm\].
    pub gradient: [f64; 3],
    /// Temperature change at `reference` \[K\].
    #[serde(default)]
    pub offset: f64,
    /// Expansion coefficient \[1/K\].
    #[serde(default = "aluminium_alpha")]
    pub alpha: f64,
    /// Where the change is `offset` \[mm\].
    #[serde(default)]
    pub reference: [f64; 3],
}

fn standard_gravity() -> f64 {
    STANDARD_GRAVITY
}
fn aluminium_density() -> f64 {
    ALUMINIUM_DENSITY
}
fn aluminium_alpha() -> f64 {
    ALUMINIUM_ALPHA
}

/// What the effects do to a model: extra nodal loads \[N\] (per node; empty for none) and
/// extra length errors \[mm\] (per member; empty for none).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Applied {
    /// Extra force on each node \[N\].
    pub loads: Vec<[f64; 3]>,
    /// Extra length error of each member \[mm\].
    pub length_changes: Vec<f64>,
}

impl EffectsSpec {
    /// Checks the parameters; the error names the field (relative to `effects`).
    pub fn check(&self) -> Result<(), (String, String)> {
        let finite = |field: &str, v: &[f64]| {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err((field.to_string(), "must be finite numbers".to_string()))
            }
        };
        if let Some(g) = &self.gravity {
            finite("gravity.direction", &g.direction)?;
            finite("gravity.g", &[g.g])?;
            finite("gravity.density", &[g.density])?;
            if g.direction == [0.0; 3] {
                return Err(("gravity.direction".into(), "must not be zero".into()));
            }
            if g.g < 0.0 || g.density < 0.0 {
                return Err((
                    "gravity".into(),
                    "g and density must not be negative".into(),
                ));
            }
        }
        if let Some(t) = &self.thermal_gradient {
            finite("thermal_gradient.gradient", &t.gradient)?;
            finite("thermal_gradient.offset", &[t.offset])?;
            finite("thermal_gradient.alpha", &[t.alpha])?;
            finite("thermal_gradient.reference", &t.reference)?;
        }
        Ok(())
    }

    /// Whether any effect is given.
    pub fn is_empty(&self) -> bool {
        self.gravity.is_none() && self.thermal_gradient.is_none()
    }

    /// The loads and length changes on `model` (see the module doc).
    pub fn apply(&self, model: &Model) -> Applied {
        let mut applied = Applied::default();
        if let Some(g) = &self.gravity {
            let norm = g.direction.iter().map(|x| x * x).sum::<f64>().sqrt();
            let dir = g.direction.map(|x| x / norm);
            let mut loads = vec![[0.0; 3]; model.nodes().len()];
            for (m, member) in model.members().iter().enumerate() {
                let weight = g.density * member.area * model.nominal_length(m) * g.g;
                for &node in &member.nodes {
                    for k in 0..3 {
                        loads[node][k] += 0.5 * weight * dir[k];
                    }
                }
            }
            applied.loads = loads;
        }
        if let Some(t) = &self.thermal_gradient {
            applied.length_changes = model
                .members()
                .iter()
                .enumerate()
                .map(|(m, member)| {
                    let [a, b] = member.nodes.map(|n| model.nodes()[n].xyz);
                    let mid = [0, 1, 2].map(|k| 0.5 * (a[k] + b[k]) - t.reference[k]);
                    let dt = t.offset + (0..3).map(|k| t.gradient[k] * mid[k]).sum::<f64>();
                    t.alpha * dt * model.nominal_length(m)
                })
                .collect();
        }
        applied
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use truss_core::prism::PrismOptions;

    /// Total weight = ρ·g·Σ A·L, all of it along the direction; each batten of 380 mm and
    /// 14.9 mm² weighs 2.7e-6 · 14.9 · 380 · 9.80665 = 0.149918 N.
    #[test]
    fn gravity_lumps_each_members_weight_half_to_each_end() {
        let model = PrismOptions::with_stages(2).model().unwrap();
        let fx = EffectsSpec {
            gravity: Some(GravitySpec {
                direction: [0.0, 0.0, -2.0],
                g: STANDARD_GRAVITY,
                density: ALUMINIUM_DENSITY,
            }),
            thermal_gradient: None,
        }
        .apply(&model);
        let total: f64 = fx.loads.iter().map(|f| f[2]).sum();
        let expected: f64 = model
            .members()
            .iter()
            .enumerate()
            .map(|(m, mem)| {
                ALUMINIUM_DENSITY * mem.area * model.nominal_length(m) * STANDARD_GRAVITY
            })
            .sum();
        assert!((total + expected).abs() < 1e-12 * expected);
        assert!(fx.loads.iter().all(|f| f[0] == 0.0 && f[1] == 0.0));
        let batten: f64 = 2.7e-6 * 14.9 * 380.0 * 9.80665;
        assert!((batten - 0.149918).abs() < 1e-6);
    }

    /// A uniform change ΔT lengthens every member by α·ΔT·L; a gradient along z by
    /// α·(dT/dz)·z_mid·L.
    #[test]
    fn thermal_field_lengthens_members_by_their_midpoint_temperature() {
        let model = PrismOptions::with_stages(2).model().unwrap();
        let fx = EffectsSpec {
            gravity: None,
            thermal_gradient: Some(ThermalSpec {
                gradient: [0.0, 0.0, 0.01],
                offset: 2.0,
                alpha: 1e-5,
                reference: [0.0; 3],
            }),
        }
        .apply(&model);
        let m = model.member_index("longeron.2.1").unwrap();
        let expected = 1e-5 * (2.0 + 0.01 * 570.0) * 380.0;
        assert!((fx.length_changes[m] - expected).abs() < 1e-15);
    }
}
