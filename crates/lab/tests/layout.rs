//! The lab's layout holds: the modules of `src/` form no cycle, the generic
//! core uses nothing of `suites` nor of the middle layer `runs`, `runs` uses
//! no suite and no command module, and no suite is named outside the
//! registry's folder. And across the workspace: in every crate, the
//! children of every module (the crate root's included) form no cycle,
//! counting `crate::`, `super::` and `self::` paths.

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

/// Names a module root re-exports (`pub use m::{A, B}`, `pub use m::A`),
/// with the child module each comes from: `parent::A` elsewhere depends
/// on `m`.
fn reexports(root: &str) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    for stmt in root.split(';') {
        let Some(rest) = stmt.trim().strip_prefix("pub use ") else {
            continue;
        };
        let rest = rest.strip_prefix("self::").unwrap_or(rest);
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

/// A file's module path under `src` (`lib.rs`/`main.rs`: the crate,
/// `a/mod.rs` and `a.rs`: `a`, `a/b.rs`: `a::b`).
fn module_path(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .with_extension("")
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        parts.pop();
    }
    parts
}

/// The code of a file without its unit tests (`#[cfg(test)]` onwards:
/// tests sit at the end) and without comments.
fn code_of(text: &str) -> String {
    let text = match text.find("#[cfg(test)]") {
        Some(k) => &text[..k],
        None => text,
    };
    code_only(text)
}

/// Paths a file names through `crate::`, `super::` or `self::`, made
/// absolute from the file's module `here` (grouped imports expanded one
/// level: `use super::{a, b::c}`).
fn module_paths(code: &str, here: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for (prefix, base) in [
        ("crate::", Vec::new()),
        ("super::", here[..here.len().saturating_sub(1)].to_vec()),
        ("self::", here.to_vec()),
    ] {
        for path in prefixed_paths(code, prefix) {
            let mut base = base.clone();
            let mut rest = path.as_slice();
            // `super::super::x`
            while let Some((head, tail)) = rest.split_first()
                && head == "super"
            {
                base.pop();
                rest = tail;
            }
            base.extend(rest.iter().cloned());
            out.push(base);
        }
    }
    out
}

/// Paths after `prefix` in `code` (a group `prefix a::{b, c::d}` expanded
/// one level), each split at `::`; a `prefix` inside a longer path or
/// identifier does not count.
fn prefixed_paths(code: &str, prefix: &str) -> Vec<Vec<String>> {
    let split = |p: &str| -> Vec<String> {
        p.split("::")
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect()
    };
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find(prefix) {
        let at = from + k;
        from = at + prefix.len();
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        let rest = &code[from..];
        let end = rest
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
            .unwrap_or(rest.len());
        let head = split(&rest[..end]);
        match rest[end..].strip_prefix('{') {
            Some(inner) if end == 0 || rest[..end].ends_with("::") => {
                let close = inner.find('}').unwrap_or(inner.len());
                for item in inner[..close].split(',') {
                    let tail = split(item);
                    if !tail.is_empty() {
                        out.push([head.clone(), tail].concat());
                    }
                }
            }
            _ if !head.is_empty() => out.push(head),
            _ => {}
        }
    }
    out
}

/// Module graphs by parent module: children as nodes, edges between them.
type ModuleGraphs = BTreeMap<Vec<String>, BTreeMap<String, BTreeSet<String>>>;

