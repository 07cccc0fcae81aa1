//! The answer: the few lines a test engineer reads first. Which effects are missing and
//! how large they are in hardware units with their 95 % intervals, what the data cannot
//! tell apart, what they could not have seen, and what to measure or do next.
//!
//! It is built once from the diagnosis ([`Answer::of`]). `diagnosis.md` opens with its
//! lines, `diagnosis.json` carries it as `answer` (its lines and the record they are
//! written from), and `truss diagnose` prints its lines ([`Answer::plain_lines`]): the
//! three cannot disagree, and a test compares them. The step-by-step reasoning follows
//! below the answer in `diagnosis.md`.
//!
//! Sizes read in the hardware's units: a length in µm (the fit's unit is mm), a
//! temperature in K, a gradient in K/mm, self-weight in g; a scatter's factor as the
//! fitted scatter in µm.

use super::wording::{code_list, effect, rival_effects};
use crate::candidates::candidate::{Candidate, separating_measurement};
use crate::candidates::parameter::two_digit_decimals;
use crate::comparison::measured::Measured;
use crate::likelihood::score::FittedParameter;
use crate::selection::Diagnosis;
use crate::selection::decide::Verdict;
use crate::selection::unseen::in_hardware_units as hardware;
use serde::Serialize;

/// The answer record (`diagnosis.json`'s `answer`).
#[derive(Debug, Clone, Serialize)]
pub struct Answer {
    /// The verdict (as `diagnosis.json`'s `verdict`).
    pub verdict: Verdict,
    /// The effects missing from the baseline: the final model's, fitted jointly.
    pub missing: Vec<MissingEffect>,
    /// Per effect of the model, the rivals the data cannot tell from it, and what would
    /// separate them.
    pub cannot_tell_apart: Vec<CannotTellApart>,
    /// The detection limits of the candidates not in the final model, in words
    /// ([`crate::likelihood::power::Unseen::words`]).
    pub could_not_have_seen: Vec<String>,
    /// The specimens the limits are for.
    pub specimens: usize,
    /// What to measure or do next, most specific first.
    pub next: Vec<String>,
    /// The lines, Markdown: what `diagnosis.md` opens with.
    pub lines: Vec<String>,
}

/// An effect the baseline lacks, as the final model fits it.
#[derive(Debug, Clone, Serialize)]
pub struct MissingEffect {
    /// The candidate's name.
    pub effect: String,
    /// Its parameters in hardware units.
    pub parameters: Vec<Size>,
}

/// A fitted parameter in the hardware's units.
#[derive(Debug, Clone, Serialize)]
pub struct Size {
    /// The parameter's name.
    pub name: String,
    /// The hardware unit of `value`, `lower`, `upper` (µm for a length fitted in mm).
    pub unit: &'static str,
    /// The fitted value.
    pub value: f64,
    /// The 95 % interval's lower end (null where not found).
    pub lower: Option<f64>,
    /// Its upper end.
    pub upper: Option<f64>,
    /// Whether the data determine it ([`FittedParameter::determined`]).
    pub determined: bool,
    /// Whether its interval excludes the null (the parameter shows the effect).
    pub shown: bool,
}

/// What the data cannot tell from an effect of the model.
#[derive(Debug, Clone, Serialize)]
pub struct CannotTellApart {
    /// The effect.
    pub effect: String,
    /// Its rivals.
    pub rivals: Vec<String>,
    /// Per rival, the measurement that would separate them.
    pub separate_by: Vec<String>,
}

/// `v` to the second significant digit of `scale` (an interval's width: 0.68 µm gives
/// 0.01 µm), with a true minus sign and no "−0".
fn number(v: f64, scale: f64) -> String {
    let digits = two_digit_decimals(scale).map_or(2, |d| d.min(9));
    let s = format!("{v:.digits$}");
    // No "-0.0".
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s.replace('-', "−")
    }
}

impl Size {
    fn of(p: &FittedParameter) -> Self {
        let (value, unit) = hardware(p.value, p.unit);
        let end = |v: Option<f64>| v.map(|v| hardware(v, p.unit).0);
        let (lower, upper) = (end(p.interval.lower), end(p.interval.upper));
        let null = hardware(p.null, p.unit).0;
        let shown =
            p.determined && (lower.is_some_and(|l| l > null) || upper.is_some_and(|u| u < null));
        Self {
            name: p.name.clone(),
            unit,
            value,
            lower,
            upper,
            determined: p.determined,
            shown,
        }
    }

