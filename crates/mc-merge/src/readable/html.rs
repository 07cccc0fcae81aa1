//! `report.html`: the [`Document`] as one self-contained HTML page to mail or put on a wiki.
//!
//! - **Self-contained.** The style sheet is inlined, and each plot's SVG is inlined as a
//!   `data:image/svg+xml` URI in an `<img>` (percent-encoded, about 9 % larger than the
//!   file; base64 would add a third). The page names no other file and no network address,
//!   and says so to the browser: its Content-Security-Policy (`default-src 'none'`) allows
//!   only inline styles and `data:` images, so even a plot with a script in it could run
//!   nothing and fetch nothing. There is no JavaScript.
//! - **Accessible.** `lang`, a `<title>`, headings in order (one `<h1>`), tables with a
//!   `<caption>`, column headers (`scope="col"`) and row headers (`scope="row"`), every image
//!   with alternative text that carries its message and numbers, sizes given so the page
//!   does not jump while it loads, and internal links for the contents.
//! - **Readable and printable.** Sans-serif text of a comfortable measure, numbers in
//!   tabular figures aligned right, wide tables scrolling on their own rather than the page;
//!   printed, the page drops its margins and link colours and keeps tables, rows and plots
//!   from splitting across pages.
//!
//! Every text is HTML-escaped (`&`, `<`, `>`, `"`, `'`), so a case named
//! `<script>alert(1)</script>` is shown as written; in running text, headers and captions
//! θ_P, θ_x, θ_y and σ_t are set with subscripts, as in the plots.

use super::document::{Block, Document, Line, Plot, Span, Table, hidden_code_point};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The page's style sheet.
const STYLE: &str = include_str!("report.css");

/// What the page may load: nothing but its own styles and `data:` images.
pub const CONTENT_SECURITY_POLICY: &str =
    "default-src 'none'; img-src data:; style-src 'unsafe-inline'";

/// The document as one HTML page; `svgs` holds each plot's SVG file by name.
pub fn html(doc: &Document, svgs: &BTreeMap<String, Vec<u8>>) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta http-equiv=\"Content-Security-Policy\" content=\"{CONTENT_SECURITY_POLICY}\">\n\
         <title>{}</title>\n<style>\n{STYLE}</style>\n</head>\n<body>\n<main>\n",
        escape(&doc.title)
    );
    for block in &doc.blocks {
        match block {
            Block::Heading {
                level,
                text,
                anchor,
            } => {
                let l = (*level).clamp(1, 6);
                let _ = writeln!(
                    h,
                    "<h{l} id=\"{}\">{}</h{l}>",
                    escape(anchor),
                    content(text)
                );
            }
            Block::Paragraph(line) => {
                let _ = writeln!(h, "<p>{}</p>", spans(line));
            }
            Block::List(items) => {
                h.push_str("<ul>\n");
                for item in items {
                    let _ = writeln!(h, "<li>{}</li>", spans(item));
                }
                h.push_str("</ul>\n");
            }
            Block::Table(t) => table(&mut h, t),
            Block::Plot(p) => plot(&mut h, p, svgs.get(&p.svg).map(Vec::as_slice)),
        }
    }
    h.push_str("</main>\n</body>\n</html>\n");
    h
}

fn spans(line: &Line) -> String {
    line.iter()
        .map(|s| match s {
            Span::Text(t) => content(t),
            Span::Strong(t) => format!("<strong>{}</strong>", content(t)),
            Span::Code(t) => format!("<code>{}</code>", escape(t)),
            Span::Anchor { text, anchor } => {
                format!("<a href=\"#{}\">{}</a>", escape(anchor), content(text))
            }
        })
        .collect()
}

/// Whether a cell holds a number (aligned right) rather than words.
fn numeric(cell: &str) -> bool {
    cell.chars()
        .next()
        .is_some_and(|c| c.is_ascii_digit() || "[+−-—".contains(c))
}

