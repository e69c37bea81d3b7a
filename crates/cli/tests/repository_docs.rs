//! Repository-wide checks of the documentation, run on the tree of a fresh
//! clone (the repository root is two levels above this crate):
//!
//! 1. every Markdown document cited in a `.rs`, `.md`, `.toml` or `.py`
//!    file exists in the repository;
//! 2. `ARCHITECTURE.md` names every source file under `crates/*/src`.
//!
//! Both walk the tree rather than list files, so they keep holding when
//! crates are split or files move.

use std::path::{Path, PathBuf};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// Directories that are not part of the repository's sources: build
/// output, virtual environments, VCS metadata, hidden folders.
fn skipped_dir(name: &str) -> bool {
    name.starts_with('.') || matches!(name, "target" | "node_modules" | "__pycache__" | "venv")
}

/// Every file under `dir` whose extension is one of `exts`.
fn walk(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() {
            if !skipped_dir(&name) {
                walk(&p, exts, out);
            }
        } else if p.extension().is_some_and(|e| exts.iter().any(|x| e == *x)) {
            out.push(p);
        }
    }
}

/// File names the programs *write*, not documents they cite: the lab's
/// report page `tables.md`.
const WRITTEN_NOT_CITED: &[&str] = &["tables.md"];

fn path_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '/')
}

/// The `….md` names in `text`: a run of path characters (letters, digits,
/// `_ - . /`) ending in `.md` not followed by a letter or digit. URLs
/// (`https://…/x.md`) are left out.
fn cited_md(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let bytes = text.as_bytes();
    let mut from = 0;
    while let Some(k) = text[from..].find(".md") {
        let end = from + k + 3;
        from = end;
        if bytes
            .get(end)
            .is_some_and(|b| b.is_ascii_alphanumeric() || *b == b'_')
        {
            continue;
        }
        let start = text[..end]
            .char_indices()
            .rev()
            .take_while(|(_, c)| path_char(*c))
            .last()
            .map_or(end, |(i, _)| i);
        let name = &text[start..end];
        let url = name.starts_with("//") || text[..start].ends_with(':');
        if name.len() > 3 && !url {
            out.push(name.trim_start_matches("./").to_string());
        }
    }
    out
}

/// The nearest folder at or above `file` holding a `Cargo.toml` or a
/// `pyproject.toml` (a crate or package), below or at the root.
fn package_dir(root: &Path, file: &Path) -> PathBuf {
    let mut dir = file.parent().unwrap();
    while dir.starts_with(root) && dir != root {
        if dir.join("Cargo.toml").exists() || dir.join("pyproject.toml").exists() {
            return dir.to_path_buf();
        }
        dir = dir.parent().unwrap();
    }
    root.to_path_buf()
}

/// Outcome 1 of issue 40: a fresh clone holds every document its code and
/// docs cite. A cited name resolves relative to (a) the citing file's
/// folder, (b) the citing file's crate or package (the folder of its
/// `Cargo.toml` or `pyproject.toml`: a crate's `BENCHMARKS.md`), or (c) the
/// repository root (`docs/tour-guide.md`, `crates/guide/EXPERIMENTS.md`).
/// A bare design-document name (`tour-guide.md`) is not looked up in
/// `docs/`: cite it as `docs/tour-guide.md`.
#[test]
fn every_cited_document_exists() {
    let root = repo_root();
    let mut files = Vec::new();
    walk(&root, &["rs", "md", "toml", "py"], &mut files);
    let mut missing = Vec::new();
    // This file's own examples are not citations.
    let this_file = root.join(file!());
    for file in files.iter().filter(|f| **f != this_file) {
        let text = std::fs::read_to_string(file).unwrap();
        let here = file.parent().unwrap();
        let package = package_dir(&root, file);
        for (line_no, line) in text.lines().enumerate() {
            for name in cited_md(line) {
                if WRITTEN_NOT_CITED.contains(&name.as_str()) {
                    continue;
                }
                let found = [here, package.as_path(), root.as_path()]
                    .iter()
                    .any(|base| base.join(&name).is_file());
                if !found {
                    missing.push(format!(
                        "{}:{}: {name}",
                        file.strip_prefix(&root).unwrap().display(),
                        line_no + 1
                    ));
                }
            }
        }
    }
    assert!(
        missing.is_empty(),
        "cited documents that are not in the repository:\n{}",
        missing.join("\n")
    );
}

