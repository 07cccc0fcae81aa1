//! After the selection: the final model's effects with the intervals of their joint fit, and
//! the rivals that explain part of the same signal.
//!
//! ## The final fit
//!
//! The numbers read last are those of the final model's effects fitted jointly (the last
//! kept step's re-fit; for a model of one effect, its own step's fit with its profile
//! intervals). The joint fit's intervals are the sandwich Wald ones; where a Wald interval
//! is cut at the plausible range (a quadratic ℓ would reach beyond it, so the interval
//! says little of where ℓ itself falls), the profile-likelihood interval of that parameter
//! in the joint fit replaces it ([`crate::likelihood::profile`]). A parameter whose interval
//! covers most of its plausible range is *not determined* by the data
//! ([`crate::likelihood::score::UNDETERMINED`]).
//!
//! ## Confounding
//!
//! A named effect's extra parameters can take up a rival's signal: a temperature field's
//! uniform offset and vertical gradient lengthen the columns much as a longeron length bias
//! does, and a temperature field named alone then reports a wrong field while nothing says
//! a length bias explains part of the same signal. So each rival R (a candidate significant
//! at a kept step, not in the final model nor removed from it; at most [`MAX_RIVALS`], the
//! strongest first) is added to the final model, all effects fitted jointly from their
//! final values and R's own fit at the step where it was strongest (R's explanation of the
//! signal: where the two share it, the joint fit moves the model's parameters off the part
//! R explains; a fit that ends below the model's ℓ̂ (by more than [`WORSE_BY`]), which a
//! maximum cannot since the model is R at its null, is started again from R's null, and R
//! is not judged where that one too ends below), and
//!
//! - R's contribution is tested as an effect given the others: Λ_R = 2(ℓ̂_{M+R} − ℓ̂_M)/(c·λ_R),
//!   p = P(χ²_{k_R} ≥ Λ_R), ΔBIC_R = λ_R·(k_R ln n − Λ_R) (as backward elimination does);
//! - each parameter θ of the model's effects is compared with and without R: θ is
//!   *confounded with R* when its value with R lies outside its final 95 % interval (R
//!   takes over part of what it explained), or when its Wald interval widens by a factor of
//!   at least [`WIDENED`] on the fit's own scale (R could take over part of it: the data
//!   cannot say how the signal divides between the two; judged only where both Wald
//!   intervals were found).
//!
//! An effect lists R as indistinguishable from it for that part, with the confounded
//! parameters, R's test and the measurement that separates them
//! ([`crate::candidates::separating_measurement`]), when R moves one of its parameters out
//! of its interval, or when R is significant given the model (p < α/2, the level at which
//! backward elimination keeps an effect) and widens one; and never when the joint fit with
//! R ends below the model's ℓ̂ (by more than [`WORSE_BY`]): the model is R at its null, so
//! such a fit is not the maximum with R but a point short of it, and its moved values are
//! a reading the data like less than the model's, not a second explanation (gravity was
//! once listed as confounded with backlash by a re-fit that found backlash near 0 and ℓ̂
//! slightly below the model's). The fit from R's own values is therefore started again
//! from R's null wherever it ends below ℓ̂_M, not only beyond [`NESTED_SLACK`]; a fit
//! started from the model's own maximum cannot end below it. A widening alone, by
//! a rival the data do not call for, is not listed: a rival with free parameters of its own
//! widens every interval it shares a direction with, however little of the signal it
//! explains (a temperature field of four parameters, far from significant, widened a
//! backlash model's diagonal scatter and pretension four-fold on data with no temperature
//! change). A parameter the final fit leaves *not determined* is never confounded: it has
//! no reading for a rival to take over, and its interval, half its range or more, is
//! mostly where the data leave it free, not what it explained (gravity's axial g_z, free
//! since gravity has no \|g\| ≤ 1, moved from −0.04 to −0.83 g in its [−0.69, 0.60] with a
//! temperature field whose offset lengthens the columns as an axial self-weight shortens
//! them, on data with self-weight along x alone, and gravity was listed as confounded with
//! the field, p = 0.65). A rival with no confounded parameter is not listed, whatever its test: either
//! it explains nothing the model does not (a rival the model already excludes), or what it
//! adds is separate from the model's effects, and the selection's own steps judge it.
//!
//! ## The ridge probe
//!
//! Where R and an effect explain the same signal equally well, ℓ has a flat ridge: the
//! joint maximum with R added may sit anywhere along it, and often at R's null, where it
//! moves nothing (a 2 K temperature offset with every batten 3 µm long was explained by an
//! offset and a vertical gradient, and a batten bias added to that fit stayed at 0, though
//! ℓ at the truth is only a few units below). So where R is not significant and moves nothing,
//! the joint fit's curvature is asked where the ridge would be. Moving R by r with the
//! model's parameters following it (their maximum given R) moves them by −X·r,
//! X = A_MM⁻¹·A_MR, and costs ½·rᵀSr in ℓ, S = A_RR − A_RM·X (R's curvature given the
//! model; taken as |S|, floored, since a flat or negative curvature is what is looked
//! for). Parameter j moves most cheaply along r ∝ S⁻¹xⱼ (xⱼ row j of X), and its Wald
//! interval would widen √(1 + 1.96²·xⱼᵀS⁻¹xⱼ/hⱼ²)-fold (hⱼ its interval's half-width).
//! For each parameter predicted to widen by [`WIDENED`] or more (at most [`RIDGE_PROBES`],
//! the widest first), the fit is moved along that direction until the parameter lies
//! [`RIDGE_BEYOND`] of the way past its interval's end, and all effects are fitted jointly
//! again from there. A fit that ends within [`NESTED_SLACK`] of ℓ̂_M with a parameter
//! still outside its interval shows, on ℓ itself and not on its quadratic model, that R
//! can take over part of what the effect explains (with R held at its null, such a point
//! would lie more than 1.92 units of ℓ below the maximum: outside the profile interval).
//! The rival is then listed with the parameters this fit moved (`along_ridge`). The Wald
//! prediction alone lists nothing: where ℓ does not bear it out, the fit climbs back
//! inside the interval and the rival is not listed.

