//! A TOML net cut into its head and its items, so that the reader parses
//! one `[[place]]` or `[[transition]]` at a time: the TOML parser's
//! document tree then holds one item, not the whole file (on a 50 MB net
//! the whole file's tree took 43 times the file's size).
//!
//! The cut is made only where it cannot change what the file means:
//!
//! - at a line that starts (after blanks) an array-of-tables header
//!   `[[place]]` or `[[transition]]`, outside any string, comment or
//!   bracket — found by a small scanner that knows TOML's strings (basic,
//!   literal, multi-line, with escapes), comments and nesting;
//! - only if every other header after the first item belongs to its item
//!   (`[transition.outputs]` under a `[[transition]]`): then each item's
//!   text defines exactly that element, the text before the first item
//!   (the head: `name`, `doc`, `[params]`) defines the rest, and parsing
//!   the pieces one by one gives what parsing the whole would. Any other
//!   file ([`items`] returns `None`) is parsed whole, as before.
//!
//! Cost: one pass over the bytes, nothing allocated per item.

use std::ops::Range;

/// What an item is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum ItemKind {
    /// A `[[place]]`.
    Place,
    /// A `[[transition]]`.
    Transition,
}

/// The text cut into head and items.
#[derive(Debug, Clone)]
pub(super) struct Items {
    len: usize,
    /// Where each item starts, and what it is, in file order.
    starts: Vec<(usize, ItemKind)>,
}

/// A header line: where its line starts and its text without blanks.
struct Header {
    line_start: usize,
    name: String,
}

