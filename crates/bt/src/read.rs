//! Reading BehaviorTree.CPP XML (v3 and v4, `BTCPP_format`): `BehaviorTree`
//! definitions, `include`, `TreeNodesModel`, and the main tree expanded with
//! its `SubTree`s (port remapping, `_autoremap`, v3 `SubTreePlus` and
//! `__shared_blackboard`).
//!
//! Every error names the file, the line and the node's path; no input
//! panics. Limits ([`ReadOptions`]) bound the file size, the number of nodes
//! after expansion and the nesting depth, so that a huge or hostile file is
//! refused with an error instead of exhausting memory or the stack.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use roxmltree::{Document, Node as XNode};

use crate::error::{Error, Result};
use crate::model::{Models, Role, builtin_port_direction, looks_like_condition};
#[cfg(test)]
use crate::tree::Direction;
use crate::tree::{Kind, MissingSubtree, Node, NodeId, Port, Tree};

/// How to read a tree.
#[derive(Debug, Clone)]
pub struct ReadOptions {
    /// Node models added to the file's own `TreeNodesModel` (which wins).
    pub models: Models,
    /// Also use Nav2's model (default `true`).
    pub nav2_model: bool,
    /// The tree to expand; default: `main_tree_to_execute`, or the only
    /// `BehaviorTree` of the main file.
    pub main: Option<String>,
    /// Keep going past `SubTree`s that no file defines or that close a
    /// cycle (recorded in [`Tree::missing`] and [`Tree::cycles`], each
    /// replaced by a leaf that may succeed or fail) instead of failing: what
    /// `bt check` does.
    /// Default `false`.
    pub keep_missing: bool,
    /// Largest file read, bytes (default 64 MiB).
    pub max_bytes: u64,
    /// Largest expanded tree, nodes (default 100,000).
    pub max_nodes: usize,
    /// Deepest nesting of nodes and subtrees (default 256).
    pub max_depth: usize,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            models: Models::default(),
            nav2_model: true,
            main: None,
            keep_missing: false,
            max_bytes: 64 << 20,
            max_nodes: 100_000,
            max_depth: 256,
        }
    }
}

/// Reads a tree file (and the files it includes, relative to it).
pub fn read_file(path: impl AsRef<Path>, options: &ReadOptions) -> Result<Tree> {
    let path = path.as_ref();
    let text = load(path, options.max_bytes)?;
    read_source(
        text,
        path.display().to_string(),
        path.parent().map(Path::to_path_buf),
        options,
    )
}

/// Reads a tree from text; `name` names it in errors; `include`s are
/// resolved against `base_dir` (an error without one).
pub fn read_str(text: &str, name: &str, base_dir: Option<&Path>, options: &ReadOptions) -> Result<Tree> {
    if text.len() as u64 > options.max_bytes {
        return Err(too_large(name, text.len() as u64, options.max_bytes));
    }
    read_source(
        text.to_string(),
        name.to_string(),
        base_dir.map(Path::to_path_buf),
        options,
    )
}

fn too_large(name: &str, len: u64, max: u64) -> Error {
    Error::Tree {
        file: name.to_string(),
        line: 1,
        path: "(file)".into(),
        message: format!("the file has {len} bytes, more than the limit of {max} (ReadOptions::max_bytes)"),
    }
}

fn load(path: &Path, max_bytes: u64) -> Result<String> {
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let len = std::fs::metadata(path).map_err(io)?.len();
    if len > max_bytes {
        return Err(too_large(&path.display().to_string(), len, max_bytes));
    }
    let bytes = std::fs::read(path).map_err(io)?;
    String::from_utf8(bytes).map_err(|e| Error::Xml {
        file: path.display().to_string(),
        line: 1,
        column: 1,
        message: format!("not UTF-8 (byte {})", e.utf8_error().valid_up_to()),
    })
}

/// One source file.
struct Source {
    name: String,
    dir: Option<PathBuf>,
    text: String,
}

/// Byte offsets of line starts, for line numbers in O(log n) (roxmltree's
/// `text_pos_at` scans from the start: quadratic on large files).
struct Lines(Vec<usize>);

impl Lines {
    fn of(text: &str) -> Lines {
        Lines(
            std::iter::once(0)
                .chain(
                    text.bytes()
                        .enumerate()
                        .filter(|&(_, b)| b == b'\n')
                        .map(|(i, _)| i + 1),
                )
                .collect(),
        )
    }

