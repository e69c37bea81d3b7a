//! The lab's layout holds: the modules of `src/` form no cycle, the generic
//! core uses nothing of `suites` nor of the middle layer `runs`, `runs` uses
//! no suite and no command module, and no suite is named outside the
//! registry's folder. And across the workspace: the top-level modules of
//! every crate form no cycle either.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`.
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The node of a file: `crate` for lib.rs, a core module (`runner`), the
/// registry (`suites`), or one suite's folder or shared file
/// (`suites::voting`, `suites::shared`).
fn node_of(rel: &Path) -> String {
    let parts: Vec<String> = rel
        .with_extension("")
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    match parts.as_slice() {
        [lib] if lib == "lib" => "crate".into(),
        [m] => m.clone(),
        [s, m] if s == "suites" && m == "mod" => "suites".into(),
        [s, m, ..] if s == "suites" => format!("suites::{m}"),
        [r, m] if r == "runs" && m == "mod" => "runs".into(),
        [r, m, ..] if r == "runs" => format!("runs::{m}"),
        [m, ..] => m.clone(),
        [] => unreachable!(),
    }
}

/// The node a path after `crate::` names.
fn node_of_path(segments: &[&str]) -> Option<String> {
    match segments {
        ["suites", next, ..] if next.chars().all(|c| c.is_ascii_lowercase() || c == '_') => {
            // `crate::suites::REGISTRY` is the registry itself.
            Some(format!("suites::{next}"))
        }
        ["runs", next, ..] => Some(format!("runs::{next}")),
        [first, ..] => Some(first.to_string()),
        [] => None,
    }
}

/// The modules behind the commands, shared by `cli` and `py`: the only
/// core modules that may use the middle layer `runs`.
const COMMANDS: [&str; 5] = ["batch", "gspn", "map_file", "optimize", "tours"];

/// Paths used after `crate::` in a file (`use crate::{a, b::c}` expanded).
fn crate_paths(text: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(k) = rest.find("crate::") {
        rest = &rest[k + "crate::".len()..];
        if let Some(inner) = rest.strip_prefix('{') {
            let end = inner.find('}').unwrap_or(inner.len());
            for item in inner[..end].split(',') {
                let path: Vec<String> = item
                    .trim()
                    .split("::")
                    .map(|s| s.trim().to_string())
                    .filter(|s| !s.is_empty())
                    .collect();
                if !path.is_empty() {
                    out.push(path);
                }
            }
        } else {
            let end = rest
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(rest.len());
            out.push(
                rest[..end]
                    .split("::")
                    .filter(|s| !s.is_empty())
                    .map(str::to_string)
                    .collect(),
            );
        }
    }
    out
}

/// The lines of a source file that are code: doc links and comments name
/// modules without depending on them.
fn code_only(text: &str) -> String {
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .map(|l| format!("{l}\n"))
        .collect()
}

fn graph() -> (BTreeMap<String, BTreeSet<String>>, BTreeMap<String, String>) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut texts = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap().to_path_buf();
        let node = node_of(&rel);
        let text = std::fs::read_to_string(&f).unwrap();
        let code = code_only(&text);
        let targets = edges.entry(node.clone()).or_default();
        for path in crate_paths(&code) {
            let segs: Vec<&str> = path.iter().map(String::as_str).collect();
            if let Some(t) = node_of_path(&segs) {
                targets.insert(t);
            }
        }
        // `super::x` inside a suite's folder names a sibling in `suites`.
        if node.starts_with("suites::") && rel.iter().count() == 3 {
            for line in code.lines().filter(|l| l.trim_start().starts_with("use super::")) {
                let name = line.trim_start()["use super::".len()..]
                    .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                    .next()
                    .unwrap_or("");
                targets.insert(format!("suites::{name}"));
            }
        }
        targets.remove(&node);
        texts.insert(rel.display().to_string(), code);
    }
    (edges, texts)
}

#[test]
fn the_modules_form_no_cycle() {
    let (edges, _) = graph();
    assert!(edges.contains_key("runner") && edges.contains_key("suites::voting"));
    // Depth-first search for a back edge.
    fn visit(
        n: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) {
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for t in edges.get(n).into_iter().flatten() {
            match state.get(t.as_str()) {
                Some(1) => panic!("module cycle: {} → {t}", stack.join(" → ")),
                Some(_) => {}
                None => visit(t, edges, state, stack),
            }
        }
        stack.pop();
        state.insert(n.to_string(), 2);
    }
    let mut state = BTreeMap::new();
    for n in edges.keys() {
        if !state.contains_key(n.as_str()) {
            visit(n, &edges, &mut state, &mut Vec::new());
        }
    }
}

#[test]
fn the_core_uses_no_suite_and_names_none() {
    let (edges, texts) = graph();
    for (node, targets) in &edges {
        if node.starts_with("suites") || node == "crate" {
            continue;
        }
        if !node.starts_with("runs") && !COMMANDS.contains(&node.as_str()) {
            let into_runs: Vec<&String> = targets.iter().filter(|t| t.starts_with("runs")).collect();
            assert!(
                into_runs.is_empty(),
                "core module `{node}` uses the middle layer: {into_runs:?}"
            );
        }
        let into_suites: Vec<&String> = targets.iter().filter(|t| t.starts_with("suites")).collect();
        assert!(
            into_suites.is_empty(),
            "core module `{node}` uses {into_suites:?}"
        );
    }
    let names: Vec<&str> = lab::suites::REGISTRY.iter().map(|r| r.name).collect();
    assert!(names.contains(&"voting") && names.contains(&"deadlock"));
    for (file, text) in &texts {
        if file.starts_with("suites") {
            continue;
        }
        for name in &names {
            assert!(
                !text.contains(&format!("\"{name}\"")),
                "{file} names the suite `{name}`: suites are looked up in the registry"
            );
        }
    }
}