    /// `bias.longeron 3.3 µm (95 % CI 3.0 to 3.7)`, or `… not determined`.
    fn words(&self) -> String {
        if !self.determined {
            return format!("{} not determined by these data", self.name);
        }
        let scale = match (self.lower, self.upper) {
            (Some(l), Some(u)) if u > l => u - l,
            _ => self.value.abs(),
        };
        let end = |v: Option<f64>| v.map_or("?".to_string(), |v| number(v, scale));
        format!(
            "{} {} {} (95 % CI {} to {}){}",
            self.name,
            number(self.value, scale),
            self.unit,
            end(self.lower),
            end(self.upper),
            if self.shown {
                ""
            } else {
                ", consistent with none"
            }
        )
    }
}

impl Answer {
    /// The answer of diagnosis `d` of the data `measured`.
    pub fn of(measured: &Measured, d: &Diagnosis) -> Self {
        let missing: Vec<MissingEffect> = d
            .final_fit
            .iter()
            .map(|e| MissingEffect {
                effect: e.name.clone(),
                parameters: e.parameters.iter().map(Size::of).collect(),
            })
            .collect();
        let cannot_tell_apart = cannot_tell_apart(d);
        let could_not_have_seen: Vec<String> = d
            .unseen
            .iter()
            .map(|u| u.words(effect(d, &u.name)))
            .collect();
        let specimens = d.unseen.first().map_or(measured.n(), |u| u.specimens);
        let next = next_steps(measured, d, &cannot_tell_apart);
        let mut answer = Self {
            verdict: d.verdict,
            missing,
            cannot_tell_apart,
            could_not_have_seen,
            specimens,
            next,
            lines: Vec::new(),
        };
        answer.lines = answer.write();
        answer
    }

    /// The lines from the record: one per missing effect, per effect with rivals, the
    /// limits in one, and one per next step.
    fn write(&self) -> Vec<String> {
        let mut lines = vec![format!("**Verdict: {}.**", self.verdict.words())];
        for e in &self.missing {
            // What shows the effect first, then what is consistent with none, then what
            // the data do not determine.
            let mut sizes: Vec<&Size> = e.parameters.iter().collect();
            sizes.sort_by_key(|s| (!s.shown, !s.determined));
            lines.push(format!(
                "- **Missing: `{}`**: {}.",
                e.effect,
                sizes
                    .iter()
                    .map(|s| s.words())
                    .collect::<Vec<_>>()
                    .join("; ")
            ));
        }
        if self.missing.is_empty() {
            lines.push(format!(
                "- **Missing:** {}.",
                match self.verdict {
                    Verdict::None => "none above the sizes below",
                    Verdict::Unexplained =>
                        "something none of the candidates describes (the model disagrees with the data)",
                    _ => "none named; the data cannot decide",
                }
            ));
        }
        for k in &self.cannot_tell_apart {
            lines.push(format!(
                "- **Cannot be told apart:** `{}` from {}; what would separate them: {}.",
                k.effect,
                code_list(&k.rivals, ", "),
                k.separate_by.join("; ")
            ));
        }
        if !self.could_not_have_seen.is_empty() {
            lines.push(format!(
                "- **Could not have been seen** with these {} specimens (80 % power): {}.",
                self.specimens,
                self.could_not_have_seen.join("; ")
            ));
        }
        for n in &self.next {
            lines.push(format!("- **Next:** {n}"));
        }
        lines
    }

    /// The lines as the console prints them: without Markdown's emphasis and code marks.
    pub fn plain_lines(&self) -> Vec<String> {
        self.lines
            .iter()
            .map(|l| l.replace("**", "").replace('`', ""))
            .collect()
    }
}

/// Per effect with rivals, the record of what cannot be told apart from it
/// ([`Diagnosis::indistinguishable`]), for the effects of the final model (an effect
/// entered at several steps keeps its rivals of each, once).
fn cannot_tell_apart(d: &Diagnosis) -> Vec<CannotTellApart> {
    let mut out: Vec<CannotTellApart> = Vec::new();
    let model = d.named_effects();
    for r in d
        .indistinguishable
        .iter()
        .filter(|r| r.kept && !r.rivals.is_empty() && model.contains(&r.effect.as_str()))
    {
        let a = effect(d, &r.effect);
        let entry = match out.iter_mut().position(|k| k.effect == r.effect) {
            Some(i) => &mut out[i],
            None => {
                out.push(CannotTellApart {
                    effect: r.effect.clone(),
                    rivals: Vec::new(),
                    separate_by: Vec::new(),
                });
                out.last_mut().expect("just pushed")
            }
        };
        for o in &r.rivals {
            if !entry.rivals.contains(o) {
                entry.rivals.push(o.clone());
                let by: Vec<&str> = rival_effects(d, o, &r.effect)
                    .into_iter()
                    .map(|b| separating_measurement(a, b))
                    .collect();
                entry
                    .separate_by
                    .push(format!("from `{o}`, {}", by.join("; and ")));
            }
        }
    }
    out
}