    fn line(&self, offset: usize) -> u32 {
        self.0.partition_point(|&start| start <= offset) as u32
    }
}

fn parse<'a>(src: &'a Source) -> Result<Document<'a>> {
    let opts = roxmltree::ParsingOptions {
        allow_dtd: false,
        ..roxmltree::ParsingOptions::default()
    };
    Document::parse_with_options(&src.text, opts).map_err(|e| {
        // The parser places an unclosed root or an early end at 1:1: the
        // place the reader stopped is the end of the text.
        let pos = match e {
            roxmltree::Error::UnclosedRootNode | roxmltree::Error::UnexpectedEndOfStream => {
                end_position(&src.text)
            }
            _ => e.pos(),
        };
        Error::Xml {
            file: src.name.clone(),
            line: pos.row,
            column: pos.col,
            message: e.to_string(),
        }
    })
}

/// Line and column (1-based, in characters) just past the last character of `text`.
fn end_position(text: &str) -> roxmltree::TextPos {
    let line_start = text.rfind('\n').map_or(0, |i| i + 1);
    let row = 1 + text.bytes().filter(|&b| b == b'\n').count() as u32;
    let col = 1 + text[line_start..].chars().count() as u32;
    roxmltree::TextPos::new(row, col)
}

fn line_of(doc: &Document<'_>, el: XNode<'_, '_>) -> u32 {
    doc.text_pos_at(el.range().start).row
}

/// Loads the main source and every file it includes (transitively, each once).
fn load_sources(
    text: String,
    name: String,
    dir: Option<PathBuf>,
    options: &ReadOptions,
) -> Result<Vec<Source>> {
    let mut sources = vec![Source { name, dir, text }];
    let mut seen: BTreeSet<PathBuf> = BTreeSet::new();
    let mut next = 0;
    while next < sources.len() {
        let mut includes = Vec::new();
        {
            let src = &sources[next];
            let doc = parse(src)?;
            for inc in doc
                .root_element()
                .children()
                .filter(|e| e.has_tag_name("include"))
            {
                let line = line_of(&doc, inc);
                let err = |message: String| Error::Tree {
                    file: src.name.clone(),
                    line,
                    path: "include".into(),
                    message,
                };
                if inc.attribute("ros_pkg").is_some() {
                    return Err(err(
                        "`ros_pkg` includes need a ROS installation: give the file's path instead".into(),
                    ));
                }
                let rel = inc
                    .attribute("path")
                    .ok_or_else(|| err("<include> without a `path` attribute".into()))?;
                let dir = src.dir.clone().ok_or_else(|| {
                    err(format!(
                        "cannot resolve the include `{rel}`: the tree was not read from a file"
                    ))
                })?;
                includes.push((dir.join(rel), line, src.name.clone()));
            }
        }
        for (path, line, from) in includes {
            let key = path.canonicalize().unwrap_or_else(|_| path.clone());
            if !seen.insert(key) {
                continue;
            }
            let text = load(&path, options.max_bytes).map_err(|e| Error::Tree {
                file: from.clone(),
                line,
                path: "include".into(),
                message: format!("cannot include `{}`: {e}", path.display()),
            })?;
            sources.push(Source {
                name: path.display().to_string(),
                dir: path.parent().map(Path::to_path_buf),
                text,
            });
        }
        next += 1;
    }
    Ok(sources)
}

