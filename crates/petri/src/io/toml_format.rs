//! petrinav's own TOML format: the one the repository's models use, meant to
//! be written by hand.
//!
//! ```toml
//! name = "supervisor"            # optional; default: the file stem, or "net"
//! doc = "free text"              # optional
//!
//! [params]                       # optional; in file order
//! lambda1 = 0.001                # a real parameter with a value
//! p = "1/3"                      # a value may be an expression over numbers
//! N = { kind = "int", value = 3, doc = "pallets" }
//! K = { kind = "int", suggested = 2 }   # no value: give it at load/solve time
//!
//! [[place]]
//! name = "P0"
//! initial = 1                    # number or expression string ("N"); default 0
//! capacity = 4                   # optional
//! doc = "…"                      # optional
//! position = [1.0, 2.0]          # optional
//!
//! [[transition]]
//! name = "t2"
//! kind = "timed"                 # "timed" (default) | "immediate"
//! rate = "lambda1"               # timed: number or expression; optional (plain P/T nets)
//! servers = "single"             # timed: "single" (default) | "infinite" | k (a whole number ≥ 1)
//! inputs = ["P1", "P5"]          # place names (multiplicity 1)…
//! outputs = { P2 = 1, P5 = "K" } # …or a table of multiplicities (numbers or expressions)
//! inhibitors = { P3 = 1 }
//! doc = "…"
//! position = [3.0, 2.0]
//!
//! [[transition]]
//! name = "t0"
//! kind = "immediate"
//! weight = "p"                   # immediate: default 1
//! priority = 1                   # immediate: default 1
//! inputs = ["P0"]
//! outputs = ["P1"]
//!
//! [[transition]]
//! name = "t1"
//! kind = "immediate"
//! decision = true                # a policy chooses it (no weight)
//! inputs = ["P0"]
//! outputs = ["P2"]
//!
//! [labels]                       # named marking sets, for properties ("goal")
//! goal = "#P3 = 1"
//!
//! [rewards.cost]                 # a reward model, for R{"cost"} properties
//! rate = "#P1 + 2 * #P2"         # earned per unit of time in a marking
//! impulse = { t2 = 1, t0 = "p" } # earned at each firing
//! ```
//!
//! - A parameter is either a number (a real parameter with that value) or a
//!   table with `kind` (`"int"` or `"real"`, default `"real"`), `value`,
//!   `suggested` (a value shown when one must be given; never used silently)
//!   and `doc`. A value given as a string is an expression over numbers,
//!   evaluated when reading.
//! - Unknown keys are errors naming the key, so typos do not go unnoticed.
//!   Every error carries `file:line:column`.
//! - `rate` or `servers` on an immediate transition, and `weight` or
//!   `priority` on a timed one, are errors naming the transition. Arcs name
//!   places; an unknown place is [`Error::UnknownNode`].
//! - Arc lists also accept, for the rare net with parallel arcs of different
//!   multiplicities, an array mixing names and one-entry tables:
//!   `inputs = ["P1", { P1 = 2 }]`.
//! - `servers = 1` means k = 1 server, which behaves like `"single"`.
//! - `decision = true` makes an immediate transition a decision
//!   (docs/gspn.md, *Decisions*); it is an error on a timed transition and
//!   together with `weight`, which a decision does not have.
//! - `[labels]` maps a name to a condition over token counts; `[rewards.NAME]`
//!   holds a reward model's `rate` (an expression over token counts and
//!   parameters, per unit of time) and `impulse` (transition = expression
//!   over parameters, per firing). Both are written after the transitions.
//!
//! # Writing
//!
//! [`write_toml`] writes this format: defaults are left out, numbers are
//! written as numbers and expressions as strings, arc lists as arrays when
//! every multiplicity is 1 and as tables otherwise. `servers` is written
//! whenever it is not single (note that PNPRO's default is infinite, ours is
//! single). Reading what it wrote gives back the same [`Net`] (arcs in the
//! canonical order, see [`sort_arcs`](super::sort_arcs)).

use std::collections::{BTreeMap, HashMap, HashSet};
use std::fmt::{self, Write as _};
use std::ops::Range;

use serde::Deserialize;
use serde::de::{self, MapAccess, SeqAccess, Visitor};
use toml::Spanned;

use super::toml_split::ItemKind;
use super::{location_at, parse_expr};
use crate::error::{Error, Result};
use crate::expr::Expr;
use crate::net::{ArcKind, Net, Param, ParamKind, Place, PlaceId, Servers, Transition, TransitionKind};

