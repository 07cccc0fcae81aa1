//! `report.md`: the [`Document`] as CommonMark with GitHub's tables. Text is escaped, so a
//! case name such as `a*b|c` or `<σ>` reads as written and never breaks a table or starts
//! emphasis; plots are images linked by their file names in the report directory, so the
//! file reads with its plots wherever the directory is viewed (a repository, a wiki, an
//! editor's preview).

use super::document::{Block, Document, Line, Plot, Span, Table, hidden_code_point};

/// The document as Markdown.
pub fn markdown(doc: &Document) -> String {
    let mut m = String::new();
    for block in &doc.blocks {
        match block {
            Block::Heading { level, text, .. } => {
                m.push_str(&"#".repeat(usize::from((*level).clamp(1, 6))));
                m.push(' ');
                m.push_str(&escape(text));
                m.push_str("\n\n");
            }
            Block::Paragraph(line) => {
                m.push_str(&spans(line));
                m.push_str("\n\n");
            }
            Block::List(items) => {
                for item in items {
                    m.push_str("- ");
                    m.push_str(&spans(item));
                    m.push('\n');
                }
                m.push('\n');
            }
            Block::Table(t) => table(&mut m, t),
            Block::Plot(p) => plot(&mut m, p),
        }
    }
    m.truncate(m.trim_end().len());
    m.push('\n');
    m
}

fn spans(line: &Line) -> String {
    line.iter()
        .map(|s| match s {
            Span::Text(t) => escape(t),
            Span::Strong(t) => format!("**{}**", escape(t)),
            Span::Code(t) => code(t),
            Span::Anchor { text, .. } => format!("[{}](#{})", escape_label(text), slug(text)),
        })
        .collect()
}

fn table(m: &mut String, t: &Table) {
    m.push_str(&format!("*{}*\n\n", escape(&t.caption)));
    let row = |cells: &[String]| {
        let cells: Vec<String> = cells.iter().map(|c| escape(c)).collect();
        format!("| {} |\n", cells.join(" | "))
    };
    m.push_str(&row(&t.header));
    m.push_str(&format!("|{}\n", "---|".repeat(t.header.len())));
    for r in &t.rows {
        m.push_str(&row(r));
    }
    m.push('\n');
}

fn plot(m: &mut String, p: &Plot) {
    m.push_str(&format!("![{}]({})\n\n", escape_label(&p.alt), url(&p.svg)));
    let mut files = format!("[{}]({})", code(&p.svg), url(&p.svg));
    if let Some(png) = &p.png {
        files.push_str(&format!(", [{}]({})", code(png), url(png)));
    }
    m.push_str(&format!("*{}* ({files})\n\n", escape(&p.caption)));
}

/// Plain text escaped for Markdown: every character that could start markup is
/// backslash-escaped (an underscore only where it could, not inside a word such as `θ_P`; a
/// closing bracket only where a link could follow, so `[rad]` stays as it is), a line
/// break becomes a space, a bare URL (`https://…`, `www.…`) is kept from being linked, and
/// a character that would act on the display (ESC, a
/// bidirectional override, a zero-width space: [`hidden_code_point`]) is shown as
/// `[U+XXXX]`.
pub fn escape(s: &str) -> String {
    escape_with(s, false)
}

/// Text escaped for a link's or an image's words, where any bracket would end them: like
/// [`escape`], with every bracket escaped.
pub fn escape_label(s: &str) -> String {
    escape_with(s, true)
}

fn escape_with(s: &str, brackets: bool) -> String {
    let chars: Vec<char> = s.chars().collect();
    let mut out = String::with_capacity(s.len());
    for (k, &c) in chars.iter().enumerate() {
        let word = |j: Option<usize>| {
            j.and_then(|j| chars.get(j))
                .is_some_and(|c| c.is_alphanumeric())
        };
        if let Some(code_point) = hidden_code_point(c) {
            out.push_str(&format!("\\[{code_point}\\]"));
            continue;
        }
        match c {
            '\\' | '`' | '*' | '<' | '>' | '|' | '#' | '&' | '~' | '$' => {
                out.push('\\');
                out.push(c);
            }
            '[' | ']' if brackets => {
                out.push('\\');
                out.push(c);
            }
            // A bracket starts a link only if `(`, `[` or `:` follows its closing one.
            ']' if chars.get(k + 1).is_some_and(|n| "([:".contains(*n)) => out.push_str("\\]"),
            '_' if !(word(k.checked_sub(1)) && word(Some(k + 1))) => out.push_str("\\_"),
            '\n' | '\r' => out.push(' '),
            // GitHub links a bare `scheme://…` or `www.…` by itself: escaped, neither is.
            ':' if chars.get(k + 1..k + 3) == Some(&['/', '/']) => out.push_str("\\:"),
            '.' if k >= 3
                && chars[k - 3..k]
                    .iter()
                    .collect::<String>()
                    .eq_ignore_ascii_case("www") =>
            {
                out.push_str("\\.")
            }
            _ => out.push(c),
        }
    }
    out
}

