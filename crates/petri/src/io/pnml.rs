//! PNML (ISO/IEC 15909-2) place/transition nets, the format of the Model
//! Checking Contest, with the GSPN extensions other tools put in it.
//!
//! # Reading
//!
//! The first `<net>` of the `<pnml>` document is read. Elements are matched
//! by local name, so any namespace (or none, as PIPE writes) is accepted.
//!
//! - **Pages** are flattened: places, transitions and arcs are collected from
//!   the net and from every page, nested pages included, in document order.
//!   `referencePlace` and `referenceTransition` are resolved to the node they
//!   refer to (through chains of references).
//! - **Naming rule.** Arcs refer to ids, but a net's nodes are known by name.
//!   A place or transition is named by its `<name><text>` (trimmed) when that
//!   text is not empty and no other place or transition has the same text;
//!   otherwise by its `id`. If that id is already the name of another node,
//!   `_2`, `_3`, … is appended until it is unique.
//! - **Places**: `<initialMarking><text>` (a whole number; 0 when absent
//!   or empty; PIPE's `Default,1` form and TAPAAL's `initialMarking`
//!   attribute are accepted), `<graphics><position x y>` into `position`,
//!   PIPE's `<capacity><value>` (0 means unbounded).
//! - **Arcs**: `source`/`target` ids; place → transition is an input arc,
//!   transition → place an output arc; place → place and transition →
//!   transition are errors. `<inscription><text>` is the multiplicity (a
//!   whole number ≥ 1; 1 when absent or empty; PIPE's
//!   `<value>Default,1</value>` and TAPAAL's `weight` attribute are
//!   accepted).
//! - **Inhibitor arcs**, in every common encoding: an arc `type` attribute,
//!   or a `<type>` child — or an `<arctype>` child, as pm4py and ProM write
//!   it — (its `value` attribute, or its `<text>`/`<value>` child or own
//!   text), saying `inhibitor` or `inhibition` (any case), or
//!   TAPAAL's `tapnInhibitor`. `normal`, `regular`, `timed` and `default`
//!   are ordinary arcs; other arc types (reset, transport, read…) are refused.
//! - **Transitions** of a plain P/T net are timed, with no rate (`rate:
//!   None`: a default must be given to solve the net) and a single server.
//!   GSPN attributes are read where present, both as direct children of
//!   `<transition>` (PIPE) and inside any `<toolspecific>` child, each as
//!   `<attr><value>…</value></attr>` (a `<text>` child or plain text also
//!   works): `rate` (an expression), `timed` (`true`/`false`), `priority`,
//!   `weight`, `infiniteServer` (`true` gives infinite servers). A transition
//!   with `timed` false is immediate; its weight is `weight` if given, else
//!   its `rate` (as PIPE stores it), else 1; its priority defaults to 1.
//!   Values inside `<toolspecific tool="petrinav">` take precedence over
//!   other tools', which take precedence over direct children.
//! - Other tool-specific content (e.g. the MCC's `nupn` units) and graphics
//!   other than node positions are ignored.
//! - **Refused**: coloured and high-level nets (a net `type` naming symmetric
//!   or high-level nets, `<declaration>`, `<hlinitialMarking>`,
//!   `<hlinscription>`, a place `<type>`), non-integer markings and
//!   inscriptions, PIPE markings with tokens of several classes.
//!
//! # Writing, and the petrinav tool-specific form
//!
//! [`write_pnml`] writes a standard ptnet document (namespace
//! `http://www.pnml.org/version-2009/grammar/pnml`, net type
//! `http://www.pnml.org/version-2009/grammar/ptnet`) with one page. Node ids
//! are the names, made valid XML ids when needed (characters other than
//! ASCII letters, digits, `_`, `-` and `.` become `_`, a leading `_` is added
//! before a digit, and `_2`, `_3`… keep them unique); every node also gets its
//! exact name as `<name><text>`, so the naming rule above reads it back.
//! Inhibitor arcs carry `<type value="inhibitor"/>` and, for pm4py and
//! ProM, `<arctype><text>inhibitor</text></arctype>`.
//!
//! Everything a plain P/T net cannot say goes into `<toolspecific
//! tool="petrinav" version="1">` elements, each attribute written as
//! `<attr><value>text</value></attr>` with expressions in
//! [`Expr`] syntax:
//!
//! ```xml
//! <net id="supervisor" type="http://www.pnml.org/version-2009/grammar/ptnet">
//!   <name><text>supervisor</text></name>
//!   <toolspecific tool="petrinav" version="1">
//!     <doc><value>free text</value></doc>
//!     <parameter name="lambda1" kind="real" value="0.001"/>
//!     <parameter name="N" kind="int" suggested="3" doc="pallets"/>
//!   </toolspecific>
//!   <page id="page0">
//!     <place id="P0">
//!       <name><text>P0</text></name>
//!       <initialMarking><text>3</text></initialMarking>
//!       <toolspecific tool="petrinav" version="1">
//!         <marking><value>N</value></marking>   <!-- when not a plain number -->
//!         <capacity><value>4</value></capacity>
//!         <doc><value>free text</value></doc>
//!       </toolspecific>
//!     </place>
//!     <transition id="t2">
//!       <name><text>t2</text></name>
//!       <toolspecific tool="petrinav" version="1">
//!         <timed><value>true</value></timed>
//!         <rate><value>lambda1</value></rate>
//!         <servers><value>infinite</value></servers> <!-- single (default), infinite or k -->
//!       </toolspecific>
//!     </transition>
//!     <transition id="t0">
//!       <name><text>t0</text></name>
//!       <toolspecific tool="petrinav" version="1">
//!         <timed><value>false</value></timed>
//!         <weight><value>p</value></weight>
//!         <priority><value>1</value></priority>
//!       </toolspecific>
//!     </transition>
//!     <arc id="a0" source="P0" target="t2">
//!       <inscription><text>2</text></inscription>
//!       <toolspecific tool="petrinav" version="1">
//!         <multiplicity><value>K</value></multiplicity> <!-- when not a plain number -->
//!       </toolspecific>
//!     </arc>
//!     <arc id="a1" source="P3" target="t5">
//!       <type value="inhibitor"/>
//!       <arctype><text>inhibitor</text></arctype>
//!     </arc>
//!   </page>
//! </net>
//! ```
//!
//! - Net: `<doc>`, and one `<parameter name kind value suggested doc>` per
//!   parameter in order (`kind` is `int` or `real`; the other attributes are
//!   written when present); one `<label name expr>` per label and one
//!   `<reward name rate>` (with an `<impulse transition value>` per
//!   impulse) per reward model.
//! - A decision (docs/gspn.md, *Decisions*) is an immediate transition
//!   with `<decision><value>true</value></decision>` in its block; other
//!   tools see an ordinary immediate transition.
//! - Place: `<initialMarking>` holds the value of the marking whenever it
//!   evaluates to a whole number with the parameters' values (other tools
//!   see that); when the marking is anything but a plain number, the
//!   expression itself is kept in `<marking>`, which the reader prefers.
//!   `<capacity>` (0 is a capacity of 0 here, unlike PIPE's) and `<doc>`.
//! - Transition: omitted entirely for a timed transition without rate,
//!   single server and no doc; otherwise `<timed>`, then `<rate>` and
//!   `<servers>` (when not single) or `<weight>` and `<priority>`, and `<doc>`.
//! - Arc: `<inscription>` holds the evaluated multiplicity, `<multiplicity>`
//!   the expression when it is not a plain number.
//!
//! Reading what [`write_pnml`] wrote gives back the same [`Net`].