use crate::candidates::candidate::{Candidate, separating_measurement};
use crate::candidates::parameter::Parameter;
use crate::errors::DiagnoseError;
use crate::likelihood::fit::{Interval, adjustments};
use crate::likelihood::joint::{Combined, JointFit};
use crate::likelihood::profile::{Problem, Profile, profile_some};
use crate::likelihood::score::{FittedParameter, p_text, projection};
use crate::selection::model::{Context, RefitEffect};
use crate::selection::ridge::ridges;
use crate::selection::step::Step;
use crate::selection::update::fit_jointly;
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Most rivals tried against the final model.
pub const MAX_RIVALS: usize = 3;

/// The factor by which a parameter's Wald interval must widen, with a rival added, for the
/// parameter to be confounded with it (a variance inflation of 4).
pub const WIDENED: f64 = 2.0;

/// How far below the final model's ℓ̂ a ridge probe's fit may end and still count as "as
/// good as the model" (module doc, the ridge probe): a point on a flat ridge the rival
/// opens, not a maximum, which the probe asks only of a joint fit that is not worse than
/// the model ([`WORSE_BY`]).
pub const NESTED_SLACK: f64 = 1.0;

/// How far below the final model's ℓ̂ the joint fit with a rival may end and still be
/// judged (module doc): a hundredth of a unit of ℓ (Λ = 0.02), room for rounding in a fit
/// that started at the model's maximum, far below any difference the tests could see.
pub const WORSE_BY: f64 = 0.01;

/// How far past its interval's end the ridge probe moves a widened parameter, in units of
/// the distance from its value to that end.
pub const RIDGE_BEYOND: f64 = 0.5;

/// Most ridge probes per rival.
pub const RIDGE_PROBES: usize = 3;

/// The final model's effects fitted jointly.
pub struct FinalFit {
    /// Each effect with its parameters and their intervals (module doc).
    pub effects: Vec<RefitEffect>,
    /// ℓ̂ of the fit; `None` where the effects were not fitted jointly (the joint re-fit
    /// failed), and rivals are then not tried.
    pub log_likelihood: Option<f64>,
}

