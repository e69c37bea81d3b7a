//! A Petri net as a page draws it beside a replayed run: its places and
//! transitions where the net file puts them, its arcs, and which of the
//! run's values holds each place's tokens — a live monitor of the net as
//! the run plays ([`crate::viewer`]). The supervisor of the tour-guide
//! robot notes its net's marking every cycle (`net.P1` … `net.P8`).
//!
//! ```
//! let net = petri::io::read_str(
//!     "name = \"n\"\n[[place]]\nname = \"A\"\ninitial = 1\n[[place]]\nname = \"B\"\n\
//!      [[transition]]\nname = \"go\"\ninputs = [\"A\"]\noutputs = [\"B\"]\n",
//!     petri::io::Format::Toml,
//!     "n.toml",
//! )?;
//! let view = lab::net_view::NetView::of(&net, "net.", "decision");
//! assert_eq!(view.places[1].value, "net.B");
//! assert_eq!(view.arcs.len(), 2);
//! # Ok::<(), petri::Error>(())
//! ```

/// A node of the drawing.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NetNode {
    /// Its name in the net.
    pub name: String,
    /// Position, the net file's units (y down, as drawing tools write it).
    pub x: f64,
    /// See `x`.
    pub y: f64,
    /// What it means (the net file's `doc`).
    pub doc: String,
}

/// How an arc joins a place and a transition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ArcKind {
    /// Place → transition.
    Input,
    /// Transition → place.
    Output,
    /// Both: the transition reads the place.
    Read,
    /// The place inhibits the transition.
    Inhibitor,
}

/// An arc of the drawing.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct NetArc {
    /// Index in [`NetView::places`].
    pub place: usize,
    /// Index in [`NetView::transitions`].
    pub transition: usize,
    /// Its kind.
    pub kind: ArcKind,
}

/// A net drawn beside a run, its marking read from the run's values.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NetView {
    /// The net's name.
    pub name: String,
    /// Places.
    pub places: Vec<NetPlace>,
    /// Transitions (immediate ones drawn as bars).
    pub transitions: Vec<NetTransition>,
    /// Arcs.
    pub arcs: Vec<NetArc>,
    /// The kind of event whose payload the page shows beside the net at
    /// the last one played (the supervisor's `decision`).
    pub event: String,
}

/// A place of the drawing.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NetPlace {
    /// Where and what.
    #[serde(flatten)]
    pub node: NetNode,
    /// The run's value holding its tokens (absent from a run: unknown).
    pub value: String,
}

/// A transition of the drawing.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NetTransition {
    /// Where and what.
    #[serde(flatten)]
    pub node: NetNode,
    /// Immediate (a bar) or timed (a box).
    pub immediate: bool,
}

impl NetView {
    /// The drawing of `net`: the tokens of place `P` in the run's value
    /// `{prefix}P`, the payload of the last `event` shown beside it. Nodes
    /// without a position in the file are put on a circle.
    pub fn of(net: &petri::Net, prefix: &str, event: &str) -> NetView {
        let n = (net.places.len() + net.transitions.len()).max(1) as f64;
        let circle = |k: usize| {
            let a = std::f64::consts::TAU * k as f64 / n;
            (200.0 + 150.0 * a.cos(), 200.0 + 150.0 * a.sin())
        };
        let node = |name: &str, doc: &Option<String>, at: Option<(f64, f64)>, k: usize| {
            let (x, y) = at.unwrap_or_else(|| circle(k));
            NetNode {
                name: name.to_string(),
                x,
                y,
                doc: doc.clone().unwrap_or_default(),
            }
        };
        let places = net
            .places
            .iter()
            .enumerate()
            .map(|(k, p)| NetPlace {
                node: node(&p.name, &p.doc, p.position, k),
                value: format!("{prefix}{}", p.name),
            })
            .collect();
        let offset = net.places.len();
        let transitions = net
            .transitions
            .iter()
            .enumerate()
            .map(|(k, t)| NetTransition {
                node: node(&t.name, &t.doc, t.position, offset + k),
                immediate: t.is_immediate(),
            })
            .collect();
        let has = |kind: petri::ArcKind, a: &petri::Arc| {
            net.arcs
                .iter()
                .any(|b| b.kind == kind && b.place == a.place && b.transition == a.transition)
        };
        let arcs = net
            .arcs
            .iter()
            .filter_map(|a| {
                let kind = match a.kind {
                    petri::ArcKind::Input if has(petri::ArcKind::Output, a) => ArcKind::Read,
                    petri::ArcKind::Input => ArcKind::Input,
                    // Drawn once, as the input's read arc.
                    petri::ArcKind::Output if has(petri::ArcKind::Input, a) => return None,
                    petri::ArcKind::Output => ArcKind::Output,
                    petri::ArcKind::Inhibitor => ArcKind::Inhibitor,
                };
                Some(NetArc {
                    place: a.place.0 as usize,
                    transition: a.transition.0 as usize,
                    kind,
                })
            })
            .collect();
        NetView {
            name: net.name.clone(),
            places,
            transitions,
            arcs,
            event: event.to_string(),
        }
    }
}