use std::collections::{HashMap, HashSet};

use roxmltree::Node;

use super::{fmt_f64, parse_expr, parse_f64, push_attr, push_xml_escaped};
use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::net::{
    Arc, ArcKind, Net, Param, ParamKind, Place, PlaceId, Servers, Transition, TransitionId, TransitionKind,
};

/// The PNML 2009 grammar namespace.
pub const PNML_NAMESPACE: &str = "http://www.pnml.org/version-2009/grammar/pnml";
/// The net type of place/transition nets.
pub const PTNET_TYPE: &str = "http://www.pnml.org/version-2009/grammar/ptnet";
/// The `tool` attribute of petrinav's `<toolspecific>` elements.
pub const TOOL: &str = "petrinav";
/// The `version` attribute of petrinav's `<toolspecific>` elements.
pub const TOOL_VERSION: &str = "1";

/// Reads the first net of a PNML document. `source` names the text in error
/// messages (a file name).
pub fn read_pnml(text: &str, source: &str) -> Result<Net> {
    let text = super::prepare(text, source)?;
    // One place, transition or arc parsed at a time where the file allows
    // it (`xml_split`), else the whole document at once.
    let split = super::xml_split::split(text, &["page"]);
    let doc = super::parse_xml(split.as_ref().map_or(text, |s| s.skeleton.as_str()), source)?;
    let r = Reader {
        source,
        text,
        split: split.as_ref(),
        base: None,
    };
    let root = doc.root_element();
    if root.tag_name().name() != "pnml" {
        return Err(r.error(
            root,
            format!(
                "expected a PNML document (root element <pnml>), found <{}>",
                root.tag_name().name()
            ),
        ));
    }
    let net_el = elements(root)
        .find(|n| n.tag_name().name() == "net")
        .ok_or_else(|| r.error(root, "the document has no <net>".into()))?;
    let net = r.read_net(net_el)?;
    super::finish(net)
}

fn elements<'a, 'i>(node: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    node.children().filter(Node::is_element)
}

fn child<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    elements(node).find(|n| n.tag_name().name() == name)
}

/// The text directly inside an element.
fn own_text(node: Node<'_, '_>) -> String {
    node.children()
        .filter(Node::is_text)
        .filter_map(|n| n.text())
        .collect()
}

/// The value of a PNML attribute element: its `<value>` child (PIPE), its
/// `<text>` child (PNML), or its own text.
fn value_text(node: Node<'_, '_>) -> String {
    match child(node, "value").or_else(|| child(node, "text")) {
        Some(c) => own_text(c),
        None => own_text(node),
    }
}

fn is_petrinav(node: Node<'_, '_>) -> bool {
    node.tag_name().name() == "toolspecific" && node.attribute("tool") == Some(TOOL)
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

/// An object of the net: a node of the document, or a fragment of the
/// cut file, parsed when it is read.
#[derive(Clone, Copy)]
enum Obj<'a, 'i, 's> {
    Node(Node<'a, 'i>),
    Fragment(&'s super::xml_split::Fragment),
}

/// Where an attribute element was found.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Source {
    /// A child of the object itself (PNML, PIPE).
    Direct,
    /// Inside another tool's `<toolspecific>`.
    OtherTool,
    /// Inside `<toolspecific tool="petrinav">`.
    Petrinav,
}

/// Where an arc end is.
#[derive(Clone, Copy)]
enum End {
    Place(PlaceId),
    Transition(TransitionId),
}

/// The objects of a net, pages flattened.
struct Objects<'a, 'i, 's> {
    places: Vec<Obj<'a, 'i, 's>>,
    transitions: Vec<Obj<'a, 'i, 's>>,
    references: Vec<Obj<'a, 'i, 's>>,
    arcs: Vec<Obj<'a, 'i, 's>>,
}

impl<'s> Reader<'s> {
    /// `file:line:column` of a node, in the whole file.
    fn loc(&self, node: Node<'_, '_>) -> String {
        super::located(self.source, super::xml_pos(node), self.base)
    }

    /// `file:line:column` of an attribute's value (or its element), in
    /// the whole file.
    fn attr_loc(&self, node: Node<'_, '_>, attr: &str) -> String {
        super::located(self.source, super::attr_pos(node, attr), self.base)
    }

    /// `f` on an object's element, with the reader of the fragment it is
    /// parsed from when the file was cut.
    fn with<T>(
        &self,
        obj: Obj<'_, '_, 's>,
        f: impl FnOnce(&Reader<'s>, Node<'_, '_>) -> Result<T>,
    ) -> Result<T> {
        match obj {
            Obj::Node(n) => f(self, n),
            Obj::Fragment(fragment) => {
                let doc = super::parse_fragment(self.text, fragment, self.source)?;
                let r = Reader {
                    base: Some(fragment),
                    ..*self
                };
                f(&r, doc.root_element())
            }
        }
    }

    /// An object's element name.
    fn tag<'i>(&self, obj: Obj<'_, 'i, 's>) -> &'i str
    where
        's: 'i,
    {
        match obj {
            Obj::Node(n) => n.tag_name().name(),
            Obj::Fragment(f) => f.tag(self.text),
        }
    }

    fn error(&self, node: Node<'_, '_>, message: String) -> Error {
        Error::Format {
            location: self.loc(node),
            message,
        }
    }

    fn id<'a>(&self, node: Node<'a, '_>) -> Result<&'a str> {
        node.attribute("id").filter(|id| !id.is_empty()).ok_or_else(|| {
            self.error(
                node,
                format!("<{}> without an `id` attribute", node.tag_name().name()),
            )
        })
    }