#[test]
fn the_middle_layer_uses_no_suite_and_no_command() {
    let (edges, _) = graph();
    assert!(edges.contains_key("runs::mission") && edges.contains_key("runs::topo"));
    for (node, targets) in edges.iter().filter(|(n, _)| n.starts_with("runs")) {
        let bad: Vec<&String> = targets
            .iter()
            .filter(|t| t.starts_with("suites") || COMMANDS.contains(&t.as_str()))
            .collect();
        assert!(bad.is_empty(), "`{node}` (middle layer) uses {bad:?}");
    }
    // Its users: suites and commands.
    let users: BTreeSet<&str> = edges
        .iter()
        .filter(|(n, t)| !n.starts_with("runs") && t.iter().any(|t| t.starts_with("runs")))
        .map(|(n, _)| n.as_str())
        .collect();
    assert!(
        users.contains("tours") && users.contains("suites::topo"),
        "{users:?}"
    );
}

#[test]
fn the_scanner_sees_grouped_and_nested_paths() {
    let paths = crate_paths("use crate::{page::Block, tables};\nlet x = crate::suites::voting::FIELDS;");
    assert_eq!(
        paths,
        vec![
            vec!["page".to_string(), "Block".into()],
            vec!["tables".to_string()],
            vec!["suites".to_string(), "voting".into(), "FIELDS".into()],
        ]
    );
    assert_eq!(
        node_of(Path::new("suites/voting/explanation.rs")),
        "suites::voting"
    );
    assert_eq!(node_of(Path::new("suites/mod.rs")), "suites");
    assert_eq!(node_of(Path::new("runs/topo.rs")), "runs::topo");
    assert_eq!(
        node_of_path(&["runs", "mission", "LegRun"]),
        Some("runs::mission".into())
    );
}

/// Names a crate root re-exports (`pub use m::{A, B}`, `pub use m::A`),
/// with the module each comes from: `crate::A` elsewhere depends on `m`.
fn reexports(lib: &str) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    for stmt in lib.split(';') {
        let Some(rest) = stmt.trim().strip_prefix("pub use ") else {
            continue;
        };
        let Some((module, items)) = rest.split_once("::") else {
            continue;
        };
        let items = items.trim().trim_start_matches('{').trim_end_matches('}');
        for item in items.split(',') {
            let last = item.rsplit("::").next().unwrap_or("");
            let name = last
                .split(" as ")
                .last()
                .unwrap_or("")
                .trim_matches(|c: char| c == '{' || c == '}' || c.is_whitespace());
            if !name.is_empty() {
                out.insert(name.to_string(), module.trim().to_string());
            }
        }
    }
    out
}

/// The top-level module graph of the crate in `src`: a node per file or
/// folder under `src/` (lib.rs and main.rs excluded), an edge for every
/// `crate::` path, a name the root re-exports counted as its module.
fn top_level_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let root = ["lib.rs", "main.rs"]
        .iter()
        .filter_map(|f| std::fs::read_to_string(src.join(f)).ok())
        .collect::<String>();
    let names = reexports(&root);
    let mut files = Vec::new();
    sources(src, &mut files);
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(src).unwrap();
        let node = rel
            .iter()
            .next()
            .unwrap()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        if node == "lib" || node == "main" {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        let code = code_only(&text);
        let targets = edges.entry(node.clone()).or_default();
        for path in crate_paths(&code) {
            if let Some(first) = path.first() {
                targets.insert(names.get(first).cloned().unwrap_or_else(|| first.clone()));
            }
        }
        targets.remove(&node);
    }
    edges
}

/// A cycle in `edges`, as the path round it, if there is one.
fn find_cycle(edges: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for t in edges
            .get(n)
            .into_iter()
            .flatten()
            .filter(|t| edges.contains_key(t.as_str()))
        {
            match state.get(t.as_str()) {
                Some(1) => {
                    let from = stack.iter().position(|s| s == t).unwrap();
                    let mut cycle = stack[from..].to_vec();
                    cycle.push(t.clone());
                    return Some(cycle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(t, edges, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in edges.keys() {
        if !state.contains_key(n.as_str()) {
            if let Some(c) = visit(n, edges, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn no_crate_of_the_workspace_has_a_module_cycle() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut checked = Vec::new();
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&crates)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    dirs.sort();
    for dir in dirs {
        let src = dir.join("src");
        if !src.is_dir() {
            continue;
        }
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        let edges = top_level_graph(&src);
        if let Some(cycle) = find_cycle(&edges) {
            panic!("module cycle in crates/{name}: {}", cycle.join(" → "));
        }
        checked.push(name);
    }
    for expected in ["lab", "sim", "petri", "cli", "guide", "topo"] {
        assert!(checked.iter().any(|c| c == expected), "{checked:?}");
    }
}

#[test]
fn the_cycle_finder_finds_one() {
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    edges.entry("a".into()).or_default().insert("b".into());
    edges.entry("b".into()).or_default().insert("c".into());
    edges.entry("c".into()).or_default().insert("a".into());
    assert_eq!(find_cycle(&edges).unwrap(), ["a", "b", "c", "a"]);
    edges.get_mut("c").unwrap().clear();
    assert_eq!(find_cycle(&edges), None);
    let names =
        reexports("pub use people::{Crowd, CrowdParams};\npub use world::World;\npub use a::b::{C as D};");
    assert_eq!(names["Crowd"], "people");
    assert_eq!(names["World"], "world");
    assert_eq!(names["D"], "a");
}