// ---------------------------------------------------------------------------
// The schema
// ---------------------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSpec {
    name: Option<String>,
    doc: Option<String>,
    #[serde(default)]
    params: BTreeMap<Spanned<String>, Spanned<ParamSpec>>,
    place: Option<Vec<Spanned<PlaceSpec>>>,
    transition: Option<Vec<Spanned<TransitionSpec>>>,
    #[serde(default)]
    labels: BTreeMap<Spanned<String>, Spanned<String>>,
    #[serde(default)]
    rewards: BTreeMap<Spanned<String>, Spanned<RewardSpec>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RewardSpec {
    rate: Option<Spanned<Value>>,
    #[serde(default)]
    impulse: BTreeMap<Spanned<String>, Spanned<Value>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaceSpec {
    name: String,
    initial: Option<Spanned<Value>>,
    capacity: Option<u32>,
    doc: Option<String>,
    position: Option<[f64; 2]>,
}

#[derive(Deserialize, Default, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum KindSpec {
    #[default]
    Timed,
    Immediate,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransitionSpec {
    name: String,
    #[serde(default)]
    kind: KindSpec,
    rate: Option<Spanned<Value>>,
    servers: Option<Spanned<ServersSpec>>,
    weight: Option<Spanned<Value>>,
    priority: Option<Spanned<Value>>,
    decision: Option<Spanned<bool>>,
    #[serde(default)]
    inputs: ArcList,
    #[serde(default)]
    outputs: ArcList,
    #[serde(default)]
    inhibitors: ArcList,
    doc: Option<String>,
    position: Option<[f64; 2]>,
}

/// A number or an expression in a string.
enum Value {
    Num(f64),
    Text(String),
}

struct ValueVisitor;

impl<'de> Visitor<'de> for ValueVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a number or an expression in a string")
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Value, E> {
        Ok(Value::Num(v as f64))
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Value, E> {
        Ok(Value::Num(v as f64))
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Value, E> {
        Ok(Value::Num(v))
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<Value, E> {
        Ok(Value::Text(v.to_string()))
    }
}

impl<'de> Deserialize<'de> for Value {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ValueVisitor)
    }
}

/// A parameter: a number, an expression, or a table.
enum ParamSpec {
    Value(Value),
    Table(ParamTable),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ParamTable {
    kind: Option<ParamKindSpec>,
    value: Option<Spanned<Value>>,
    suggested: Option<Spanned<Value>>,
    doc: Option<String>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum ParamKindSpec {
    Int,
    Real,
}

impl<'de> Deserialize<'de> for ParamSpec {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ParamSpec;

            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number, an expression in a string, or a table { kind, value, suggested, doc }")
            }

            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ParamSpec, E> {
                ValueVisitor.visit_i64(v).map(ParamSpec::Value)
            }

            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ParamSpec, E> {
                ValueVisitor.visit_u64(v).map(ParamSpec::Value)
            }

            fn visit_f64<E: de::Error>(self, v: f64) -> Result<ParamSpec, E> {
                ValueVisitor.visit_f64(v).map(ParamSpec::Value)
            }

            fn visit_str<E: de::Error>(self, v: &str) -> Result<ParamSpec, E> {
                ValueVisitor.visit_str(v).map(ParamSpec::Value)
            }

            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<ParamSpec, A::Error> {
                ParamTable::deserialize(de::value::MapAccessDeserializer::new(map)).map(ParamSpec::Table)
            }
        }
        d.deserialize_any(V)
    }
}

/// `"single"`, `"infinite"`, or k.
struct ServersSpec(Servers);

impl<'de> Deserialize<'de> for ServersSpec {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ServersSpec;

            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("\"single\", \"infinite\" or a whole number ≥ 1")
            }

            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ServersSpec, E> {
                match u32::try_from(v) {
                    Ok(k) if k >= 1 => Ok(ServersSpec(Servers::K(k))),
                    _ => Err(E::invalid_value(de::Unexpected::Signed(v), &self)),
                }
            }

            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ServersSpec, E> {
                match u32::try_from(v) {
                    Ok(k) if k >= 1 => Ok(ServersSpec(Servers::K(k))),
                    _ => Err(E::invalid_value(de::Unexpected::Unsigned(v), &self)),
                }
            }

            fn visit_str<E: de::Error>(self, v: &str) -> Result<ServersSpec, E> {
                if v.eq_ignore_ascii_case("single") {
                    Ok(ServersSpec(Servers::Single))
                } else if v.eq_ignore_ascii_case("infinite") {
                    Ok(ServersSpec(Servers::Infinite))
                } else {
                    Err(E::invalid_value(de::Unexpected::Str(v), &self))
                }
            }
        }
        d.deserialize_any(V)
    }
}

