//! Floating stages and loose joints in the readable report (models with pin joints in free
//! play): per case the samples that record them, how many float or have a loose joint, and
//! the fractions with their Clopper–Pearson intervals. The caveat a large floating fraction
//! brings is the case's own (in the caveats section).

use super::document::{Document, Table};
use super::words::{NONE, percent_figure, plain};
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
}
