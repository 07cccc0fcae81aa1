//! # truss-units: the unit conversions the reports and plots share
//!
//! Every number truss-mc computes, stores and writes to a file is in N, mm, MPa and rad (the
//! units table of `truss-core`). People read a pointing budget in arcseconds, small angles in
//! microradians and displacements in micrometres: the factors between those and the stored
//! units are defined here, once, for every crate that shows them (the merge's table and
//! plots, the tolerance study, the diagnosis). This crate links nothing, so any crate can use
//! it without changing the layering.
//!
//! | from | to | factor |
//! |---|---|---|
//! | rad | arcsec | [`ARCSEC_PER_RAD`] = 648000/π ≈ 206264.8 |
//! | rad | µrad | [`MICRORAD_PER_RAD`] = 10⁶ |
//! | µrad | arcsec | [`ARCSEC_PER_MICRORAD`] = 0.648/π ≈ 0.206265 |
//! | mm | µm | [`MICROMETRE_PER_MM`] = 10³ |
//!
//! A value in the stored unit times the factor is the value in the shown unit:
//! `theta * ARCSEC_PER_RAD` is θ in arcseconds, `arcsec / ARCSEC_PER_RAD` the angle in rad.
//!
//! A pointing target is written one way everywhere ([`TargetAngle`]'s `Display`): the value
//! as the user gave it, in the unit they gave it in, then the other unit, so that the console,
//! the reports and the plots of every tool name the same target, and a target given as
//! `9.69e-5` rad is never shown as if it were 20 arcsec (it is 19.99).

use std::fmt;

/// Arcseconds in a radian: 180·3600/π = 648000/π.
pub const ARCSEC_PER_RAD: f64 = 648_000.0 / std::f64::consts::PI;

/// Microradians in a radian.
pub const MICRORAD_PER_RAD: f64 = 1e6;

/// Arcseconds in a microradian: 0.648/π.
pub const ARCSEC_PER_MICRORAD: f64 = ARCSEC_PER_RAD / MICRORAD_PER_RAD;

/// Micrometres in a millimetre.
pub const MICROMETRE_PER_MM: f64 = 1e3;

/// A target angle as the user set it: in rad or in arcsec.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TargetAngle {
    /// Given in rad (`--target-angle`).
    Rad(f64),
    /// Given in arcsec (`--target-arcsec`).
    Arcsec(f64),
}

impl TargetAngle {
    /// The angle \[rad\].
    pub fn rad(self) -> f64 {
        match self {
            Self::Rad(r) => r,
            Self::Arcsec(a) => a / ARCSEC_PER_RAD,
        }
    }

    /// The angle \[arcsec\].
    pub fn arcsec(self) -> f64 {
        match self {
            Self::Rad(r) => r * ARCSEC_PER_RAD,
            Self::Arcsec(a) => a,
        }
    }
}

impl fmt::Display for TargetAngle {
    /// `9.69e-5 rad (19.99″)` for a target given in rad (its shortest exact form, so as it
    /// was typed), `20″ (9.6963e-5 rad)` for one given in arcsec.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Rad(r) => write!(f, "{r:e} rad ({:.2}″)", r * ARCSEC_PER_RAD),
            Self::Arcsec(a) => write!(f, "{a}″ ({:.4e} rad)", a / ARCSEC_PER_RAD),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A target reads as it was set, with the other unit beside it.
    #[test]
    fn a_target_reads_as_it_was_set() {
        assert_eq!(
            TargetAngle::Rad(9.69e-5).to_string(),
            "9.69e-5 rad (19.99″)"
        );
        assert_eq!(TargetAngle::Arcsec(20.0).to_string(), "20″ (9.6963e-5 rad)");
        assert_eq!(TargetAngle::Arcsec(20.0).arcsec(), 20.0);
        assert_eq!(TargetAngle::Rad(1e-4).rad(), 1e-4);
    }

    /// The factors against independent definitions: a full turn is 360 degrees of 3600
    /// arcseconds, 20 arcseconds is the paper's 9.69e-5 rad.
    #[test]
    fn factors_agree_with_their_definitions() {
        let turn = 2.0 * std::f64::consts::PI * ARCSEC_PER_RAD;
        assert!((turn - 360.0 * 3600.0).abs() < 1e-6, "{turn}");
        assert!((20.0 / ARCSEC_PER_RAD - 9.69e-5).abs() < 1e-7);
        assert_eq!(ARCSEC_PER_RAD, 206_264.806_247_096_36);
        let one = ARCSEC_PER_MICRORAD * MICRORAD_PER_RAD / ARCSEC_PER_RAD;
        assert!((one - 1.0).abs() < 1e-15);
        assert_eq!(0.001 * MICROMETRE_PER_MM, 1.0);
    }
}
