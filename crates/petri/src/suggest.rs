//! The closest valid name to a mistyped one, for "unknown …" messages
//! (`unknown parameter `lamda7`; did you mean `lambda7`?`).
//!
//! ```
//! let known = ["lambda1", "lambda7", "p"];
//! assert_eq!(petri::closest("lamda7", &known), Some("lambda7"));
//! assert_eq!(petri::closest("LAMBDA1", &known), Some("lambda1"));
//! assert_eq!(petri::closest("speed", &known), None);
//! ```
//!
//! A name equal but for case (or surrounding blanks) wins; otherwise the
//! name at the smallest edit distance (Levenshtein: insertions, deletions,
//! substitutions of characters), if that distance is at most a third of
//! the longer name's length (at least 1) — further than that, a
//! suggestion would mislead more than help. Ties go to the first name.
//! Cost: `O(|given| · |name|)` per known name.

/// The name of `known` closest to `given` (module docs), if one is close.
pub fn closest<'a>(given: &str, known: &[&'a str]) -> Option<&'a str> {
    let trimmed = given.trim();
    if let Some(k) = known.iter().find(|k| k.trim().eq_ignore_ascii_case(trimmed)) {
        return Some(k);
    }
    let given: Vec<char> = trimmed.to_lowercase().chars().collect();
    let mut best: Option<(usize, &'a str)> = None;
    for &k in known {
        let name: Vec<char> = k.to_lowercase().chars().collect();
        let limit = (given.len().max(name.len()) / 3).max(1);
        let d = edit_distance(&given, &name);
        if d <= limit && best.is_none_or(|(b, _)| d < b) {
            best = Some((d, k));
        }
    }
    best.map(|(_, k)| k)
}

/// Levenshtein distance between two character sequences (one row of the
/// dynamic programme).
fn edit_distance(a: &[char], b: &[char]) -> usize {
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (above + 1).min(row[j] + 1).min(diagonal + usize::from(ca != cb));
            diagonal = above;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_are_levenshtein() {
        let d =
            |a: &str, b: &str| edit_distance(&a.chars().collect::<Vec<_>>(), &b.chars().collect::<Vec<_>>());
        assert_eq!(d("kitten", "sitting"), 3);
        assert_eq!(d("", "abc"), 3);
        assert_eq!(d("voting", "voting"), 0);
        assert_eq!(d("deadlok", "deadlock"), 1);
    }

    #[test]
    fn only_close_names_are_suggested() {
        let suites = ["voting", "deadlock", "maps", "tourguide", "topo", "files"];
        assert_eq!(closest("votin", &suites), Some("voting"));
        assert_eq!(closest("Tourguide", &suites), Some("tourguide"));
        assert_eq!(closest("map", &suites), Some("maps"));
        assert_eq!(closest("experiment", &suites), None);
        assert_eq!(closest("x", &[]), None);
    }
}
