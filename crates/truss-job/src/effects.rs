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
//!
//! ## Plausible values
//!
//! Beyond being finite, each value must be plausible, so that a typo such as `1e308` is
//! refused by name rather than failing every sample: `0 ≤ g ≤` [`MAX_GRAVITY`],
//! `0 ≤ density ≤` [`MAX_DENSITY`], `|α| ≤` [`MAX_ALPHA`], `|offset| ≤` [`MAX_TEMPERATURE_CHANGE`],
//! each gradient component at most [`MAX_GRADIENT`], each `direction` and `reference`
//! component at most [`truss_core::model::MAX_COORDINATE`]. The job also refuses a thermal
//! strain `α·ΔT` beyond [`truss_core::MAX_LENGTH_ERROR_FRACTION`] in any member.

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

/// Largest gravity, 1000 m/s² (about 100 g₀, beyond any ground test) \[m/s²\].
pub const MAX_GRAVITY: f64 = 1000.0;
/// Largest density, 10⁻⁴ kg/mm³ (100,000 kg/m³, four times osmium's) \[kg/mm³\].
pub const MAX_DENSITY: f64 = 1e-4;
/// Largest |α|, 10⁻³ /K (five times that of the most expansive plastics) \[1/K\].
pub const MAX_ALPHA: f64 = 1e-3;
/// Largest |temperature change| at the reference point, 1000 K \[K\].
pub const MAX_TEMPERATURE_CHANGE: f64 = 1000.0;
/// Largest |temperature gradient| component, 10 K/mm \[K/mm\].
pub const MAX_GRADIENT: f64 = 10.0;

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
    /// Checks the parameters (finite, and within the plausible bounds of the module doc);
    /// the error names the field (relative to `effects`).
    pub fn check(&self) -> Result<(), (String, String)> {
        use truss_core::model::MAX_COORDINATE;
        let bounded = |field: &str, v: &[f64], max: f64, unit: &str| match v
            .iter()
            .find(|x| !x.is_finite() || x.abs() > max)
        {
            None => Ok(()),
            Some(x) if !x.is_finite() => Err((field.to_string(), "must be finite numbers".into())),
            Some(x) => Err((
                field.to_string(),
                format!(
                    "{} is beyond the plausible ±{max:e} {unit}",
                    truss_core::readable(*x)
                ),
            )),
        };
        if let Some(g) = &self.gravity {
            bounded("gravity.direction", &g.direction, MAX_COORDINATE, "")?;
            bounded("gravity.g", &[g.g], MAX_GRAVITY, "m/s²")?;
            bounded("gravity.density", &[g.density], MAX_DENSITY, "kg/mm³")?;
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
            bounded(
                "thermal_gradient.gradient",
                &t.gradient,
                MAX_GRADIENT,
                "K/mm",
            )?;
            bounded(
                "thermal_gradient.offset",
                &[t.offset],
                MAX_TEMPERATURE_CHANGE,
                "K",
            )?;
            bounded("thermal_gradient.alpha", &[t.alpha], MAX_ALPHA, "/K")?;
            bounded(
                "thermal_gradient.reference",
                &t.reference,
                MAX_COORDINATE,
                "mm",
            )?;
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

    /// Each value beyond its plausible bound, or not finite, is refused by its field.
    #[test]
    fn implausible_values_are_refused_by_field() {
        let gravity = |g: f64, density: f64| EffectsSpec {
            gravity: Some(GravitySpec {
                direction: [0.0, 0.0, -1.0],
                g,
                density,
            }),
            thermal_gradient: None,
        };
        assert!(gravity(STANDARD_GRAVITY, ALUMINIUM_DENSITY).check().is_ok());
        assert_eq!(
            gravity(1e308, ALUMINIUM_DENSITY).check().unwrap_err().0,
            "gravity.g"
        );
        assert_eq!(gravity(f64::NAN, 0.0).check().unwrap_err().0, "gravity.g");
        assert_eq!(
            gravity(9.8, 1e308).check().unwrap_err().0,
            "gravity.density"
        );
        let thermal = |offset: f64, alpha: f64| EffectsSpec {
            gravity: None,
            thermal_gradient: Some(ThermalSpec {
                gradient: [0.0, 0.0, 0.002],
                offset,
                alpha,
                reference: [0.0; 3],
            }),
        };
        assert!(thermal(0.5, ALUMINIUM_ALPHA).check().is_ok());
        let e = thermal(1e308, ALUMINIUM_ALPHA).check().unwrap_err();
        assert_eq!(e.0, "thermal_gradient.offset");
        assert!(e.1.contains("1e308"), "{}", e.1);
        assert_eq!(
            thermal(0.5, 1.0).check().unwrap_err().0,
            "thermal_gradient.alpha"
        );
    }

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
