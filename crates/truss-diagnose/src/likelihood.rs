//! The likelihood and the fits: how well a case explains the measurements, and the values
//! of a candidate's parameters that explain them best.
//!
//! - [`gaussian`]: the Gaussian synthetic likelihood of the specimens' displacement vectors,
//!   and the member term;
//! - [`conditional`]: each specimen's node term conditioned on its own measured members;
//! - [`derivatives`]: finite-difference gradient, curvature and score variability;
//! - [`fit`]: the trust-region Newton maximisation and the sandwich Wald intervals;
//! - [`profile`]: profile-likelihood intervals;
//! - [`score`]: one candidate against the current model: its fit, likelihood-ratio test,
//!   BIC and intervals;
//! - [`joint`]: several effects fitted as one (the joint re-fit of a model's effects).
//! - [`power`]: the power of a candidate's test and its detection limits.

pub mod conditional;
pub mod derivatives;
pub mod fit;
pub mod gaussian;
pub mod joint;
pub mod power;
pub mod profile;
pub mod score;
