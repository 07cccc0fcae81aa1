//! run-dir's integration tests, one binary.

mod manifest;