/// The lines of `ARCHITECTURE.md` under the heading `## \`crates/<name>\``,
/// up to the next `## ` heading.
fn crate_section<'a>(architecture: &'a str, name: &str) -> Option<Vec<&'a str>> {
    let heading = format!("## `crates/{name}`");
    let mut lines = architecture.lines();
    lines.by_ref().find(|l| l.starts_with(&heading))?;
    Some(lines.take_while(|l| !l.starts_with("## ")).collect())
}

/// Outcome 1 of issue 40, second half: `ARCHITECTURE.md` names every source
/// file. In the section of its crate (`## \`crates/<name>\``), a file
/// `crates/<name>/src/a/b.rs` is named by `` `a/b.rs` `` or `` `src/a/b.rs` ``
/// anywhere in the section, or by `` `b.rs` `` on a line that also names its
/// folder (`` `a/` ``); a `mod.rs` is also named by its folder `` `a/` ``.
/// Top-level files are named by `` `b.rs` ``.
#[test]
fn architecture_names_every_source_file() {
    let root = repo_root();
    let architecture = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let mut crates: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("src").is_dir())
        .collect();
    crates.sort();
    assert!(!crates.is_empty());
    let mut unnamed = Vec::new();
    for krate in &crates {
        let name = krate.file_name().unwrap().to_string_lossy().into_owned();
        let Some(section) = crate_section(&architecture, &name) else {
            unnamed.push(format!("crates/{name}: no section `## \\`crates/{name}\\``"));
            continue;
        };
        let mut files = Vec::new();
        walk(&krate.join("src"), &["rs"], &mut files);
        for file in files {
            let rel = file
                .strip_prefix(krate.join("src"))
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let (folder, base) = match rel.rsplit_once('/') {
                Some((d, b)) => (Some(format!("`{d}/`")), b.to_string()),
                None => (None, rel.clone()),
            };
            let full = [format!("`{rel}`"), format!("`src/{rel}`")];
            let named = section.iter().any(|line| {
                full.iter().any(|f| line.contains(f.as_str()))
                    || match &folder {
                        None => line.contains(&format!("`{base}`")),
                        Some(dir) => {
                            line.contains(dir.as_str())
                                && (base == "mod.rs" || line.contains(&format!("`{base}`")))
                        }
                    }
            });
            if !named {
                unnamed.push(format!("crates/{name}/src/{rel}"));
            }
        }
    }
    assert!(
        unnamed.is_empty(),
        "source files ARCHITECTURE.md does not name:\n{}",
        unnamed.join("\n")
    );
}

#[test]
fn cited_names_are_found_in_text() {
    assert_eq!(
        cited_md("see docs/tour-guide.md#the-supervisor and (gspn.md, \"x\")."),
        ["docs/tour-guide.md", "gspn.md"]
    );
    assert_eq!(cited_md("https://example.org/a.md, ./README.md"), ["README.md"]);
    assert!(cited_md("a.mdx, x.md_y").is_empty());
}

/// Whether `needle` occurs in `hay` as whole words (not inside a longer
/// word), both lowercase.
fn has_words(hay: &str, needle: &str) -> bool {
    let word = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
    hay.match_indices(needle).any(|(i, _)| {
        let before = hay[..i].chars().next_back();
        let after = hay[i + needle.len()..].chars().next();
        (!needle.starts_with(|c: char| c.is_alphanumeric()) || !word(before))
            && (!needle.ends_with(|c: char| c.is_alphanumeric()) || !word(after))
    })
}

/// Whether a doc paragraph narrates a measurement or an attempt — the rule
/// of `scripts/doc_history.py`, which prints the same count per file.
fn is_history(paragraph: &str) -> bool {
    let text = paragraph.to_lowercase();
    let tokens: Vec<&str> = text
        .split(|c: char| !c.is_ascii_alphanumeric() && c != '-')
        .collect();
    let is_date = |t: &str| {
        let b = t.as_bytes();
        b.len() == 10
            && b[4] == b'-'
            && b[7] == b'-'
            && b.iter()
                .enumerate()
                .all(|(i, c)| i == 4 || i == 7 || c.is_ascii_digit())
    };
    let is_commit = |t: &str| {
        (7..=40).contains(&t.len())
            && t.chars().all(|c| c.is_ascii_hexdigit())
            && t.chars().any(|c| c.is_ascii_digit())
            && t.chars().any(|c| c.is_ascii_alphabetic())
    };
    let dates_or_ids = tokens
        .iter()
        .any(|t| t.split('-').any(is_commit) || t.match_indices('-').count() >= 2 && has_date(t, is_date));
    let seeds = ["seed ", "seeds "].iter().any(|s| {
        text.match_indices(s).any(|(i, _)| {
            let before = text[..i].chars().next_back();
            !before.is_some_and(|c| c.is_alphanumeric())
                && text[i + s.len()..].starts_with(|c: char| c.is_ascii_digit())
        })
    });
    let measured = [" on", " with", " in", " and", " again", ",", " (", ":"]
        .iter()
        .any(|tail| has_words(&text, &format!("measured{tail}")));
    let used_to = ["it", "they", "we", "robot", "tracker", "which"]
        .iter()
        .any(|who| has_words(&text, &format!("{who} used to")));
    let phrases = [
        "branch",
        "at `main`",
        "on `main`",
        "we tried",
        "was tried",
        "were tried",
        "been tried",
        "tried and",
        "tried but",
        "not kept",
        "before →",
        "→ after",
        "before:",
        "| before",
        "we ran",
        "traced",
        "what remains",
        "was changed",
    ];
    dates_or_ids || seeds || measured || used_to || phrases.iter().any(|p| has_words(&text, p))
}