/// The module graphs of the crate in `src`, one per module that has
/// children (the crate root's included): nodes are its children (a file
/// or a folder, all that lies inside counted as the child), and an edge
/// `a → b` for every path from inside `a` to `b` or to a name the parent
/// re-exports from `b`. Unit tests are left out.
fn module_graphs(src: &Path) -> ModuleGraphs {
    let mut files = Vec::new();
    sources(src, &mut files);
    let mut modules: BTreeSet<Vec<String>> = BTreeSet::new();
    let mut texts = Vec::new();
    for f in &files {
        let m = module_path(f.strip_prefix(src).unwrap());
        modules.insert(m.clone());
        texts.push((m, code_of(&std::fs::read_to_string(f).unwrap())));
    }
    // Every module's ancestors are modules too (a folder beside `a.rs`).
    for m in modules.clone() {
        for k in 0..m.len() {
            modules.insert(m[..k].to_vec());
        }
    }
    let mut roots: BTreeMap<Vec<String>, BTreeMap<String, String>> = BTreeMap::new();
    for (m, code) in &texts {
        roots.entry(m.clone()).or_default().extend(reexports(code));
    }
    let mut graphs = ModuleGraphs::new();
    for m in &modules {
        if let Some((last, parent)) = m.split_last() {
            graphs
                .entry(parent.to_vec())
                .or_default()
                .entry(last.clone())
                .or_default();
        }
    }
    for (here, code) in &texts {
        for path in module_paths(code, here) {
            // The level at which `here` and `path` part ways.
            let common = here.iter().zip(&path).take_while(|(a, b)| a == b).count();
            if common >= here.len() || common >= path.len() {
                continue; // into the file's own module, or an item above it
            }
            let parent = &path[..common];
            let from = &here[common];
            let mut to = path[common].clone();
            if !modules.contains(&[parent, std::slice::from_ref(&to)].concat()) {
                match roots.get(parent).and_then(|r| r.get(&to)) {
                    Some(child) => to = child.clone(),
                    None => continue, // an item of the parent itself
                }
            }
            if &to != from {
                graphs
                    .entry(parent.to_vec())
                    .or_default()
                    .entry(from.clone())
                    .or_default()
                    .insert(to);
            }
        }
    }
    graphs
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
fn no_module_of_any_crate_has_a_cycle_among_its_children() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut checked = Vec::new();
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&crates)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    dirs.sort();
    let mut cycles = Vec::new();
    for dir in dirs {
        let src = dir.join("src");
        if !src.is_dir() {
            continue;
        }
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        for (parent, edges) in module_graphs(&src) {
            let at = [name.as_str()]
                .into_iter()
                .chain(parent.iter().map(String::as_str))
                .collect::<Vec<_>>()
                .join("::");
            if let Some(cycle) = find_cycle(&edges) {
                cycles.push(format!("{at}: {}", cycle.join(" → ")));
            }
            checked.push(at);
        }
    }
    assert!(cycles.is_empty(), "module cycles:\n{}", cycles.join("\n"));
    for expected in [
        "lab",
        "lab::suites",
        "sim",
        "petri::io",
        "guide::supervisor",
        "topo",
    ] {
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

/// Regression test: the supervisor's learners and their log imported each
/// other through `super::` (`credit_learning → learning → log →
/// credit_learning`), which a check of the crates' top-level modules
/// alone did not see.
#[test]
fn the_module_graphs_see_siblings_through_super_and_nested_crate_paths() {
    let here = |s: &str| s.split("::").map(str::to_string).collect::<Vec<_>>();
    let code = "use super::credit_learning::Segment;\nuse crate::supervisor::{learning::X, Behaviour};\nlet y = super::super::z::W;";
    let paths = module_paths(code, &here("supervisor::log"));
    assert!(
        paths.contains(&here("supervisor::credit_learning::Segment")),
        "{paths:?}"
    );
    assert!(paths.contains(&here("supervisor::learning::X")), "{paths:?}");
    assert!(paths.contains(&here("z::W")), "{paths:?}");
    assert_eq!(module_path(Path::new("supervisor/mod.rs")), here("supervisor"));
    assert!(module_path(Path::new("lib.rs")).is_empty());
    // A crate with that cycle (through a re-export), in a temporary folder;
    // a unit test's import does not count.
    let dir = std::env::temp_dir().join(format!("layout-cycle-{}", std::process::id()));
    let sup = dir.join("supervisor");
    std::fs::create_dir_all(&sup).unwrap();
    std::fs::write(dir.join("lib.rs"), "pub mod supervisor;\n").unwrap();
    std::fs::write(
        sup.join("mod.rs"),
        "pub mod a;\npub mod b;\npub mod c;\npub use c::Seg;\n",
    )
    .unwrap();
    std::fs::write(sup.join("a.rs"), "use super::b::learn;\n").unwrap();
    std::fs::write(sup.join("b.rs"), "use super::Seg;\n").unwrap();
    std::fs::write(
        sup.join("c.rs"),
        "use crate::supervisor::a::Segment;\n#[cfg(test)]\nmod tests { use super::super::b::X; }\n",
    )
    .unwrap();
    let graphs = module_graphs(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    let edges = &graphs[&here("supervisor")];
    assert_eq!(find_cycle(edges).unwrap(), ["a", "b", "c", "a"]);
    assert!(!edges["c"].contains("b"), "{edges:?}");
}