/// A place name with its multiplicity (`None`: 1).
type ArcEntry = (Spanned<String>, Option<Spanned<Value>>);

/// Arcs of one kind of a transition, in the order given.
#[derive(Default)]
struct ArcList(Vec<ArcEntry>);

/// One item of an arc array: a name, or a table of names and multiplicities.
struct ArcItem(Vec<ArcEntry>);

fn read_entries<'de, A: MapAccess<'de>>(mut map: A) -> Result<Vec<ArcEntry>, A::Error> {
    let mut out = Vec::new();
    while let Some(key) = map.next_key::<Spanned<String>>()? {
        let value = map.next_value::<Spanned<Value>>()?;
        out.push((key, Some(value)));
    }
    Ok(out)
}

impl<'de> Deserialize<'de> for ArcItem {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ArcItem;

            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a place name or a table { place = multiplicity }")
            }

            fn visit_str<E: de::Error>(self, v: &str) -> Result<ArcItem, E> {
                // The span is filled in by the caller.
                Ok(ArcItem(vec![(Spanned::new(0..0, v.to_string()), None)]))
            }

            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<ArcItem, A::Error> {
                read_entries(map).map(ArcItem)
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for ArcList {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ArcList;

            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an array of place names or a table { place = multiplicity }")
            }

            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<ArcList, A::Error> {
                let mut out = Vec::new();
                while let Some(item) = seq.next_element::<Spanned<ArcItem>>()? {
                    let span = item.span();
                    for (name, mult) in item.into_inner().0 {
                        let name = if mult.is_none() {
                            Spanned::new(span.clone(), name.into_inner())
                        } else {
                            name
                        };
                        out.push((name, mult));
                    }
                }
                Ok(ArcList(out))
            }

            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<ArcList, A::Error> {
                read_entries(map).map(ArcList)
            }
        }
        d.deserialize_any(V)
    }
}

// ---------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------

/// Reads a net in petrinav's TOML format. `source` names the text in error
/// messages (a file name) and gives the net its default name (the stem).
///
/// A file is parsed one item at a time where that cannot change its
/// meaning (`super::toml_split`), so that the parser's document tree
/// never holds more than one place or transition; other files are parsed
/// whole.
pub fn read_toml(text: &str, source: &str) -> Result<Net> {
    let text = super::prepare(text, source)?;
    let Some(items) = super::toml_split::items(text) else {
        return read_whole(text, source);
    };
    let mut head = parse_spec(text, items.head(), source)?;
    if head.place.is_some() || head.transition.is_some() {
        // `place = [...]` written inline in the head: not cut.
        return read_whole(text, source);
    }
    let labels = std::mem::take(&mut head.labels);
    let rewards = std::mem::take(&mut head.rewards);
    let mut b = Builder::new(text, source, head)?;
    for (kind, is_place) in [(ItemKind::Place, true), (ItemKind::Transition, false)] {
        for range in items.of(kind) {
            let spec = parse_spec(text, range.clone(), source)?;
            let r = Reader {
                source,
                text,
                offset: range.start,
            };
            match (spec, is_place) {
                (
                    FileSpec {
                        place: Some(mut p),
                        transition: None,
                        ..
                    },
                    true,
                ) if p.len() == 1 => b.place(&r, p.remove(0))?,
                (
                    FileSpec {
                        place: None,
                        transition: Some(mut t),
                        ..
                    },
                    false,
                ) if t.len() == 1 => b.transition(&r, t.remove(0))?,
                // Not one item (cannot happen, module docs of toml_split):
                // the whole file decides.
                _ => return read_whole(text, source),
            }
        }
    }
    let r = Reader {
        source,
        text,
        offset: 0,
    };
    b.finish(&r, labels, rewards)
}