/// A code span that holds `s` whatever backticks it contains.
fn code(s: &str) -> String {
    let s: String = s
        .chars()
        .map(|c| match hidden_code_point(c) {
            Some(code_point) => format!("[{code_point}]"),
            None if matches!(c, '\n' | '\r') => " ".into(),
            None => c.into(),
        })
        .collect();
    let longest = s.split(|c| c != '`').map(str::len).max().unwrap_or(0);
    let fence = "`".repeat(longest + 1);
    let pad = if s.starts_with('`') || s.ends_with('`') || s.starts_with(' ') {
        " "
    } else {
        ""
    };
    format!("{fence}{pad}{s}{pad}{fence}")
}

/// A file name as a link destination: characters other than ASCII letters, digits and
/// `.-_~` percent-encoded.
fn url(name: &str) -> String {
    let mut out = String::new();
    for b in name.bytes() {
        if b.is_ascii_alphanumeric() || b"._-~".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// The anchor that GitHub, GitLab and most Markdown viewers give a heading: lower case,
/// punctuation but `-` and `_` dropped, spaces as `-`.
pub fn slug(heading: &str) -> String {
    heading
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::readable::document::{code as code_span, text};

    #[test]
    fn text_is_escaped_but_words_stay_readable() {
        assert_eq!(escape("θ_P95 [rad]"), "θ_P95 [rad]");
        assert_eq!(escape("[a](b) [c][d] [e]: f"), "[a\\](b) [c\\][d] [e\\]: f");
        assert_eq!(
            escape("a*b|c <σ> _x_ #1 & ~"),
            "a\\*b\\|c \\<σ\\> \\_x\\_ \\#1 \\& \\~"
        );
        assert_eq!(escape("two\nlines"), "two lines");
        assert_eq!(
            escape("a\u{1b}[31mb\u{202e}c\u{200b}d"),
            "a\\[U+001B\\][31mb\\[U+202E\\]c\\[U+200B\\]d"
        );
        assert_eq!(code("x\u{1b}y"), "`x[U+001B]y`");
        assert_eq!(escape("https://x.org"), "https\\://x.org");
        assert_eq!(escape("WWW.x.org a.b"), "WWW\\.x.org a.b");
        assert_eq!(escape_label("a ] b [c]"), "a \\] b \\[c\\]");
        assert_eq!(code("a`b"), "``a`b``");
        assert_eq!(code("`x"), "`` `x ``");
        assert_eq!(url("theta_p-a b~1.svg"), "theta_p-a%20b~1.svg");
        assert_eq!(
            slug("Sweeps over σ and the allowable σ"),
            "sweeps-over-σ-and-the-allowable-σ"
        );
        assert_eq!(slug("Percentiles of θ_P"), "percentiles-of-θ_p");
    }

    #[test]
    fn a_table_cell_cannot_break_its_row() {
        let doc = Document {
            title: "t".into(),
            blocks: vec![
                Block::Table(Table {
                    caption: "c".into(),
                    header: vec!["case".into(), "x".into()],
                    rows: vec![vec!["a|b".into(), "1".into()]],
                }),
                Block::Paragraph(vec![text("see "), code_span("a|b")]),
            ],
        };
        let m = markdown(&doc);
        let row = m.lines().find(|l| l.contains("a\\|b")).unwrap();
        // Three unescaped pipes: the row has two cells.
        assert_eq!(row.replace("\\|", "").matches('|').count(), 3, "{m}");
        assert!(m.ends_with("see `a|b`\n"), "{m}");
    }
}