fn read_source(text: String, name: String, dir: Option<PathBuf>, options: &ReadOptions) -> Result<Tree> {
    let sources = load_sources(text, name, dir, options)?;
    let docs: Vec<Document<'_>> = sources.iter().map(parse).collect::<Result<_>>()?;
    let root = docs[0].root_element();
    if root.tag_name().name() != "root" {
        return Err(Error::Tree {
            file: sources[0].name.clone(),
            line: line_of(&docs[0], root),
            path: format!("<{}>", root.tag_name().name()),
            message: "a behaviour-tree file has a <root> element".into(),
        });
    }
    let format = match root.attribute("BTCPP_format") {
        None => 3,
        Some(v) => v
            .trim()
            .parse::<u32>()
            .ok()
            .filter(|f| *f == 3 || *f == 4)
            .ok_or_else(|| Error::Tree {
                file: sources[0].name.clone(),
                line: line_of(&docs[0], root),
                path: "root".into(),
                message: format!("BTCPP_format = `{v}`: 3 or 4"),
            })?,
    };
    let mut models = options.models.clone();
    if options.nav2_model {
        let nav2 = Models::nav2();
        for (k, v) in nav2.0 {
            models.0.entry(k).or_insert(v);
        }
    }
    let mut defs: BTreeMap<String, (usize, XNode<'_, '_>)> = BTreeMap::new();
    for (d, doc) in docs.iter().enumerate() {
        for el in doc.root_element().children().filter(|e| e.is_element()) {
            match el.tag_name().name() {
                "TreeNodesModel" => models.add_from(el),
                "BehaviorTree" => {
                    let id = el.attribute("ID").unwrap_or("").to_string();
                    if let Some((d0, first)) = defs.insert(id.clone(), (d, el)) {
                        return Err(Error::Tree {
                            file: sources[d].name.clone(),
                            line: line_of(doc, el),
                            path: format!("BehaviorTree({id})"),
                            message: format!(
                                "defined twice (first at {}:{})",
                                sources[d0].name,
                                line_of(&docs[d0], first)
                            ),
                        });
                    }
                }
                _ => {}
            }
        }
    }
    let main = choose_main(&sources, &docs, &defs, options)?;
    let lines: Vec<Lines> = sources.iter().map(|s| Lines::of(&s.text)).collect();
    let mut ex = Expander {
        sources: &sources,
        lines: &lines,
        docs: &docs,
        defs: &defs,
        models: &models,
        options,
        nodes: Vec::new(),
        scopes: vec![Scope::root()],
        chain: Vec::new(),
        reached: BTreeSet::new(),
        missing: Vec::new(),
        cycles: Vec::new(),
        instances: 0,
    };
    ex.expand_tree(&main, None, 0, main.clone(), 0, 0)?;
    let mut unused: Vec<(String, usize, u32)> = defs
        .iter()
        .filter(|(id, _)| !ex.reached.contains(*id))
        .map(|(id, (d, el))| (id.clone(), *d, line_of(&docs[*d], *el)))
        .collect();
    unused.sort();
    Ok(Tree {
        main,
        nodes: ex.nodes,
        files: sources.iter().map(|s| s.name.clone()).collect(),
        format,
        unused_trees: unused,
        missing: ex.missing,
        cycles: ex.cycles,
    })
}

fn choose_main(
    sources: &[Source],
    docs: &[Document<'_>],
    defs: &BTreeMap<String, (usize, XNode<'_, '_>)>,
    options: &ReadOptions,
) -> Result<String> {
    let root = docs[0].root_element();
    let err = |message: String| Error::Tree {
        file: sources[0].name.clone(),
        line: line_of(&docs[0], root),
        path: "root".into(),
        message,
    };
    if let Some(m) = options.main.as_deref().or(root.attribute("main_tree_to_execute")) {
        if !defs.contains_key(m) {
            return Err(err(format!(
                "the main tree `{m}` is not defined (defined: {})",
                defs.keys().cloned().collect::<Vec<_>>().join(", ")
            )));
        }
        return Ok(m.to_string());
    }
    let own: Vec<&String> = defs
        .iter()
        .filter(|(_, (d, _))| *d == 0)
        .map(|(k, _)| k)
        .collect();
    match own.as_slice() {
        [one] => Ok((*one).clone()),
        [] => Err(err("no <BehaviorTree> in the file".into())),
        _ => Err(err(format!(
            "several trees and no `main_tree_to_execute`: choose one of {}",
            own.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
        ))),
    }
}

/// How a subtree instance names blackboard entries.
#[derive(Debug, Clone)]
struct Scope {
    /// Index of the enclosing scope (`None` for the root blackboard).
    parent: Option<usize>,
    /// Inner entry → `Some(outer entry)` or `None` (a literal value).
    remap: BTreeMap<String, Option<String>>,
    /// Unmapped entries are the parent's (`_autoremap`, v3 shared blackboard).
    shared: bool,
    /// Prefix of entries private to this instance.
    prefix: String,
}

impl Scope {
    fn root() -> Scope {
        Scope {
            parent: None,
            remap: BTreeMap::new(),
            shared: true,
            prefix: String::new(),
        }
    }
}

/// The blackboard entry of `{…}` in an attribute value, if it is one.
fn entry_of(value: &str) -> Option<&str> {
    let v = value.trim();
    v.strip_prefix('{')
        .and_then(|r| r.strip_suffix('}'))
        .map(str::trim)
}

struct Expander<'s, 'd, 'x> {
    sources: &'s [Source],
    lines: &'s [Lines],
    docs: &'d [Document<'x>],
    defs: &'d BTreeMap<String, (usize, XNode<'x, 'x>)>,
    models: &'d Models,
    options: &'d ReadOptions,
    nodes: Vec<Node>,
    scopes: Vec<Scope>,
    /// Subtree ids being expanded (cycle detection).
    chain: Vec<String>,
    reached: BTreeSet<String>,
    missing: Vec<MissingSubtree>,
    cycles: Vec<(String, MissingSubtree)>,
    instances: usize,
}