/// Parses the whole text at once.
fn read_whole(text: &str, source: &str) -> Result<Net> {
    let mut spec = parse_spec(text, 0..text.len(), source)?;
    let places = spec.place.take().unwrap_or_default();
    let transitions = spec.transition.take().unwrap_or_default();
    let labels = std::mem::take(&mut spec.labels);
    let rewards = std::mem::take(&mut spec.rewards);
    let r = Reader {
        source,
        text,
        offset: 0,
    };
    let mut b = Builder::new(text, source, spec)?;
    for p in places {
        b.place(&r, p)?;
    }
    for t in transitions {
        b.transition(&r, t)?;
    }
    b.finish(&r, labels, rewards)
}

/// The schema read from `text[range]`; errors located in the whole text.
fn parse_spec(text: &str, range: Range<usize>, source: &str) -> Result<FileSpec> {
    let start = range.start;
    toml::from_str(&text[range]).map_err(|e| Error::Format {
        location: match e.span() {
            Some(span) => location_at(source, text, start + span.start),
            None => source.to_string(),
        },
        message: e.message().trim().to_string(),
    })
}

/// The net as it is read: places and transitions added one by one, names
/// checked.
struct Builder {
    net: Net,
    place_ids: HashMap<String, PlaceId>,
    transition_names: HashSet<String>,
}

impl Builder {
    /// The net's name, documentation and parameters, from the head.
    fn new(text: &str, source: &str, head: FileSpec) -> Result<Builder> {
        let r = Reader {
            source,
            text,
            offset: 0,
        };
        let mut net = Net::new(head.name.unwrap_or_else(|| super::default_net_name(source)));
        net.doc = head.doc;
        let mut params: Vec<_> = head.params.into_iter().collect();
        params.sort_by_key(|(key, _)| key.span().start);
        for (key, spec) in params {
            let span = spec.span();
            let name = key.into_inner();
            net.params.push(r.param(name, spec.into_inner(), span)?);
        }
        Ok(Builder {
            net,
            place_ids: HashMap::new(),
            transition_names: HashSet::new(),
        })
    }

    fn place(&mut self, r: &Reader<'_>, spec: Spanned<PlaceSpec>) -> Result<()> {
        let span = spec.span();
        let p = spec.into_inner();
        if self.place_ids.contains_key(&p.name) {
            return Err(Error::DuplicateName {
                name: p.name,
                first: "a place",
                second: "a place",
            });
        }
        self.place_ids
            .insert(p.name.clone(), PlaceId(self.net.places.len() as u32));
        let owner = format!("place `{}`", p.name);
        let initial = match p.initial {
            None => Expr::Num(0.0),
            Some(v) => r.expr(v, &owner, "initial")?,
        };
        if p.name.is_empty() {
            return Err(r.error(span, "a place has an empty `name`".into()));
        }
        self.net.places.push(Place {
            name: p.name,
            initial,
            capacity: p.capacity,
            position: p.position.map(|[x, y]| (x, y)),
            doc: p.doc,
        });
        Ok(())
    }

    fn transition(&mut self, r: &Reader<'_>, spec: Spanned<TransitionSpec>) -> Result<()> {
        let span = spec.span();
        let t = spec.into_inner();
        let first = if self.place_ids.contains_key(&t.name) {
            Some("a place")
        } else if self.transition_names.contains(&t.name) {
            Some("a transition")
        } else {
            None
        };
        if let Some(first) = first {
            return Err(Error::DuplicateName {
                name: t.name,
                first,
                second: "a transition",
            });
        }
        if t.name.is_empty() {
            return Err(r.error(span, "a transition has an empty `name`".into()));
        }
        let transition = r.transition(&t, &mut self.net, &self.place_ids)?;
        self.transition_names.insert(t.name);
        self.net.transitions.push(transition);
        Ok(())
    }

    /// The named marking sets and the reward models (they name places and
    /// transitions, so they come once all are read), then the net checked
    /// as a whole.
    fn finish(
        mut self,
        r: &Reader<'_>,
        labels: BTreeMap<Spanned<String>, Spanned<String>>,
        rewards: BTreeMap<Spanned<String>, Spanned<RewardSpec>>,
    ) -> Result<Net> {
        let mut labels: Vec<_> = labels.into_iter().collect();
        labels.sort_by_key(|(key, _)| key.span().start);
        for (key, text) in labels {
            let name = key.into_inner();
            let owner = format!("label `{name}`");
            let expr = r.expr(text.map(Value::Text), &owner, "condition")?;
            self.net.labels.push(crate::net::Label { name, expr });
        }
        let mut rewards: Vec<_> = rewards.into_iter().collect();
        rewards.sort_by_key(|(key, _)| key.span().start);
        for (key, reward) in rewards {
            let reward = r.reward(key.into_inner(), reward.into_inner(), &self.net)?;
            self.net.rewards.push(reward);
        }
        super::finish(self.net)
    }
}

