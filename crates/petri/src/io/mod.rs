//! Reading and writing nets: GreatSPN's PNPRO, ISO/IEC 15909-2 PNML, our own
//! TOML format, and DOT export.
//!
//! ```
//! use petri::io::{self, Format};
//!
//! let text = r#"
//! name = "mm1k"
//! [params]
//! lambda = 1.0
//! mu = 2.0
//! [[place]]
//! name = "free"
//! initial = 3
//! [[place]]
//! name = "busy"
//! [[transition]]
//! name = "arrive"
//! rate = "lambda"
//! inputs = ["free"]
//! outputs = ["busy"]
//! [[transition]]
//! name = "serve"
//! rate = "mu"
//! inputs = ["busy"]
//! outputs = ["free"]
//! "#;
//! let net = io::read_str(text, Format::Toml, "mm1k.toml")?;
//! assert_eq!(net.places.len(), 2);
//!
//! // Any net can be written in any format; TOML and PNML read back identically.
//! let pnml = io::write_string(&net, Format::Pnml)?;
//! assert_eq!(io::read_str(&pnml, Format::Pnml, "mm1k.pnml")?, net);
//! # Ok::<(), petri::Error>(())
//! ```
//!
//! # Formats
//!
//! | format | read | write | file extensions | module |
//! |---|---|---|---|---|
//! | GreatSPN editor project | yes | yes | `.pnpro` | [`pnpro`] |
//! | PNML, place/transition nets | yes | yes | `.pnml`, `.xml` | [`pnml`] |
//! | petrinav TOML | yes | yes | `.toml` | [`toml_format`] |
//! | Graphviz DOT | no | yes | `.dot`, `.gv` | [`dot`] |
//!
//! Storm's DRN format holds state spaces, not nets (Markov chains, MDPs,
//! Markov automata): [`drn`] reads and writes [`crate::mdp::Model`]s.
//!
//! Each module documents what its format holds, the defaults applied when an
//! attribute is absent, and what is refused. In short:
//!
//! - **TOML** holds everything a [`Net`] holds; `read(write(net)) == net`.
//! - **PNML** holds everything too: standard P/T content plus one documented
//!   `<toolspecific tool="petrinav">` form for rates, weights, priorities,
//!   servers, expressions, capacities, documentation and parameters;
//!   `read(write(net)) == net`.
//! - **PNPRO** holds everything except capacities (refused when writing),
//!   documentation, values suggested for parameters that have a value, k = 1
//!   servers (read back as a single server) and a missing rate (GreatSPN's
//!   default rate 1 is read back).
//!
//! # Decisions common to all readers
//!
//! - Every reader ends with [`Net::validate`]; names are unique across places
//!   and transitions, and parameter names are unique too.
//! - **Arc order.** Readers return arcs in a canonical order (see
//!   [`sort_arcs`]): by transition, then input, output, inhibitor, then by
//!   place; arcs that tie keep their order in the file. The order of arcs in a
//!   file carries no meaning, and the canonical order is what lets every
//!   format read back exactly the net it wrote.
//! - Parallel arcs (same place, transition and kind) are kept as they are;
//!   [`Gspn`](crate::Gspn) merges them.
//! - Errors carry a `file:line:column` location wherever the format has one,
//!   and name the element and attribute at fault. Bad input never panics.
//! - A leading byte-order mark is skipped; an empty file is an error.
//! - Expressions in files are limited to [`MAX_EXPRESSION_CHARS`] characters
//!   and [`crate::expr::MAX_DEPTH`] nested parentheses, so that a file cannot
//!   exhaust the stack of the (recursive) expression parser.

use std::fmt;
use std::path::Path;

use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::net::Net;

pub mod dot;
pub mod drn;
pub mod pnml;
pub mod pnpro;
pub mod toml_format;
mod toml_split;
mod xml_split;