/// Where an element is being expanded.
struct At<'x> {
    el: XNode<'x, 'x>,
    doc: usize,
    line: u32,
    path: String,
}

impl<'x> Expander<'_, '_, 'x> {
    fn err(&self, at: &At<'_>, message: String) -> Error {
        Error::Tree {
            file: self.sources[at.doc].name.clone(),
            line: at.line,
            path: at.path.clone(),
            message,
        }
    }

    /// Resolves blackboard entry `k` of scope `s` to the root's name.
    fn resolve(&self, k: &str, s: usize) -> Option<String> {
        let k = k.strip_prefix('@').unwrap_or(k);
        let scope = &self.scopes[s];
        match scope.remap.get(k) {
            Some(Some(outer)) => match scope.parent {
                Some(p) => self.resolve(outer, p),
                None => Some(outer.clone()),
            },
            Some(None) => None,
            None => match (scope.parent, scope.shared) {
                (None, _) => Some(k.to_string()),
                (Some(p), true) => self.resolve(k, p),
                (Some(_), false) => Some(format!("{}{k}", scope.prefix)),
            },
        }
    }

    /// Expands `BehaviorTree` `id` as the child of `parent`.
    fn expand_tree(
        &mut self,
        id: &str,
        parent: Option<NodeId>,
        scope: usize,
        path: String,
        depth: usize,
        index: usize,
    ) -> Result<NodeId> {
        let (d, def) = self.defs[id];
        self.reached.insert(id.to_string());
        let kids: Vec<XNode<'x, 'x>> = def
            .children()
            .filter(|e| e.is_element() && !e.has_tag_name("TreeNodesModel"))
            .collect();
        let at = At {
            el: def,
            doc: d,
            line: line_of(&self.docs[d], def),
            path: path.clone(),
        };
        let [child] = kids.as_slice() else {
            return Err(self.err(
                &at,
                format!(
                    "a <BehaviorTree> has exactly one root node, `{id}` has {}",
                    kids.len()
                ),
            ));
        };
        let _ = index;
        self.chain.push(id.to_string());
        let r = self.expand(*child, d, parent, scope, &path, depth, 0);
        self.chain.pop();
        r
    }

    #[allow(clippy::too_many_arguments)]
    fn expand(
        &mut self,
        el: XNode<'x, 'x>,
        doc: usize,
        parent: Option<NodeId>,
        scope: usize,
        parent_path: &str,
        depth: usize,
        index: usize,
    ) -> Result<NodeId> {
        let tag = el.tag_name().name();
        let explicit = matches!(
            tag,
            "Action" | "Condition" | "Control" | "Decorator" | "SubTree" | "SubTreePlus"
        );
        let id = match (explicit, el.attribute("ID")) {
            (true, Some(i)) if !matches!(tag, "SubTree" | "SubTreePlus") => i.to_string(),
            _ => tag.to_string(),
        };
        let name = el.attribute("name").map(str::to_string);
        let step = match &name {
            Some(n) if n != &id => format!("{id}({n})"),
            _ if matches!(tag, "SubTree" | "SubTreePlus") => {
                format!("{tag}({})", el.attribute("ID").unwrap_or(""))
            }
            _ => format!("{id}#{index}"),
        };
        let path = format!("{parent_path}/{step}");
        let at = At {
            el,
            doc,
            line: self.lines[doc].line(el.range().start),
            path,
        };
        if depth > self.options.max_depth {
            return Err(self.err(
                &at,
                format!(
                    "nested deeper than {} levels (ReadOptions::max_depth)",
                    self.options.max_depth
                ),
            ));
        }
        if self.nodes.len() >= self.options.max_nodes {
            return Err(self.err(
                &at,
                format!(
                    "the expanded tree has more than {} nodes (ReadOptions::max_nodes)",
                    self.options.max_nodes
                ),
            ));
        }
        if matches!(tag, "SubTree" | "SubTreePlus") {
            return self.expand_subtree(&at, parent, scope, depth);
        }
        let children: Vec<XNode<'x, 'x>> = el.children().filter(|e| e.is_element()).collect();
        let kind = self.classify(&at, &id, children.len())?;
        let ports = self.ports(&at, &id, scope);
        let me = NodeId(self.nodes.len() as u32);
        self.nodes.push(Node {
            kind,
            id,
            name,
            path: at.path.clone(),
            file: doc,
            line: at.line,
            children: Vec::new(),
            parent,
            ports,
        });
        for (i, c) in children.into_iter().enumerate() {
            let cid = self.expand(c, doc, Some(me), scope, &at.path, depth + 1, i)?;
            self.nodes[me.index()].children.push(cid);
        }
        Ok(me)
    }

