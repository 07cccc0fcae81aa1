//! Cross-crate pipeline tests live in `tests/tests/`.