    fn coloured(&self, node: Node<'_, '_>, what: &str) -> Error {
        self.error(
            node,
            format!("{what}: coloured and high-level nets are not supported, only place/transition nets"),
        )
    }

    fn read_net(&self, net_el: Node<'_, '_>) -> Result<Net> {
        let ty = net_el.attribute("type").unwrap_or_default().to_ascii_lowercase();
        if [
            "symmetric",
            "highlevel",
            "high-level",
            "hlpn",
            "hlpng",
            "colored",
            "coloured",
        ]
        .iter()
        .any(|k| ty.contains(k))
        {
            return Err(self.coloured(
                net_el,
                &format!("net type `{}`", net_el.attribute("type").unwrap_or_default()),
            ));
        }
        let objects = self.collect(net_el)?;

        let name = child(net_el, "name")
            .map(value_text)
            .map(|t| t.trim().to_string())
            .filter(|t| !t.is_empty())
            .or_else(|| {
                net_el
                    .attribute("id")
                    .filter(|i| !i.is_empty())
                    .map(str::to_string)
            })
            .unwrap_or_else(|| super::default_net_name(self.source));
        let mut net = Net::new(name);
        for ts in elements(net_el).filter(|n| is_petrinav(*n)) {
            self.net_toolspecific(ts, &mut net)?;
        }

        // Ids and names.
        let mut ids: HashMap<String, End> = HashMap::new();
        let names = self.node_names(&objects)?;
        for (i, obj) in objects.places.iter().enumerate() {
            let id = self.with(*obj, |r, n| Ok(r.id(n)?.to_string()))?;
            self.claim_id(&mut ids, id, End::Place(PlaceId(i as u32)))?;
        }
        for (i, obj) in objects.transitions.iter().enumerate() {
            let id = self.with(*obj, |r, n| Ok(r.id(n)?.to_string()))?;
            self.claim_id(&mut ids, id, End::Transition(TransitionId(i as u32)))?;
        }
        let mut names = names.into_iter();
        for obj in &objects.places {
            let name = names.next().unwrap_or_default();
            net.places.push(self.with(*obj, |r, n| r.place(n, name))?);
        }
        for obj in &objects.transitions {
            let name = names.next().unwrap_or_default();
            net.transitions
                .push(self.with(*obj, |r, n| r.transition(n, name))?);
        }
        let ends = self.resolve_references(&objects, ids)?;
        for obj in &objects.arcs {
            self.with(*obj, |r, n| r.arc(n, &ends, &mut net))?;
        }
        for ts in elements(net_el).filter(|n| is_petrinav(*n)) {
            self.net_rewards(ts, &mut net)?;
        }
        Ok(net)
    }

    /// The reward models of a net's petrinav block (read once the
    /// transitions they name are known).
    fn net_rewards(&self, ts: Node<'_, '_>, net: &mut Net) -> Result<()> {
        for item in elements(ts).filter(|n| n.tag_name().name() == "reward") {
            let name = item
                .attribute("name")
                .filter(|n| !n.is_empty())
                .ok_or_else(|| self.error(item, "<reward> without a `name`".into()))?;
            let owner = format!("reward model `{name}`");
            let expr_attr = |node: Node<'_, '_>, attr: &str| -> Result<Option<Expr>> {
                node.attribute(attr)
                    .map(|t| parse_expr(t, || self.attr_loc(node, attr), || format!("{owner}, `{attr}`")))
                    .transpose()
            };
            let rate = expr_attr(item, "rate")?;
            let mut impulses = Vec::new();
            for imp in elements(item).filter(|n| n.tag_name().name() == "impulse") {
                let tname = imp.attribute("transition").unwrap_or_default();
                let t = net.transition_id(tname).ok_or_else(|| Error::UnknownNode {
                    arc: format!("{}: impulse of {owner}", self.loc(imp)),
                    expected: "transition",
                    name: tname.to_string(),
                    hint: crate::suggest::hint(tname, net.transitions.iter().map(|t| t.name.as_str())),
                })?;
                let value = expr_attr(imp, "value")?
                    .ok_or_else(|| self.error(imp, format!("{owner}: <impulse> without a `value`")))?;
                impulses.push((t, value));
            }
            net.rewards.push(crate::net::RewardModel {
                name: name.to_string(),
                rate,
                impulses,
            });
        }
        Ok(())
    }