/// What to measure or do next: for each effect whose rivals the member lengths would
/// separate and were not measured, to measure them; then what the verdict asks.
fn next_steps(measured: &Measured, d: &Diagnosis, apart: &[CannotTellApart]) -> Vec<String> {
    let mut advice = Vec::new();
    for k in apart {
        let a: &dyn Candidate = effect(d, &k.effect);
        let mistaken: Vec<&String> = k
            .rivals
            .iter()
            .filter(|o| {
                rival_effects(d, o, &k.effect).iter().any(|b| {
                    a.mistaken_without_members(b.trace()) || b.mistaken_without_members(a.trace())
                })
            })
            .collect();
        if !mistaken.is_empty() && measured.members.is_none() {
            advice.push(format!(
                "`{}` and {} fit the node positions equally well: joint free play shortens the truss much as a member-length error does. Measure the member lengths one by one (longerons and diagonals, to a few µm) and run again with `--measured-members`: then they separate.",
                k.effect,
                code_list(&mistaken, ", ")
            ));
        } else {
            advice.push(format!(
                "Measure what separates `{}` from {} (above), and run again with it.",
                k.effect,
                code_list(&k.rivals, ", ")
            ));
        }
    }
    match d.verdict {
        Verdict::Named => advice.push(
            "Run `updated-job.json` with mc-shard and mc-merge for the precision budget with the effects added.".into(),
        ),
        Verdict::None => advice.push(
            "None needed: the baseline job's prediction stands for these trusses.".into(),
        ),
        Verdict::CannotTell => advice.push(format!(
            "Measure more specimens: with {} the data cannot decide; about four times as many halve the intervals.",
            measured.n()
        )),
        Verdict::Unexplained => advice.push(
            "Look for a mechanism outside the candidates (a support that moves, a member bent or damaged, the instrument's own error): measure the supports and the instrument against a reference.".into(),
        ),
    }
    if !measured.report.outliers.is_empty() {
        advice.push(
            "Check the outlier rows listed under Data against the instrument's records; they were left out.".into(),
        );
    }
    advice
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::likelihood::fit::Interval;

    fn parameter(unit: &'static str, value: f64, lower: f64, upper: f64) -> FittedParameter {
        let interval = Interval {
            lower: Some(lower),
            upper: Some(upper),
            lower_at_range_end: false,
            upper_at_range_end: false,
            method: "profile",
            threshold: None,
        };
        FittedParameter {
            name: "bias.longeron".into(),
            unit,
            value,
            interval: interval.clone(),
            wald_interval: interval,
            joint_interval: None,
            range: [-0.02, 0.02],
            null: 0.0,
            determined: true,
        }
    }

    /// A length fitted in mm reads in µm, to the interval width's second significant
    /// digit; an interval across the null reads "consistent with none", one clear of it
    /// does not (by hand: 0.003312 mm = 3.312 µm, width 0.689 µm: two decimals; width
    /// 1.52 µm: one).
    #[test]
    fn a_size_reads_in_hardware_units_with_its_interval() {
        let s = Size::of(&parameter("mm", 0.003312, 0.002971, 0.003660));
        assert_eq!((s.unit, s.shown), ("µm", true));
        assert_eq!(s.words(), "bias.longeron 3.31 µm (95 % CI 2.97 to 3.66)");
        let s = Size::of(&parameter("mm", 9.54e-5, -6.64e-4, 8.51e-4));
        assert!(!s.shown);
        assert_eq!(
            s.words(),
            "bias.longeron 0.1 µm (95 % CI −0.7 to 0.9), consistent with none"
        );
        let s = Size::of(&parameter("K", 2.04, 1.91, 2.17));
        assert_eq!(s.words(), "bias.longeron 2.04 K (95 % CI 1.91 to 2.17)");
        let mut p = parameter("g", 0.5, -1.0, 1.0);
        p.determined = false;
        assert_eq!(
            Size::of(&p).words(),
            "bias.longeron not determined by these data"
        );
        assert_eq!(
            (number(-0.04, 1.0), number(-1.26, 1.0)),
            ("0.0".into(), "−1.3".into())
        );
    }
}