/// Calls `f` on every table header of `text` (module docs), in order.
fn headers(text: &str, mut f: impl FnMut(Header) -> bool) {
    let b = text.as_bytes();
    let mut i = 0;
    let mut depth = 0usize;
    let mut line_start = true;
    while i < b.len() {
        if line_start {
            line_start = false;
            let start = i;
            while i < b.len() && (b[i] == b' ' || b[i] == b'\t') {
                i += 1;
            }
            if i == b.len() {
                break;
            }
            if depth == 0 && i < b.len() && b[i] == b'[' {
                let end = b[i..].iter().position(|&c| c == b'\n').map_or(b.len(), |k| i + k);
                let line = &text[i..end];
                let close = line.find(']').map_or(line.len(), |k| {
                    // `]]` closes an array-of-tables header.
                    if line[k..].starts_with("]]") { k + 2 } else { k + 1 }
                });
                let name: String = line[..close].chars().filter(|c| !c.is_whitespace()).collect();
                if !f(Header {
                    line_start: start,
                    name,
                }) {
                    return;
                }
                i = end;
                continue;
            }
        }
        match b[i] {
            b'\n' => line_start = true,
            b'#' => {
                while i + 1 < b.len() && b[i + 1] != b'\n' {
                    i += 1;
                }
            }
            b'"' | b'\'' => {
                i = skip_string(b, i);
                continue;
            }
            b'[' | b'{' => depth += 1,
            b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        i += 1;
    }
}

/// The index just past the string starting at `i` (a quote): basic or
/// literal, single- or multi-line; an unterminated string runs to the end
/// of its line (single-line) or of the text (multi-line), where the TOML
/// parser will report it.
fn skip_string(b: &[u8], i: usize) -> usize {
    let q = b[i];
    let escapes = q == b'"';
    let multi = b.len() >= i + 3 && b[i + 1] == q && b[i + 2] == q;
    let mut k = if multi { i + 3 } else { i + 1 };
    while k < b.len() {
        let c = b[k];
        if escapes && c == b'\\' {
            k += 2;
            continue;
        }
        if !multi && c == b'\n' {
            return k;
        }
        if c == q {
            if !multi {
                return k + 1;
            }
            let run = b[k..].iter().take_while(|&&x| x == q).count();
            if run >= 3 {
                // Up to two quotes before the closing three are content.
                return k + run.min(5);
            }
            k += run;
            continue;
        }
        k += 1;
    }
    b.len()
}

fn kind_of(name: &str) -> Option<ItemKind> {
    match name {
        "[[place]]" => Some(ItemKind::Place),
        "[[transition]]" => Some(ItemKind::Transition),
        _ => None,
    }
}

fn belongs(name: &str, kind: ItemKind) -> bool {
    let prefix = match kind {
        ItemKind::Place => "place.",
        ItemKind::Transition => "transition.",
    };
    let inner = name.trim_start_matches('[');
    inner.starts_with(prefix)
}

/// `text` cut into head and items, or `None` when it cannot be cut
/// without changing its meaning (module docs).
pub(super) fn items(text: &str) -> Option<Items> {
    let mut starts = Vec::new();
    let mut plain = true;
    headers(text, |h| {
        if let Some(k) = kind_of(&h.name) {
            starts.push((h.line_start, k));
        } else if let Some(&(_, k)) = starts.last()
            && !belongs(&h.name, k)
        {
            plain = false;
            return false;
        }
        true
    });
    plain.then_some(Items {
        len: text.len(),
        starts,
    })
}

impl Items {
    /// The head: the text before the first item.
    pub(super) fn head(&self) -> Range<usize> {
        0..self.starts.first().map_or(self.len, |s| s.0)
    }

    /// Every item of `kind`, its text's range, in file order.
    pub(super) fn of(&self, kind: ItemKind) -> impl Iterator<Item = Range<usize>> + '_ {
        self.starts
            .iter()
            .enumerate()
            .filter(move |(_, s)| s.1 == kind)
            .map(|(n, &(start, _))| start..self.starts.get(n + 1).map_or(self.len, |s| s.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cut(text: &str) -> Option<(String, Vec<String>, Vec<String>)> {
        let items = items(text)?;
        let texts = |k| items.of(k).map(|r| text[r].to_string()).collect();
        Some((
            text[items.head()].to_string(),
            texts(ItemKind::Place),
            texts(ItemKind::Transition),
        ))
    }

    #[test]
    fn a_plain_net_is_cut_at_its_item_headers() {
        let text = "name = \"n\"\n[params]\na = 1\n[[place]]\nname = \"P\"\n  [[transition]]\nname = \"t\"\n[transition.outputs]\nP = 2\n[[place]] # more\nname = \"Q\"\n";
        let (head, places, transitions) = cut(text).unwrap();
        assert_eq!(head, "name = \"n\"\n[params]\na = 1\n");
        assert_eq!(
            places,
            ["[[place]]\nname = \"P\"\n", "[[place]] # more\nname = \"Q\"\n"]
        );
        assert_eq!(
            transitions,
            ["  [[transition]]\nname = \"t\"\n[transition.outputs]\nP = 2\n"]
        );
    }

    #[test]
    fn headers_in_strings_comments_and_arrays_are_not_headers() {
        let text = "doc = \"\"\"\n[[place]]\n\"\"\"\n# [[place]]\nx = '''\n[[transition]]'''\ny = [\n[1],\n]\ns = \"a\\\"[[place]]\"\n[[place]]\nname = \"P\"\ndoc = \"\"\"a\"\"\"\"\n";
        let (head, places, transitions) = cut(text).unwrap();
        assert!(head.ends_with("s = \"a\\\"[[place]]\"\n"), "{head}");
        assert_eq!(places.len(), 1);
        assert!(transitions.is_empty());
    }

    /// Regression: blanks at the very end of the text read past it.
    #[test]
    fn a_text_ending_in_blanks_is_scanned_to_its_end() {
        assert!(items("a = 1\n  ").is_some());
        assert!(items("  ").is_some());
    }

    #[test]
    fn a_file_with_tables_after_its_items_is_not_cut() {
        assert!(cut("[[place]]\nname = \"P\"\n[params]\na = 1\n").is_none());
        assert!(cut("[[place]]\nname = \"P\"\n[transition.outputs]\nP = 1\n").is_none());
        assert!(cut("[[place]]\nname = \"P\"\n[\"place\".x]\n").is_none());
        // No item at all: the whole text is the head.
        let (head, p, t) = cut("name = \"n\"\n").unwrap();
        assert_eq!((head.as_str(), p.len(), t.len()), ("name = \"n\"\n", 0, 0));
    }
}
