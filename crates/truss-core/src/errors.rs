//! Errors of model validation and of solving, each carrying what is needed to find the fault.

use std::path::PathBuf;

/// A model that cannot be used: each variant names the offending item.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The model file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The model file was refused before it was parsed: not a regular file, too large, or
    /// not UTF-8 (see [`crate::model_file::read_input`]).
    #[error("{}: {reason}", path.display())]
    Refused {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: InputRefusal,
    },
    /// The text is not a model file (bad JSON, a missing or misspelled field).
    #[error("{origin}: line {line}, column {column}: {message}")]
    Syntax {
        /// Where the text came from (a path, or `<string>`).
        origin: String,
        /// Line of the fault, from 1.
        line: usize,
        /// Column of the fault, from 1.
        column: usize,
        /// serde_json's description.
        message: String,
    },
    /// The model has no nodes or no members.
    #[error("the model has no {what}")]
    Empty {
        /// `nodes` or `members`.
        what: &'static str,
    },
    /// Two items of the same kind share an id.
    #[error("{kind} id {id:?} is used twice (at {kind}s[{first}] and [{second}])")]
    DuplicateId {
        /// `node`, `member` or `joint`.
        kind: &'static str,
        /// The repeated id.
        id: String,
        /// Index of the first use.
        first: usize,
        /// Index of the second use.
        second: usize,
    },
    /// An item refers to a node that does not exist.
    #[error("{item} refers to unknown node {node:?}")]
    UnknownNode {
        /// The referring item, as a JSON path (`members[3] (id "batten.0.1")`).
        item: String,
        /// The missing node id.
        node: String,
    },
    /// A number that must be finite is not.
    #[error("{item}: {field} is not a finite number")]
    NotFinite {
        /// The item, as a JSON path.
        item: String,
        /// The field.
        field: &'static str,
    },
    /// A number that must be positive is not.
    #[error("{item}: {field} must be positive, got {value}")]
    NotPositive {
        /// The item, as a JSON path.
        item: String,
        /// The field.
        field: &'static str,
        /// The value found.
        value: f64,
    },
    /// A member joins a node to itself or to a node at the same position.
    #[error("{item}: zero-length member (its two nodes {a:?} and {b:?} coincide)")]
    ZeroLength {
        /// The member, as a JSON path.
        item: String,
        /// First node id.
        a: String,
        /// Second node id.
        b: String,
    },
    /// Any other invalid value, explained.
    #[error("{item}: {message}")]
    Invalid {
        /// The item, as a JSON path.
        item: String,
        /// What is wrong.
        message: String,
    },
    /// The nominal structure cannot carry load: a node can move without straining any member.
    #[error(
        "the model is a mechanism: node {node:?} can move in {dof} without straining any member (add a member or a support)"
    )]
    Mechanism {
        /// The node id.
        node: String,
        /// The direction, `x`, `y` or `z`.
        dof: char,
    },
}

/// Why an input file (a model file, a job file) was refused before it was parsed (see
/// [`crate::model_file::read_input`]). Each is an invalid input, not an I/O failure: the file
/// was read, or could have been, and is not what the command takes.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum InputRefusal {
    /// A device, pipe, directory or socket: only regular files are read, so that
    /// `/dev/zero` or a FIFO cannot feed an endless input.
    #[error("not a regular file ({kind}); give the path of a file")]
    NotRegularFile {
        /// What it is: `a directory`, `a character device`, …
        kind: &'static str,
    },
    /// Larger than [`crate::model_file::MAX_INPUT_BYTES`].
    #[error("{bytes} bytes is more than the {limit} bytes an input file may have")]
    TooLarge {
        /// The file's size \[bytes\].
        bytes: u64,
        /// The limit \[bytes\].
        limit: u64,
    },
    /// Not UTF-8 text.
    #[error("not UTF-8 text: invalid bytes at line {line}, column {column} (byte {offset})")]
    NotUtf8 {
        /// Line of the first invalid byte, from 1.
        line: usize,
        /// Column (in bytes) of the first invalid byte, from 1.
        column: usize,
        /// Offset of the first invalid byte, from 0.
        offset: usize,
    },
}

/// A solve that did not produce an equilibrium. Never returned as NaN.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// Newton's method did not meet the tolerance.
    #[error(
        "Newton did not converge in {iterations} iterations (out-of-balance force {residual:.3e} N, last step {step:.3e} mm)"
    )]
    NotConverged {
        /// Iterations taken.
        iterations: u32,
        /// Final out-of-balance force, max over free DOFs \[N\].
        residual: f64,
        /// Size of the last step, max over free DOFs \[mm\].
        step: f64,
    },
    /// The tangent stiffness is singular: a mechanism in the deformed state.
    #[error("mechanism at iteration {iteration}: node {node:?} can move in {dof} freely")]
    Mechanism {
        /// Iteration at which it was found.
        iteration: u32,
        /// The node id.
        node: String,
        /// The direction, `x`, `y` or `z`.
        dof: char,
    },
    /// A number became NaN or infinite (for example a member collapsed to zero length).
    #[error("non-finite value at iteration {iteration}: {what}")]
    NonFinite {
        /// Iteration at which it appeared.
        iteration: u32,
        /// What became non-finite.
        what: String,
    },
    /// The per-sample input does not fit the model.
    #[error("bad input: {0}")]
    Input(String),
}

/// A number as an error message shows it: as Rust writes it (the shortest form that reads
/// back the same) for magnitudes from 10⁻⁴ to 10⁶, and zero; in e-notation beyond, so that
/// `1e308` is not written with 309 digits.
pub fn readable(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || !a.is_finite() || (1e-4..1e6).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