trait SpannedMap<T> {
    fn map<U>(self, f: impl FnOnce(T) -> U) -> Spanned<U>;
}

impl<T> SpannedMap<T> for Spanned<T> {
    fn map<U>(self, f: impl FnOnce(T) -> U) -> Spanned<U> {
        let span = self.span();
        Spanned::new(span, f(self.into_inner()))
    }
}

/// Errors and expressions of one piece of the text: `offset` is where the
/// piece starts in `text`, the whole file, to which spans are relative.
struct Reader<'a> {
    source: &'a str,
    text: &'a str,
    offset: usize,
}

impl Reader<'_> {
    fn error(&self, span: Range<usize>, message: String) -> Error {
        Error::Format {
            location: location_at(self.source, self.text, self.offset + span.start),
            message,
        }
    }

    fn expr(&self, v: Spanned<Value>, owner: &str, key: &str) -> Result<Expr> {
        let span = v.span();
        match v.into_inner() {
            Value::Num(x) => Ok(Expr::Num(x)),
            Value::Text(t) => parse_expr(
                &t,
                || location_at(self.source, self.text, self.offset + span.start),
                || format!("{owner}, `{key}`"),
            ),
        }
    }

    /// A parameter value: a number, or an expression over numbers.
    fn number(&self, v: Spanned<Value>, owner: &str, key: &str) -> Result<f64> {
        let span = v.span();
        let e = self.expr(v, owner, key)?;
        e.eval_params(&|_| None, owner).map_err(|err| {
            self.error(
                span,
                format!("{owner}, `{key}`: a parameter's value must be a number or an expression over numbers ({err})"),
            )
        })
    }

    fn param(&self, name: String, spec: ParamSpec, span: Range<usize>) -> Result<Param> {
        let owner = format!("parameter `{name}`");
        Ok(match spec {
            ParamSpec::Value(v) => Param {
                value: Some(self.number(Spanned::new(span, v), &owner, "value")?),
                name,
                kind: ParamKind::Real,
                suggested: None,
                doc: None,
            },
            ParamSpec::Table(t) => Param {
                value: t.value.map(|v| self.number(v, &owner, "value")).transpose()?,
                suggested: t
                    .suggested
                    .map(|v| self.number(v, &owner, "suggested"))
                    .transpose()?,
                kind: match t.kind {
                    Some(ParamKindSpec::Int) => ParamKind::Int,
                    Some(ParamKindSpec::Real) | None => ParamKind::Real,
                },
                doc: t.doc,
                name,
            },
        })
    }

    fn reward(&self, name: String, spec: RewardSpec, net: &Net) -> Result<crate::net::RewardModel> {
        let owner = format!("reward model `{name}`");
        let rate = spec.rate.map(|v| self.expr(v, &owner, "rate")).transpose()?;
        let mut impulses = Vec::new();
        let mut entries: Vec<_> = spec.impulse.into_iter().collect();
        entries.sort_by_key(|(key, _)| key.span().start);
        for (key, value) in entries {
            let Some(t) = net.transition_id(key.get_ref()) else {
                let hint =
                    crate::suggest::hint(key.get_ref(), net.transitions.iter().map(|t| t.name.as_str()));
                return Err(Error::UnknownNode {
                    arc: format!(
                        "{}: impulse of {owner}",
                        location_at(self.source, self.text, self.offset + key.span().start)
                    ),
                    expected: "transition",
                    name: key.into_inner(),
                    hint,
                });
            };
            impulses.push((t, self.expr(value, &owner, "impulse")?));
        }
        Ok(crate::net::RewardModel { name, rate, impulses })
    }

    fn transition(
        &self,
        t: &TransitionSpec,
        net: &mut Net,
        place_ids: &HashMap<String, PlaceId>,
    ) -> Result<Transition> {
        let owner = format!("transition `{}`", t.name);
        let refuse = |key: &str, v: Option<Range<usize>>, why: &str| -> Result<()> {
            match v {
                Some(span) => Err(self.error(span, format!("{owner} is {why}: it cannot have `{key}`"))),
                None => Ok(()),
            }
        };
        let kind = match t.kind {
            KindSpec::Timed => {
                let why = "timed (kind = \"timed\", the default); `weight`, `priority` and `decision` are for kind = \"immediate\"";
                refuse("weight", t.weight.as_ref().map(Spanned::span), why)?;
                refuse("priority", t.priority.as_ref().map(Spanned::span), why)?;
                refuse(
                    "decision",
                    t.decision.as_ref().filter(|d| *d.get_ref()).map(Spanned::span),
                    why,
                )?;
                TransitionKind::Timed {
                    rate: t
                        .rate
                        .as_ref()
                        .map(|v| self.expr(clone_value(v), &owner, "rate"))
                        .transpose()?,
                    servers: t.servers.as_ref().map_or(Servers::Single, |s| s.get_ref().0),
                }
            }
            KindSpec::Immediate => {
                let why = "immediate: it fires in zero time, its `weight` sets its probability";
                refuse("rate", t.rate.as_ref().map(Spanned::span), why)?;
                refuse("servers", t.servers.as_ref().map(Spanned::span), why)?;
                if t.decision.as_ref().is_some_and(|d| *d.get_ref()) {
                    refuse(
                        "weight",
                        t.weight.as_ref().map(Spanned::span),
                        "a decision (decision = true): the policy chooses it, it has no weight",
                    )?;
                }
                TransitionKind::Immediate {
                    weight: t
                        .weight
                        .as_ref()
                        .map(|v| self.expr(clone_value(v), &owner, "weight"))
                        .transpose()?
                        .unwrap_or(Expr::Num(1.0)),
                    priority: t
                        .priority
                        .as_ref()
                        .map(|v| self.expr(clone_value(v), &owner, "priority"))
                        .transpose()?
                        .unwrap_or(Expr::Num(1.0)),
                }
            }
        };
        let tid = crate::net::TransitionId(net.transitions.len() as u32);
        for (list, kind, key) in [
            (&t.inputs, ArcKind::Input, "inputs"),
            (&t.outputs, ArcKind::Output, "outputs"),
            (&t.inhibitors, ArcKind::Inhibitor, "inhibitors"),
        ] {
            for (place, mult) in &list.0 {
                let Some(&pid) = place_ids.get(place.get_ref()) else {
                    return Err(Error::UnknownNode {
                        arc: format!(
                            "{}: {} arc of {owner} (`{key}`)",
                            location_at(self.source, self.text, self.offset + place.span().start),
                            kind.name()
                        ),
                        expected: "place",
                        name: place.get_ref().clone(),
                        hint: crate::suggest::hint(place.get_ref(), place_ids.keys().map(String::as_str)),
                    });
                };
                let multiplicity = match mult {
                    None => Expr::Num(1.0),
                    Some(v) => self.expr(
                        clone_value(v),
                        &format!("{owner}, {} arc from `{}`", kind.name(), place.get_ref()),
                        key,
                    )?,
                };
                net.add_arc(kind, pid, tid, multiplicity);
            }
        }
        Ok(Transition {
            name: t.name.clone(),
            kind,
            decision: t.decision.as_ref().is_some_and(|d| *d.get_ref()),
            position: t.position.map(|[x, y]| (x, y)),
            doc: t.doc.clone(),
        })
    }
}

