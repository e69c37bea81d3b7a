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
    name.starts_with('.')
        || matches!(name, "target" | "node_modules" | "__pycache__" | "venv")
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
        } else if p
            .extension()
            .is_some_and(|e| exts.iter().any(|x| e == *x))
        {
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
/// repository root (`docs/tour-guide.md`, `crates/nav/EXPERIMENTS.md`).
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
