//! An XML net cut into a skeleton and fragments, so that a reader builds
//! the document tree of one place, transition or arc at a time: the tree
//! of a whole 50 MB PNPRO file took 8.7 times the file's size before the
//! net was built at all.
//!
//! The elements directly inside a *container* (PNPRO's `<nodes>` and
//! `<edges>`, PNML's `<page>`) are the fragments; each is parsed alone. The
//! skeleton is the text with every fragment blanked (a blank character of
//! the same length for each, newlines kept, so that every position is
//! where it was): its tree is small and holds everything else. A container inside a container (a PNML page in a
//! page) stays in the skeleton, its own children cut out in turn.
//!
//! The cut is made only where it cannot change what the file means or
//! where an error is reported: no document type declaration (its entities
//! could be used anywhere), no namespace prefix on any element or
//! attribute but `xmlns` and `xml` (a fragment alone would not know it);
//! otherwise ([`split`] returns `None`) the reader parses the whole
//! document, as before. Every tag of the skeleton's path is matched while
//! scanning; the skeleton and each fragment are then parsed by the same
//! parser, so a malformed file is an error as before, its position mapped
//! back to the whole file ([`Fragment`]).
//!
//! Cost: one pass over the bytes; the skeleton is one copy of the text.

use std::collections::BTreeMap;
use std::ops::Range;

/// A fragment: its bytes in the text and where it starts (1-based line, and
/// column in characters), to place its positions in the whole file.
#[derive(Debug, Clone)]
pub(super) struct Fragment {
    /// Its bytes in the whole text.
    pub range: Range<usize>,
    /// Its element's name (local, without a prefix), as bytes of the text.
    pub name: Range<usize>,
    /// The line it starts on.
    pub row: u32,
    /// The column it starts at, in characters.
    pub col: u32,
}

impl Fragment {
    /// Its element's local name.
    pub fn tag<'t>(&self, text: &'t str) -> &'t str {
        &text[self.name.clone()]
    }

    /// The position in the whole file of `(row, col)` within the fragment.
    pub fn place(&self, row: u32, col: u32) -> (u32, u32) {
        if row <= 1 {
            (self.row, self.col + col - 1)
        } else {
            (self.row + row - 1, col)
        }
    }
}

/// A text cut into a skeleton and the fragments of its containers.
#[derive(Debug)]
pub(super) struct XmlSplit {
    /// The text with every fragment blanked.
    pub skeleton: String,
    /// Each container's fragments, in order, by the byte offset of the
    /// container's start tag.
    children: BTreeMap<usize, Vec<Fragment>>,
}

impl XmlSplit {
    /// The fragments directly inside the container whose start tag begins
    /// at byte `start` (its node's `range().start` in the skeleton).
    pub fn children(&self, start: usize) -> &[Fragment] {
        self.children.get(&start).map_or(&[], Vec::as_slice)
    }
}

/// An open element while scanning: its name's bytes, where its start tag
/// begins, and whether it is a container.
struct Open {
    name: Range<usize>,
    start: usize,
    container: bool,
}

/// Where the scanner is: the text, the offset, the line and where it
/// began.
struct Scanner<'a> {
    b: &'a [u8],
    text: &'a str,
    i: usize,
    row: u32,
    line_start: usize,
}

impl Scanner<'_> {
    /// Moves to `to`, counting lines.
    fn advance(&mut self, to: usize) {
        let to = to.min(self.b.len());
        for k in self.i..to {
            if self.b[k] == b'\n' {
                self.row += 1;
                self.line_start = k + 1;
            }
        }
        self.i = to;
    }

    /// The offset just past the first `pat` from `i`, or the end.
    fn past(&self, pat: &[u8]) -> usize {
        self.b[self.i..]
            .windows(pat.len())
            .position(|w| w == pat)
            .map_or(self.b.len(), |k| self.i + k + pat.len())
    }

    /// The column of the current offset, in characters.
    fn col(&self) -> u32 {
        self.text[self.line_start..self.i].chars().count() as u32 + 1
    }
}

/// A name's bytes starting at `i`: up to a blank, `/`, `>` or `=`.
fn name_end(b: &[u8], i: usize) -> usize {
    b[i..]
        .iter()
        .position(|c| c.is_ascii_whitespace() || matches!(c, b'/' | b'>' | b'='))
        .map_or(b.len(), |k| i + k)
}

