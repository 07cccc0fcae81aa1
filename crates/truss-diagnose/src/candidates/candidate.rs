//! What every candidate effect is: the [`Candidate`] trait, the trace a direct measurement
//! of the hardware sees of it ([`Trace`]), and how an effect registers ([`Registration`]).
//! Each effect lives in a file of its own beside this one and says everything about itself
//! through the trait: its parameters and how it edits a case, how its fitted values read
//! for the hardware, and which measurement tells it from a rival.

use super::parameter::Parameter;
use crate::comparison::baseline::{Baseline, CaseEdit};
use crate::errors::DiagnoseError;

/// What a direct measurement of the hardware would show of an effect, beside the node
/// positions the diagnosis compares: the kind of evidence that separates two effects the
/// node positions cannot tell apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trace {
    /// The effect turns with the test orientation (self-weight).
    Orientation,
    /// The truss's temperatures show it.
    Temperature,
    /// The bars' (longerons', battens') lengths, measured one by one, are off on average.
    BarLengths,
    /// The diagonals' (cables') lengths, measured one by one, are off on average.
    CableLengths,
    /// The members' lengths, measured one by one, scatter more or less than stated.
    LengthScatter,
    /// The joints have free play while the members' lengths are as stated.
    JointPlay,
}

/// The member lengths measured one by one: what separates two length effects, or a length
/// effect from joint free play.
pub const MEMBER_LENGTHS: &str = "the member lengths measured one by one, longerons and diagonals to a few µm (`--measured-members`)";

/// What separates two effects when neither names a measurement for the other.
const ANY_SEPARATE: &str = "a measurement that only one of them affects (member lengths for length effects, temperatures for a thermal field, a test in another orientation for self-weight)";

/// A physical mechanism the baseline may lack. A new mechanism is one more implementation
/// in a file of its own and one more [`Registration`] in [`super::REGISTRY`]: the library,
/// the error messages, the reports and `truss synth-measured` all read it from there.
pub trait Candidate: Send + Sync {
    /// The name reports use (`gravity`, `thermal_gradient`, …).
    fn name(&self) -> &'static str;
    /// One line on the mechanism, for the report.
    fn mechanism(&self) -> &'static str;
    /// The parameters and their plausible ranges.
    fn parameters(&self) -> &[Parameter];
    /// Applies the effect with `values` (one per parameter) to the case.
    fn apply(&self, values: &[f64], edit: &mut CaseEdit) -> Result<(), DiagnoseError>;
    /// Moves `values` onto the feasible set if the box alone does not describe it
    /// (backlash's spread no larger than its mean clearance), leaving `values[fixed]` where it is if `fixed` is given (a
    /// profile holds that parameter); the default does nothing.
    fn project(&self, _values: &mut [f64], _fixed: Option<usize>) {}
    /// Parameter `j` at `value` in plain words: what it means for the hardware; `span` is
    /// the model's size along x, y, z \[mm\].
    fn reading(&self, j: usize, value: f64, span: [f64; 3]) -> String;
    /// What it means that parameter `j`'s interval reaches its null value, where that is a
    /// result of its own (backlash's spread: the joints may all have one clearance).
    fn unresolved(&self, _j: usize) -> Option<&'static str> {
        None
    }
    /// What a direct measurement of the hardware shows of the effect.
    fn trace(&self) -> Trace;
    /// Whether the effect puts the joints in free play: ℓ then has a kink wherever a
    /// sample's contact state changes, on the scale of its own standard error, and a fit
    /// measures its curvature on a longer scale ([`crate::likelihood::fit`], a rough
    /// likelihood). The default: where the trace is the joints' play.
    fn free_play(&self) -> bool {
        self.trace() == Trace::JointPlay
    }
    /// The measurement that tells this effect from a rival whose trace is `rival`, where
    /// this effect knows one.
    fn separated_from(&self, _rival: Trace) -> Option<&'static str> {
        None
    }
    /// Whether node positions alone make this effect look like a rival whose trace is
    /// `rival` in a way that only the member measurements undo (joint free play against a
    /// length error).
    fn mistaken_without_members(&self, _rival: Trace) -> bool {
        false
    }
    /// The candidates (by name) whose effect this one's changes, so that the two may show
    /// only together: each alone fits the data poorly, both fitted at once fit well
    /// (backlash with a diagonal pretension: the pretension sets how far the joints are
    /// pulled into contact). The selection fits such a pair jointly when one of the two is
    /// significant at a step and neither is named ([`crate::selection::pair`]). Declared
    /// by one of the two ([`interact`] asks either); the default is none.
    fn interacts_with(&self) -> &'static [&'static str] {
        &[]
    }
}

/// Whether `a` and `b` declare that their effects interact ([`Candidate::interacts_with`],
/// either side).
pub fn interact(a: &dyn Candidate, b: &dyn Candidate) -> bool {
    a.name() != b.name()
        && (a.interacts_with().contains(&b.name()) || b.interacts_with().contains(&a.name()))
}

/// The measurement that tells `a` from `b` when node positions cannot: the one either
/// names for the other's trace, else any measurement that only one of them affects.
pub fn separating_measurement(a: &dyn Candidate, b: &dyn Candidate) -> &'static str {
    a.separated_from(b.trace())
        .or_else(|| b.separated_from(a.trace()))
        .unwrap_or(ANY_SEPARATE)
}

/// How a registered candidate is made for a baseline: the candidate, or why it does not
/// apply.
pub type Make = fn(baseline: &Baseline, with_members: bool) -> Result<Box<dyn Candidate>, String>;

/// A candidate effect as it registers: its name, and how it is made for a baseline (or why
/// it does not apply to it). `with_members`: member lengths were measured one by one.
#[derive(Clone, Copy)]
pub struct Registration {
    /// The candidate's name ([`Candidate::name`]).
    pub name: &'static str,
    /// The candidate for `baseline`, or why it does not apply.
    pub make: Make,
}

/// The names of the model's member groups made wholly of cables (`cables`), or of those
/// with a bar.
pub fn member_groups(baseline: &Baseline, cables: bool) -> Vec<String> {
    let model = baseline.model();
    model
        .groups()
        .into_iter()
        .filter(|&g| {
            model
                .members()
                .iter()
                .filter(|m| m.group == g)
                .all(|m| m.behaviour.is_cable())
                == cables
        })
        .map(|g| g.to_string())
        .collect()
}
