//! Stage 4 of a step, *update*: the named effect is added to the model at its fitted
//! values, every effect of the model is re-fitted jointly ([`crate::likelihood::joint`]),
//! and each effect added in an earlier step is tested for removal given the others and
//! tried swapped for a rival; the candidates still to try (`Pool`) follow.
//!
//! ## Backward elimination
//!
//! For each effect e added in an earlier step (not the one just added, nor a pair just
//! named together, [`crate::selection::pair`], which their own step has just tested given
//! all the others), the model without e is re-fitted jointly, and e
//! is tested as a candidate is, against that reduced model: Λₑ = 2(ℓ̂ − ℓ̂₋ₑ)/(c·λₑ),
//! p = P(χ²_{kₑ} ≥ Λₑ), ΔBICₑ = λₑ·(kₑ ln n − Λₑ), with c = 1 + n/N and λₑ = max(1, the mean
//! over e's parameters of the one-parameter misspecification factor (A⁻¹BA⁻¹)ⱼⱼ/(A⁻¹)ⱼⱼ of
//! the joint fit). The effect least needed (largest ΔBICₑ) is removed when it is not both
//! significant at α/2 and better by ΔBIC ≤ −2 — what it explained, the others explain as
//! well; then the remaining earlier effects are tested again, until every one is needed.
//! Keeping needs p < α/2, entering needed p < α/(2K): removing is the harder of the two, as
//! stepwise selection needs to avoid cycling; a removed effect is not tried again.
//!
//! A removed effect is reported as indistinguishable from the effect that took over what
//! it explained: the one whose parameters move furthest, on their plausible ranges (the unit
//! cube of [`crate::candidates::parameter::Parameter::internal`]), when it is removed (a uniform
//! temperature change takes over a length bias of every member by moving its `offset`),
//! with the measurement that would separate the two ([`crate::candidates::separating_measurement`]).
//!
//! ## Swap
//!
//! Forward selection can add first an effect that mimics two true ones at once (a longeron
//! length bias standing in for a diagonal pretension and part of a larger scatter), and
//! once the second true effect is in, the first true one may fit no better than the
//! stand-in given the others, so neither elimination nor a later step corrects it. So, once
//! no earlier effect can be removed, each earlier effect e is tried replaced by each
//! remaining candidate r that competed with it when e was named (r significant then, and
//! explaining at least half as much: ΔBIC_r ≤ ½·ΔBIC_e; a pruning of the search, to spare
//! joint fits of candidates that explained something else), the new model fitted jointly
//! from the current values and r's fit of that step. The best swap is made when the new
//! model's BIC, −2ℓ̂/c + tr(A⁻¹B)·ln n (tr(A⁻¹B) ≥ k the joint fit's effective number of
//! parameters), is lower by at least 2: r explains jointly what e explained, better. A
//! swap keeps the number of effects. At most one swap per step; after a swap the
//! elimination runs again on the swapped model, since the effect swapped in may leave
//! another earlier effect unneeded (a temperature field that stood in for part of a
//! horizontal self-weight while a length bias stood in for a pretension: once the
//! pretension is swapped in, the field explains nothing the others do not).

use crate::candidates::candidate::{Candidate, separating_measurement};
use crate::candidates::parameter::Parameter;
use crate::comparison::baseline::CaseEdit;
use crate::errors::DiagnoseError;
use crate::likelihood::joint::{JointFit, bic, joint_fit};
use crate::likelihood::score::{CandidateScore, p_text};
use crate::selection::decide::DELTA_BIC;
use crate::selection::eliminate::{Removal, furthest_moved, removal_test};
use crate::selection::model::{Added, Context, ModelEffect, Pool, RefitEffect};

/// What stage 4 makes of the model.
pub(crate) struct Update {
    /// The updated model's case.
    pub edit: CaseEdit,
    /// The model's effects re-fitted jointly (empty with one effect, or when the fit failed).
    pub refitted: Vec<RefitEffect>,
    /// Effects added before that this step removed or swapped.
    pub removed: Vec<Removal>,
    /// The model's effects after the step, at their values.
    pub effects: Vec<ModelEffect>,
    /// The last joint fit of the model's effects (the one `refitted` reports), if any.
    pub joint: Option<JointFit>,
}