/// Whether a prefixed name would need a namespace a fragment cannot see.
fn foreign_prefix(name: &[u8]) -> bool {
    match name.iter().position(|&c| c == b':') {
        None => false,
        Some(k) => !matches!(&name[..k], b"xmlns" | b"xml"),
    }
}

/// The offset just past a start tag's `>` from `i` (its attributes
/// scanned), whether it closes itself, and whether a name in it has a
/// foreign prefix; `None` when it never ends.
fn start_tag_end(b: &[u8], mut i: usize) -> Option<(usize, bool, bool)> {
    let mut foreign = false;
    while i < b.len() {
        match b[i] {
            b'"' | b'\'' => {
                let q = b[i];
                i += 1 + b[i + 1..].iter().position(|&c| c == q)?;
            }
            b'>' => return Some((i + 1, i > 0 && b[i - 1] == b'/', foreign)),
            c if !c.is_ascii_whitespace() && c != b'/' && c != b'=' => {
                let end = name_end(b, i);
                foreign |= foreign_prefix(&b[i..end]);
                i = end;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// Writes over `text`'s bytes in `out` a blank of the same bytes and
/// characters: a space for each ASCII character but newlines (kept), and
/// for a longer character another of its length (U+00A0, U+2000,
/// U+10000), so that columns after it on its line stay where they were.
fn blank(text: &str, out: &mut [u8]) {
    let mut k = 0;
    for c in text.chars() {
        let n = c.len_utf8();
        let filler = match (c, n) {
            ('\n', _) => '\n',
            (_, 1) => ' ',
            (_, 2) => '\u{a0}',
            (_, 3) => '\u{2000}',
            _ => '\u{10000}',
        };
        filler.encode_utf8(&mut out[k..k + n]);
        k += n;
    }
}

/// `text` cut at the children of the elements named `containers` (local
/// names), or `None` when it cannot be cut without changing its meaning
/// (module docs) or is malformed in a way the whole parser should report.
pub(super) fn split(text: &str, containers: &[&str]) -> Option<XmlSplit> {
    let b = text.as_bytes();
    let mut s = Scanner {
        b,
        text,
        i: 0,
        row: 1,
        line_start: 0,
    };
    let mut stack: Vec<Open> = Vec::new();
    let mut children: BTreeMap<usize, Vec<Fragment>> = BTreeMap::new();
    // The fragment being skipped: its depth, and where it began.
    let mut fragment: Option<(usize, Fragment)> = None;
    while s.i < b.len() {
        let Some(k) = b[s.i..].iter().position(|&c| c == b'<') else {
            break;
        };
        s.advance(s.i + k);
        let rest = &b[s.i..];
        if rest.starts_with(b"<!--") {
            let to = s.past(b"-->");
            s.advance(to);
        } else if rest.starts_with(b"<![CDATA[") {
            let to = s.past(b"]]>");
            s.advance(to);
        } else if rest.starts_with(b"<?") {
            let to = s.past(b"?>");
            s.advance(to);
        } else if rest.starts_with(b"<!") {
            return None; // a document type declaration
        } else if rest.starts_with(b"</") {
            let name = s.i + 2..name_end(b, s.i + 2);
            let to = s.past(b">");
            let open = stack.pop()?;
            if b[open.name.clone()] != b[name] {
                return None; // mismatched: the whole parser says where
            }
            s.advance(to);
            if let Some((depth, f)) = &fragment
                && stack.len() == *depth
            {
                let f = Fragment {
                    range: f.range.start..s.i,
                    ..f.clone()
                };
                children.entry(stack.last()?.start).or_default().push(f);
                fragment = None;
            }
        } else {
            let start = s.i;
            let name = start + 1..name_end(b, start + 1);
            if foreign_prefix(&b[name.clone()]) {
                return None;
            }
            let (end, closed, foreign) = start_tag_end(b, name.end)?;
            if foreign {
                return None;
            }
            let local_start = text[name.clone()]
                .rfind(':')
                .map_or(name.start, |k| name.start + k + 1);
            let local = &text[local_start..name.end];
            let container = containers.contains(&local);
            let inside = stack.last().is_some_and(|o| o.container);
            if fragment.is_none() && inside && !container {
                let here = Fragment {
                    range: start..start,
                    name: local_start..name.end,
                    row: s.row,
                    col: s.col(),
                };
                if closed {
                    s.advance(end);
                    let f = Fragment {
                        range: start..s.i,
                        ..here
                    };
                    children.entry(stack.last()?.start).or_default().push(f);
                    continue;
                }
                fragment = Some((stack.len(), here));
            }
            s.advance(end);
            if !closed {
                stack.push(Open {
                    name,
                    start,
                    container: container && fragment.is_none(),
                });
            }
        }
    }
    if !stack.is_empty() || fragment.is_some() {
        return None;
    }
    let mut skeleton = text.as_bytes().to_vec();
    for f in children.values().flatten() {
        blank(&text[f.range.clone()], &mut skeleton[f.range.clone()]);
    }
    // Whole characters were written over whole characters, so the text
    // stays UTF-8.
    let skeleton = String::from_utf8(skeleton).ok()?;
    Some(XmlSplit { skeleton, children })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(text: &str, containers: &[&str]) -> Option<(String, Vec<Vec<String>>)> {
        let s = split(text, containers)?;
        let kids = s
            .children
            .values()
            .map(|v| v.iter().map(|f| text[f.range.clone()].to_string()).collect())
            .collect();
        Some((s.skeleton, kids))
    }

    #[test]
    fn children_of_containers_are_cut_out_and_blanked() {
        let text = "<project>\n<gspn name=\"n\">\n<nodes>\n  <place name=\"a>\"/>\n  <transition name='t'>\n   <x/>\n  </transition>\n</nodes>\n<edges><arc head=\"t\" tail=\"a\"/></edges>\n</gspn>\n</project>\n";
        let (skeleton, kids) = texts(text, &["nodes", "edges"]).unwrap();
        assert_eq!(skeleton.len(), text.len());
        assert_eq!(skeleton.lines().count(), text.lines().count());
        assert!(
            skeleton.contains("<nodes>") && !skeleton.contains("place"),
            "{skeleton}"
        );
        assert_eq!(
            kids,
            [
                vec![
                    "<place name=\"a>\"/>".to_string(),
                    "<transition name='t'>\n   <x/>\n  </transition>".to_string()
                ],
                vec!["<arc head=\"t\" tail=\"a\"/>".to_string()]
            ]
        );
        assert!(roxmltree::Document::parse(&skeleton).is_ok());
        // Characters of every length keep their columns.
        let text = "<nodes><a x=\"é€😀\"/></nodes> <b/>";
        let s = split(text, &["nodes"]).unwrap();
        assert_eq!(s.skeleton.chars().count(), text.chars().count());
        assert!(s.skeleton.ends_with("</nodes> <b/>"));
    }

    #[test]
    fn fragments_know_where_they_start() {
        let text = "<pnml><net><page id=\"p\">\n  <place id=\"a\"/><place id=\"é\"/>\n<page id=\"q\"><arc id=\"x\"/></page></page></net></pnml>";
        let s = split(text, &["page"]).unwrap();
        let all: Vec<&Fragment> = s.children.values().flatten().collect();
        assert_eq!(all.len(), 3);
        assert_eq!((all[0].row, all[0].col), (2, 3));
        assert_eq!((all[1].row, all[1].col), (2, 18));
        // The nested page stays in the skeleton; its arc is its own child.
        assert!(s.skeleton.contains("<page id=\"q\">"));
        assert_eq!(all[1].place(1, 5), (2, 22));
        assert_eq!(all[1].place(3, 5), (4, 5));
    }

    #[test]
    fn documents_that_cannot_be_cut_are_left_whole() {
        let c = ["nodes"];
        assert!(split("<!DOCTYPE x [<!ENTITY e \"v\">]><nodes><a/></nodes>", &c).is_none());
        assert!(split("<nodes><p:a xmlns:p=\"u\"/></nodes>", &c).is_none());
        assert!(split("<nodes><a p:x=\"1\"/></nodes>", &c).is_none());
        assert!(split("<nodes><a></b></nodes>", &c).is_none());
        assert!(split("<nodes><a>", &c).is_none());
        // Comments, CDATA and processing instructions are skipped.
        let (_, kids) = texts(
            "<?xml version=\"1.0\"?><nodes><!-- <a> --><b><![CDATA[</b>]]></b></nodes>",
            &c,
        )
        .unwrap();
        assert_eq!(kids, [vec!["<b><![CDATA[</b>]]></b>".to_string()]]);
        // `xmlns` and `xml` prefixes are no obstacle.
        assert!(split("<nodes xmlns:p=\"u\"><a xml:lang=\"en\"/></nodes>", &c).is_some());
    }
}