pub use dot::{write_dot, write_reachability_dot, write_tangible_dot};
pub use pnml::{read_pnml, write_pnml};
pub use pnpro::{read_pnpro, read_pnpro_named, write_pnpro};
pub use toml_format::{read_toml, write_toml};

/// A file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// GreatSPN editor project (`.pnpro`), also read and written by Storm.
    Pnpro,
    /// ISO/IEC 15909-2 PNML place/transition net (`.pnml`, `.xml`).
    Pnml,
    /// petrinav's own TOML format (`.toml`).
    Toml,
    /// Graphviz DOT (`.dot`, `.gv`); write only.
    Dot,
}

impl Format {
    /// Every format.
    pub const ALL: [Format; 4] = [Format::Pnpro, Format::Pnml, Format::Toml, Format::Dot];

    /// The format a file name's extension says (case-insensitive): `.pnpro`,
    /// `.pnml` or `.xml`, `.toml`, `.dot` or `.gv`.
    pub fn from_path(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        match ext.as_str() {
            "pnpro" => Ok(Format::Pnpro),
            "pnml" | "xml" => Ok(Format::Pnml),
            "toml" => Ok(Format::Toml),
            "dot" | "gv" => Ok(Format::Dot),
            _ => Err(Error::UnknownFormat { path: path.into() }),
        }
    }

    /// A short lower-case name: `pnpro`, `pnml`, `toml`, `dot`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Pnpro => "pnpro",
            Format::Pnml => "pnml",
            Format::Toml => "toml",
            Format::Dot => "dot",
        }
    }

    /// The usual file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Pnpro => "PNPRO",
            Format::Pnml => "pnml",
            Format::Toml => "toml",
            Format::Dot => "dot",
        }
    }

    /// Whether nets can be read from this format (all but DOT).
    pub fn can_read(self) -> bool {
        !matches!(self, Format::Dot)
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Memory reading a net takes per byte of its file, at most: the text, the
/// parser's structures (one item at a time for TOML, the document tree
/// for XML) and the net. Measured on 50 MB files of each format
/// (`crates/petri/BENCHMARKS.md`, "Reading large files"); [`read_file`]
/// checks a file's size against the memory guard with it before reading.
pub const READ_BYTES_PER_FILE_BYTE: u64 = 10;

/// Reads a net from a file, in the format its extension says, if reading
/// it fits the default memory guard ([`read_file_within`] with
/// [`crate::default_max_memory`]).
pub fn read_file(path: impl AsRef<Path>) -> Result<Net> {
    read_file_within(path, crate::default_max_memory())
}

/// Reads a net from a file, in the format its extension says; a file
/// whose reading would take more than `max_memory` bytes
/// ([`READ_BYTES_PER_FILE_BYTE`] per byte) is refused before it is read
/// ([`Error::FileTooLarge`]).
pub fn read_file_within(path: impl AsRef<Path>, max_memory: u64) -> Result<Net> {
    let path = path.as_ref();
    let format = Format::from_path(path)?;
    if !format.can_read() {
        return Err(dot_not_readable(&path.display().to_string()));
    }
    let io = |source| Error::Io {
        path: path.into(),
        source,
    };
    let bytes = std::fs::metadata(path).map_err(io)?.len();
    let needed = bytes.saturating_mul(READ_BYTES_PER_FILE_BYTE);
    if needed > max_memory {
        return Err(Error::FileTooLarge {
            path: path.into(),
            bytes,
            needed,
            limit: max_memory,
        });
    }
    let text = std::fs::read_to_string(path).map_err(io)?;
    read_str(&text, format, &path.display().to_string())
}

/// Reads a net from text. `source_name` (a file name, or e.g. `<stdin>`) is
/// used in error locations and, when the file does not name the net, for its
/// name (the file stem).
pub fn read_str(text: &str, format: Format, source_name: &str) -> Result<Net> {
    match format {
        Format::Pnpro => read_pnpro(text, source_name),
        Format::Pnml => read_pnml(text, source_name),
        Format::Toml => read_toml(text, source_name),
        Format::Dot => Err(dot_not_readable(source_name)),
    }
}

/// Writes a net as text in `format`.
pub fn write_string(net: &Net, format: Format) -> Result<String> {
    match format {
        Format::Pnpro => write_pnpro(net),
        Format::Pnml => write_pnml(net),
        Format::Toml => write_toml(net),
        Format::Dot => write_dot(net),
    }
}

/// Writes a net to a file, in the format its extension says.
pub fn write_file(net: &Net, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    let text = write_string(net, Format::from_path(path)?)?;
    std::fs::write(path, text).map_err(|source| Error::Io {
        path: path.into(),
        source,
    })
}

/// Puts the arcs in the canonical order the readers return: by transition,
/// then input before output before inhibitor, then by place. The sort is
/// stable, so arcs that tie (parallel arcs) keep their relative order.
///
/// Round trips through any format are exact for nets whose arcs are in this
/// order; sort a net built by hand before comparing it with one read back.
pub fn sort_arcs(net: &mut Net) {
    net.arcs.sort_by_key(|a| (a.transition, a.kind, a.place));
}

fn dot_not_readable(source: &str) -> Error {
    Error::Format {
        location: source.to_string(),
        message: "DOT is an export format only and cannot be read; read the net from .pnpro, .pnml or .toml"
            .into(),
    }
}

// ---------------------------------------------------------------------------
// Helpers shared by the readers and writers.
// ---------------------------------------------------------------------------

/// Skips a byte-order mark and refuses empty text.
fn prepare<'a>(text: &'a str, source: &str) -> Result<&'a str> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim().is_empty() {
        return Err(Error::Format {
            location: source.to_string(),
            message: "the file is empty".into(),
        });
    }
    Ok(text)
}