/// An entering effect's rivals for a later swap: each name and its fitted values.
type Rivals = Vec<(String, Vec<f64>)>;

/// An effect of the model during the update: the candidate, its values, the step that added
/// it.
type Member<'a> = (&'a dyn Candidate, Vec<f64>, usize);

/// Fits `effects` jointly against the baseline's case, counting the simulations.
pub(crate) fn fit_jointly(
    ctx: &Context,
    effects: &[(&dyn Candidate, &[f64])],
    steps: Option<&[f64]>,
) -> Result<JointFit, DiagnoseError> {
    let ev = ctx.evaluator(&ctx.baseline.derived_case());
    let fit = joint_fit(&ev, effects, steps, ctx.settings.candidate_level());
    ctx.count(&ev);
    fit
}

/// Stage 4, update: the candidates `entering` of the pool (each its index and values: the
/// named one at its fitted values, or a pair named together at their joint fit's,
/// [`crate::selection::pair`]; `scores`, the step's scores of the pool's candidates in
/// order) added to the model, every effect re-fitted jointly, the earlier effects tested
/// for removal given the others, the least needed removed while it is not needed, then the
/// best swap for a rival (module doc); the pool follows (the entering ones and a
/// swapped-in rival leave the candidates still to try; the model's effects take their new
/// values). A joint fit that fails leaves the values as they were (and nothing is
/// removed), with a note.
pub(crate) fn update(
    ctx: &Context,
    number: usize,
    pool: &mut Pool,
    entering: &[(usize, Vec<f64>)],
    scores: &[CandidateScore],
) -> Result<Update, DiagnoseError> {
    let (members, refitted, removed, edit, joint) = {
        let rivals: Vec<&dyn Candidate> = pool
            .remaining
            .iter()
            .enumerate()
            .filter(|&(j, _)| !entering.iter().any(|e| e.0 == j))
            .map(|(_, c)| c.as_ref())
            .collect();
        let new: Vec<(&dyn Candidate, &[f64])> = entering
            .iter()
            .map(|(i, v)| (pool.remaining[*i].as_ref(), v.as_slice()))
            .collect();
        let (members, refitted, removed, joint) =
            refit_and_eliminate(ctx, number, &pool.added, &new, &rivals)?;
        let mut edit = ctx.baseline.derived_case();
        for m in &members {
            m.0.apply(&m.1, &mut edit)?;
        }
        let members: Vec<(String, Vec<f64>)> = members
            .into_iter()
            .map(|(c, v, _)| (c.name().to_string(), v))
            .collect();
        (members, refitted, removed, edit, joint)
    };
    let named: Vec<usize> = entering.iter().map(|e| e.0).collect();
    admit(pool, number, &named, scores, &removed);
    for (a, (name, v)) in pool.added.iter_mut().zip(&members) {
        debug_assert_eq!(a.candidate.name(), name);
        a.values.clone_from(v);
    }
    let effects = pool
        .added
        .iter()
        .map(|a| ModelEffect {
            name: a.candidate.name().into(),
            parameters: a
                .candidate
                .parameters()
                .iter()
                .zip(&a.values)
                .map(|(p, &x)| (p.name.clone(), p.unit, x))
                .collect(),
        })
        .collect();
    Ok(Update {
        edit,
        refitted,
        removed,
        effects,
        joint,
    })
}

