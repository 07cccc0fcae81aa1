//! The `truss` binary's tests, in one binary: its commands ([`cli`]) and its refusals of
//! hostile or meaningless input ([`limits`]).

mod cli;
mod files;
mod limits;

use std::process::Command;

/// Runs `truss` with `args`.
pub fn truss(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_truss"))
        .args(args)
        .output()
        .unwrap()
}

/// The JSON `truss` printed.
pub fn json(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(&out.stdout)))
}