/// Sorts the arcs and validates: the last step of every reader.
fn finish(mut net: Net) -> Result<Net> {
    sort_arcs(&mut net);
    check_param_names(&net)?;
    net.validate()?;
    Ok(net)
}

/// Parameter names must be unique among themselves ([`Net::validate`]
/// checks them against place and transition names only).
fn check_param_names(net: &Net) -> Result<()> {
    let mut seen = std::collections::BTreeSet::new();
    for p in &net.params {
        if p.name.is_empty() {
            return Err(Error::Invalid("a parameter has an empty name".into()));
        }
        if !seen.insert(p.name.as_str()) {
            return Err(Error::DuplicateName {
                name: p.name.clone(),
                first: "a parameter",
                second: "a parameter",
            });
        }
    }
    Ok(())
}

/// The net name to use when the file gives none: the stem of the source
/// name, or `net`.
fn default_net_name(source: &str) -> String {
    Path::new(source)
        .file_stem()
        .and_then(|s| s.to_str())
        .filter(|s| !s.is_empty())
        .unwrap_or("net")
        .to_string()
}

/// 1-based line and column (counted in characters) of byte `offset`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = before[line_start..].chars().count() + 1;
    (line, col)
}

/// `source:line:column` of byte `offset` of `text`.
fn location_at(source: &str, text: &str, offset: usize) -> String {
    let (line, col) = line_col(text, offset);
    format!("{source}:{line}:{col}")
}

/// Where an XML node starts in its document.
fn xml_pos(node: roxmltree::Node<'_, '_>) -> roxmltree::TextPos {
    node.document().text_pos_at(node.range().start)
}

/// Where an attribute's value starts in its document, or its element when
/// the attribute is absent.
fn attr_pos(node: roxmltree::Node<'_, '_>, attr: &str) -> roxmltree::TextPos {
    match node.attribute_node(attr) {
        Some(a) => node.document().text_pos_at(a.range_value().start),
        None => xml_pos(node),
    }
}

/// `source:line:column` of a position in a document: the whole file's, or
/// the fragment `base` of it ([`xml_split`]).
fn located(source: &str, pos: roxmltree::TextPos, base: Option<&xml_split::Fragment>) -> String {
    let (row, col) = base.map_or((pos.row, pos.col), |f| f.place(pos.row, pos.col));
    format!("{source}:{row}:{col}")
}