/// The pool after a step: the named candidates (one, or a pair named together) join the
/// model in order, each with its rivals for a later swap (the other candidates significant
/// at this step that explained at least half as much as it did alone; none for a member of
/// a pair that alone explained nothing, ΔBIC ≥ 0), a swapped-in rival
/// takes the place of the effect it replaced, and removed effects leave.
fn admit(
    pool: &mut Pool,
    number: usize,
    named: &[usize],
    scores: &[CandidateScore],
    removed: &[Removal],
) {
    let rivals = |i: usize| -> Rivals {
        let best = &scores[i];
        scores
            .iter()
            .enumerate()
            .filter(|&(j, c)| {
                best.delta_bic < 0.0
                    && !named.contains(&j)
                    && c.significant
                    && c.error.is_none()
                    && c.delta_bic <= 0.5 * best.delta_bic
            })
            .map(|(_, c)| {
                (
                    c.name.clone(),
                    c.parameters.iter().map(|p| p.value).collect(),
                )
            })
            .collect()
    };
    let entering: Vec<(String, Rivals)> = named
        .iter()
        .map(|&i| (scores[i].name.clone(), rivals(i)))
        .collect();
    for (name, rivals) in entering {
        let i = pool
            .remaining
            .iter()
            .position(|c| c.name() == name)
            .expect("a named candidate was remaining");
        pool.added.push(Added {
            candidate: pool.remaining.remove(i),
            values: Vec::new(),
            step: number,
            rivals,
        });
    }
    for r in removed {
        let Some(by) = &r.replaced_by else { continue };
        let e = pool
            .added
            .iter()
            .position(|a| a.candidate.name() == r.name)
            .expect("a swapped effect is in the model");
        let j = pool
            .remaining
            .iter()
            .position(|c| c.name() == by)
            .expect("a swapped-in candidate was remaining");
        pool.added[e] = Added {
            candidate: pool.remaining.remove(j),
            values: Vec::new(),
            step: number,
            rivals: Vec::new(),
        };
    }
    pool.added.retain(|a| {
        !removed
            .iter()
            .any(|r| r.replaced_by.is_none() && r.name == a.candidate.name())
    });
}

