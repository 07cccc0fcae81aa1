//! Floating stages and loose joints in the readable report (models with pin joints in free
//! play): per case the samples that record them, how many float or have a loose joint, and
//! the fractions with their Clopper–Pearson intervals; then how firmly they are held, the
//! holding forces' percentiles and the loosely held samples, among all and in θ_P's upper
//! tail. The caveats a large floating fraction or a loosely held tail bring are the case's
//! own (in the caveats section).

use super::document::{Document, Table};
use super::words::{NONE, percent_figure, plain, sci};
use crate::report::{CaseReport, Figure, Report};

/// Appends the floating stages and loose joints, if any case records them.
pub fn floating_section(doc: &mut Document, report: &Report) {
    let recorded = |c: &CaseReport| c.floating.recorded > 0 || c.loose_joints.recorded > 0;
    if !report.cases.iter().any(recorded) {
        return;
    }
    let conf = plain(100.0 * report.settings.confidence);
    let tail = 100.0 - report.sweep.percentile.0;
    doc.heading(2, "Floating stages and loose joints", "floating");
    doc.text(format!(
        "For models with pin joints in free play: a sample floats when some stage's tilt is held by pretension alone, not by the members that bear; a joint is loose when its pin does not touch its hole. Where more samples float than the {} % tail that θ_P{} reads, θ_P's upper percentiles rest on what the model leaves out (see the caveats).",
        plain(tail),
        plain(report.sweep.percentile.0)
    ));
    let count = |recorded: u64, set: u64, f: &Figure| {
        if recorded == 0 {
            [NONE.to_string(), "not recorded".into()]
        } else {
            [format!("{set} of {recorded}"), percent_figure(f)]
        }
    };
    let rows = report
        .cases
        .iter()
        .filter(|c| recorded(c))
        .map(|c| {
            let [fl, flf] = count(
                c.floating.recorded,
                c.floating.floating,
                &c.floating.fraction,
            );
            let [lo, lof] = count(
                c.loose_joints.recorded,
                c.loose_joints.with_loose,
                &c.loose_joints.fraction,
            );
            vec![c.name.clone(), fl, flf, lo, lof]
        })
        .collect();
    doc.table(Table {
        caption: format!(
            "Samples with a floating stage and with a loose joint, among the converged samples that record them, with {conf} % Clopper–Pearson intervals."
        ),
        header: vec![
            "case".into(),
            "floating [samples]".into(),
            format!("floating fraction [{conf} % interval]"),
            "with a loose joint [samples]".into(),
            format!("loose-joint fraction [{conf} % interval]"),
        ],
        rows,
    });
    holding_table(doc, report, &conf);
}

/// The holding forces: per case that records them, their 5th, 50th and 95th percentiles and
/// the samples held by less than 1 µN, among all and above the target percentile.
fn holding_table(doc: &mut Document, report: &Report, conf: &str) {
    let cases: Vec<&CaseReport> = report
        .cases
        .iter()
        .filter(|c| c.holding_force.recorded > 0)
        .collect();
    if cases.is_empty() {
        return;
    }
    let target = plain(report.sweep.percentile.0);
    doc.text(format!(
        "How firmly each sample is held: its holding force is the largest force on one node of the top surface that, to first order, moves θ_P by at most 1 % and lets no bearing cable or joint go. A sample held by micronewtons or less sits wherever friction, the diagonals' bending stiffness or the assembly left it, and its θ_P is the model's choice among nearly equal states; where such samples reach above θ_P{target}, θ_P{target} rests on them (see the caveats)."
    ));
    let rows = cases
        .iter()
        .map(|c| {
            let h = &c.holding_force;
            let mut row = vec![c.name.clone()];
            for p in &h.percentiles {
                row.push(p.value.map_or(NONE.to_string(), |v| sci(v.0)));
            }
            row.push(format!("{} of {}", h.loose, h.recorded));
            row.push(percent_figure(&h.loose_fraction));
            row.push(if h.tail_recorded == 0 {
                NONE.to_string()
            } else {
                format!("{} of {}", h.tail_loose, h.tail_recorded)
            });
            row
        })
        .collect();
    doc.table(Table {
        caption: format!(
            "Holding forces [N] of the converged samples that record them: percentiles, and the samples held by less than 1 µN, among all (with the {conf} % Clopper–Pearson interval of their fraction) and among those above θ_P{target}."
        ),
        header: vec![
            "case".into(),
            "5th percentile [N]".into(),
            "median [N]".into(),
            "95th percentile [N]".into(),
            "held by < 1 µN [samples]".into(),
            format!("fraction [{conf} % interval]"),
            format!("above θ_P{target}: held by < 1 µN"),
        ],
        rows,
    });
}