/// Parses one fragment of a cut XML text ([`xml_split`]) on its own; an
/// error's position is placed in the whole file.
fn parse_fragment<'a>(
    text: &'a str,
    fragment: &xml_split::Fragment,
    source: &str,
) -> Result<roxmltree::Document<'a>> {
    let piece = &text[fragment.range.clone()];
    roxmltree::Document::parse(piece).map_err(|e| {
        let pos = match e {
            roxmltree::Error::UnexpectedEndOfStream | roxmltree::Error::UnclosedRootNode => {
                let (row, col) = line_col(piece, piece.len());
                roxmltree::TextPos::new(row as u32, col as u32)
            }
            _ => e.pos(),
        };
        let message = e.to_string();
        let suffix = format!(" at {}", e.pos());
        let message = message.strip_suffix(&suffix).unwrap_or(&message).to_string();
        Error::Xml {
            location: located(source, pos, Some(fragment)),
            message,
        }
    })
}

/// Parses XML, turning the parser's error into [`Error::Xml`] with its
/// position.
fn parse_xml<'a>(text: &'a str, source: &str) -> Result<roxmltree::Document<'a>> {
    roxmltree::Document::parse(text).map_err(|e| {
        let (location, message) = match e {
            // Errors without a position of their own: point at the end.
            roxmltree::Error::UnexpectedEndOfStream | roxmltree::Error::UnclosedRootNode => {
                (location_at(source, text, text.len()), e.to_string())
            }
            _ => {
                let pos = e.pos();
                let message = e.to_string();
                let suffix = format!(" at {pos}");
                let message = message.strip_suffix(&suffix).unwrap_or(&message).to_string();
                (format!("{source}:{}:{}", pos.row, pos.col), message)
            }
        };
        Error::Xml { location, message }
    })
}

/// The longest expression a file may hold, in characters.
pub const MAX_EXPRESSION_CHARS: usize = 2000;
/// Why an expression is too long to accept from a file, if it is (nesting
/// depth is limited by the parser itself).
fn too_big(text: &str) -> Option<String> {
    (text.chars().count() > MAX_EXPRESSION_CHARS)
        .then(|| format!("the expression is longer than {MAX_EXPRESSION_CHARS} characters"))
}

/// Parses an expression found in a file; `what` names the element and
/// attribute for the error message. Expressions longer than
/// [`MAX_EXPRESSION_CHARS`] or nested deeper than [`crate::expr::MAX_DEPTH`]
/// are refused.
fn parse_expr(text: &str, location: impl FnOnce() -> String, what: impl FnOnce() -> String) -> Result<Expr> {
    if let Some(message) = too_big(text) {
        return Err(Error::Format {
            location: location(),
            message: format!("{}: {message}", what()),
        });
    }
    Expr::parse(text).map_err(|e| Error::Format {
        location: location(),
        message: format!("{}: {e}", what()),
    })
}

/// Appends `s` escaped for XML text (`attribute = false`) or a double-quoted
/// attribute value. Characters XML 1.0 cannot hold are an error naming
/// `what`.
fn push_xml_escaped(out: &mut String, s: &str, attribute: bool, what: &dyn Fn() -> String) -> Result<()> {
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' if attribute => out.push_str("&quot;"),
            '\n' if attribute => out.push_str("&#10;"),
            '\t' if attribute => out.push_str("&#9;"),
            '\r' => out.push_str("&#13;"),
            '\n' | '\t' => out.push(c),
            c if (c as u32) < 0x20 || c == '\u{fffe}' || c == '\u{ffff}' => {
                return Err(Error::Invalid(format!(
                    "{} contains the character U+{:04X}, which XML cannot represent",
                    what(),
                    c as u32
                )));
            }
            c => out.push(c),
        }
    }
    Ok(())
}