/// The model's effects with the new ones (one, or a pair named together), re-fitted
/// jointly, the earlier ones eliminated while not needed and the best swap made: the
/// members at their values, the joint fit's effects, the removals, and the last joint fit.
#[allow(clippy::type_complexity)]
fn refit_and_eliminate<'a>(
    ctx: &Context,
    number: usize,
    added: &'a [Added],
    new: &[(&'a dyn Candidate, &[f64])],
    pool: &[&'a dyn Candidate],
) -> Result<
    (
        Vec<Member<'a>>,
        Vec<RefitEffect>,
        Vec<Removal>,
        Option<JointFit>,
    ),
    DiagnoseError,
> {
    let note = |m: &str| ctx.progress.note(m);
    let mut members: Vec<Member> = added
        .iter()
        .map(|a| (a.candidate.as_ref(), a.values.clone(), a.step))
        .chain(new.iter().map(|&(c, v)| (c, v.to_vec(), number)))
        .collect();
    let fresh = new.len();
    let fit_of = |members: &[Member], steps: Option<&[f64]>| {
        let effects: Vec<(&dyn Candidate, &[f64])> =
            members.iter().map(|m| (m.0, m.1.as_slice())).collect();
        fit_jointly(ctx, &effects, steps)
    };
    let mut joint: Option<JointFit> = None;
    if members.len() > 1 {
        note("re-fitting the model's effects jointly…");
        match fit_of(&members, None) {
            Ok(j) => joint = Some(j),
            Err(e) => note(&format!("  the joint re-fit failed ({e}); values kept")),
        }
    }
    let mut removed = Vec::new();
    joint = joint.map(|full| eliminate(ctx, &mut members, fresh, full, &mut removed));
    if let Some(full) = joint.take() {
        let (fit, swap) = best_swap(ctx, &members, fresh, added, pool, full);
        if let Some((e, r, lr, delta_bic)) = swap {
            let gone = members[e].0;
            note(&format!(
                "  {} replaced by {}: jointly the model fits better with it (ΔBIC {delta_bic:.1})",
                gone.name(),
                r.name()
            ));
            removed.push(Removal {
                name: gone.name().into(),
                replaced_by: Some(r.name().into()),
                added_in_step: members[e].2,
                lr_statistic: lr,
                p_value: None,
                delta_bic,
                explained_by: Some(r.name().into()),
                separate_by: separating_measurement(gone, r).into(),
            });
            members[e] = (r, Vec::new(), number);
            // The swapped model may leave another earlier effect unneeded (a stand-in for
            // the swapped-in effect's part): eliminate again from its fit.
            joint = Some(eliminate(ctx, &mut members, fresh, fit, &mut removed));
        } else {
            joint = Some(fit);
        }
    }
    if let Some(j) = &joint {
        for (m, v) in members.iter_mut().zip(&j.values) {
            m.1.clone_from(v);
        }
    }
    let refitted = match &joint {
        Some(j) => members
            .iter()
            .zip(&j.parameters)
            .map(|(m, p)| RefitEffect {
                name: m.0.name().into(),
                parameters: p.clone(),
            })
            .collect(),
        None => Vec::new(),
    };
    Ok((members, refitted, removed, joint))
}

/// Backward elimination (module doc) from the joint fit `full` of `members` (the last
/// `fresh` just added, tested by their own step): the least needed earlier effect removed
/// while it is not needed, each removal added to `removed`; returns the joint fit of the
/// members left.
fn eliminate<'a>(
    ctx: &Context,
    members: &mut Vec<Member<'a>>,
    fresh: usize,
    full: JointFit,
    removed: &mut Vec<Removal>,
) -> JointFit {
    let note = |m: &str| ctx.progress.note(m);
    let fit_of = |members: &[Member], steps: Option<&[f64]>| {
        let effects: Vec<(&dyn Candidate, &[f64])> =
            members.iter().map(|m| (m.0, m.1.as_slice())).collect();
        fit_jointly(ctx, &effects, steps)
    };
    let mut joint = Some(full);
    while let Some(full) = joint.take() {
        for (m, v) in members.iter_mut().zip(&full.values) {
            m.1.clone_from(v);
        }
        let mut worst: Option<(usize, JointFit, (f64, f64, f64))> = None;
        for e in 0..members.len() - fresh {
            let rest: Vec<Member> = members
                .iter()
                .enumerate()
                .filter(|&(i, _)| i != e)
                .map(|(_, m)| m.clone())
                .collect();
            let offset: usize = full.values[..e].iter().map(Vec::len).sum();
            let k = full.values[e].len();
            let steps: Vec<f64> = full
                .fit
                .steps
                .iter()
                .enumerate()
                .filter(|&(i, _)| !(offset..offset + k).contains(&i))
                .map(|(_, &h)| h)
                .collect();
            let reduced = match fit_of(&rest, Some(&steps)) {
                Ok(r) => r,
                Err(err) => {
                    note(&format!(
                        "  the model without {} could not be fitted ({err}); it stays",
                        members[e].0.name()
                    ));
                    continue;
                }
            };
            let t = removal_test((ctx.measured.n(), ctx.inflation()), &full, &reduced, (e, k));
            note(&format!(
                "  {} given the others: Λ {:.1}, p {}, ΔBIC {:.1}",
                members[e].0.name(),
                t.0,
                p_text(t.1),
                t.2
            ));
            if worst.as_ref().is_none_or(|w| t.2 > w.2.2) {
                worst = Some((e, reduced, t));
            }
        }
        let Some((e, reduced, (lr, p, delta_bic))) = worst else {
            joint = Some(full);
            break;
        };
        if p < ctx.settings.candidate_level() && delta_bic <= -DELTA_BIC {
            joint = Some(full);
            break;
        }
        let gone = members.remove(e);
        let mut before = full.values.clone();
        before.remove(e);
        let parameters: Vec<Vec<Parameter>> =
            members.iter().map(|m| m.0.parameters().to_vec()).collect();
        let explained_by =
            furthest_moved(&parameters, &before, &reduced.values).map(|(i, _)| members[i].0);
        note(&format!(
            "  {} removed: given the others it no longer improves the fit{}",
            gone.0.name(),
            explained_by.map_or(String::new(), |x| format!(
                " ({} takes over what it explained)",
                x.name()
            ))
        ));
        removed.push(Removal {
            name: gone.0.name().into(),
            replaced_by: None,
            added_in_step: gone.2,
            lr_statistic: lr,
            p_value: Some(p),
            delta_bic,
            separate_by: explained_by.map_or("a measurement that only it affects".into(), |x| {
                separating_measurement(gone.0, x).into()
            }),
            explained_by: explained_by.map(|x| x.name().to_string()),
        });
        joint = Some(reduced);
        if members.len() == fresh {
            break;
        }
    }
    joint.expect("the loop leaves the last joint fit")
}

/// The best swap of an earlier effect (not one of the last `fresh`, just added) for one of
/// its rivals still in the pool (module doc): the joint fit to go on with (the swapped
/// model's, or `full`), and the swap made (the effect's index, the rival,
/// 2(ℓ̂_swap − ℓ̂)/c, the BIC difference).
#[allow(clippy::type_complexity)]
fn best_swap<'a>(
    ctx: &Context,
    members: &[Member<'a>],
    fresh: usize,
    added: &[Added],
    pool: &[&'a dyn Candidate],
    full: JointFit,
) -> (JointFit, Option<(usize, &'a dyn Candidate, f64, f64)>) {
    let (n, c) = (ctx.measured.n(), ctx.inflation());
    let now = bic(&full, n, ctx.samples);
    let mut best: Option<(usize, &dyn Candidate, JointFit, f64)> = None;
    for (e, m) in members[..members.len() - fresh].iter().enumerate() {
        let Some(a) = added.iter().find(|a| a.candidate.name() == m.0.name()) else {
            continue;
        };
        for (name, start) in &a.rivals {
            let Some(&r) = pool.iter().find(|r| r.name() == name) else {
                continue;
            };
            let mut swapped: Vec<(&dyn Candidate, &[f64])> =
                members.iter().map(|m| (m.0, m.1.as_slice())).collect();
            swapped[e] = (r, start);
            ctx.progress.note(&format!(
                "  trying {} in place of {}…",
                r.name(),
                m.0.name()
            ));
            let fit = match fit_jointly(ctx, &swapped, None) {
                Ok(f) => f,
                Err(err) => {
                    ctx.progress.note(&format!("  failed ({err})"));
                    continue;
                }
            };
            let delta = bic(&fit, n, ctx.samples) - now;
            ctx.progress.note(&format!("  ΔBIC {delta:.1}"));
            if delta <= -DELTA_BIC && best.as_ref().is_none_or(|b| delta < b.3) {
                best = Some((e, r, fit, delta));
            }
        }
    }
    match best {
        Some((e, r, fit, delta)) => {
            let lr = 2.0 * (fit.log_likelihood - full.log_likelihood) / c;
            (fit, Some((e, r, lr, delta)))
        }
        None => (full, None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pair named together joins the model in the step's order, both leaving the
    /// candidates still to try: backlash (alone ΔBIC −8) keeps as rivals the significant
    /// candidates that explained at least half as much (length_bias at −20), the
    /// pretension (alone +1, explaining nothing) none, and neither has the other as a
    /// rival.
    #[test]
    fn a_pair_joins_the_model_each_with_its_own_rivals() {
        let baseline = crate::comparison::baseline::Baseline::of_test();
        let (remaining, _) = crate::candidates::library(&baseline);
        let order: Vec<&str> = remaining.iter().map(|c| c.name()).collect();
        let scores: Vec<CandidateScore> = order
            .iter()
            .map(|&n| match n {
                "backlash" => CandidateScore::of_test(n, 1, -8.0, true),
                "length_bias" => CandidateScore::of_test(n, 3, -20.0, true),
                "diagonal_pretension" => CandidateScore::of_test(n, 1, 1.0, false),
                _ => CandidateScore::of_test(n, 3, 5.0, false),
            })
            .collect();
        let at = |n: &str| order.iter().position(|&o| o == n).unwrap();
        let mut pool = Pool {
            remaining,
            added: Vec::new(),
        };
        let named = [at("backlash"), at("diagonal_pretension")];
        admit(&mut pool, 1, &named, &scores, &[]);
        let added: Vec<&str> = pool.added.iter().map(|a| a.candidate.name()).collect();
        assert_eq!(added, ["backlash", "diagonal_pretension"]);
        assert_eq!(pool.remaining.len(), order.len() - 2);
        assert!(pool.remaining.iter().all(|c| !added.contains(&c.name())));
        let rivals =
            |i: usize| -> Vec<&str> { pool.added[i].rivals.iter().map(|r| r.0.as_str()).collect() };
        assert_eq!(rivals(0), ["length_bias"]);
        assert!(rivals(1).is_empty());
        assert!(pool.added.iter().all(|a| a.step == 1));
    }
}
