//! Repository-wide checks of the documentation, run on the tree of a fresh
//! clone (the repository root is two levels above this crate):
//!
//! 1. every Markdown document cited in a `.rs`, `.md`, `.toml` or `.py`
//!    file exists in the repository;
//! 2. `ARCHITECTURE.md` names every source file under `crates/*/src`;
//! 3. every relative link and `#anchor` of the book (`docs/**/*.md`) and of
//!    `README.md` resolves, the book links only within `docs/`, and
//!    `docs/SUMMARY.md` lists every page (mdBook checks none of this).
//!
//! They walk the tree rather than list files, so they keep holding when
//! crates are split or files move.

use std::collections::BTreeSet;
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
            // docs/book/ is the built book (`mdbook build docs`), not a source.
            if !skipped_dir(&name) && !p.ends_with("docs/book") {
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

/// The lines of a Markdown text outside fenced code blocks (```` ``` ````
/// or `~~~`), with their 1-based numbers.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut fence: Option<&str> = None;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        let marker = ["```", "~~~"].into_iter().find(|m| t.starts_with(m));
        match (fence, marker) {
            (None, Some(m)) => fence = Some(m),
            (Some(f), Some(m)) if f == m => fence = None,
            (None, None) => out.push((i + 1, line)),
            _ => {}
        }
    }
    out
}

/// `line` without its code spans (`` `…` ``): links inside them are text.
/// `in_code` says whether the line starts inside a code span (one that
/// began on an earlier line of its paragraph) and is left as the line ends.
fn without_code_spans(line: &str, in_code: &mut bool) -> String {
    let mut out = String::new();
    for c in line.chars() {
        if c == '`' {
            *in_code = !*in_code;
        } else if !*in_code {
            out.push(c);
        }
    }
    out
}

/// The targets of the inline links and images in `line` (`[text](target)`,
/// `![alt](target "title")`), in order.
fn link_targets(line: &str) -> Vec<String> {
    link_targets_in(line, &mut false)
}

/// [`link_targets`] of a line of a paragraph whose code span may have
/// begun on an earlier line (`in_code`, updated).
fn link_targets_in(line: &str, in_code: &mut bool) -> Vec<String> {
    let text = without_code_spans(line, in_code);
    let mut out = Vec::new();
    let mut rest = text.as_str();
    while let Some(k) = rest.find("](") {
        let after = &rest[k + 2..];
        let mut depth = 0usize;
        let end = after
            .char_indices()
            .find(|&(_, c)| match c {
                '(' => {
                    depth += 1;
                    false
                }
                ')' if depth == 0 => true,
                ')' => {
                    depth -= 1;
                    false
                }
                _ => false,
            })
            .map_or(after.len(), |(i, _)| i);
        let target = after[..end].split_whitespace().next().unwrap_or("");
        out.push(target.trim_matches(|c| c == '<' || c == '>').to_string());
        rest = &after[end..];
    }
    out
}

/// The anchor mdBook gives a heading's text: the text as rendered (code
/// spans' backticks, emphasis stars and link targets gone), trimmed and
/// lowercased, whitespace turned into `-`, every character but letters,
/// digits, `_` and `-` dropped (mdBook 0.5's `id_from_content` in
/// `mdbook-html`; GitHub's README anchors agree for such text).
fn heading_slug(heading: &str) -> String {
    let mut text = String::new();
    let mut rest = heading;
    // Links keep their text only.
    while let Some(k) = rest.find("](") {
        text.push_str(&rest[..k]);
        rest = rest[k + 2..].split_once(')').map_or("", |(_, r)| r);
    }
    text.push_str(rest);
    text.trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| {
            if c.is_alphanumeric() || c == '_' || c == '-' {
                Some(c)
            } else if c.is_whitespace() {
                Some('-')
            } else {
                None
            }
        })
        .collect()
}

/// The anchors of a Markdown document's ATX headings (`## …`), repeated
/// ones numbered as mdBook does (`-1`, `-2`, …).
fn anchors(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (_, line) in prose_lines(text) {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        let Some(title) = line[hashes..].strip_prefix(' ') else {
            continue;
        };
        if !(1..=6).contains(&hashes) {
            continue;
        }
        let slug = heading_slug(title.trim().trim_end_matches('#').trim());
        let mut id = slug.clone();
        let mut n = 0;
        while out.contains(&id) {
            n += 1;
            id = format!("{slug}-{n}");
        }
        out.insert(id);
    }
    out
}