/// Appends ` name="value"` with the value escaped.
fn push_attr(out: &mut String, name: &str, value: &str, what: &dyn Fn() -> String) -> Result<()> {
    out.push(' ');
    out.push_str(name);
    out.push_str("=\"");
    push_xml_escaped(out, value, true, what)?;
    out.push('"');
    Ok(())
}

/// A number written so that it parses back to the same `f64` (integers
/// without a fraction).
fn fmt_f64(v: f64) -> String {
    crate::expr::fmt_number(v)
}

/// Parses a coordinate or other plain number.
fn parse_f64(text: &str) -> Option<f64> {
    text.trim().parse::<f64>().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_from_extension_is_case_insensitive() {
        let f = |p: &str| Format::from_path(Path::new(p));
        assert_eq!(f("a/FMS.PNPRO").unwrap(), Format::Pnpro);
        assert_eq!(f("x.pnml").unwrap(), Format::Pnml);
        assert_eq!(f("x.XML").unwrap(), Format::Pnml);
        assert_eq!(f("x.toml").unwrap(), Format::Toml);
        assert_eq!(f("x.gv").unwrap(), Format::Dot);
        assert_eq!(f("x.Dot").unwrap(), Format::Dot);
        assert!(matches!(f("x.net"), Err(Error::UnknownFormat { .. })));
        assert!(matches!(f("noext"), Err(Error::UnknownFormat { .. })));
    }

    #[test]
    fn dot_cannot_be_read() {
        let err = read_str("digraph {}", Format::Dot, "a.dot").unwrap_err();
        assert!(err.to_string().contains("export format only"), "{err}");
        assert!(
            read_file("/nonexistent/a.dot")
                .unwrap_err()
                .to_string()
                .contains("DOT")
        );
    }

    #[test]
    fn line_and_column_count_characters() {
        let t = "ab\ncdé\nf";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 3), (2, 1));
        assert_eq!(line_col(t, 7), (2, 4));
        // Inside a multi-byte character, and past the end: no panic.
        assert_eq!(line_col(t, 6), (2, 3));
        assert_eq!(line_col(t, 100), (3, 2));
    }

    #[test]
    fn xml_escaping() {
        let mut s = String::new();
        let what = || "x".to_string();
        push_xml_escaped(&mut s, "a<b>&\"c\"\n\t\r", true, &what).unwrap();
        assert_eq!(s, "a&lt;b&gt;&amp;&quot;c&quot;&#10;&#9;&#13;");
        let mut s = String::new();
        push_xml_escaped(&mut s, "a\"\nb", false, &what).unwrap();
        assert_eq!(s, "a\"\nb");
        assert!(push_xml_escaped(&mut s, "bell\u{7}", false, &what).is_err());
    }

    #[test]
    fn huge_expressions_are_refused_before_parsing() {
        let loc = || "f:1:1".to_string();
        let what = || "x".to_string();
        let deep = format!("{}1{}", "(".repeat(500), ")".repeat(500));
        let err = parse_expr(&deep, loc, what).unwrap_err().to_string();
        assert!(err.contains("nested more than 64 levels"), "{err}");
        let long = "-".repeat(100_000) + "1";
        let err = parse_expr(&long, loc, what).unwrap_err().to_string();
        assert!(err.contains("longer than 2000"), "{err}");
        let ok = format!("{}1{}", "(".repeat(64), ")".repeat(64));
        assert_eq!(parse_expr(&ok, loc, what).unwrap(), Expr::Num(1.0));
    }

    #[test]
    fn default_names() {
        assert_eq!(default_net_name("models/supervisor.toml"), "supervisor");
        assert_eq!(default_net_name(""), "net");
    }

    #[test]
    fn empty_text_is_refused() {
        for f in [Format::Pnpro, Format::Pnml, Format::Toml] {
            let err = read_str("\u{feff}  \n", f, "e").unwrap_err();
            assert!(err.to_string().contains("empty"), "{err}");
        }
    }
}