/// A parameter confounded with a rival.
#[derive(Debug, Clone, Serialize)]
pub struct ConfoundedParameter {
    /// The parameter.
    pub name: String,
    /// Its unit.
    pub unit: &'static str,
    /// Its final value.
    pub value: f64,
    /// Its value with the rival added.
    pub with_rival: f64,
    /// Its final 95 % interval.
    pub interval: Interval,
    /// Whether the value with the rival lies outside that interval.
    pub moved: bool,
    /// The width of its Wald interval with the rival over the width without (on the fit's
    /// scale; 1 where either was not found).
    pub widening: f64,
}

/// A rival that explains part of what an effect of the final model explains.
#[derive(Debug, Clone, Serialize)]
pub struct Confounding {
    /// The model's effect.
    pub effect: String,
    /// The rival candidate.
    pub rival: String,
    /// The effect's parameters confounded with it.
    pub parameters: Vec<ConfoundedParameter>,
    /// Λ_R of the rival given the model's effects, fitted jointly.
    pub lr_statistic: f64,
    /// P(χ²_{k_R} ≥ Λ_R).
    pub p_value: f64,
    /// ΔBIC_R (negative: the model with the rival is better).
    pub delta_bic: f64,
    /// The measurement that would separate the two.
    pub separate_by: String,
    /// Whether the moves were found by the ridge probe (module doc): the joint fit's
    /// maximum did not move them, but a fit from along the flat direction the rival opens
    /// ended as good as the model with them outside their intervals (`with_rival` is that
    /// fit's value).
    pub along_ridge: bool,
}

/// The final model's effects fitted jointly: `last` the final model's step (the last kept
/// one), `steps` every step up to it; `library` the candidates.
pub(crate) fn final_fit(
    ctx: &Context,
    steps: &[Step],
    last: &Step,
    library: &[Box<dyn Candidate>],
) -> FinalFit {
    if let (Some(joint), false) = (&last.joint, last.refitted.is_empty()) {
        let mut effects = last.refitted.clone();
        let parts: Vec<&dyn Candidate> = last
            .refitted
            .iter()
            .map(|e| effect(library, &e.name))
            .collect();
        profile_cut(ctx, &parts, joint, &mut effects);
        return FinalFit {
            effects,
            log_likelihood: Some(joint.log_likelihood),
        };
    }
    // One effect, fitted at its own step; or the joint re-fit failed, and each effect's
    // own step's fit is all there is.
    let effects: Vec<RefitEffect> = last
        .effects
        .iter()
        .filter_map(|e| {
            let score = steps
                .iter()
                .filter(|s| s.kept)
                .find_map(|s| s.named_score().filter(|c| c.name == e.name))?;
            Some(RefitEffect {
                name: e.name.clone(),
                parameters: score.parameters.clone(),
            })
        })
        .collect();
    let single = (last.effects.len() == 1 && effects.len() == 1)
        .then(|| {
            steps
                .iter()
                .find_map(|s| s.named_score().filter(|c| c.name == effects[0].name))
        })
        .flatten();
    FinalFit {
        effects,
        log_likelihood: single.map(|c| c.log_likelihood),
    }
}

/// The library's candidate of this name: the model's effects and their rivals are all there.
fn effect<'a>(library: &'a [Box<dyn Candidate>], name: &str) -> &'a dyn Candidate {
    library
        .iter()
        .find(|c| c.name() == name)
        .map(|c| c.as_ref())
        .expect("the model's effects and their rivals are in the library")
}

