//! GreatSPN editor project files (`.PNPRO`), the de-facto exchange format for
//! GSPNs, also read and written by the Storm model checker.
//!
//! # Reading
//!
//! A project holds one or more `<gspn name=…>` nets (and other pages, such as
//! measures, which are skipped). [`read_pnpro`] reads the first net;
//! [`read_pnpro_named`] picks one by name.
//!
//! | element | read as | defaults (GreatSPN's) |
//! |---|---|---|
//! | `<place name marking>` | [`Place`], `marking` an expression | `marking` 0 |
//! | `<transition type="EXP" delay nservers>` | timed; `delay` is the **rate** expression | `delay` 1.0; `nservers` absent: **infinite** servers |
//! | `<transition type="IMM" weight priority>` | immediate | `weight` 1.0, `priority` 1 |
//! | `<transition type="IMM" weight="0">` | a **decision** (Storm's convention: a weight-0 immediate transition is a choice of its own) | |
//! | `<constant name consttype value>` | [`Param`] with its value | `INTEGER` → int, `REAL` → real |
//! | `<template name type last-binding>` | [`Param`] without value, `last-binding` as the suggested value | |
//! | `<arc kind head tail mult>` | `INPUT` (tail = place, head = transition), `OUTPUT` (tail = transition, head = place), `INHIBITOR` (tail = place) | `mult` 1 |
//!
//! - `nservers` is `Infinite`, `Single`, `1` (single server), or a whole
//!   number `k` (k servers); it may be an expression over constants that have
//!   a value, evaluated when reading.
//! - A constant without a value is read as a parameter without value, like a
//!   template: it must be given at load or solve time (`--param N=3`).
//! - A constant's value may be an expression over other constants; it is
//!   evaluated when reading (a parameter holds a number). One that depends on
//!   a template is refused, naming both.
//! - A template's suggested value is taken from the project's measures page
//!   (`<measures gspn-name=…><assignments><assignment varname single-val>`)
//!   when it has one, else from `last-binding`. It is never used silently: the
//!   error for a missing value shows it.
//! - Node positions (`x`, `y`) are kept in `position`. Every other layout
//!   attribute and element (`label-x`, `delay-x`, `rotation`, `magnets`,
//!   `mult-k`, `<point>`, `<text-box>`, `<measures>`, `<resource-list>`, …) is
//!   skipped, as are unknown elements.
//! - Refused with an error naming the element: transitions of type `GEN`
//!   (general distributions), `CONT` and continuous places (fluid nets),
//!   coloured nets (`<colorclass>`, `<color-var>`, places with a `domain`),
//!   transitions with a `guard`, `<clock-var>`.
//! - Expressions are parsed with [`Expr::parse`]; an
//!   error names the element and attribute and gives `file:line:column` of
//!   the attribute's value.
//!
//! # Writing
//!
//! [`write_pnpro`] writes a project the GreatSPN editor opens:
//! `<project name version="121"><gspn name><nodes>…</nodes><edges>…</edges></gspn></project>`.
//!
//! - Parameters with a value become `<constant consttype value>`, parameters
//!   without one `<template type last-binding>` (`last-binding` = the
//!   suggested value, when there is one).
//! - `nservers` is written as `1` for a single server and `k` for k servers,
//!   and omitted for infinite servers (the editor's default).
//! - Rates, weights, priorities, markings and multiplicities are written as
//!   expression text ([`Expr`]'s `Display`), which GreatSPN shares for
//!   numbers, names and arithmetic. Default values are omitted.
//! - Nodes without a position are laid out on a grid below the others;
//!   parameters are placed below the net.
//!
//! What PNPRO cannot hold: place **capacities** (writing refuses them rather
//! than change the net's behaviour silently), labels and reward models
//! (refused rather than lost), documentation, a value
//! suggested for a parameter that has a value, k = 1 servers as distinct from
//! a single server, and a timed transition **without rate** (the `delay` is
//! omitted, which GreatSPN reads as rate 1). Names are written as they are:
//! the GreatSPN editor expects identifiers (letters, digits, `_`) and may
//! refuse others.

use std::collections::HashMap;

use roxmltree::Node;

use super::{fmt_f64, parse_expr, parse_f64, push_attr};
use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::net::{
    ArcKind, Net, Param, ParamKind, Place, PlaceId, Servers, Transition, TransitionId, TransitionKind,
};

/// Reads the first `<gspn>` net of a GreatSPN project. `source` names the
/// text in error messages (a file name).
pub fn read_pnpro(text: &str, source: &str) -> Result<Net> {
    read_pnpro_named(text, source, None)
}