fn table(h: &mut String, t: &Table) {
    let _ = write!(
        h,
        "<div class=\"table\" role=\"region\" aria-label=\"{}\" tabindex=\"0\">\n<table>\n<caption>{}</caption>\n<thead>\n<tr>",
        escape(&t.caption),
        content(&t.caption)
    );
    for c in &t.header {
        let _ = write!(h, "<th scope=\"col\">{}</th>", content(c));
    }
    h.push_str("</tr>\n</thead>\n<tbody>\n");
    for row in &t.rows {
        h.push_str("<tr>");
        for (k, c) in row.iter().enumerate() {
            if k == 0 {
                let _ = write!(h, "<th scope=\"row\">{}</th>", escape(c));
            } else if numeric(c) {
                let _ = write!(h, "<td class=\"num\">{}</td>", escape(c));
            } else {
                let _ = write!(h, "<td>{}</td>", escape(c));
            }
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody>\n</table>\n</div>\n");
}

fn plot(h: &mut String, p: &Plot, svg: Option<&[u8]>) {
    h.push_str("<figure>\n");
    match svg {
        Some(svg) => {
            let size = svg_size(svg)
                .map(|(w, ht)| format!(" width=\"{w}\" height=\"{ht}\""))
                .unwrap_or_default();
            let _ = writeln!(
                h,
                "<img src='{}' alt=\"{}\"{size}>",
                data_uri(svg),
                escape(&p.alt)
            );
        }
        None => {
            let _ = writeln!(h, "<p class=\"missing\">{}</p>", escape(&p.alt));
        }
    }
    let mut files = escape(&p.svg);
    if let Some(png) = &p.png {
        files.push_str(", ");
        files.push_str(&escape(png));
    }
    let _ = writeln!(
        h,
        "<figcaption>{} <span class=\"files\">(beside this report: {files})</span></figcaption>\n</figure>",
        content(&p.caption)
    );
}

/// Text for an element's content: escaped, and the subscripts of θ_P, θ_x, θ_y and σ_t
/// (a Greek letter, `_`, then letters and digits) set as `<sub>`, as the plots set them.
pub fn content(s: &str) -> String {
    let chars: Vec<char> = s.chars().collect();
    let mut out = String::with_capacity(s.len());
    let mut k = 0;
    while k < chars.len() {
        let c = chars[k];
        let run = chars[(k + 2).min(chars.len())..]
            .iter()
            .take_while(|c| c.is_ascii_alphanumeric())
            .count();
        if matches!(c, 'θ' | 'σ') && chars.get(k + 1) == Some(&'_') && run > 0 {
            out.push(c);
            out.push_str("<sub>");
            out.extend(&chars[k + 2..k + 2 + run]);
            out.push_str("</sub>");
            k += 2 + run;
        } else {
            out.push_str(&escape(c.encode_utf8(&mut [0; 4])));
            k += 1;
        }
    }
    out
}

/// Text escaped for HTML content and attribute values; a character that would act on the
/// display (ESC, a bidirectional override, a zero-width space: [`hidden_code_point`]) is
/// shown as `[U+XXXX]`.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if let Some(code_point) = hidden_code_point(c) {
            let _ = write!(out, "[{code_point}]");
            continue;
        }
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// An SVG as a `data:` URI for a single-quoted attribute: bytes that a URL or the attribute
/// could misread (`%`, `#`, `<`, `>`, `&`, `'`, `` ` ``, `\`, controls, non-ASCII)
/// percent-encoded, the rest (spaces, double quotes) as they are.
pub fn data_uri(svg: &[u8]) -> String {
    let mut out = String::with_capacity(svg.len() + svg.len() / 8 + 24);
    out.push_str("data:image/svg+xml,");
    for &b in svg {
        let plain = (0x20..0x7f).contains(&b) && !b"%#<>&'`\\".contains(&b);
        if plain {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

/// The `width` and `height` of the SVG's root element, in pixels, when plain integers.
pub fn svg_size(svg: &[u8]) -> Option<(u32, u32)> {
    let head = &svg[..svg.len().min(512)];
    let head = std::str::from_utf8(head).ok().or_else(|| {
        // Cut inside a character: read up to the last whole one.
        let valid = std::str::from_utf8(head).err()?.valid_up_to();
        std::str::from_utf8(&head[..valid]).ok()
    })?;
    let root = &head[head.find("<svg")?..];
    let root = &root[..root.find('>')?];
    let attribute = |name: &str| -> Option<u32> {
        let at = root.find(&format!(" {name}=\""))? + name.len() + 3;
        root[at..].split('"').next()?.parse().ok()
    };
    Some((attribute("width")?, attribute("height")?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_and_plots_are_escaped() {
        assert_eq!(
            escape("<script>alert('x')</script> & \"y\""),
            "&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; &quot;y&quot;"
        );
        assert_eq!(
            escape("a\u{1b}b\u{202e}c\u{2066}d\u{feff}"),
            "a[U+001B]b[U+202E]c[U+2066]d[U+FEFF]"
        );
        let svg = "<svg width=\"960\" height=\"780\" xmlns=\"http://www.w3.org/2000/svg\"><text>θ #1 50% a'b &amp;</text></svg>\n";
        let uri = data_uri(svg.as_bytes());
        assert!(
            uri.starts_with("data:image/svg+xml,%3Csvg width=\"960\""),
            "{uri}"
        );
        assert!(uri.contains("%CE%B8 %231 50%25 a%27b %26amp;"), "{uri}");
        assert!(!uri.contains(['\'', '<', '>', '#', '\n']), "{uri}");
        assert_eq!(svg_size(svg.as_bytes()), Some((960, 780)));
        assert_eq!(svg_size(b"<svg viewBox=\"0 0 1 1\">"), None);
        assert_eq!(
            content("θ_P95 of <a_b>, σ_t², θ_x; θ_ alone"),
            "θ<sub>P95</sub> of &lt;a_b&gt;, σ<sub>t</sub>², θ<sub>x</sub>; θ_ alone"
        );
    }

    /// Decoding the URI gives the SVG's bytes back.
    #[test]
    fn the_data_uri_round_trips() {
        let svg: Vec<u8> = (0..=255u8).chain("<svg>µ</svg>".bytes()).collect();
        let uri = data_uri(&svg);
        let body = uri.strip_prefix("data:image/svg+xml,").unwrap().as_bytes();
        let mut back = vec![];
        let mut k = 0;
        while k < body.len() {
            if body[k] == b'%' {
                let hex = std::str::from_utf8(&body[k + 1..k + 3]).unwrap();
                back.push(u8::from_str_radix(hex, 16).unwrap());
                k += 3;
            } else {
                back.push(body[k]);
                k += 1;
            }
        }
        assert_eq!(back, svg);
    }
}