/// Profile-likelihood intervals, in the joint fit, of the parameters whose Wald interval is
/// cut at the plausible range; where a profile fails or finds a higher point, the Wald
/// interval stays (with a note).
fn profile_cut(
    ctx: &Context,
    parts: &[&dyn Candidate],
    joint: &JointFit,
    effects: &mut [RefitEffect],
) {
    let cut: Vec<usize> = effects
        .iter()
        .flat_map(|e| &e.parameters)
        .enumerate()
        .filter(|(_, p)| p.wald_interval.at_range_end())
        .map(|(j, _)| j)
        .collect();
    if cut.is_empty() {
        return;
    }
    let combined = Combined::new(parts.to_vec());
    let params = combined.parameters().to_vec();
    ctx.progress.note(&format!(
        "final fit: profile intervals of {} (Wald cut at the range)…",
        cut.iter()
            .map(|&j| params[j].name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    let ev = ctx.evaluator(&ctx.baseline.derived_case());
    let project = projection(&combined);
    let mut objective = |t: &[f64]| {
        let v: Vec<f64> = params.iter().zip(t).map(|(p, &x)| p.value(x)).collect();
        ev.terms_at(&combined, &v)
    };
    let problem = Problem {
        parameters: &params,
        project: &project,
        inflation: ctx.inflation(),
    };
    let outcome = profile_some(&joint.fit, &problem, &mut objective, false, &cut);
    ctx.count(&ev);
    match outcome {
        Ok(Profile::Intervals(iv)) => {
            let mut flat: Vec<&mut FittedParameter> =
                effects.iter_mut().flat_map(|e| &mut e.parameters).collect();
            for (&j, interval) in cut.iter().zip(iv.marginal) {
                flat[j].set_interval(&params[j], interval);
            }
        }
        Ok(Profile::Higher(..)) => ctx
            .progress
            .note("  the profile found a higher point than the joint fit; Wald intervals kept"),
        Err(e) => ctx
            .progress
            .note(&format!("  profile failed ({e}); Wald intervals kept")),
    }
}

/// The rivals to try against the final model (module doc): candidates significant at a
/// kept step among `steps`, not in the final model nor removed from it, strongest (lowest
/// ΔBIC at their step) first, at most [`MAX_RIVALS`]; each with its fitted values at the
/// step where it was strongest.
fn rivals(steps: &[Step], model: &[RefitEffect]) -> Vec<(String, Vec<f64>)> {
    let gone: Vec<&str> = steps
        .iter()
        .filter(|s| s.kept)
        .flat_map(|s| s.removed.iter().map(|r| r.name.as_str()))
        .collect();
    let mut found: Vec<(String, f64, Vec<f64>)> = Vec::new();
    for c in steps
        .iter()
        .filter(|s| s.kept)
        .flat_map(|s| &s.candidates)
        .filter(|c| c.significant && c.error.is_none())
    {
        if model.iter().any(|e| e.name == c.name) || gone.contains(&c.name.as_str()) {
            continue;
        }
        let values = c.parameters.iter().map(|p| p.value).collect();
        match found.iter_mut().find(|(n, ..)| *n == c.name) {
            Some(f) if c.delta_bic < f.1 => *f = (c.name.clone(), c.delta_bic, values),
            Some(_) => {}
            None => found.push((c.name.clone(), c.delta_bic, values)),
        }
    }
    found.sort_by(|a, b| a.1.total_cmp(&b.1));
    found
        .into_iter()
        .take(MAX_RIVALS)
        .map(|(name, _, values)| (name, values))
        .collect()
}

/// The rivals confounded with the final model's effects (module doc); `steps` up to the
/// final model's, `library` the candidates.
pub(crate) fn confounding(
    ctx: &Context,
    steps: &[Step],
    fit: &FinalFit,
    library: &[Box<dyn Candidate>],
) -> Vec<Confounding> {
    let Some(l_model) = fit.log_likelihood else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (name, start) in rivals(steps, &fit.effects) {
        let rival = effect(library, &name);
        ctx.progress.note(&format!(
            "confounding: {name} added to the final model, all fitted jointly…"
        ));
        match with_rival(ctx, fit, l_model, (rival, &start), library) {
            Ok(found) => {
                for c in &found {
                    ctx.progress.note(&format!(
                        "  {} confounded with {name} ({}; {name} given the model: Λ {:.1}, p {}, ΔBIC {:.1})",
                        c.effect,
                        c.parameters
                            .iter()
                            .map(|p| p.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", "),
                        c.lr_statistic,
                        p_text(c.p_value),
                        c.delta_bic
                    ));
                }
                out.extend(found);
            }
            Err(e) => ctx.progress.note(&format!("  failed ({e})")),
        }
    }
    out
}

/// The model's effects fitted jointly with `rival` (from the final values and the rival's
/// own fit, `start`), and what it confounds.
fn with_rival<'a>(
    ctx: &Context,
    fit: &FinalFit,
    l_model: f64,
    (rival, start): (&'a dyn Candidate, &[f64]),
    library: &'a [Box<dyn Candidate>],
) -> Result<Vec<Confounding>, DiagnoseError> {
    let values: Vec<Vec<f64>> = fit
        .effects
        .iter()
        .map(|e| e.parameters.iter().map(|p| p.value).collect())
        .collect();
    let mut members: Vec<(&dyn Candidate, &[f64])> = fit
        .effects
        .iter()
        .zip(&values)
        .map(|(e, v)| (effect(library, &e.name), v.as_slice()))
        .collect();
    members.push((rival, start));
    let nulls: Vec<f64> = rival.parameters().iter().map(|q| q.null).collect();
    // The model with the rival at its null is the model itself: a joint fit that ends below
    // the model's ℓ̂ stopped short of the maximum, and its values say nothing.
    let as_good = |j: &JointFit| !worse(j.log_likelihood, l_model);
    let joint = match fit_jointly(ctx, &members, None) {
        Ok(j) if as_good(&j) => j,
        first => {
            ctx.progress.note(&format!(
                "  the fit from {}'s own values ended below the model ({}); again from its null",
                rival.name(),
                first.map_or_else(|e| e.to_string(), |j| format!("ℓ̂ {:.1}", j.log_likelihood))
            ));
            *members.last_mut().expect("the rival is there") = (rival, &nulls);
            let j = fit_jointly(ctx, &members, None)?;
            if !as_good(&j) {
                ctx.progress.note(&format!(
                    "  ended below the model again (ℓ̂ {:.1}): {} not judged",
                    j.log_likelihood,
                    rival.name()
                ));
                return Ok(Vec::new());
            }
            j
        }
    };
    let (lr, p, delta_bic) = contribution(ctx, &joint, l_model, rival.parameters().len());
    ctx.progress.note(&format!(
        "  ℓ̂ {:.1} (the model's {l_model:.1}); {}",
        joint.log_likelihood,
        fit.effects
            .iter()
            .zip(&joint.parameters)
            .flat_map(|(now, with)| now.parameters.iter().zip(with))
            .map(|(a, b)| format!("{} {:.4e} → {:.4e}", a.name, a.value, b.value))
            .chain(
                joint
                    .parameters
                    .last()
                    .into_iter()
                    .flatten()
                    .map(|r| format!("{} {:.4e}", r.name, r.value))
            )
            .collect::<Vec<_>>()
            .join(", ")
    ));
    let significant = p < ctx.settings.candidate_level();
    let mut judged = judge(fit, &joint, &members);
    let mut along_ridge = false;
    if !significant && !judged.iter().flatten().any(|p| p.moved) {
        // Nothing moved, and the rival is not called for: does ℓ itself hold a ridge the
        // two share?
        if let Some(moved) = ridge_probe(ctx, fit, &joint, &members, l_model) {
            judged = moved;
            along_ridge = true;
        }
    }
    let mut out = Vec::new();
    let gain = joint.log_likelihood - l_model;
    for (e, parameters) in judged.into_iter().enumerate() {
        if !listed(&parameters, significant, gain) {
            continue;
        }
        out.push(Confounding {
            effect: fit.effects[e].name.clone(),
            rival: rival.name().into(),
            parameters,
            lr_statistic: lr,
            p_value: p,
            delta_bic,
            separate_by: separating_measurement(members[e].0, rival).into(),
            along_ridge,
        });
    }
    Ok(out)
}

/// Each model effect's parameters confounded with the rival of `joint` (the model's
/// effects and the rival fitted jointly; `members` the model's effects, then the rival).
fn judge(
    fit: &FinalFit,
    joint: &JointFit,
    members: &[(&dyn Candidate, &[f64])],
) -> Vec<Vec<ConfoundedParameter>> {
    fit.effects
        .iter()
        .zip(&joint.parameters)
        .zip(members)
        .map(|((now, with), (c, _))| {
            now.parameters
                .iter()
                .zip(with)
                .zip(c.parameters())
                .filter_map(|((a, b), q)| confounded(q, a, b))
                .collect()
        })
        .collect()
}

/// The ridge probe (module doc): where the rival `joint` fitted with the model's effects
/// widened one of their Wald intervals by [`WIDENED`] or more, or left it undetermined (`A`
/// not positive definite: a flat direction), each parameter predicted to widen by
/// [`WIDENED`] or more ([`ridges`]; at most [`RIDGE_PROBES`], the widest first) is moved
/// [`RIDGE_BEYOND`] of the way past its interval's end along its ridge, and the effects are
/// fitted jointly again from there. The confounded parameters ([`judge`]) of the first such
/// fit that ends as good as the model with a parameter outside its interval; `None` where
/// none does.
fn ridge_probe(
    ctx: &Context,
    fit: &FinalFit,
    joint: &JointFit,
    members: &[(&dyn Candidate, &[f64])],
    l_model: f64,
) -> Option<Vec<Vec<ConfoundedParameter>>> {
    let found = |w: &Interval| w.lower.is_some() && w.upper.is_some();
    let opened = fit
        .effects
        .iter()
        .zip(&joint.parameters)
        .zip(members)
        .flat_map(|((now, with), (c, _))| now.parameters.iter().zip(with).zip(c.parameters()))
        .any(|((a, b), q)| {
            let width = |w: &Interval| {
                q.internal(w.upper.unwrap_or(0.0)) - q.internal(w.lower.unwrap_or(0.0))
            };
            found(&a.wald_interval)
                && (!found(&b.wald_interval)
                    || width(&b.wald_interval) >= WIDENED * width(&a.wald_interval))
        });
    if !opened {
        return None;
    }
    // Each parameter's interval half-width, internal coordinates, and the effect it is of.
    let mut half = Vec::new();
    let mut owner = Vec::new();
    for (e, (now, (c, _))) in fit.effects.iter().zip(members).enumerate() {
        for (i, (p, q)) in now.parameters.iter().zip(c.parameters()).enumerate() {
            half.push(match (p.interval.lower, p.interval.upper) {
                (Some(lo), Some(hi)) => Some(0.5 * (q.internal(hi) - q.internal(lo))),
                _ => None,
            });
            owner.push((e, i));
        }
    }
    let k_r = members.last()?.0.parameters().len();
    let found = ridges(&joint.fit.curvature, k_r, &half)?;
    let combined = Combined::new(members.iter().map(|m| m.0).collect());
    let params = combined.parameters();
    for ridge in found
        .into_iter()
        .filter(|r| r.widening >= WIDENED)
        .take(RIDGE_PROBES)
    {
        let (j, widening, per_unit) = (ridge.parameter, ridge.widening, ridge.per_unit);
        let (e, i) = owner[j];
        let p = &fit.effects[e].parameters[i];
        let q = &members[e].0.parameters()[i];
        let value = q.internal(p.value);
        let Some(target) = [
            (p.interval.upper, p.interval.upper_at_range_end),
            (p.interval.lower, p.interval.lower_at_range_end),
        ]
        .into_iter()
        .filter_map(|(end, cut)| end.filter(|_| !cut))
        .map(|end| {
            let end = q.internal(end);
            end + RIDGE_BEYOND * (end - value)
        })
        .find(|t| (0.0..=1.0).contains(t)) else {
            continue;
        };
        if per_unit == 0.0 {
            continue;
        }
        let scale = (target - joint.fit.internal[j]) / per_unit;
        let mut t: Vec<f64> = (0..params.len())
            .map(|k| (joint.fit.internal[k] + scale * ridge.direction[k]).clamp(0.0, 1.0))
            .collect();
        projection(&combined)(&mut t, Some(j));
        let values: Vec<f64> = params.iter().zip(&t).map(|(p, &x)| p.value(x)).collect();
        let parts = combined.split(&values);
        let start: Vec<(&dyn Candidate, &[f64])> = members
            .iter()
            .zip(&parts)
            .map(|(&(c, _), v)| (c, v.as_slice()))
            .collect();
        ctx.progress.note(&format!(
            "  {}'s interval would widen {widening:.1}-fold with {}: fitting again from {} = {:.4e}",
            p.name,
            members.last().expect("the rival is there").0.name(),
            p.name,
            q.value(t[j])
        ));
        match fit_jointly(ctx, &start, Some(&joint.fit.steps)) {
            Ok(probe) if probe.log_likelihood >= l_model - NESTED_SLACK => {
                ctx.progress.note(&format!(
                    "  ℓ̂ {:.1} (the model's {l_model:.1}); {} {:.4e}",
                    probe.log_likelihood, p.name, probe.parameters[e][i].value
                ));
                let judged = judge(fit, &probe, members);
                if judged.iter().flatten().any(|c| c.moved) {
                    return Some(judged);
                }
            }
            Ok(probe) => ctx.progress.note(&format!(
                "  ended below the model (ℓ̂ {:.1}): no ridge",
                probe.log_likelihood
            )),
            Err(err) => ctx.progress.note(&format!("  failed ({err})")),
        }
    }
    None
}

/// The rival's test given the model's effects (module doc): Λ_R, p, ΔBIC_R; the rival's
/// parameters are the last `k` of the joint fit.
fn contribution(ctx: &Context, joint: &JointFit, l_model: f64, k: usize) -> (f64, f64, f64) {
    let n = ctx.measured.n() as f64;
    let total = joint.fit.internal.len();
    let lambda = adjustments(&joint.fit)
        .map_or(1.0, |(_, per)| {
            per[total - k..].iter().sum::<f64>() / k as f64
        })
        .max(1.0);
    let lr = (2.0 * (joint.log_likelihood - l_model) / (ctx.inflation() * lambda)).max(0.0);
    let p = 1.0 - ChiSquared::new(k as f64).expect("k ≥ 1").cdf(lr);
    (lr, p, lambda * (k as f64 * n.ln() - lr))
}

/// Whether a joint fit with a rival that ends at ℓ̂ `with` is worse than the model's ℓ̂
/// `model` (by more than [`WORSE_BY`]; module doc).
fn worse(with: f64, model: f64) -> bool {
    with < model - WORSE_BY
}

/// Whether a rival whose parameters `confounded` with an effect's are these is listed as
/// confounded with it (module doc): its joint fit with the model, `gain` = ℓ̂_{M+R} − ℓ̂_M,
/// is not worse than the model ([`worse`]), and one of them moved out of its interval, or
/// the rival `significant` given the model and one of them widened.
fn listed(confounded: &[ConfoundedParameter], significant: bool, gain: f64) -> bool {
    !worse(gain, 0.0)
        && (confounded.iter().any(|p| p.moved) || (significant && !confounded.is_empty()))
}

/// Whether parameter `q`, fitted as `now` in the final model and as `with` with a rival
/// added, is confounded with the rival (module doc); never where the final fit leaves it
/// not determined (it has no reading for the rival to take over).
fn confounded(
    q: &Parameter,
    now: &FittedParameter,
    with: &FittedParameter,
) -> Option<ConfoundedParameter> {
    if !now.determined {
        return None;
    }
    let i = &now.interval;
    let moved = i.lower.is_some_and(|l| with.value < l) || i.upper.is_some_and(|u| with.value > u);
    // On the fit's scale; none where an end is missing (the curvature not positive
    // definite: a rival at the edge of its range, whose fit says nothing of the others).
    let width = |w: &Interval| Some(q.internal(w.upper?) - q.internal(w.lower?));
    let widening = match (width(&now.wald_interval), width(&with.wald_interval)) {
        (Some(before), Some(after)) if before > 0.0 => after / before,
        _ => 1.0,
    };
    (moved || widening >= WIDENED).then(|| ConfoundedParameter {
        name: now.name.clone(),
        unit: now.unit,
        value: now.value,
        with_rival: with.value,
        interval: now.interval.clone(),
        moved,
        widening,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fitted(value: f64, interval: (f64, f64), wald: (f64, f64)) -> FittedParameter {
        let iv = |(a, b): (f64, f64)| Interval {
            lower: Some(a),
            upper: Some(b),
            lower_at_range_end: false,
            upper_at_range_end: false,
            method: "wald",
            threshold: None,
        };
        FittedParameter {
            name: "offset".into(),
            unit: "K",
            value,
            interval: iv(interval),
            wald_interval: iv(wald),
            joint_interval: None,
            range: [-20.0, 20.0],
            null: 0.0,
            determined: true,
        }
    }

    /// A parameter is confounded with a rival when the rival moves it out of its interval
    /// (−0.28 K in [−0.4, −0.16] moved to 0.01 K), or widens its Wald interval by 2 or more
    /// (0.24 K wide to 0.5 K: 2.08); a move within the interval that widens it by 1.5 is
    /// not, nor is a parameter not determined, however far it moves. The rival is listed for
    /// a move whatever its own test, for a widening only when it is significant given the
    /// model, and never without a confounded parameter.
    #[test]
    fn moved_or_widened_is_confounded_and_a_widening_lists_only_a_significant_rival() {
        let q = Parameter::linear("offset", "K", -20.0, 20.0, 0.0);
        let now = fitted(-0.28, (-0.4, -0.16), (-0.4, -0.16));
        let moved = confounded(&q, &now, &fitted(0.01, (-0.1, 0.12), (-0.1, 0.12))).unwrap();
        assert!(moved.moved && moved.with_rival == 0.01, "{moved:?}");
        let wide = confounded(&q, &now, &fitted(-0.3, (-0.55, -0.05), (-0.55, -0.05))).unwrap();
        assert!(
            !wide.moved && (wide.widening - 0.5 / 0.24).abs() < 1e-9,
            "{wide:?}"
        );
        assert!(confounded(&q, &now, &fitted(-0.25, (-0.43, -0.07), (-0.43, -0.07))).is_none());
        // The same move of a parameter the final fit leaves not determined: none.
        let open = FittedParameter {
            determined: false,
            ..now.clone()
        };
        assert!(confounded(&q, &open, &fitted(0.01, (-0.1, 0.12), (-0.1, 0.12))).is_none());
        assert!(listed(std::slice::from_ref(&moved), false, 0.0));
        assert!(listed(&[wide.clone(), moved], false, 3.0));
        assert!(listed(std::slice::from_ref(&wide), true, 9.0));
        assert!(!listed(&[wide], false, 0.0));
        assert!(!listed(&[], true, 9.0));
    }

    /// The gravity case: a rival whose joint re-fit with the model ends below the
    /// model's ℓ̂ (here 0.3 units, within the old slack of 1) is not listed, though it moved
    /// a parameter out of its interval (a |g| at its bound trading its direction, the rival
    /// near its null): that fit is short of the maximum with the rival, whose ℓ̂ is at least
    /// the model's. The same moves with the fit as good as the model (gain 0, or within
    /// rounding, −0.005) or better are listed; significance does not rescue a worse fit.
    #[test]
    fn a_rival_whose_joint_refit_is_worse_is_not_listed() {
        let q = Parameter::linear("offset", "K", -20.0, 20.0, 0.0);
        let now = fitted(-0.28, (-0.4, -0.16), (-0.4, -0.16));
        let moved = confounded(&q, &now, &fitted(0.01, (-0.1, 0.12), (-0.1, 0.12))).unwrap();
        let one = std::slice::from_ref(&moved);
        assert!(!listed(one, false, -0.3));
        assert!(!listed(one, true, -0.3));
        assert!(!listed(one, false, -2.0 * WORSE_BY));
        assert!(listed(one, false, -0.5 * WORSE_BY));
        assert!(listed(one, false, 0.0));
        assert!(listed(one, true, 4.0));
        // A fit judged worse than the model is restarted from the rival's null.
        assert!(worse(-100.3, -100.0) && !worse(-100.0, -100.0) && !worse(-99.0, -100.0));
    }
}