    /// Collects the net's objects, flattening pages (without recursion, so
    /// that deep nesting cannot overflow the stack), in document order.
    fn collect<'a, 'i>(&self, net_el: Node<'a, 'i>) -> Result<Objects<'a, 'i, 's>> {
        let mut objects = Objects {
            places: Vec::new(),
            transitions: Vec::new(),
            references: Vec::new(),
            arcs: Vec::new(),
        };
        let mut stack: Vec<Obj<'a, 'i, 's>> = elements(net_el).map(Obj::Node).collect();
        stack.reverse();
        while let Some(obj) = stack.pop() {
            match self.tag(obj) {
                "page" => {
                    let Obj::Node(page) = obj else {
                        continue; // pages are never fragments (they are containers)
                    };
                    let start = stack.len();
                    stack.extend(self.children(page));
                    stack[start..].reverse();
                }
                "place" => objects.places.push(obj),
                "transition" => objects.transitions.push(obj),
                "referencePlace" | "referenceTransition" => objects.references.push(obj),
                "arc" => objects.arcs.push(obj),
                "declaration" | "declarations" => {
                    return Err(self.with(obj, |r, n| Ok(r.coloured(n, "<declaration>")))?);
                }
                _ => {}
            }
        }
        Ok(objects)
    }

    /// A page's child elements in document order: its nodes, or, when the
    /// file was cut, its fragments and the pages nested in it (which stay
    /// in the skeleton).
    fn children<'a, 'i>(&self, page: Node<'a, 'i>) -> Vec<Obj<'a, 'i, 's>> {
        let Some(split) = self.split else {
            return elements(page).map(Obj::Node).collect();
        };
        let mut out: Vec<(usize, Obj<'a, 'i, 's>)> = split
            .children(page.range().start)
            .iter()
            .map(|f| (f.range.start, Obj::Fragment(f)))
            .collect();
        out.extend(elements(page).map(|n| (n.range().start, Obj::Node(n))));
        out.sort_by_key(|(at, _)| *at);
        out.into_iter().map(|(_, o)| o).collect()
    }

    fn claim_id(&self, ids: &mut HashMap<String, End>, id: String, end: End) -> Result<()> {
        let what = |e: &End| match e {
            End::Place(_) => "a place",
            End::Transition(_) => "a transition",
        };
        if let Some(first) = ids.get(&id) {
            return Err(Error::DuplicateName {
                name: id,
                first: what(first),
                second: what(&end),
            });
        }
        ids.insert(id, end);
        Ok(())
    }

    /// Names of the places then transitions, by the naming rule.
    fn node_names(&self, objects: &Objects<'_, '_, 's>) -> Result<Vec<String>> {
        let nodes: Vec<Obj<'_, '_, 's>> = objects
            .places
            .iter()
            .chain(&objects.transitions)
            .copied()
            .collect();
        let labels: Vec<Option<String>> = nodes
            .iter()
            .map(|obj| {
                self.with(*obj, |_, n| {
                    Ok(child(n, "name")
                        .map(value_text)
                        .or_else(|| n.attribute("name").map(str::to_string))
                        .map(|t| t.trim().to_string())
                        .filter(|t| !t.is_empty()))
                })
            })
            .collect::<Result<_>>()?;
        let mut count: HashMap<&str, usize> = HashMap::new();
        for l in labels.iter().flatten() {
            *count.entry(l.as_str()).or_default() += 1;
        }
        let chosen: Vec<Option<String>> = labels
            .iter()
            .map(|l| l.clone().filter(|l| count.get(l.as_str()) == Some(&1)))
            .collect();
        let mut taken: HashSet<String> = chosen.iter().flatten().cloned().collect();
        let mut names = Vec::with_capacity(nodes.len());
        for (node, name) in nodes.iter().zip(chosen) {
            let name = match name {
                Some(n) => n,
                None => {
                    let id = self.with(*node, |r, n| Ok(r.id(n)?.to_string()))?;
                    let mut candidate = id.clone();
                    let mut k = 2;
                    while taken.contains(&candidate) {
                        candidate = format!("{id}_{k}");
                        k += 1;
                    }
                    taken.insert(candidate.clone());
                    candidate
                }
            };
            names.push(name);
        }
        Ok(names)
    }

    fn resolve_references(
        &self,
        objects: &Objects<'_, '_, 's>,
        ids: HashMap<String, End>,
    ) -> Result<HashMap<String, End>> {
        /// What a reference node says, read once.
        struct Reference {
            id: String,
            target: String,
            place: bool,
            location: String,
        }
        let mut refs: HashMap<String, usize> = HashMap::new();
        let mut read: Vec<Reference> = Vec::with_capacity(objects.references.len());
        for obj in &objects.references {
            let r = self.with(*obj, |r, n| {
                let id = r.id(n)?.to_string();
                let target = n.attribute("ref").ok_or_else(|| {
                    r.error(
                        n,
                        format!("<{}> `{id}` without a `ref` attribute", n.tag_name().name()),
                    )
                })?;
                Ok(Reference {
                    target: target.to_string(),
                    place: n.tag_name().name() == "referencePlace",
                    location: r.loc(n),
                    id,
                })
            })?;
            if ids.contains_key(&r.id) || refs.insert(r.id.clone(), read.len()).is_some() {
                return Err(Error::DuplicateName {
                    name: r.id,
                    first: "a node",
                    second: "a reference node",
                });
            }
            read.push(r);
        }
        let mut ends = ids;
        // In document order, so that the first error reported does not
        // depend on hashing.
        for r in &read {
            let mut target = r.target.as_str();
            let mut steps = 0;
            let end = loop {
                if let Some(e) = ends.get(target) {
                    break *e;
                }
                match refs.get(target) {
                    Some(&next) if steps <= refs.len() => {
                        target = read[next].target.as_str();
                        steps += 1;
                    }
                    Some(_) => {
                        return Err(Error::Format {
                            location: r.location.clone(),
                            message: format!("reference `{}`: the references form a cycle", r.id),
                        });
                    }
                    None => {
                        return Err(Error::UnknownNode {
                            arc: format!("{}: reference `{}`", r.location, r.id),
                            expected: "place or transition",
                            name: target.to_string(),
                            hint: crate::suggest::hint(target, ends.keys().map(String::as_str)),
                        });
                    }
                }
            };
            if r.place != matches!(end, End::Place(_)) {
                return Err(Error::Format {
                    location: r.location.clone(),
                    message: format!(
                        "<{}> `{}` refers to `{}`, which is a {}",
                        if r.place {
                            "referencePlace"
                        } else {
                            "referenceTransition"
                        },
                        r.id,
                        r.target,
                        if r.place { "transition" } else { "place" }
                    ),
                });
            }
            ends.insert(r.id.clone(), end);
        }
        Ok(ends)
    }

    fn net_toolspecific(&self, ts: Node<'_, '_>, net: &mut Net) -> Result<()> {
        for item in elements(ts) {
            match item.tag_name().name() {
                "doc" => net.doc = Some(value_text(item)),
                "parameter" => {
                    let name = item
                        .attribute("name")
                        .filter(|n| !n.is_empty())
                        .ok_or_else(|| self.error(item, "<parameter> without a `name`".into()))?;
                    let number = |attr: &str| -> Result<Option<f64>> {
                        match item.attribute(attr) {
                            None => Ok(None),
                            Some(t) => parse_f64(t).map(Some).ok_or_else(|| Error::Format {
                                location: self.attr_loc(item, attr),
                                message: format!("parameter `{name}`: `{attr}` is not a number: `{t}`"),
                            }),
                        }
                    };
                    let kind = match item.attribute("kind") {
                        None | Some("real") => ParamKind::Real,
                        Some("int") => ParamKind::Int,
                        Some(k) => {
                            return Err(Error::Format {
                                location: self.attr_loc(item, "kind"),
                                message: format!("parameter `{name}`: kind `{k}` (expected `int` or `real`)"),
                            });
                        }
                    };
                    net.params.push(Param {
                        name: name.to_string(),
                        value: number("value")?,
                        kind,
                        suggested: number("suggested")?,
                        doc: item.attribute("doc").map(str::to_string),
                    });
                }
                "label" => {
                    let name = item
                        .attribute("name")
                        .filter(|n| !n.is_empty())
                        .ok_or_else(|| self.error(item, "<label> without a `name`".into()))?;
                    let text = item
                        .attribute("expr")
                        .ok_or_else(|| self.error(item, format!("label `{name}` without an `expr`")))?;
                    let expr =
                        parse_expr(text, || self.attr_loc(item, "expr"), || format!("label `{name}`"))?;
                    net.labels.push(crate::net::Label {
                        name: name.to_string(),
                        expr,
                    });
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn position(&self, node: Node<'_, '_>, owner: &str) -> Result<Option<(f64, f64)>> {
        let Some(pos) = child(node, "graphics").and_then(|g| child(g, "position")) else {
            return Ok(None);
        };
        let coord = |a: &str| -> Result<f64> {
            let t = pos.attribute(a).unwrap_or_default();
            parse_f64(t).ok_or_else(|| Error::Format {
                location: self.attr_loc(pos, a),
                message: format!("{owner}: position `{a}` is not a number: `{t}`"),
            })
        };
        Ok(Some((coord("x")?, coord("y")?)))
    }

    /// A token count or inscription: a whole number ≥ `min`, or PIPE's
    /// `Class,count` list with tokens of one class.
    fn count(&self, text: &str, node: Node<'_, '_>, what: &dyn Fn() -> String, min: u32) -> Result<Expr> {
        let text = text.trim();
        if text.is_empty() {
            // An empty marking or inscription element: the default.
            return Ok(Expr::Num(f64::from(min)));
        }
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        let number = if parts.len() == 1 {
            text
        } else if parts.len() % 2 == 0 {
            let nonzero: Vec<&str> = parts
                .chunks(2)
                .filter_map(|c| c.get(1).copied())
                .filter(|c| parse_f64(c) != Some(0.0))
                .collect();
            match nonzero.as_slice() {
                [] => "0",
                [one] => one,
                _ => {
                    return Err(self.error(
                        node,
                        format!("{}: `{text}` has tokens of several classes (coloured PIPE net), which is not supported", what()),
                    ));
                }
            }
        } else {
            return Err(self.error(node, format!("{}: `{text}` is not a number", what())));
        };
        match parse_f64(number) {
            Some(v) if v.is_finite() && v == v.trunc() && v >= f64::from(min) && v <= f64::from(u32::MAX) => {
                Ok(Expr::Num(v))
            }
            _ => Err(self.error(
                node,
                format!("{}: `{text}` is not a whole number ≥ {min}", what()),
            )),
        }
    }

    /// Children of an element that hold its attributes, with where they
    /// come from: direct children first, then other tools' `<toolspecific>`
    /// content, then petrinav's, so that later ones win.
    fn attributes<'a, 'i>(node: Node<'a, 'i>) -> Vec<(Node<'a, 'i>, Source)> {
        let mut out: Vec<(Node<'a, 'i>, Source)> = elements(node)
            .filter(|n| n.tag_name().name() != "toolspecific")
            .map(|n| (n, Source::Direct))
            .collect();
        for ts in elements(node).filter(|n| n.tag_name().name() == "toolspecific" && !is_petrinav(*n)) {
            out.extend(elements(ts).map(|n| (n, Source::OtherTool)));
        }
        for ts in elements(node).filter(|n| is_petrinav(*n)) {
            out.extend(elements(ts).map(|n| (n, Source::Petrinav)));
        }
        out
    }

    fn place(&self, node: Node<'_, '_>, name: String) -> Result<Place> {
        let owner = format!("place `{name}`");
        let what = || owner.clone();
        let mut initial = Expr::Num(0.0);
        if let Some(t) = node.attribute("initialMarking") {
            initial = self.count(t, node, &what, 0)?;
        }
        let mut capacity = None;
        let mut doc = None;
        for (item, source) in Self::attributes(node) {
            match (item.tag_name().name(), source) {
                ("initialMarking", Source::Direct) => {
                    initial = self.count(&value_text(item), item, &what, 0)?
                }
                ("hlinitialMarking", Source::Direct) => return Err(self.coloured(item, &owner)),
                ("type", Source::Direct) => {
                    return Err(self.coloured(item, &format!("{owner} has a sort (<type>)")));
                }
                ("capacity", Source::Direct | Source::OtherTool) => {
                    // PIPE: 0 means unbounded.
                    capacity = match self.count(&value_text(item), item, &what, 0)?.as_number() {
                        Some(v) if v > 0.0 => Some(v as u32),
                        _ => None,
                    };
                }
                ("marking", Source::Petrinav) => initial = self.expr_child(item, &owner, "marking")?,
                ("capacity", Source::Petrinav) => {
                    capacity = self
                        .count(&value_text(item), item, &what, 0)?
                        .as_number()
                        .map(|v| v as u32)
                }
                ("doc", Source::Petrinav) => doc = Some(value_text(item)),
                _ => {}
            }
        }
        Ok(Place {
            initial,
            capacity,
            position: self.position(node, &owner)?,
            doc,
            name,
        })
    }

    fn expr_child(&self, item: Node<'_, '_>, owner: &str, attr: &str) -> Result<Expr> {
        parse_expr(
            value_text(item).trim(),
            || self.loc(item),
            || format!("{owner}, <{attr}>"),
        )
    }

    fn boolean(&self, item: Node<'_, '_>, owner: &str) -> Result<bool> {
        let t = value_text(item);
        match t.trim().to_ascii_lowercase().as_str() {
            "true" => Ok(true),
            "false" => Ok(false),
            _ => Err(self.error(
                item,
                format!(
                    "{owner}, <{}>: expected true or false, got `{}`",
                    item.tag_name().name(),
                    t.trim()
                ),
            )),
        }
    }

    fn transition(&self, node: Node<'_, '_>, name: String) -> Result<Transition> {
        let owner = format!("transition `{name}`");
        let mut timed = true;
        let mut rate = None;
        let mut weight = None;
        let mut priority = None;
        let mut servers = Servers::Single;
        let mut doc = None;
        let mut decision = false;
        for (item, source) in Self::attributes(node) {
            let tag = item.tag_name().name();
            let blank = value_text(item).trim().is_empty();
            match (tag, source) {
                ("timed", _) => timed = self.boolean(item, &owner)?,
                ("rate", _) if !blank => rate = Some(self.expr_child(item, &owner, tag)?),
                ("weight", _) if !blank => weight = Some(self.expr_child(item, &owner, tag)?),
                ("priority", _) if !blank => priority = Some(self.expr_child(item, &owner, tag)?),
                ("infiniteServer", _) => {
                    servers = if self.boolean(item, &owner)? {
                        Servers::Infinite
                    } else {
                        Servers::Single
                    }
                }
                ("servers", Source::Petrinav) => servers = self.servers(item, &owner)?,
                ("doc", Source::Petrinav) => doc = Some(value_text(item)),
                ("decision", Source::Petrinav) => decision = self.boolean(item, &owner)?,
                _ => {}
            }
        }
        if decision && timed {
            return Err(self.error(
                node,
                format!("{owner} is a decision but timed: decisions are immediate (<timed> false)"),
            ));
        }
        let kind = if timed {
            TransitionKind::Timed { rate, servers }
        } else {
            TransitionKind::Immediate {
                weight: weight.or(rate).unwrap_or(Expr::Num(1.0)),
                priority: priority.unwrap_or(Expr::Num(1.0)),
            }
        };
        Ok(Transition {
            kind,
            decision,
            position: self.position(node, &owner)?,
            doc,
            name,
        })
    }

    fn servers(&self, item: Node<'_, '_>, owner: &str) -> Result<Servers> {
        let t = value_text(item);
        let t = t.trim();
        if t.eq_ignore_ascii_case("single") {
            return Ok(Servers::Single);
        }
        if t.eq_ignore_ascii_case("infinite") {
            return Ok(Servers::Infinite);
        }
        match t.parse::<u32>() {
            Ok(k) if k >= 1 => Ok(Servers::K(k)),
            _ => Err(self.error(
                item,
                format!("{owner}, <servers>: expected single, infinite or a whole number ≥ 1, got `{t}`"),
            )),
        }
    }

    /// Whether an arc is an inhibitor arc, from its `type` attribute or
    /// `<type>` (or pm4py's `<arctype>`) child.
    fn is_inhibitor(&self, arc: Node<'_, '_>, describe: &dyn Fn() -> String) -> Result<bool> {
        let mut texts: Vec<(String, Node<'_, '_>)> = Vec::new();
        if let Some(t) = arc.attribute("type") {
            texts.push((t.to_string(), arc));
        }
        for ty in elements(arc).filter(|n| matches!(n.tag_name().name(), "type" | "arctype")) {
            let t = ty
                .attribute("value")
                .map_or_else(|| value_text(ty), str::to_string);
            texts.push((t, ty));
        }
        let mut inhibitor = false;
        for (t, node) in texts {
            match t.trim().to_ascii_lowercase().as_str() {
                "inhibitor" | "inhibition" | "inhibitorarc" | "tapninhibitor" => inhibitor = true,
                "" | "normal" | "regular" | "timed" | "default" | "ordinary" => {}
                other => {
                    return Err(self.error(
                        node,
                        format!(
                            "{}: arc type `{other}` is not supported (only ordinary and inhibitor arcs)",
                            describe()
                        ),
                    ));
                }
            }
        }
        Ok(inhibitor)
    }

    fn arc(&self, arc: Node<'_, '_>, ends: &HashMap<String, End>, net: &mut Net) -> Result<()> {
        let attr = |a: &str| -> Result<&str> {
            arc.attribute(a)
                .ok_or_else(|| self.error(arc, format!("<arc> without a `{a}` attribute")))
        };
        let (source, target) = (attr("source")?, attr("target")?);
        let id = arc.attribute("id").unwrap_or("");
        let describe = || format!("{}: arc `{id}` from `{source}` to `{target}`", self.loc(arc));
        let end = |x: &str| -> Result<End> {
            ends.get(x).copied().ok_or_else(|| Error::UnknownNode {
                arc: describe(),
                expected: "place or transition",
                name: x.to_string(),
                hint: crate::suggest::hint(x, ends.keys().map(String::as_str)),
            })
        };
        let (from, to) = (end(source)?, end(target)?);
        let inhibitor = self.is_inhibitor(arc, &describe)?;
        let (kind, place, transition) = match (from, to) {
            (End::Place(p), End::Transition(t)) => (
                if inhibitor {
                    ArcKind::Inhibitor
                } else {
                    ArcKind::Input
                },
                p,
                t,
            ),
            (End::Transition(t), End::Place(p)) => {
                if inhibitor {
                    return Err(self.error(
                        arc,
                        format!("arc `{id}`: an inhibitor arc must go from a place to a transition, not from transition `{source}` to place `{target}`"),
                    ));
                }
                (ArcKind::Output, p, t)
            }
            (End::Place(_), End::Place(_)) => {
                return Err(self.error(
                    arc,
                    format!("arc `{id}` joins two places (`{source}` → `{target}`): an arc must join a place and a transition"),
                ));
            }
            (End::Transition(_), End::Transition(_)) => {
                return Err(self.error(
                    arc,
                    format!("arc `{id}` joins two transitions (`{source}` → `{target}`): an arc must join a place and a transition"),
                ));
            }
        };
        let owner = format!("arc `{id}` from `{source}` to `{target}`");
        let what = || owner.clone();
        let mut multiplicity = Expr::Num(1.0);
        if let Some(w) = arc.attribute("weight") {
            multiplicity = self.count(w, arc, &what, 1)?;
        }
        for (item, source) in Self::attributes(arc) {
            match (item.tag_name().name(), source) {
                ("inscription", Source::Direct) => {
                    multiplicity = self.count(&value_text(item), item, &what, 1)?
                }
                ("hlinscription", Source::Direct) => return Err(self.coloured(item, &owner)),
                ("multiplicity", Source::Petrinav) => {
                    multiplicity = self.expr_child(item, &owner, "multiplicity")?;
                }
                _ => {}
            }
        }
        net.add_arc(kind, place, transition, multiplicity);
        Ok(())
    }
}

// ---------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------

/// A valid XML id (an NCName restricted to ASCII) made from a name.
fn sanitize_id(name: &str) -> String {
    let mut id: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if !id.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
        id.insert(0, '_');
    }
    id
}

fn unique_id(base: String, used: &mut HashSet<String>) -> String {
    let mut id = base.clone();
    let mut k = 2;
    while used.contains(&id) {
        id = format!("{base}_{k}");
        k += 1;
    }
    used.insert(id.clone());
    id
}

/// The value of an expression as a whole number in `min..=u32::MAX`, using
/// the parameters' values.
fn whole_value(e: &Expr, values: &HashMap<&str, f64>, min: f64) -> Option<u64> {
    let v = e.eval_params(&|n| values.get(n).copied(), "").ok()?;
    (v.is_finite() && v == v.trunc() && v >= min && v <= f64::from(u32::MAX)).then_some(v as u64)
}

/// Whether an expression is a plain number that `<initialMarking>` or
/// `<inscription>` holds exactly.
fn is_plain(e: &Expr, min: f64) -> bool {
    matches!(e, Expr::Num(v) if v.is_finite() && *v == v.trunc() && *v >= min && *v <= f64::from(u32::MAX))
}

/// Writes `<tag><value>text</value></tag>`.
fn push_value(
    out: &mut String,
    indent: &str,
    tag: &str,
    text: &str,
    what: &dyn Fn() -> String,
) -> Result<()> {
    out.push_str(&format!("{indent}<{tag}><value>"));
    push_xml_escaped(out, text, false, what)?;
    out.push_str(&format!("</value></{tag}>\n"));
    Ok(())
}

fn push_name(out: &mut String, indent: &str, name: &str, what: &dyn Fn() -> String) -> Result<()> {
    out.push_str(&format!("{indent}<name><text>"));
    push_xml_escaped(out, name, false, what)?;
    out.push_str("</text></name>\n");
    Ok(())
}

fn push_position(out: &mut String, indent: &str, position: Option<(f64, f64)>) {
    if let Some((x, y)) = position {
        out.push_str(&format!(
            "{indent}<graphics><position x=\"{}\" y=\"{}\"/></graphics>\n",
            fmt_f64(x),
            fmt_f64(y)
        ));
    }
}

const TOOL_OPEN: &str = "<toolspecific tool=\"petrinav\" version=\"1\">\n";

/// The net's tool-specific block: its documentation and parameters (none
/// when it has neither).
fn push_net_tools(out: &mut String, net: &Net) -> Result<()> {
    let net_what = || "the net".to_string();
    if net.doc.is_some() || !net.params.is_empty() || !net.labels.is_empty() || !net.rewards.is_empty() {
        out.push_str("    ");
        out.push_str(TOOL_OPEN);
        if let Some(doc) = &net.doc {
            push_value(out, "      ", "doc", doc, &net_what)?;
        }
        for p in &net.params {
            let what = || format!("parameter `{}`", p.name);
            out.push_str("      <parameter");
            push_attr(out, "name", &p.name, &what)?;
            out.push_str(match p.kind {
                ParamKind::Int => " kind=\"int\"",
                ParamKind::Real => " kind=\"real\"",
            });
            if let Some(v) = p.value {
                out.push_str(&format!(" value=\"{}\"", fmt_f64(v)));
            }
            if let Some(v) = p.suggested {
                out.push_str(&format!(" suggested=\"{}\"", fmt_f64(v)));
            }
            if let Some(doc) = &p.doc {
                push_attr(out, "doc", doc, &what)?;
            }
            out.push_str("/>\n");
        }
        push_labels_and_rewards(out, net)?;
        out.push_str("    </toolspecific>\n");
    }
    Ok(())
}

/// `<label name expr/>` per label and `<reward name rate>` with an
/// `<impulse transition value/>` per impulse, per reward model.
fn push_labels_and_rewards(out: &mut String, net: &Net) -> Result<()> {
    for l in &net.labels {
        let what = || format!("label `{}`", l.name);
        out.push_str("      <label");
        push_attr(out, "name", &l.name, &what)?;
        push_attr(out, "expr", &l.expr.to_string(), &what)?;
        out.push_str("/>\n");
    }
    for r in &net.rewards {
        let what = || format!("reward model `{}`", r.name);
        out.push_str("      <reward");
        push_attr(out, "name", &r.name, &what)?;
        if let Some(rate) = &r.rate {
            push_attr(out, "rate", &rate.to_string(), &what)?;
        }
        out.push_str(">\n");
        for (t, value) in &r.impulses {
            let Some(tr) = net.transitions.get(t.index()) else {
                continue;
            };
            out.push_str("        <impulse");
            push_attr(out, "transition", &tr.name, &what)?;
            push_attr(out, "value", &value.to_string(), &what)?;
            out.push_str("/>\n");
        }
        out.push_str("      </reward>\n");
    }
    Ok(())
}

/// A `<place>` element with id `id`; `values` are the parameters' values
/// (an initial marking given by an expression is written as its value too).
fn push_place(out: &mut String, p: &Place, id: &str, values: &HashMap<&str, f64>) -> Result<()> {
    let what = || format!("place `{}`", p.name);
    out.push_str(&format!("      <place id=\"{id}\">\n"));
    push_name(out, "        ", &p.name, &what)?;
    push_position(out, "        ", p.position);
    if let Some(v) = whole_value(&p.initial, values, 0.0).filter(|&v| v > 0) {
        out.push_str(&format!(
            "        <initialMarking><text>{v}</text></initialMarking>\n"
        ));
    }
    let expression = !is_plain(&p.initial, 0.0);
    if expression || p.capacity.is_some() || p.doc.is_some() {
        out.push_str("        ");
        out.push_str(TOOL_OPEN);
        if expression {
            push_value(out, "          ", "marking", &p.initial.to_string(), &what)?;
        }
        if let Some(c) = p.capacity {
            push_value(out, "          ", "capacity", &c.to_string(), &what)?;
        }
        if let Some(doc) = &p.doc {
            push_value(out, "          ", "doc", doc, &what)?;
        }
        out.push_str("        </toolspecific>\n");
    }
    out.push_str("      </place>\n");
    Ok(())
}

/// A `<transition>` element with id `id`, its GSPN attributes in the
/// tool-specific block (none for a plain single-server timed transition
/// without a rate).
fn push_transition(out: &mut String, t: &Transition, id: &str) -> Result<()> {
    let what = || format!("transition `{}`", t.name);
    out.push_str(&format!("      <transition id=\"{id}\">\n"));
    push_name(out, "        ", &t.name, &what)?;
    push_position(out, "        ", t.position);
    let plain = matches!(
        t.kind,
        TransitionKind::Timed {
            rate: None,
            servers: Servers::Single
        }
    ) && t.doc.is_none();
    if !plain {
        let ind = "          ";
        out.push_str("        ");
        out.push_str(TOOL_OPEN);
        match &t.kind {
            TransitionKind::Timed { rate, servers } => {
                push_value(out, ind, "timed", "true", &what)?;
                if let Some(r) = rate {
                    push_value(out, ind, "rate", &r.to_string(), &what)?;
                }
                match servers {
                    Servers::Single => {}
                    Servers::Infinite => push_value(out, ind, "servers", "infinite", &what)?,
                    Servers::K(k) => push_value(out, ind, "servers", &k.to_string(), &what)?,
                }
            }
            TransitionKind::Immediate { weight, priority } => {
                push_value(out, ind, "timed", "false", &what)?;
                push_value(out, ind, "weight", &weight.to_string(), &what)?;
                push_value(out, ind, "priority", &priority.to_string(), &what)?;
                if t.decision {
                    push_value(out, ind, "decision", "true", &what)?;
                }
            }
        }
        if let Some(doc) = &t.doc {
            push_value(out, ind, "doc", doc, &what)?;
        }
        out.push_str("        </toolspecific>\n");
    }
    out.push_str("      </transition>\n");
    Ok(())
}

/// An `<arc>` element with id `id` between the place `pid` and the
/// transition `tid`, in the direction of its kind.
fn push_arc(
    out: &mut String,
    a: &Arc,
    id: &str,
    pid: &str,
    tid: &str,
    values: &HashMap<&str, f64>,
) -> Result<()> {
    let what = || format!("an arc of transition `{tid}`");
    let (source, target) = match a.kind {
        ArcKind::Input | ArcKind::Inhibitor => (pid, tid),
        ArcKind::Output => (tid, pid),
    };
    let mut inner = String::new();
    if let Some(v) = whole_value(&a.multiplicity, values, 1.0).filter(|&v| v != 1) {
        inner.push_str(&format!("        <inscription><text>{v}</text></inscription>\n"));
    }
    if a.kind == ArcKind::Inhibitor {
        inner.push_str("        <type value=\"inhibitor\"/>\n");
        // pm4py's form (and ProM's), which ignores `<type>`.
        inner.push_str("        <arctype><text>inhibitor</text></arctype>\n");
    }
    if !is_plain(&a.multiplicity, 1.0) {
        inner.push_str("        ");
        inner.push_str(TOOL_OPEN);
        push_value(
            &mut inner,
            "          ",
            "multiplicity",
            &a.multiplicity.to_string(),
            &what,
        )?;
        inner.push_str("        </toolspecific>\n");
    }
    out.push_str(&format!(
        "      <arc id=\"{id}\" source=\"{source}\" target=\"{target}\""
    ));
    if inner.is_empty() {
        out.push_str("/>\n");
    } else {
        out.push_str(">\n");
        out.push_str(&inner);
        out.push_str("      </arc>\n");
    }
    Ok(())
}

/// Writes a net as a PNML place/transition net, with its GSPN attributes in
/// the petrinav tool-specific form (see the module documentation).
///
/// Fails only if a name or text contains a character XML cannot represent.
pub fn write_pnml(net: &Net) -> Result<String> {
    net.validate()?;
    let mut used = HashSet::new();
    let place_ids: Vec<String> = net
        .places
        .iter()
        .map(|p| unique_id(sanitize_id(&p.name), &mut used))
        .collect();
    let transition_ids: Vec<String> = net
        .transitions
        .iter()
        .map(|t| unique_id(sanitize_id(&t.name), &mut used))
        .collect();
    let net_id = unique_id(sanitize_id(&net.name), &mut used);
    let page_id = unique_id("page0".into(), &mut used);
    let values: HashMap<&str, f64> = net
        .params
        .iter()
        .filter_map(|p| p.value.map(|v| (p.name.as_str(), v)))
        .collect();

    let mut out =
        String::with_capacity(512 + 200 * (net.places.len() + net.transitions.len() + net.arcs.len()));
    out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    out.push_str(&format!("<pnml xmlns=\"{PNML_NAMESPACE}\">\n"));
    out.push_str(&format!("  <net id=\"{net_id}\" type=\"{PTNET_TYPE}\">\n"));
    let net_what = || "the net".to_string();
    push_name(&mut out, "    ", &net.name, &net_what)?;
    push_net_tools(&mut out, net)?;
    out.push_str(&format!("    <page id=\"{page_id}\">\n"));

    for (p, id) in net.places.iter().zip(&place_ids) {
        push_place(&mut out, p, id, &values)?;
    }

    for (t, id) in net.transitions.iter().zip(&transition_ids) {
        push_transition(&mut out, t, id)?;
    }

    for (i, a) in net.arcs.iter().enumerate() {
        let (Some(pid), Some(tid)) = (
            place_ids.get(a.place.index()),
            transition_ids.get(a.transition.index()),
        ) else {
            continue;
        };
        let id = unique_id(format!("a{i}"), &mut used);
        push_arc(&mut out, a, &id, pid, tid, &values)?;
    }
    out.push_str("    </page>\n  </net>\n</pnml>\n");
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_valid_and_unique() {
        assert_eq!(sanitize_id("P0"), "P0");
        assert_eq!(sanitize_id("1st place"), "_1st_place");
        assert_eq!(sanitize_id("é"), "_");
        assert_eq!(sanitize_id(""), "_");
        let mut used = HashSet::new();
        assert_eq!(unique_id("a".into(), &mut used), "a");
        assert_eq!(unique_id("a".into(), &mut used), "a_2");
        assert_eq!(unique_id("a".into(), &mut used), "a_3");
    }

    #[test]
    fn naming_rule() {
        let text = r#"<pnml><net id="n">
          <place id="p1"><name><text> same </text></name></place>
          <place id="p2"><name><text>same</text></name></place>
          <place id="p3"><name><text>p1</text></name></place>
          <place id="p4"/>
          <transition id="t"><name><text>go</text></name></transition>
        </net></pnml>"#;
        let net = read_pnml(text, "n.pnml").unwrap();
        let names: Vec<&str> = net.places.iter().map(|p| p.name.as_str()).collect();
        // `same` is ambiguous: ids; p3's unique name `p1` wins over p1's id.
        assert_eq!(names, ["p1_2", "p2", "p1", "p4"]);
        assert_eq!(net.transitions[0].name, "go");
        assert_eq!(net.name, "n");
    }

    #[test]
    fn pipe_counts() {
        let r = Reader {
            source: "s",
            text: "<a/>",
            split: None,
            base: None,
        };
        let doc = roxmltree::Document::parse("<a/>").unwrap();
        let node = doc.root_element();
        let what = || "x".to_string();
        assert_eq!(r.count("Default,3", node, &what, 0).unwrap(), Expr::Num(3.0));
        assert_eq!(r.count(" 2 ", node, &what, 1).unwrap(), Expr::Num(2.0));
        assert_eq!(
            r.count("Default,0,Red,2", node, &what, 0).unwrap(),
            Expr::Num(2.0)
        );
        assert!(r.count("Default,1,Red,2", node, &what, 0).is_err());
        assert!(r.count("1.5", node, &what, 0).is_err());
        assert!(r.count("0", node, &what, 1).is_err());
        assert!(r.count("-1", node, &what, 0).is_err());
        assert!(r.count("a,b,c", node, &what, 0).is_err());
    }
}
