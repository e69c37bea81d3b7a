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
//! name at the smallest edit distance (insertions, deletions,
//! substitutions and transpositions of characters: the optimal string
//! alignment distance), if that distance is at most a third of
//! the longer name's length (at least 1) — further than that, a
//! suggestion would mislead more than help. Ties go to the name first in
//! alphabetical order, so that the answer does not depend on the order
//! the names come in (a hash map's).
//! Cost: `O(|given| · |name|)` per known name.

/// The name of `known` closest to `given` (module docs), if one is close.
pub fn closest<'a>(given: &str, known: &[&'a str]) -> Option<&'a str> {
    closest_of(given, known.iter().copied())
}

/// `; did you mean `NAME`?` for the name of `known` closest to `given`,
/// or an empty string: the tail of an "unknown …" message.
pub fn hint<'a>(given: &str, known: impl IntoIterator<Item = &'a str>) -> String {
    closest_of(given, known).map_or(String::new(), |c| format!("; did you mean `{c}`?"))
}

fn closest_of<'a>(given: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let trimmed = given.trim();
    let lower: Vec<char> = trimmed.to_lowercase().chars().collect();
    // (distance, name): 0 for a name equal but for case and blanks.
    let mut best: Option<(usize, &'a str)> = None;
    for k in known {
        let d = if k.trim().eq_ignore_ascii_case(trimmed) {
            0
        } else {
            let name: Vec<char> = k.to_lowercase().chars().collect();
            let limit = (lower.len().max(name.len()) / 3).max(1);
            let d = edit_distance(&lower, &name);
            if d > limit || d == 0 {
                continue;
            }
            d
        };
        if best.is_none_or(|b| (d, k) < b) {
            best = Some((d, k));
        }
    }
    best.map(|(_, k)| k)
}

/// Edit distance between two character sequences: insertions, deletions,
/// substitutions and transpositions of adjacent characters, each 1 (the
/// optimal string alignment distance; `gaol` is 1 from `goal`).
fn edit_distance(a: &[char], b: &[char]) -> usize {
    // Rows i - 2, i - 1 and i of the dynamic programme.
    let mut before: Vec<usize> = vec![0; b.len() + 1];
    let mut above: Vec<usize> = (0..=b.len()).collect();
    let mut row: Vec<usize> = vec![0; b.len() + 1];
    for i in 1..=a.len() {
        row[0] = i;
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut d = (above[j] + 1).min(row[j - 1] + 1).min(above[j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                d = d.min(before[j - 2] + 1);
            }
            row[j] = d;
        }
        std::mem::swap(&mut before, &mut above);
        std::mem::swap(&mut above, &mut row);
    }
    above[b.len()]
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
        assert_eq!(d("gaol", "goal"), 1);
        assert_eq!(d("ab", "ba"), 1);
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