/// Reads the `<gspn>` net called `gspn` of a GreatSPN project (the first
/// one when `None`).
pub fn read_pnpro_named(text: &str, source: &str, gspn: Option<&str>) -> Result<Net> {
    let text = super::prepare(text, source)?;
    // One place, transition or arc parsed at a time where the file allows
    // it (`xml_split`), else the whole document at once.
    let split = super::xml_split::split(text, &["nodes", "edges"]);
    let doc = super::parse_xml(split.as_ref().map_or(text, |s| s.skeleton.as_str()), source)?;
    let root = doc.root_element();
    let r = Reader {
        source,
        text,
        split: split.as_ref(),
        base: None,
    };
    if root.tag_name().name() != "project" {
        return Err(r.error(
            root,
            format!(
                "expected a GreatSPN project (root element <project>), found <{}>",
                root.tag_name().name()
            ),
        ));
    }
    let pages: Vec<Node<'_, '_>> = elements(root).filter(|n| n.tag_name().name() == "gspn").collect();
    let page = match gspn {
        None => pages.first().copied(),
        Some(name) => pages.iter().copied().find(|p| p.attribute("name") == Some(name)),
    };
    let Some(page) = page else {
        let names: Vec<String> = pages
            .iter()
            .filter_map(|p| p.attribute("name"))
            .map(|n| format!("`{n}`"))
            .collect();
        let message = match gspn {
            None => "the project has no <gspn> net".to_string(),
            Some(name) => format!(
                "the project has no <gspn> net called `{name}` (its nets: {})",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            ),
        };
        return Err(r.error(root, message));
    };
    let net = r.read_gspn(root, page)?;
    super::finish(net)
}

fn elements<'a, 'i>(node: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    node.children().filter(Node::is_element)
}

/// The file being read: its name, its text, how it was cut (`None`: one
/// document), and the fragment being read (`None`: the skeleton or the
/// whole document), whose positions are placed back in the file.
#[derive(Clone, Copy)]
struct Reader<'s> {
    source: &'s str,
    text: &'s str,
    split: Option<&'s super::xml_split::XmlSplit>,
    base: Option<&'s super::xml_split::Fragment>,
}

/// What a name in the net refers to, for duplicate detection.
#[derive(Clone, Copy)]
enum Named {
    Place(PlaceId),
    Transition(TransitionId),
    Param,
}

impl Named {
    fn what(self) -> &'static str {
        match self {
            Named::Place(_) => "a place",
            Named::Transition(_) => "a transition",
            Named::Param => "a parameter",
        }
    }
}

impl<'s> Reader<'s> {
    fn error(&self, node: Node<'_, '_>, message: String) -> Error {
        Error::Format {
            location: self.loc(node),
            message,
        }
    }

    fn attr_error(&self, node: Node<'_, '_>, attr: &str, message: String) -> Error {
        Error::Format {
            location: self.attr_loc(node, attr),
            message,
        }
    }

    /// `file:line:column` of a node, in the whole file.
    fn loc(&self, node: Node<'_, '_>) -> String {
        super::located(self.source, super::xml_pos(node), self.base)
    }

    /// `file:line:column` of an attribute's value (or its element), in
    /// the whole file.
    fn attr_loc(&self, node: Node<'_, '_>, attr: &str) -> String {
        super::located(self.source, super::attr_pos(node, attr), self.base)
    }

