//! The feature unifier (cargo-hakari's workspace-hack): no code. Its Cargo.toml names the
//! third-party crates whose features differ between builds of different sets of the
//! workspace's crates, with the union of those features, and every crate depends on it, so
//! the release binaries, a crate's tests and the Python extension share their compiled
//! dependencies. Regenerate with `cargo hakari generate` after a dependency change; the
//! pipeline test `features` says when it is needed.