/// The pages of the book (`docs/**/*.md`, the built book `docs/book/` left
/// out) and the README.
fn book_and_readme(root: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    walk(&root.join("docs"), &["md"], &mut files);
    files.push(root.join("README.md"));
    files
}

/// The broken internal links of `file`: relative targets that are not in
/// the repository, `#anchors` that name no heading of their Markdown page,
/// and, from a page of the book (`docs/`), targets outside `docs/` (the
/// book holds only that folder: cite other files by path in backticks).
fn broken_links(root: &Path, file: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap();
    let here = file.parent().unwrap();
    let in_book = file.starts_with(root.join("docs"));
    let docs = root.join("docs").canonicalize().unwrap();
    let rel = file.strip_prefix(root).unwrap().display().to_string();
    let mut broken = Vec::new();
    let mut in_code = false;
    for (line_no, line) in prose_lines(&text) {
        if line.trim().is_empty() {
            in_code = false;
        }
        for target in link_targets_in(line, &mut in_code) {
            let external = target.contains("://") || target.starts_with("mailto:");
            if external || target.is_empty() {
                continue;
            }
            let (path, anchor) = target.split_once('#').unwrap_or((&target, ""));
            let dest = if path.is_empty() {
                file.to_path_buf()
            } else {
                here.join(path)
            };
            let Ok(dest) = dest.canonicalize() else {
                broken.push(format!("{rel}:{line_no}: {target}: no such file"));
                continue;
            };
            if in_book && !dest.starts_with(&docs) {
                broken.push(format!(
                    "{rel}:{line_no}: {target}: outside docs/, so not in the book (cite it as `path` instead)"
                ));
            }
            let is_md = dest.extension().is_some_and(|e| e == "md");
            if !anchor.is_empty() && is_md {
                let ids = anchors(&std::fs::read_to_string(&dest).unwrap());
                if !ids.contains(anchor) {
                    broken.push(format!(
                        "{rel}:{line_no}: {target}: no heading with anchor #{anchor}"
                    ));
                }
            }
        }
    }
    broken
}

/// Outcome 2 of issue 50: the book and the README link to nothing that is
/// not there — every relative link of `docs/**/*.md` and `README.md`
/// resolves to a file, every `#anchor` to a heading (mdBook's slugs), the
/// book's pages link only within `docs/`, and `docs/SUMMARY.md` lists every
/// page (mdBook renders only those, so a page left out is a broken link in
/// the built book).
#[test]
fn book_and_readme_links_resolve() {
    let root = repo_root();
    let files = book_and_readme(&root);
    let mut broken: Vec<String> = files.iter().flat_map(|f| broken_links(&root, f)).collect();
    let summary = std::fs::read_to_string(root.join("docs/SUMMARY.md")).unwrap();
    let listed: BTreeSet<String> = prose_lines(&summary)
        .into_iter()
        .flat_map(|(_, l)| link_targets(l))
        .collect();
    for f in files.iter().filter(|f| f.starts_with(root.join("docs"))) {
        let page = f.strip_prefix(root.join("docs")).unwrap().display().to_string();
        if page != "SUMMARY.md" && !listed.contains(&page) {
            broken.push(format!("docs/SUMMARY.md: does not list the page docs/{page}"));
        }
    }
    assert!(broken.is_empty(), "broken internal links:\n{}", broken.join("\n"));
}

#[test]
fn links_and_anchors_are_read_as_mdbook_does() {
    assert_eq!(
        link_targets("see [a](gspn.md#the-model), ![p](img/x.png \"t\") and `[no](x.md)` [f(x)](a_(b).md)"),
        ["gspn.md#the-model", "img/x.png", "a_(b).md"]
    );
    assert_eq!(
        heading_slug("Disturbances (`disturbance.rs`)"),
        "disturbances-disturbancers"
    );
    assert_eq!(heading_slug("The [lab](lab.md): I_R, *runs*"), "the-lab-i_r-runs");
    let ids = anchors("# A\n```\n# not a heading\n```\n## A\n### B b\n#nope\n");
    assert_eq!(ids.into_iter().collect::<Vec<_>>(), ["a", "a-1", "b-b"]);
    assert_eq!(prose_lines("a\n~~~\nb\n~~~\nc").len(), 2);
    // A code span over two lines hides the link-like text inside it.
    let mut in_code = false;
    assert!(link_targets_in("see `a", &mut in_code).is_empty() && in_code);
    assert_eq!(link_targets_in("[x](y) b` and [c](d.md)", &mut in_code), ["d.md"]);
}
