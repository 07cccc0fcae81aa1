//! No doc comment holds a Rust example. Every library of the workspace sets `doctest = false`
//! (so a plain `cargo test` does not run rustdoc over 19 crates to find no tests: 23 s of a
//! warm run), which would leave a Rust example in a doc comment silently untested. This test
//! reads every crate's `src/` and fails, naming the file and line, on a fenced block in a
//! `///` or `//!` comment that rustdoc would compile: a fence with no language, `rust`, or
//! rustdoc's own attributes (`no_run`, `ignore`, `should_panic`, `compile_fail`, `edition…`).
//! Give such a block a language (`text`, `json`), or turn the crate's doc tests back on.

use std::path::{Path, PathBuf};

/// The lines (1-based) of the fences in `source` that open a block rustdoc would run
/// as a Rust doc test.
fn rust_examples(source: &str) -> Vec<usize> {
    let mut found = Vec::new();
    let mut open = false;
    for (n, line) in source.lines().enumerate() {
        let trimmed = line.trim_start();
        let Some(doc) = trimmed
            .strip_prefix("///")
            .or_else(|| trimmed.strip_prefix("//!"))
        else {
            continue;
        };
        let Some(info) = doc.trim_start().strip_prefix("```") else {
            continue;
        };
        if open {
            open = false;
            continue;
        }
        open = true;
        let words: Vec<&str> = info
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|w| !w.is_empty())
            .collect();
        let rust = words.is_empty()
            || words.iter().all(|w| {
                matches!(
                    *w,
                    "rust" | "no_run" | "ignore" | "should_panic" | "compile_fail" | "test_harness"
                ) || w.starts_with("edition")
            });
        if rust {
            found.push(n + 1);
        }
    }
    found
}

/// Every `.rs` file under `dir`.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn no_doc_comment_holds_a_rust_example() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let mut files = Vec::new();
    for e in std::fs::read_dir(workspace.join("crates")).unwrap() {
        sources(&e.unwrap().path().join("src"), &mut files);
    }
    sources(&workspace.join("tests/src"), &mut files);
    assert!(files.len() > 100, "read only {} files", files.len());
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for line in rust_examples(&text) {
            found.push(format!(
                "{}:{line}",
                f.strip_prefix(workspace).unwrap().display()
            ));
        }
    }
    assert!(
        found.is_empty(),
        "Rust examples in doc comments, which no test runs (doctest = false): give the block a \
         language (```text) or set the crate's doctest back to true:\n{}",
        found.join("\n")
    );
}

/// The reader tells a Rust example from a text block, on sources written here.
#[test]
fn the_reader_finds_a_rust_example() {
    let source = "//! ```text\n//! a = b\n//! ```\n/// ```\n/// let x = 1;\n/// ```\nfn f() {}\n\
                  /// ```json\n/// {}\n/// ```\n    /// ```no_run\n    /// g();\n    /// ```\n\
                  // ```\n/// ```rust,ignore\n/// h();\n/// ```\n";
    assert_eq!(rust_examples(source), [4, 11, 15]);
}