/// Whether a token holds a date `dddd-dd-dd` between word boundaries.
fn has_date(token: &str, is_date: impl Fn(&str) -> bool) -> bool {
    let b = token.as_bytes();
    (0..b.len().saturating_sub(9)).any(|i| {
        let edge_ok =
            (i == 0 || !b[i - 1].is_ascii_digit()) && b.get(i + 10).is_none_or(|c| !c.is_ascii_digit());
        edge_ok && is_date(&token[i..i + 10])
    })
}

/// Module-doc lines and history lines of one file: paragraphs of `//!`
/// lines, a `# Figures` section exempt (see `scripts/doc_history.py`).
fn module_doc_history(text: &str) -> (usize, usize) {
    let (mut doc, mut history) = (0, 0);
    let mut paragraph: Vec<&str> = Vec::new();
    let mut figures = false;
    let mut flush = |paragraph: &mut Vec<&str>, figures: bool| {
        if !paragraph.is_empty() && !figures && is_history(&paragraph.join(" ")) {
            history += paragraph.len();
        }
        paragraph.clear();
    };
    for line in text.lines() {
        let Some(body) = line.trim_start().strip_prefix("//!") else {
            flush(&mut paragraph, figures);
            continue;
        };
        doc += 1;
        let body = body.trim();
        if body.starts_with('#') && !body.starts_with("#[") {
            flush(&mut paragraph, figures);
            figures = body
                .trim_start_matches('#')
                .trim()
                .eq_ignore_ascii_case("figures");
        } else if body.is_empty() {
            flush(&mut paragraph, figures);
        } else {
            paragraph.push(body);
        }
    }
    flush(&mut paragraph, figures);
    (doc, history)
}

/// Outcome 2 of issue 40: module docs hold the design, not the lab
/// notebook. At most 5 % of the `//!` lines under `crates/*/src` may be
/// history lines by the rule of `scripts/doc_history.py` (run it to see
/// which files hold them); what was measured and not kept goes to the
/// crate's `EXPERIMENTS.md`.
#[test]
fn module_docs_are_not_lab_notebooks() {
    let root = repo_root();
    let mut files = Vec::new();
    for krate in std::fs::read_dir(root.join("crates")).unwrap() {
        let src = krate.unwrap().path().join("src");
        if src.is_dir() {
            walk(&src, &["rs"], &mut files);
        }
    }
    let (mut doc, mut history) = (0, 0);
    for file in &files {
        let (d, h) = module_doc_history(&std::fs::read_to_string(file).unwrap());
        doc += d;
        history += h;
    }
    assert!(doc > 0);
    assert!(
        history * 100 <= doc * 5,
        "{history} of {doc} module-doc lines narrate history ({:.1} %, at most 5 %): \
         run scripts/doc_history.py to see where",
        100.0 * history as f64 / doc as f64
    );
}

#[test]
fn history_rule_examples() {
    assert!(is_history("Measured on field 10 of the voting suite"));
    assert!(is_history("(2026-12-04, issue 13)"));
    assert!(is_history("before = `main` at f74babb"));
    assert!(is_history("with seed 4 the robot"));
    assert!(!is_history(
        "the measured increments, a seeded RNG, retraced legs"
    ));
    assert!(!is_history(
        "Rejected: the product of likelihoods, because it loses the robot"
    ));
    assert_eq!(
        module_doc_history("//! a\n//!\n//! Tried and worse: b.\n//! c\nfn f() {}\n"),
        (4, 2)
    );
    assert_eq!(module_doc_history("//! # Figures\n//!\n//! seeds 1-5\n"), (3, 0));
}