    fn expand_subtree(
        &mut self,
        at: &At<'x>,
        parent: Option<NodeId>,
        scope: usize,
        depth: usize,
    ) -> Result<NodeId> {
        let el = at.el;
        let target = el.attribute("ID").unwrap_or("").to_string();
        let me = NodeId(self.nodes.len() as u32);
        self.nodes.push(Node {
            kind: Kind::PassThrough,
            id: "SubTree".into(),
            name: Some(target.clone()),
            path: at.path.clone(),
            file: at.doc,
            line: at.line,
            children: Vec::new(),
            parent,
            ports: Vec::new(),
        });
        if let Some(pos) = self.chain.iter().position(|c| c == &target) {
            let mut cycle = self.chain[pos..].to_vec();
            cycle.push(target.clone());
            let message = format!("subtree cycle: {}", cycle.join(" → "));
            if !self.options.keep_missing {
                return Err(self.err(at, message));
            }
            self.cycles.push((
                message,
                MissingSubtree {
                    id: target,
                    path: at.path.clone(),
                    file: at.doc,
                    line: at.line,
                },
            ));
            self.nodes[me.index()].kind = Kind::Action;
            return Ok(me);
        }
        if !self.defs.contains_key(&target) {
            if !self.options.keep_missing {
                return Err(self.err(
                    at,
                    format!("the subtree `{target}` is not defined in any file read"),
                ));
            }
            self.missing.push(MissingSubtree {
                id: target,
                path: at.path.clone(),
                file: at.doc,
                line: at.line,
            });
            self.nodes[me.index()].kind = Kind::Action;
            return Ok(me);
        }
        let mut remap = BTreeMap::new();
        let mut shared = false;
        let v3 = !self.nodes.is_empty() && at.el.tag_name().name() == "SubTree" && self.is_v3(at.doc);
        for a in el.attributes() {
            let (k, v) = (a.name(), a.value());
            match k {
                "ID" | "name" => {}
                "_autoremap" | "__autoremap" | "__shared_blackboard" => {
                    shared = v.trim().eq_ignore_ascii_case("true") || v.trim() == "1";
                }
                _ if k.starts_with('_') => {}
                _ => {
                    let outer = match entry_of(v) {
                        Some("=") => Some(k.to_string()),
                        Some(e) => Some(e.to_string()),
                        // v3 `SubTree` remaps without braces.
                        None if v3 => Some(v.trim().to_string()),
                        None => None,
                    };
                    remap.insert(k.to_string(), outer);
                }
            }
        }
        self.instances += 1;
        self.scopes.push(Scope {
            parent: Some(scope),
            remap,
            shared,
            prefix: format!("{target}#{}/", self.instances),
        });
        let inner = self.scopes.len() - 1;
        let child = self.expand_tree(&target, Some(me), inner, at.path.clone(), depth + 1, 0)?;
        self.nodes[me.index()].children.push(child);
        Ok(me)
    }

    fn is_v3(&self, doc: usize) -> bool {
        self.docs[doc]
            .root_element()
            .attribute("BTCPP_format")
            .is_none_or(|f| f.trim() == "3")
    }