fn clone_value(v: &Spanned<Value>) -> Spanned<Value> {
    let inner = match v.get_ref() {
        Value::Num(x) => Value::Num(*x),
        Value::Text(t) => Value::Text(t.clone()),
    };
    Spanned::new(v.span(), inner)
}

// ---------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------

/// A TOML basic string.
fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if (c as u32) < 0x20 || c == '\u{7f}' => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A key, bare when TOML allows it.
fn key(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        s.to_string()
    } else {
        quote(s)
    }
}

/// A number that reads back as the same `f64`.
fn number(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf".into() } else { "-inf".into() }
    } else if v == v.trunc() && v.abs() < 9_007_199_254_740_992.0 {
        format!("{}", v as i64)
    } else {
        format!("{v:?}")
    }
}

/// An expression: a number when it is one, else a string.
fn expr_value(e: &Expr) -> String {
    match e {
        Expr::Num(v) => number(*v),
        e => quote(&e.to_string()),
    }
}

fn position(p: (f64, f64)) -> String {
    format!("[{}, {}]", number(p.0), number(p.1))
}

/// An arc list: an array when every multiplicity is 1, a table when no place
/// repeats, else an array of names and one-entry tables.
fn arc_list(items: &[(&str, &Expr)]) -> String {
    let one = Expr::Num(1.0);
    if items.iter().all(|(_, m)| **m == one) {
        let names: Vec<String> = items.iter().map(|(p, _)| quote(p)).collect();
        return format!("[{}]", names.join(", "));
    }
    let mut seen = std::collections::HashSet::new();
    if items.iter().all(|(p, _)| seen.insert(*p)) {
        let entries: Vec<String> = items
            .iter()
            .map(|(p, m)| format!("{} = {}", key(p), expr_value(m)))
            .collect();
        return format!("{{ {} }}", entries.join(", "));
    }
    let entries: Vec<String> = items
        .iter()
        .map(|(p, m)| {
            if **m == one {
                quote(p)
            } else {
                format!("{{ {} = {} }}", key(p), expr_value(m))
            }
        })
        .collect();
    format!("[{}]", entries.join(", "))
}

