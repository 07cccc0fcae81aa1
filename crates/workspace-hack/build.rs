//! Empty: cargo reads a package's build-dependencies (here, the proc-macro side's
//! unified features) only when it has a build script.
fn main() {}