    /// Calls `f` on every child element of `container`, with the reader of
    /// the fragment it was parsed from when the file was cut.
    fn each_child(
        &self,
        container: Node<'_, '_>,
        f: &mut dyn FnMut(&Reader<'s>, Node<'_, '_>) -> Result<()>,
    ) -> Result<()> {
        let Some(split) = self.split else {
            return elements(container).try_for_each(|n| f(self, n));
        };
        for fragment in split.children(container.range().start) {
            let doc = super::parse_fragment(self.text, fragment, self.source)?;
            let r = Reader {
                base: Some(fragment),
                ..*self
            };
            f(&r, doc.root_element())?;
        }
        Ok(())
    }

    fn name(&self, node: Node<'_, '_>) -> Result<String> {
        match node.attribute("name") {
            Some(n) if !n.trim().is_empty() => Ok(n.to_string()),
            _ => Err(self.error(
                node,
                format!("<{}> without a `name` attribute", node.tag_name().name()),
            )),
        }
    }

    /// An attribute holding an expression; absent or blank gives `default`.
    fn expr_attr(&self, node: Node<'_, '_>, attr: &str, owner: &str, default: Expr) -> Result<Expr> {
        match node.attribute(attr) {
            Some(t) if !t.trim().is_empty() => parse_expr(
                t,
                || self.attr_loc(node, attr),
                || format!("{owner}, attribute `{attr}`"),
            ),
            _ => Ok(default),
        }
    }

    fn position(&self, node: Node<'_, '_>, owner: &str) -> Result<Option<(f64, f64)>> {
        let coord = |attr: &str| -> Result<Option<f64>> {
            match node.attribute(attr) {
                None => Ok(None),
                Some(t) => parse_f64(t).map(Some).ok_or_else(|| {
                    self.attr_error(
                        node,
                        attr,
                        format!("{owner}: attribute `{attr}` is not a number: `{t}`"),
                    )
                }),
            }
        };
        Ok(match (coord("x")?, coord("y")?) {
            (Some(x), Some(y)) => Some((x, y)),
            _ => None,
        })
    }

    fn register(&self, names: &mut HashMap<String, Named>, name: &str, what: Named) -> Result<()> {
        if let Some(first) = names.get(name) {
            return Err(Error::DuplicateName {
                name: name.to_string(),
                first: first.what(),
                second: what.what(),
            });
        }
        names.insert(name.to_string(), what);
        Ok(())
    }

    fn read_gspn(&self, project: Node<'_, '_>, page: Node<'_, '_>) -> Result<Net> {
        let net_name = page
            .attribute("name")
            .or(project.attribute("name"))
            .filter(|n| !n.trim().is_empty())
            .map_or_else(|| super::default_net_name(self.source), str::to_string);
        let mut net = Net::new(net_name);
        let mut names: HashMap<String, Named> = HashMap::new();
        let containers = |tag: &'static str| elements(page).filter(move |n| n.tag_name().name() == tag);

        // First pass: parameters, so that constants have values when
        // `nservers` is evaluated.
        let suggestions = measure_assignments(project, net.name.as_str());
        let mut constants: Vec<(usize, Expr, String)> = Vec::new();
        for nodes in containers("nodes") {
            self.each_child(nodes, &mut |r, node| {
                r.parameter(node, &mut net, &mut names, &suggestions, &mut constants)
            })?;
        }
        self.evaluate_constants(&mut net, constants)?;

        // Second pass: places and transitions.
        for nodes in containers("nodes") {
            self.each_child(nodes, &mut |r, node| match node.tag_name().name() {
                "place" => r.place(node, &mut net, &mut names),
                "transition" => r.transition(node, &mut net, &mut names),
                _ => Ok(()),
            })?;
        }

        // Arcs.
        for edges in containers("edges") {
            self.each_child(edges, &mut |r, arc| {
                if arc.tag_name().name() == "arc" {
                    r.arc(arc, &mut net, &names)?;
                }
                Ok(())
            })?;
        }
        Ok(net)
    }

    /// A `<constant>` or `<template>` of `<nodes>` (other elements are
    /// left to the second pass): registered, its value's expression kept
    /// with its location for [`Reader::evaluate_constants`].
    fn parameter(
        &self,
        node: Node<'_, '_>,
        net: &mut Net,
        names: &mut HashMap<String, Named>,
        suggestions: &HashMap<&str, f64>,
        constants: &mut Vec<(usize, Expr, String)>,
    ) -> Result<()> {
        match node.tag_name().name() {
            "constant" => {
                let name = self.name(node)?;
                self.register(names, &name, Named::Param)?;
                let owner = format!("constant `{name}`");
                let kind = self.param_kind(node, "consttype", &owner)?;
                if let Some(value) = node.attribute("value").filter(|v| !v.trim().is_empty()) {
                    let e = parse_expr(
                        value,
                        || self.attr_loc(node, "value"),
                        || format!("{owner}, attribute `value`"),
                    )?;
                    constants.push((net.params.len(), e, self.attr_loc(node, "value")));
                }
                net.params.push(Param {
                    name,
                    value: None,
                    kind,
                    suggested: None,
                    doc: None,
                });
            }
            "template" => {
                let name = self.name(node)?;
                self.register(names, &name, Named::Param)?;
                let owner = format!("template `{name}`");
                let kind = self.param_kind(node, "type", &owner)?;
                let last_binding = match node.attribute("last-binding").filter(|v| !v.trim().is_empty()) {
                    None => None,
                    Some(t) => Some(parse_f64(t).ok_or_else(|| {
                        self.attr_error(
                            node,
                            "last-binding",
                            format!("{owner}: attribute `last-binding` is not a number: `{t}`"),
                        )
                    })?),
                };
                let suggested = suggestions.get(name.as_str()).copied().or(last_binding);
                net.params.push(Param {
                    name,
                    value: None,
                    kind,
                    suggested,
                    doc: None,
                });
            }
            tag @ ("colorclass" | "color-var" | "clock-var") => {
                return Err(self.error(
                    node,
                    format!(
                        "<{tag}{}>: coloured nets and clocks are not supported (only GSPNs with EXP and IMM transitions)",
                        node.attribute("name").map(|n| format!(" name=\"{n}\"")).unwrap_or_default()
                    ),
                ));
            }
            _ => {}
        }
        Ok(())
    }

    fn param_kind(&self, node: Node<'_, '_>, attr: &str, owner: &str) -> Result<ParamKind> {
        match node.attribute(attr) {
            None => Ok(ParamKind::Real),
            Some(t) if t.eq_ignore_ascii_case("REAL") => Ok(ParamKind::Real),
            Some(t) if t.eq_ignore_ascii_case("INTEGER") => Ok(ParamKind::Int),
            Some(t) => Err(self.attr_error(
                node,
                attr,
                format!("{owner}: type `{t}` is not supported (only INTEGER and REAL)"),
            )),
        }
    }

    /// Gives constants their values; a value may use other constants.
    fn evaluate_constants(&self, net: &mut Net, mut pending: Vec<(usize, Expr, String)>) -> Result<()> {
        let mut values: HashMap<String, f64> = HashMap::new();
        loop {
            let before = pending.len();
            let mut still = Vec::new();
            for (i, e, location) in pending {
                let mut ready = true;
                e.for_each_param(&mut |n| ready &= values.contains_key(n));
                if !ready {
                    still.push((i, e, location));
                    continue;
                }
                let Some(param) = net.params.get_mut(i) else {
                    continue;
                };
                let v = e
                    .eval_params(&|n| values.get(n).copied(), &format!("constant `{}`", param.name))
                    .map_err(|err| Error::Format {
                        location,
                        message: err.to_string(),
                    })?;
                param.value = Some(v);
                values.insert(param.name.clone(), v);
            }
            pending = still;
            if pending.is_empty() || pending.len() == before {
                break;
            }
        }
        let waiting: Vec<String> = pending
            .iter()
            .filter_map(|(i, _, _)| net.params.get(*i).map(|p| p.name.clone()))
            .collect();
        if let Some((i, e, location)) = pending.into_iter().next() {
            let owner = net.params.get(i).map(|p| p.name.clone()).unwrap_or_default();
            let mut missing = None;
            e.for_each_param(&mut |n| {
                if missing.is_none() && !values.contains_key(n) {
                    missing = Some(n.to_string());
                }
            });
            let missing = missing.unwrap_or_default();
            let why = if waiting.contains(&missing) {
                format!("the values of `{owner}` and `{missing}` depend on each other")
            } else if net.param(&missing).is_some() {
                format!(
                    "`{missing}` has no value (a template, or a constant without value); a constant's value may only use numbers and constants with values"
                )
            } else {
                format!("`{missing}` is not defined")
            };
            return Err(Error::Format {
                location,
                message: format!("constant `{owner}`: cannot evaluate its value `{e}`: {why}"),
            });
        }
        Ok(())
    }

    fn place(&self, node: Node<'_, '_>, net: &mut Net, names: &mut HashMap<String, Named>) -> Result<()> {
        let name = self.name(node)?;
        let owner = format!("place `{name}`");
        if let Some(t) = node
            .attribute("type")
            .filter(|t| !t.eq_ignore_ascii_case("DISCRETE"))
        {
            return Err(self.attr_error(
                node,
                "type",
                format!("{owner}: places of type `{t}` (fluid nets) are not supported"),
            ));
        }
        if let Some(d) = node.attribute("domain").filter(|d| !d.trim().is_empty()) {
            return Err(self.attr_error(
                node,
                "domain",
                format!("{owner}: coloured places (domain `{d}`) are not supported"),
            ));
        }
        let initial = self.expr_attr(node, "marking", &owner, Expr::Num(0.0))?;
        let position = self.position(node, &owner)?;
        self.register(names, &name, Named::Place(PlaceId(net.places.len() as u32)))?;
        net.places.push(Place {
            name,
            initial,
            capacity: None,
            position,
            doc: None,
        });
        Ok(())
    }

    fn transition(
        &self,
        node: Node<'_, '_>,
        net: &mut Net,
        names: &mut HashMap<String, Named>,
    ) -> Result<()> {
        let name = self.name(node)?;
        let owner = format!("transition `{name}`");
        if let Some(g) = node
            .attribute("guard")
            .filter(|g| !g.trim().is_empty() && !g.trim().eq_ignore_ascii_case("true"))
        {
            return Err(self.attr_error(
                node,
                "guard",
                format!("{owner}: transition guards are not supported (guard `{g}`)"),
            ));
        }
        let kind = match node.attribute("type").unwrap_or("EXP") {
            t if t.eq_ignore_ascii_case("EXP") => TransitionKind::Timed {
                rate: Some(self.expr_attr(node, "delay", &owner, Expr::Num(1.0))?),
                servers: self.servers(node, net, &owner)?,
            },
            t if t.eq_ignore_ascii_case("IMM") => TransitionKind::Immediate {
                weight: self.expr_attr(node, "weight", &owner, Expr::Num(1.0))?,
                priority: self.expr_attr(node, "priority", &owner, Expr::Num(1.0))?,
            },
            t => {
                let why = match t.to_ascii_uppercase().as_str() {
                    "GEN" | "DET" => "general (non-exponential) delays are not supported",
                    "CONT" => "continuous transitions (fluid nets) are not supported",
                    _ => "unknown transition type",
                };
                return Err(self.attr_error(
                    node,
                    "type",
                    format!(
                        "{owner}: type `{t}`: {why}; only EXP (timed) and IMM (immediate) transitions are"
                    ),
                ));
            }
        };
        // Storm's convention: an immediate transition of weight 0 is a
        // choice of its own, a decision (the literal number 0 only).
        let (kind, decision) = match kind {
            TransitionKind::Immediate {
                weight: Expr::Num(0.0),
                priority,
            } => (
                TransitionKind::Immediate {
                    weight: Expr::Num(1.0),
                    priority,
                },
                true,
            ),
            kind => (kind, false),
        };
        let position = self.position(node, &owner)?;
        self.register(
            names,
            &name,
            Named::Transition(TransitionId(net.transitions.len() as u32)),
        )?;
        net.transitions.push(Transition {
            name,
            kind,
            decision,
            position,
            doc: None,
        });
        Ok(())
    }

    fn servers(&self, node: Node<'_, '_>, net: &Net, owner: &str) -> Result<Servers> {
        let Some(text) = node
            .attribute("nservers")
            .map(str::trim)
            .filter(|t| !t.is_empty())
        else {
            return Ok(Servers::Infinite);
        };
        if text.eq_ignore_ascii_case("infinite") {
            return Ok(Servers::Infinite);
        }
        if text.eq_ignore_ascii_case("single") {
            return Ok(Servers::Single);
        }
        let e = parse_expr(
            text,
            || self.attr_loc(node, "nservers"),
            || format!("{owner}, attribute `nservers`"),
        )?;
        let v = e
            .eval_params(
                &|n| net.param(n).and_then(|p| p.value),
                &format!("the number of servers of {owner}"),
            )
            .map_err(|err| self.attr_error(node, "nservers", err.to_string()))?;
        if !(v.is_finite() && v >= 1.0 && v == v.trunc() && v <= f64::from(u32::MAX)) {
            return Err(self.attr_error(
                node,
                "nservers",
                format!("{owner}: `nservers` must be Infinite or a whole number ≥ 1, got `{text}` = {v}"),
            ));
        }
        Ok(if v == 1.0 {
            Servers::Single
        } else {
            Servers::K(v as u32)
        })
    }

    fn arc(&self, node: Node<'_, '_>, net: &mut Net, names: &HashMap<String, Named>) -> Result<()> {
        let attr = |a: &str| -> Result<&str> {
            node.attribute(a)
                .ok_or_else(|| self.error(node, format!("<arc> without a `{a}` attribute")))
        };
        let (head, tail, kind_text) = (attr("head")?, attr("tail")?, attr("kind")?);
        let describe = || format!("{}: {kind_text} arc from `{tail}` to `{head}`", self.loc(node));
        let (place_name, transition_name, kind) = match kind_text.to_ascii_uppercase().as_str() {
            "INPUT" => (tail, head, ArcKind::Input),
            "OUTPUT" => (head, tail, ArcKind::Output),
            "INHIBITOR" => (tail, head, ArcKind::Inhibitor),
            _ => {
                return Err(self.attr_error(
                    node,
                    "kind",
                    format!("arc from `{tail}` to `{head}`: unknown kind `{kind_text}` (expected INPUT, OUTPUT or INHIBITOR)"),
                ));
            }
        };
        let place = match names.get(place_name) {
            Some(Named::Place(p)) => *p,
            _ => {
                return Err(Error::UnknownNode {
                    arc: describe(),
                    expected: "place",
                    name: place_name.to_string(),
                    hint: crate::suggest::hint(
                        place_name,
                        names
                            .iter()
                            .filter(|(_, n)| matches!(n, Named::Place(_)))
                            .map(|(k, _)| k.as_ref()),
                    ),
                });
            }
        };
        let transition = match names.get(transition_name) {
            Some(Named::Transition(t)) => *t,
            _ => {
                return Err(Error::UnknownNode {
                    arc: describe(),
                    expected: "transition",
                    name: transition_name.to_string(),
                    hint: crate::suggest::hint(
                        transition_name,
                        names
                            .iter()
                            .filter(|(_, n)| matches!(n, Named::Transition(_)))
                            .map(|(k, _)| k.as_ref()),
                    ),
                });
            }
        };
        let owner = format!("{kind_text} arc from `{tail}` to `{head}`");
        let multiplicity = self.expr_attr(node, "mult", &owner, Expr::Num(1.0))?;
        net.add_arc(kind, place, transition, multiplicity);
        Ok(())
    }
}

/// Values assigned to templates on the project's measures pages for the net
/// `gspn` (`single-val` of `<assignment varname>`), first one wins.
fn measure_assignments<'a>(project: Node<'a, '_>, gspn: &str) -> HashMap<&'a str, f64> {
    let mut out = HashMap::new();
    let pages = elements(project)
        .filter(|n| n.tag_name().name() == "measures")
        .filter(|n| n.attribute("gspn-name").is_none_or(|g| g == gspn));
    for page in pages {
        for assignments in elements(page).filter(|n| n.tag_name().name() == "assignments") {
            for a in elements(assignments).filter(|n| n.tag_name().name() == "assignment") {
                let single = a
                    .attribute("bind-model")
                    .is_none_or(|m| m.eq_ignore_ascii_case("SINGLE_VALUE"));
                if let (true, Some(name), Some(v)) = (
                    single,
                    a.attribute("varname"),
                    a.attribute("single-val").and_then(parse_f64),
                ) {
                    out.entry(name).or_insert(v);
                }
            }
        }
    }
    out
}

/// Writes a net as a GreatSPN editor project.
///
/// Fails if a place has a capacity, or the net labels or reward models
/// (PNPRO cannot hold them), or if a name contains a character XML cannot
/// represent.
pub fn write_pnpro(net: &Net) -> Result<String> {
    net.validate()?;
    if !net.labels.is_empty() || !net.rewards.is_empty() {
        return Err(Error::Invalid(format!(
            "PNPRO cannot hold labels or reward models (the net has {} label(s) and {} reward model(s)); write the net as TOML or PNML instead",
            net.labels.len(),
            net.rewards.len()
        )));
    }
    if let Some(p) = net.places.iter().find(|p| p.capacity.is_some()) {
        return Err(Error::Invalid(format!(
            "PNPRO cannot hold place capacities (place `{}` has capacity {}); write the net as TOML or PNML instead",
            p.name,
            p.capacity.unwrap_or_default()
        )));
    }
    let layout = Layout::new(net);
    let mut out =
        String::with_capacity(256 + 120 * (net.places.len() + net.transitions.len() + net.arcs.len()));
    out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n");
    out.push_str("<!-- Written by petrinav -->\n");
    let net_what = || "the net's name".to_string();
    out.push_str("<project");
    push_attr(&mut out, "name", &net.name, &net_what)?;
    out.push_str(" version=\"121\">\n  <gspn");
    push_attr(&mut out, "name", &net.name, &net_what)?;
    out.push_str(">\n    <nodes>\n");
    for (p, &(x, y)) in net.places.iter().zip(&layout.places) {
        let what = || format!("place `{}`", p.name);
        out.push_str("      <place");
        push_attr(&mut out, "name", &p.name, &what)?;
        if p.initial != Expr::Num(0.0) {
            push_attr(&mut out, "marking", &p.initial.to_string(), &what)?;
        }
        push_xy(&mut out, x, y);
        out.push_str("/>\n");
    }
    for (t, &(x, y)) in net.transitions.iter().zip(&layout.transitions) {
        let what = || format!("transition `{}`", t.name);
        out.push_str("      <transition");
        push_attr(&mut out, "name", &t.name, &what)?;
        match &t.kind {
            TransitionKind::Timed { rate, servers } => {
                out.push_str(" type=\"EXP\"");
                if let Some(r) = rate {
                    push_attr(&mut out, "delay", &r.to_string(), &what)?;
                }
                match servers {
                    Servers::Single => out.push_str(" nservers=\"1\""),
                    Servers::K(k) => out.push_str(&format!(" nservers=\"{k}\"")),
                    Servers::Infinite => {}
                }
            }
            TransitionKind::Immediate { weight, priority } => {
                out.push_str(" type=\"IMM\"");
                if t.decision {
                    out.push_str(" weight=\"0\"");
                } else if *weight != Expr::Num(1.0) {
                    push_attr(&mut out, "weight", &weight.to_string(), &what)?;
                }
                if *priority != Expr::Num(1.0) {
                    push_attr(&mut out, "priority", &priority.to_string(), &what)?;
                }
            }
        }
        push_xy(&mut out, x, y);
        out.push_str("/>\n");
    }
    for (p, &(x, y)) in net.params.iter().zip(&layout.params) {
        let what = || format!("parameter `{}`", p.name);
        let ty = match p.kind {
            ParamKind::Int => "INTEGER",
            ParamKind::Real => "REAL",
        };
        match p.value {
            Some(v) => {
                out.push_str("      <constant");
                push_attr(&mut out, "name", &p.name, &what)?;
                out.push_str(&format!(" consttype=\"{ty}\" value=\"{}\"", fmt_f64(v)));
            }
            None => {
                out.push_str("      <template");
                push_attr(&mut out, "name", &p.name, &what)?;
                out.push_str(&format!(" type=\"{ty}\""));
                if let Some(s) = p.suggested {
                    out.push_str(&format!(" last-binding=\"{}\"", fmt_f64(s)));
                }
            }
        }
        push_xy(&mut out, x, y);
        out.push_str("/>\n");
    }
    out.push_str("    </nodes>\n    <edges>\n");
    for a in &net.arcs {
        // `validate` guarantees the indices.
        let (Some(p), Some(t)) = (
            net.places.get(a.place.index()),
            net.transitions.get(a.transition.index()),
        ) else {
            continue;
        };
        let what = || format!("the arc between `{}` and `{}`", p.name, t.name);
        let (kind, tail, head) = match a.kind {
            ArcKind::Input => ("INPUT", &p.name, &t.name),
            ArcKind::Output => ("OUTPUT", &t.name, &p.name),
            ArcKind::Inhibitor => ("INHIBITOR", &p.name, &t.name),
        };
        out.push_str("      <arc");
        push_attr(&mut out, "head", head, &what)?;
        out.push_str(&format!(" kind=\"{kind}\""));
        if a.multiplicity != Expr::Num(1.0) {
            push_attr(&mut out, "mult", &a.multiplicity.to_string(), &what)?;
        }
        push_attr(&mut out, "tail", tail, &what)?;
        out.push_str("/>\n");
    }
    out.push_str("    </edges>\n  </gspn>\n</project>\n");
    Ok(out)
}

fn push_xy(out: &mut String, x: f64, y: f64) {
    out.push_str(&format!(" x=\"{}\" y=\"{}\"", fmt_f64(x), fmt_f64(y)));
}

/// Positions for writing: the nodes' own, a grid for the others.
struct Layout {
    places: Vec<(f64, f64)>,
    transitions: Vec<(f64, f64)>,
    params: Vec<(f64, f64)>,
}

impl Layout {
    /// Distance between grid points, in GreatSPN units (a place is 2 wide).
    const STEP: f64 = 4.0;