/// Writes a net in petrinav's TOML format.
pub fn write_toml(net: &Net) -> Result<String> {
    net.validate()?;
    let mut out = String::new();
    let _ = writeln!(out, "name = {}", quote(&net.name));
    if let Some(doc) = &net.doc {
        let _ = writeln!(out, "doc = {}", quote(doc));
    }
    if !net.params.is_empty() {
        out.push_str("\n[params]\n");
        for p in &net.params {
            let simple = p.kind == ParamKind::Real && p.suggested.is_none() && p.doc.is_none();
            match (simple, p.value) {
                (true, Some(v)) => {
                    let _ = writeln!(out, "{} = {}", key(&p.name), number(v));
                }
                _ => {
                    let mut fields = vec![format!(
                        "kind = {}",
                        match p.kind {
                            ParamKind::Int => "\"int\"",
                            ParamKind::Real => "\"real\"",
                        }
                    )];
                    if let Some(v) = p.value {
                        fields.push(format!("value = {}", number(v)));
                    }
                    if let Some(v) = p.suggested {
                        fields.push(format!("suggested = {}", number(v)));
                    }
                    if let Some(d) = &p.doc {
                        fields.push(format!("doc = {}", quote(d)));
                    }
                    let _ = writeln!(out, "{} = {{ {} }}", key(&p.name), fields.join(", "));
                }
            }
        }
    }
    for p in &net.places {
        out.push_str("\n[[place]]\n");
        let _ = writeln!(out, "name = {}", quote(&p.name));
        if p.initial != Expr::Num(0.0) {
            let _ = writeln!(out, "initial = {}", expr_value(&p.initial));
        }
        if let Some(c) = p.capacity {
            let _ = writeln!(out, "capacity = {c}");
        }
        if let Some(d) = &p.doc {
            let _ = writeln!(out, "doc = {}", quote(d));
        }
        if let Some(pos) = p.position {
            let _ = writeln!(out, "position = {}", position(pos));
        }
    }
    let mut lists: Vec<[Vec<(&str, &Expr)>; 3]> = vec![Default::default(); net.transitions.len()];
    for a in &net.arcs {
        let (Some(place), Some(slot)) = (
            net.places.get(a.place.index()),
            lists.get_mut(a.transition.index()),
        ) else {
            continue;
        };
        let k = match a.kind {
            ArcKind::Input => 0,
            ArcKind::Output => 1,
            ArcKind::Inhibitor => 2,
        };
        slot[k].push((place.name.as_str(), &a.multiplicity));
    }
    for (t, lists) in net.transitions.iter().zip(&lists) {
        out.push_str("\n[[transition]]\n");
        let _ = writeln!(out, "name = {}", quote(&t.name));
        match &t.kind {
            TransitionKind::Timed { rate, servers } => {
                if let Some(r) = rate {
                    let _ = writeln!(out, "rate = {}", expr_value(r));
                }
                match servers {
                    Servers::Single => {}
                    Servers::Infinite => out.push_str("servers = \"infinite\"\n"),
                    Servers::K(k) => {
                        let _ = writeln!(out, "servers = {k}");
                    }
                }
            }
            TransitionKind::Immediate { weight, priority } => {
                out.push_str("kind = \"immediate\"\n");
                if t.decision {
                    out.push_str("decision = true\n");
                } else if *weight != Expr::Num(1.0) {
                    let _ = writeln!(out, "weight = {}", expr_value(weight));
                }
                if *priority != Expr::Num(1.0) {
                    let _ = writeln!(out, "priority = {}", expr_value(priority));
                }
            }
        }
        for (items, name) in lists.iter().zip(["inputs", "outputs", "inhibitors"]) {
            if !items.is_empty() {
                let _ = writeln!(out, "{name} = {}", arc_list(items));
            }
        }
        if let Some(d) = &t.doc {
            let _ = writeln!(out, "doc = {}", quote(d));
        }
        if let Some(pos) = t.position {
            let _ = writeln!(out, "position = {}", position(pos));
        }
    }
    write_labels_and_rewards(&mut out, net);
    Ok(out)
}

