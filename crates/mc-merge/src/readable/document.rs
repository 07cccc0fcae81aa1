//! The readable report as a document: headings, paragraphs, lists, tables and plots, with
//! their text already worded. [`super::compose()`] builds one from the report; the Markdown and
//! HTML writers render the same document, so `report.md` and `report.html` say the same
//! things in the same order. Text is plain: each writer escapes it for its own format.

/// The code point of a character that would act on the reader's display instead of
/// showing as itself, `U+XXXX`, for the writers to show in its place: a control character
/// (ESC from a forged shard header would colour or move a terminal's text; line breaks and
/// tabs excepted, which each writer handles), a bidirectional embedding, override, isolate or
/// mark (a case name could read backwards), a zero-width space, joiner or word joiner, a soft
/// hyphen or a byte-order mark (two names would look the same). `None` for any other
/// character.
pub fn hidden_code_point(c: char) -> Option<String> {
    let control = c.is_control() && !matches!(c, '\n' | '\r' | '\t');
    let format = matches!(
        c,
        '\u{00AD}'
            | '\u{061C}'
            | '\u{200B}'..='\u{200F}'
            | '\u{202A}'..='\u{202E}'
            | '\u{2060}'..='\u{2064}'
            | '\u{2066}'..='\u{2069}'
            | '\u{FEFF}'
    );
    (control || format).then(|| format!("U+{:04X}", c as u32))
}

/// A piece of running text.
#[derive(Debug, Clone, PartialEq)]
pub enum Span {
    /// Plain text.
    Text(String),
    /// Text to stand out (a verdict, the allowable σ).
    Strong(String),
    /// A name or number quoted as it is written in files (the job id, a case name).
    Code(String),
    /// A link to a place in the document ([`Block::Heading`]'s `anchor`).
    Anchor {
        /// The words linked.
        text: String,
        /// The anchor (letters, digits and `-` only).
        anchor: String,
    },
}

/// A paragraph or a list item: spans in a row.
pub type Line = Vec<Span>;

/// One table: a caption, column headers (with their units), and rows whose first cell names
/// the row (a case, a line fit).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// What the table shows, in a sentence.
    pub caption: String,
    /// Column headers, units in brackets.
    pub header: Vec<String>,
    /// The rows, each as long as `header`; the first cell is the row's header.
    pub rows: Vec<Vec<String>>,
}

/// A plot written beside the report.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// The SVG file's name in the report directory.
    pub svg: String,
    /// The PNG copy's name, when one was written.
    pub png: Option<String>,
    /// The plot in words, for readers who cannot see it (HTML `alt`, Markdown image text).
    pub alt: String,
    /// The caption shown under it.
    pub caption: String,
}

/// A block of the document, in reading order.
#[derive(Debug, Clone, PartialEq)]
pub enum Block {
    /// A heading of `level` 1 to 3; `anchor` lets the contents link to it.
    Heading {
        /// 1 (the title), 2 (a section) or 3 (a subsection).
        level: u8,
        /// The heading's words.
        text: String,
        /// Letters, digits and `-` only.
        anchor: String,
    },
    /// A paragraph.
    Paragraph(Line),
    /// A bulleted list.
    List(Vec<Line>),
    /// A table.
    Table(Table),
    /// A plot.
    Plot(Plot),
}

/// The whole readable report.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Document {
    /// The title (also the HTML page's title).
    pub title: String,
    /// The blocks, in reading order, the title heading first.
    pub blocks: Vec<Block>,
}

impl Document {
    /// Appends a heading.
    pub fn heading(&mut self, level: u8, text: impl Into<String>, anchor: impl Into<String>) {
        self.blocks.push(Block::Heading {
            level,
            text: text.into(),
            anchor: anchor.into(),
        });
    }

    /// Appends a paragraph of plain text.
    pub fn text(&mut self, text: impl Into<String>) {
        self.blocks
            .push(Block::Paragraph(vec![Span::Text(text.into())]));
    }

    /// Appends a paragraph of spans.
    pub fn paragraph(&mut self, line: Line) {
        self.blocks.push(Block::Paragraph(line));
    }

    /// Appends a list, unless it is empty.
    pub fn list(&mut self, items: Vec<Line>) {
        if !items.is_empty() {
            self.blocks.push(Block::List(items));
        }
    }

    /// Appends a table, unless it has no rows.
    pub fn table(&mut self, table: Table) {
        if !table.rows.is_empty() {
            self.blocks.push(Block::Table(table));
        }
    }

    /// The plots, in order.
    pub fn plots(&self) -> impl Iterator<Item = &Plot> {
        self.blocks.iter().filter_map(|b| match b {
            Block::Plot(p) => Some(p),
            _ => None,
        })
    }
}

/// Plain text as a span.
pub fn text(s: impl Into<String>) -> Span {
    Span::Text(s.into())
}

/// Emphasised text as a span.
pub fn strong(s: impl Into<String>) -> Span {
    Span::Strong(s.into())
}

/// Quoted text as a span.
pub fn code(s: impl Into<String>) -> Span {
    Span::Code(s.into())
}