    fn new(net: &Net) -> Layout {
        let given = net
            .places
            .iter()
            .map(|p| p.position)
            .chain(net.transitions.iter().map(|t| t.position));
        let mut max_y: Option<f64> = None;
        let mut missing = 0usize;
        for pos in given {
            match pos {
                Some((_, y)) if y.is_finite() => max_y = Some(max_y.map_or(y, |m: f64| m.max(y))),
                Some(_) => {}
                None => missing += 1,
            }
        }
        let columns = ((missing as f64).sqrt().ceil() as usize).max(1);
        let top = max_y.map_or(2.0, |m| m + Self::STEP);
        let mut k = 0usize;
        let mut bottom = max_y.unwrap_or(0.0);
        let mut place_at = |pos: Option<(f64, f64)>| -> (f64, f64) {
            match pos {
                Some(p) => p,
                None => {
                    let x = 2.0 + Self::STEP * (k % columns) as f64;
                    let y = top + Self::STEP * (k / columns) as f64;
                    k += 1;
                    bottom = bottom.max(y);
                    (x, y)
                }
            }
        };
        let places = net.places.iter().map(|p| place_at(p.position)).collect();
        let transitions = net.transitions.iter().map(|t| place_at(t.position)).collect();
        let params = (0..net.params.len())
            .map(|i| (2.0 + 8.0 * (i % 5) as f64, bottom + 4.0 + (i / 5) as f64))
            .collect();
        Layout {
            places,
            transitions,
            params,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<project name="p" version="121">
  <gspn name="first">
    <nodes>
      <place name="a" marking="N" x="1" y="2"/>
      <place name="b"/>
      <transition name="t" type="EXP" delay="2*lambda" nservers="K" x="3" y="4"/>
      <transition name="u" type="IMM" weight="0.5" priority="2"/>
      <constant name="lambda" consttype="REAL" value="0.5"/>
      <constant name="K" consttype="INTEGER" value="M + 1"/>
      <constant name="M" consttype="INTEGER" value="2"/>
      <template name="N" type="INTEGER" last-binding="4"/>
      <text-box name="__t">hello</text-box>
    </nodes>
    <edges>
      <arc head="t" kind="INPUT" tail="a" mult="2"><point x="1" y="1"/></arc>
      <arc head="b" kind="OUTPUT" tail="t"/>
      <arc head="u" kind="INPUT" tail="b"/>
      <arc head="a" kind="OUTPUT" tail="u"/>
      <arc head="t" kind="INHIBITOR" tail="b" mult="3"/>
    </edges>
  </gspn>
  <gspn name="second">
    <nodes><place name="z"/></nodes>
  </gspn>
</project>"#;

    #[test]
    fn reads_attributes_and_defaults() {
        let net = read_pnpro(SMALL, "small.PNPRO").unwrap();
        assert_eq!(net.name, "first");
        assert_eq!(net.places[0].initial, Expr::param("N"));
        assert_eq!(net.places[0].position, Some((1.0, 2.0)));
        assert_eq!(net.places[1].initial, Expr::Num(0.0));
        assert_eq!(net.places[1].position, None);
        assert_eq!(
            net.transitions[0].kind,
            TransitionKind::Timed {
                rate: Some(Expr::parse("2*lambda").unwrap()),
                servers: Servers::K(3)
            }
        );
        assert_eq!(
            net.transitions[1].kind,
            TransitionKind::Immediate {
                weight: Expr::Num(0.5),
                priority: Expr::Num(2.0)
            }
        );
        let k = net.param("K").unwrap();
        assert_eq!((k.value, k.kind), (Some(3.0), ParamKind::Int));
        let n = net.param("N").unwrap();
        assert_eq!((n.value, n.suggested), (None, Some(4.0)));
        assert_eq!(net.arcs.len(), 5);
        // Canonical order: transition t (input, output, inhibitor), then u.
        let kinds: Vec<_> = net.arcs.iter().map(|a| (a.transition.0, a.kind)).collect();
        assert_eq!(
            kinds,
            [
                (0, ArcKind::Input),
                (0, ArcKind::Output),
                (0, ArcKind::Inhibitor),
                (1, ArcKind::Input),
                (1, ArcKind::Output)
            ]
        );
    }

    #[test]
    fn picks_a_net_by_name() {
        let net = read_pnpro_named(SMALL, "s", Some("second")).unwrap();
        assert_eq!(net.places.len(), 1);
        let err = read_pnpro_named(SMALL, "s", Some("third"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("`first`, `second`"), "{err}");
    }

    #[test]
    fn constants_depending_on_templates_are_refused() {
        let text = SMALL.replace("value=\"M + 1\"", "value=\"N + 1\"");
        let err = read_pnpro(&text, "s").unwrap_err().to_string();
        assert!(err.contains("`N` has no value (a template"), "{err}");
        let text = SMALL.replace("value=\"2\"", "value=\"K\"");
        let err = read_pnpro(&text, "s").unwrap_err().to_string();
        assert!(err.contains("depend on each other"), "{err}");
    }

    #[test]
    fn writes_what_it_reads() {
        let net = read_pnpro(SMALL, "s").unwrap();
        let text = write_pnpro(&net).unwrap();
        let mut back = read_pnpro(&text, "s").unwrap();
        // The grid gave `b` and `u` positions.
        assert!(back.places[1].position.is_some());
        back.places[1].position = None;
        back.transitions[1].position = None;
        assert_eq!(back, net);
    }

    #[test]
    fn capacities_are_refused_when_writing() {
        let mut net = read_pnpro(SMALL, "s").unwrap();
        net.places[0].capacity = Some(2);
        let err = write_pnpro(&net).unwrap_err().to_string();
        assert!(err.contains("capacit"), "{err}");
    }
}