/// The `[labels]` table and one `[rewards.NAME]` table per reward model.
fn write_labels_and_rewards(out: &mut String, net: &Net) {
    if !net.labels.is_empty() {
        out.push_str("\n[labels]\n");
        for l in &net.labels {
            let _ = writeln!(out, "{} = {}", key(&l.name), quote(&l.expr.to_string()));
        }
    }
    for r in &net.rewards {
        let _ = writeln!(out, "\n[rewards.{}]", key(&r.name));
        if let Some(rate) = &r.rate {
            let _ = writeln!(out, "rate = {}", expr_value(rate));
        }
        if !r.impulses.is_empty() {
            let entries: Vec<String> = r
                .impulses
                .iter()
                .filter_map(|(t, e)| {
                    let name = &net.transitions.get(t.index())?.name;
                    Some(format!("{} = {}", key(name), expr_value(e)))
                })
                .collect();
            let _ = writeln!(out, "impulse = {{ {} }}", entries.join(", "));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_strings_round_trip_through_toml() {
        for v in [
            0.0,
            1.0,
            -3.0,
            0.001,
            1e-7,
            1.5e300,
            1e16,
            2.5,
            f64::INFINITY,
            1.0 / 3.0,
        ] {
            let text = format!("x = {}", number(v));
            let back: BTreeMap<String, f64> = toml::from_str(&text).unwrap();
            assert_eq!(back["x"], v, "{text}");
        }
        for s in [
            "plain",
            "with \"quotes\" and \\",
            "tab\tnew\nline\r",
            "bell\u{7}",
            "é ü",
        ] {
            let text = format!("x = {}\n{} = 1", quote(s), key(s));
            let back: BTreeMap<String, toml::Value> = toml::from_str(&text).unwrap();
            assert_eq!(back["x"].as_str(), Some(s), "{text}");
            assert!(back.contains_key(s), "{text}");
        }
    }

    #[test]
    fn arc_lists_choose_the_simplest_form() {
        let one = Expr::Num(1.0);
        let two = Expr::Num(2.0);
        let k = Expr::param("K");
        assert_eq!(arc_list(&[("a", &one), ("b c", &one)]), r#"["a", "b c"]"#);
        assert_eq!(arc_list(&[("a", &two), ("b", &k)]), r#"{ a = 2, b = "K" }"#);
        assert_eq!(arc_list(&[("a", &one), ("a", &two)]), r#"["a", { a = 2 }]"#);
    }

    #[test]
    fn the_documented_example_reads() {
        let doc = include_str!("toml_format.rs");
        let start = doc.find("//! ```toml").unwrap();
        let end = start + doc[start..].find("//! ```\n").unwrap();
        let example: String = doc[start..end]
            .lines()
            .skip(1)
            .map(|l| l.strip_prefix("//! ").or(l.strip_prefix("//!")).unwrap_or(l))
            .collect::<Vec<_>>()
            .join("\n")
            .replace("\"…\"", "\"text\"");
        let example = format!(
            "{example}\n[[place]]\nname = \"P1\"\n[[place]]\nname = \"P2\"\n[[place]]\nname = \"P3\"\n[[place]]\nname = \"P5\"\n"
        );
        let net = read_toml(&example, "supervisor.toml").unwrap();
        assert_eq!(net.params.len(), 4);
        assert_eq!(net.param("p").unwrap().value, Some(1.0 / 3.0));
        assert_eq!(net.param("K").unwrap().suggested, Some(2.0));
        assert_eq!(net.transitions.len(), 3);
        assert!(net.transitions[2].decision && !net.transitions[1].decision);
        assert_eq!(net.arcs.len(), 9);
        assert_eq!(net.labels.len(), 1);
        assert_eq!(net.rewards[0].impulses.len(), 2);
        let back = read_toml(&write_toml(&net).unwrap(), "supervisor.toml").unwrap();
        assert_eq!(back.labels, net.labels);
        assert_eq!(back.rewards, net.rewards);
        assert_eq!(back.transitions, net.transitions);
    }
}