    fn ports(&self, at: &At<'x>, id: &str, scope: usize) -> Vec<Port> {
        let model = self.models.get(id);
        at.el
            .attributes()
            .filter(|a| !matches!(a.name(), "ID" | "name") && !a.name().starts_with('_'))
            .map(|a| {
                let direction = match model {
                    Some(m) => m.direction(a.name()),
                    None => builtin_port_direction(id, a.name()),
                };
                let key = match entry_of(a.value()) {
                    Some("=") => self.resolve(a.name(), scope),
                    Some(e) => self.resolve(e, scope),
                    None if id == "SetBlackboard" && a.name() == "output_key" => {
                        self.resolve(a.value().trim(), scope)
                    }
                    None => None,
                };
                Port {
                    name: a.name().to_string(),
                    value: a.value().to_string(),
                    direction,
                    key,
                }
            })
            .collect()
    }

    /// A numeric attribute (`default` when absent).
    fn number(&self, at: &At<'x>, attr: &str, default: Option<f64>) -> Result<f64> {
        match at.el.attribute(attr) {
            None => default.ok_or_else(|| self.err(at, format!("the attribute `{attr}` is required"))),
            Some(v) => {
                if let Some(e) = entry_of(v) {
                    return Err(Error::Unsupported {
                        file: self.sources[at.doc].name.clone(),
                        line: at.line,
                        path: at.path.clone(),
                        id: attr.to_string(),
                        reason: format!(
                            "`{attr}` comes from the blackboard entry `{e}` at run time: write a number"
                        ),
                    });
                }
                v.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| self.err(at, format!("`{attr}` = `{v}`: a number")))
            }
        }
    }

    fn count(&self, at: &At<'x>, what: &str, n: usize, ok: bool) -> Result<()> {
        if ok {
            Ok(())
        } else {
            Err(self.err(at, format!("{what}, found {n} children")))
        }
    }

    fn classify(&self, at: &At<'x>, id: &str, n: usize) -> Result<Kind> {
        if let Some(k) = self.builtin_control(at, id, n)? {
            return Ok(k);
        }
        if let Some(k) = self.builtin_decorator(at, id)? {
            self.count(at, &format!("`{id}` is a decorator: one child"), n, n == 1)?;
            return Ok(k);
        }
        if let Some(k) = self.builtin_leaf(at, id)? {
            self.count(at, &format!("`{id}` is a leaf: no child"), n, n == 0)?;
            return Ok(k);
        }
        let unsupported = |reason: &str| Error::Unsupported {
            file: self.sources[at.doc].name.clone(),
            line: at.line,
            path: at.path.clone(),
            id: id.to_string(),
            reason: reason.to_string(),
        };
        match self.models.get(id).map(|m| m.role) {
            Some(Role::Action) | Some(Role::Condition) if n > 0 => {
                Err(self.err(at, format!("`{id}` is a leaf in its model but has {n} children")))
            }
            Some(Role::Action) => Ok(Kind::Action),
            Some(Role::Condition) => Ok(Kind::Condition),
            Some(Role::Control) | Some(Role::Decorator) => Err(unsupported(
                "a custom control node or decorator: its semantics are not known to petrinav",
            )),
            Some(Role::SubTree) => Err(self.err(
                at,
                format!("`{id}` is a subtree model: use <SubTree ID=\"{id}\"/>"),
            )),
            // v3's explicit `<Condition ID=…>` / `<Action ID=…>` says it;
            // otherwise the naming rule.
            None if n == 0 => Ok(match at.el.tag_name().name() {
                "Condition" => Kind::Condition,
                "Action" => Kind::Action,
                _ if looks_like_condition(id) => Kind::Condition,
                _ => Kind::Action,
            }),
            None => Err(Error::UnknownNode {
                file: self.sources[at.doc].name.clone(),
                line: at.line,
                path: at.path.clone(),
                role: if n == 1 { "decorator" } else { "control" },
                id: id.to_string(),
            }),
        }
    }

    fn builtin_control(&self, at: &At<'x>, id: &str, n: usize) -> Result<Option<Kind>> {
        let at_least = |k: Kind| -> Result<Option<Kind>> {
            self.count(at, &format!("`{id}` needs at least one child"), n, n >= 1)?;
            Ok(Some(k))
        };
        match id {
            "Sequence" => at_least(Kind::Sequence),
            "SequenceWithMemory" | "SequenceStar" => at_least(Kind::SequenceWithMemory),
            "ReactiveSequence" => at_least(Kind::ReactiveSequence),
            "Fallback" | "Selector" => at_least(Kind::Fallback),
            "ReactiveFallback" => at_least(Kind::ReactiveFallback),
            "PipelineSequence" => at_least(Kind::PipelineSequence),
            "RoundRobin" => at_least(Kind::RoundRobin),
            "Parallel" => {
                let v4 =
                    at.el.attribute("success_count").is_some() || at.el.attribute("failure_count").is_some();
                let (s, f) = if v4 || !self.is_v3(at.doc) {
                    ("success_count", "failure_count")
                } else {
                    ("success_threshold", "failure_threshold")
                };
                let success = self.number(at, s, Some(-1.0))? as i64;
                let failure = self.number(at, f, Some(1.0))? as i64;
                at_least(Kind::Parallel { success, failure })
            }
            "ParallelAll" => {
                let max_failures = self.number(at, "max_failures", Some(1.0))? as i64;
                at_least(Kind::ParallelAll { max_failures })
            }
            "IfThenElse" | "WhileDoElse" => {
                self.count(at, &format!("`{id}` has 2 or 3 children"), n, n == 2 || n == 3)?;
                Ok(Some(if id == "IfThenElse" {
                    Kind::IfThenElse
                } else {
                    Kind::WhileDoElse
                }))
            }
            "RecoveryNode" => {
                self.count(at, "`RecoveryNode` has exactly 2 children", n, n == 2)?;
                let r = self.number(at, "number_of_retries", Some(1.0))?;
                if r < 0.0 || r.fract() != 0.0 {
                    return Err(self.err(at, format!("number_of_retries = {r}: a whole number ≥ 0")));
                }
                Ok(Some(Kind::Recovery { retries: r as u32 }))
            }
            s if s.starts_with("Switch") && s[6..].parse::<usize>().is_ok() => {
                let cases: usize = s[6..].parse().unwrap_or(0);
                self.count(
                    at,
                    &format!("`{id}` has {} children ({cases} cases and a default)", cases + 1),
                    n,
                    n == cases + 1,
                )?;
                Ok(Some(Kind::Switch { cases: n }))
            }
            "TryCatch"
            | "ManualSelector"
            | "PersistentSequence"
            | "NonblockingSequence"
            | "PauseResumeController" => Err(Error::Unsupported {
                file: self.sources[at.doc].name.clone(),
                line: at.line,
                path: at.path.clone(),
                id: id.to_string(),
                reason: "its semantics are not modelled yet (docs/behaviour-trees.md, Limits)".into(),
            }),
            _ => Ok(None),
        }
    }

    fn builtin_decorator(&self, at: &At<'x>, id: &str) -> Result<Option<Kind>> {
        let whole = |attr: &str, default: f64| -> Result<i64> {
            let v = self.number(at, attr, Some(default))?;
            if v.fract() != 0.0 || v < -1.0 {
                return Err(self.err(at, format!("`{attr}` = {v}: a whole number ≥ -1 (-1: forever)")));
            }
            Ok(v as i64)
        };
        let seconds = |attr: &str, scale: f64| -> Result<f64> {
            let v = self.number(at, attr, None)?;
            if v < 0.0 {
                return Err(self.err(at, format!("`{attr}` = {v}: a duration ≥ 0")));
            }
            Ok(v * scale)
        };
        Ok(Some(match id {
            "Inverter" => Kind::Inverter,
            "ForceSuccess" => Kind::ForceSuccess,
            "ForceFailure" => Kind::ForceFailure,
            "Repeat" => Kind::Repeat {
                cycles: whole("num_cycles", 1.0)?,
            },
            "RetryUntilSuccessful" | "RetryUntilSuccesful" => Kind::Retry {
                attempts: whole("num_attempts", 1.0)?,
            },
            "KeepRunningUntilFailure" => Kind::KeepRunningUntilFailure,
            "Timeout" => Kind::Timeout {
                mean_s: seconds("msec", 1e-3)?,
            },
            "Delay" => Kind::Delay {
                mean_s: seconds("delay_msec", 1e-3)?,
            },
            "RateController" => {
                let hz = self.number(at, "hz", Some(10.0))?;
                if hz <= 0.0 {
                    return Err(self.err(at, format!("`hz` = {hz}: a rate > 0")));
                }
                Kind::Periodic {
                    mean_interval_s: Some(1.0 / hz),
                }
            }
            "DistanceController" | "SpeedController" | "GoalUpdatedController" => Kind::Periodic {
                mean_interval_s: None,
            },
            "GoalUpdater" | "SingleTrigger" => Kind::PassThrough,
            "PathLongerOnApproach" => Kind::Gate,
            "RunOnce"
            | "Precondition"
            | "LoopInt"
            | "LoopDouble"
            | "LoopString"
            | "LoopBool"
            | "SkipUnlessUpdated"
            | "WaitValueUpdate"
            | "ConsumeQueue"
            | "BlackboardCheckInt"
            | "BlackboardCheckDouble"
            | "BlackboardCheckString"
            | "BlackboardCheckBool" => {
                return Err(Error::Unsupported {
                    file: self.sources[at.doc].name.clone(),
                    line: at.line,
                    path: at.path.clone(),
                    id: id.to_string(),
                    reason: "its semantics depend on blackboard values or scripts, which are not modelled"
                        .into(),
                });
            }
            _ => return Ok(None),
        }))
    }

    fn builtin_leaf(&self, at: &At<'x>, id: &str) -> Result<Option<Kind>> {
        Ok(Some(match id {
            "AlwaysSuccess" | "SetBlackboard" | "UnsetBlackboard" | "Script" => {
                Kind::Constant { success: true }
            }
            "AlwaysFailure" => Kind::Constant { success: false },
            "ScriptCondition" | "WasEntryUpdated" => Kind::Condition,
            "Sleep" => {
                let ms = self.number(at, "msec", None)?;
                if ms < 0.0 {
                    return Err(self.err(at, format!("`msec` = {ms}: a duration ≥ 0")));
                }
                Kind::Sleep { mean_s: ms * 1e-3 }
            }
            _ => return Ok(None),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Tree> {
        read_str(text, "t.xml", None, &ReadOptions::default())
    }

    #[test]
    fn reads_v4_with_subtree_remapping() {
        let t = read(
            r#"<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <SetBlackboard output_key="goal" value="1"/>
      <SubTree ID="Go" target="{goal}"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Go">
    <ComputePathToPose goal="{target}" path="{path}"/>
  </BehaviorTree>
</root>"#,
        )
        .unwrap();
        assert_eq!(t.len(), 4);
        let leaf = t.nodes.iter().find(|n| n.id == "ComputePathToPose").unwrap();
        assert_eq!(leaf.path, "Main/Sequence#0/SubTree(Go)/ComputePathToPose#0");
        let goal = leaf.ports.iter().find(|p| p.name == "goal").unwrap();
        assert_eq!(goal.key.as_deref(), Some("goal"));
        assert_eq!(goal.direction, Direction::Input);
        let path = leaf.ports.iter().find(|p| p.name == "path").unwrap();
        assert_eq!(path.key.as_deref(), Some("Go#1/path"), "private to the instance");
    }

    #[test]
    fn subtree_cycle_is_an_error_naming_the_cycle() {
        let e = read(
            r#"<root BTCPP_format="4" main_tree_to_execute="A">
  <BehaviorTree ID="A"><SubTree ID="B"/></BehaviorTree>
  <BehaviorTree ID="B"><Sequence><SubTree ID="A"/></Sequence></BehaviorTree>
</root>"#,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("subtree cycle: A → B → A"), "{e}");
        assert!(e.contains("t.xml:3"), "{e}");
    }

    #[test]
    fn unknown_control_node_is_named() {
        let e = read(r#"<root BTCPP_format="4"><BehaviorTree ID="A"><Frobnicate><AlwaysSuccess/><AlwaysSuccess/></Frobnicate></BehaviorTree></root>"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown control node `Frobnicate`"), "{e}");
    }

    #[test]
    fn truncated_xml_names_the_position() {
        let e = read("<root BTCPP_format=\"4\">\n<BehaviorTree ID=\"A\">\n<Sequence>")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.xml:3:"), "{e}");
    }

    #[test]
    fn v3_explicit_forms() {
        let t = read(
            r#"<root main_tree_to_execute="M">
  <BehaviorTree ID="M">
    <SequenceStar>
      <Condition ID="BatteryOK"/>
      <Action ID="Charge"/>
      <SubTree ID="S" x="y"/>
    </SequenceStar>
  </BehaviorTree>
  <BehaviorTree ID="S"><Action ID="Use" v="{x}"/></BehaviorTree>
</root>"#,
        )
        .unwrap();
        assert_eq!(t.format, 3);
        assert_eq!(t.nodes[1].kind, Kind::Condition);
        let use_ = t.nodes.iter().find(|n| n.id == "Use").unwrap();
        assert_eq!(use_.ports[0].key.as_deref(), Some("y"));
    }
}
