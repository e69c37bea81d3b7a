//! The map for other tools: Graphviz DOT to look at, PNML to analyse.
//!
//! # DOT
//!
//! [`to_dot`]: one node per place, at its odometry position (`pos` in
//! inches, 1 m = 1 in, pinned: `neato -Tsvg` draws the map as the robot
//! saw it; `dot` ignores positions), labelled with its name and type (and
//! `concave`); one edge per transition, labelled with its id, strategy and
//! weighted cost `C`, coloured by strategy:
//!
//! | strategy | colour |
//! |---|---|
//! | free movement | black |
//! | wall following left / right | blue / dark green |
//! | detour left / right | orange / red |
//!
//! Given a [`Plan`], places show `α` too and edges `f` instead of `C`; the
//! route is drawn thick, rejected transitions dashed, the start as a double
//! circle and the goals filled.
//!
//! # PNML
//!
//! [`to_pnml`]: the place/transition net underneath — one PNML place per
//! reference place (named as the place), one PNML transition per FPN
//! transition (named `t0`, `t1`, … as in [`TransitionId`]'s display, with
//! `'` appended while that is a place's name), an arc from the origin place
//! to the transition and one from the transition to the destination, and
//! optionally one token at a place (where the robot is). The graphics
//! position of a place is its odometry position at 50 px per metre, y
//! pointing down as on screens. Everything else goes, exactly, into
//! `<toolspecific tool="petrinav" version="1">` elements, which
//! `petri`'s reader and other tools skip:
//!
//! ```xml
//! <place id="pl0">
//!   <name><text>p1</text></name>
//!   <graphics><position x="0.0" y="-0.0"/></graphics>
//!   <initialMarking><text>1</text></initialMarking>
//!   <toolspecific tool="petrinav" version="1">
//!     <fpnPlace x_m="0.0" y_m="0.0" heading_rad="0.0" kind="a" concave="true" visits="2"
//!               alpha="0.25" reached="true"/>  <!-- α with a plan -->
//!   </toolspecific>
//! </place>
//! <transition id="tr0">
//!   <name><text>t0</text></name>
//!   <toolspecific tool="petrinav" version="1">
//!     <fpnTransition strategy="wall_follow_left" exit_turn="right" duration_s="12.5"
//!                    cost="18.5" weighted_cost="0.125" lambda="1.0" attempts="3" failures="0"
//!                    f="0.25" accepted="true" on_route="true"/>  <!-- the last three with a plan -->
//!   </toolspecific>
//! </transition>
//! ```
//!
//! and at the net level `<fpnNet format="petrinav-fpn" version="1"
//! total_cost="…"/>`, with a plan `<fpnPlan mode="optimal" start="pl0"
//! cost="…"><goal place="pl4"/></fpnPlan>` (PNML ids). Numbers are written
//! in Rust's shortest round-trip form.

use std::collections::HashSet;
use std::fmt::Write as _;

use super::TopoError;
use super::fpn::{FORMAT, FORMAT_VERSION, FuzzyPetriNet, PlaceId, Strategy, TransitionId};
use super::propagation::Plan;

/// PNML graphics pixels per metre of odometry.
pub const PNML_PIXELS_PER_M: f64 = 50.0;

/// The Graphviz colour of a strategy's edges.
pub fn strategy_colour(s: Strategy) -> &'static str {
    match s {
        Strategy::FreeMovement => "black",
        Strategy::WallFollowLeft => "blue",
        Strategy::WallFollowRight => "darkgreen",
        Strategy::DetourLeft => "orange",
        Strategy::DetourRight => "red",
    }
}

fn check_plan(net: &FuzzyPetriNet, plan: Option<&Plan>) -> Result<(), TopoError> {
    match plan {
        Some(p)
            if p.alpha.len() != net.num_places()
                || p.f.len() != net.num_transitions()
                || p.route.iter().any(|t| t.index() >= net.num_transitions())
                || p.places
                    .iter()
                    .chain(&p.goals)
                    .any(|q| q.index() >= net.num_places()) =>
        {
            Err(TopoError::PlanMismatch {
                places: p.alpha.len(),
                transitions: p.f.len(),
            })
        }
        _ => Ok(()),
    }
}

/// A value in `[0, 1]` for a label: four decimals, or three significant
/// digits when smaller than 0.001.
fn short(v: f64) -> String {
    if v == 0.0 || v >= 1e-3 {
        format!("{v:.4}")
    } else {
        format!("{v:.2e}")
    }
}

fn dot_escape(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}

/// The map as a Graphviz digraph (see the module documentation). Fails
/// only when `plan` was made for another map. `O(|P| + |T|)`.
pub fn to_dot(net: &FuzzyPetriNet, plan: Option<&Plan>) -> Result<String, TopoError> {
    check_plan(net, plan)?;
    let mut on_route = vec![false; net.num_transitions()];
    let mut is_goal = vec![false; net.num_places()];
    if let Some(p) = plan {
        for t in &p.route {
            on_route[t.index()] = true;
        }
        for g in &p.goals {
            is_goal[g.index()] = true;
        }
    }
    let mut out = String::with_capacity(128 + 80 * (net.num_places() + net.num_transitions()));
    out.push_str("digraph fpn {\n");
    out.push_str("  graph [overlap=false, splines=true];\n");
    out.push_str("  node [shape=circle, fontsize=10, margin=0.02];\n");
    out.push_str("  edge [fontsize=8];\n");
    for (i, place) in net.places().iter().enumerate() {
        let mut label = format!("{}\\n({}", dot_escape(&place.name), place.kind.letter());
        if place.concave {
            label.push_str(", concave");
        }
        label.push(')');
        let mut style = String::new();
        if let Some(p) = plan {
            let _ = write!(label, "\\nα={}", short(p.alpha[i]));
            if p.start.index() == i {
                style.push_str(", shape=doublecircle");
            }
            if is_goal[i] {
                style.push_str(", style=filled, fillcolor=lightgrey");
            }
        }
        let _ = writeln!(
            out,
            "  n{i} [label=\"{label}\", pos=\"{:?},{:?}!\"{style}];",
            place.x_m, place.y_m
        );
    }
    for (i, t) in net.transitions().iter().enumerate() {
        let id = TransitionId(i as u32);
        let value = match plan {
            Some(p) => format!("f={}", short(p.f[i])),
            None => format!("C={}", short(net.weighted_cost(id))),
        };
        let mut attrs = format!(
            "label=\"{id} {}\\n{value}\", color=\"{}\", fontcolor=\"{}\"",
            t.strategy.label(),
            strategy_colour(t.strategy),
            strategy_colour(t.strategy)
        );
        if let Some(p) = plan {
            if on_route[i] {
                attrs.push_str(", penwidth=3");
            }
            if !p.accepted[i] {
                attrs.push_str(", style=dashed");
            }
        }
        let _ = writeln!(out, "  n{} -> n{} [{attrs}];", t.from.0, t.to.0);
    }
    out.push_str("}\n");
    Ok(out)
}

/// Escapes text for XML content and attribute values (control characters,
/// which place names cannot hold, become spaces).
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if c.is_control() || c == '\u{fffe}' || c == '\u{ffff}' => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// The PNML names of the transitions: `t{i}`, with `'` appended while that
/// names a place.
pub fn pnml_transition_names(net: &FuzzyPetriNet) -> Vec<String> {
    let places: HashSet<&str> = net.places().iter().map(|p| p.name.as_str()).collect();
    net.transition_ids()
        .map(|t| {
            let mut name = t.to_string();
            while places.contains(name.as_str()) {
                name.push('\'');
            }
            name
        })
        .collect()
}

/// The map as a PNML place/transition net named `net_name` (see the module
/// documentation), with one token at `marked` if given, and the values of
/// `plan` if given. Fails when `marked` is not a place of the map or `plan`
/// was made for another map. `O(|P| + |T|)`.
pub fn to_pnml(
    net: &FuzzyPetriNet,
    net_name: &str,
    marked: Option<PlaceId>,
    plan: Option<&Plan>,
) -> Result<String, TopoError> {
    check_plan(net, plan)?;
    if let Some(m) = marked.filter(|m| m.index() >= net.num_places()) {
        return Err(TopoError::NoSuchPlace {
            id: m.0,
            places: net.num_places(),
        });
    }
    let mut on_route = vec![false; net.num_transitions()];
    if let Some(p) = plan {
        for t in &p.route {
            on_route[t.index()] = true;
        }
    }
    const TOOL: &str = "<toolspecific tool=\"petrinav\" version=\"1\">";
    let mut out = String::with_capacity(512 + 400 * (net.num_places() + net.num_transitions()));
    out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    out.push_str("<pnml xmlns=\"http://www.pnml.org/version-2009/grammar/pnml\">\n");
    out.push_str("  <net id=\"fpn\" type=\"http://www.pnml.org/version-2009/grammar/ptnet\">\n");
    let _ = writeln!(out, "    <name><text>{}</text></name>", xml_escape(net_name));
    let _ = writeln!(out, "    {TOOL}");
    let _ = writeln!(
        out,
        "      <fpnNet format=\"{FORMAT}\" version=\"{FORMAT_VERSION}\" total_cost=\"{:?}\"/>",
        net.total_cost()
    );
    if let Some(p) = plan {
        let _ = writeln!(
            out,
            "      <fpnPlan mode=\"{}\" start=\"pl{}\" cost=\"{:?}\">",
            p.mode.name(),
            p.start.0,
            p.cost
        );
        for g in &p.goals {
            let _ = writeln!(out, "        <goal place=\"pl{}\"/>", g.0);
        }
        out.push_str("      </fpnPlan>\n");
    }
    out.push_str("    </toolspecific>\n");
    out.push_str("    <page id=\"page0\">\n");
    for (i, place) in net.places().iter().enumerate() {
        let _ = writeln!(out, "      <place id=\"pl{i}\">");
        let _ = writeln!(
            out,
            "        <name><text>{}</text></name>",
            xml_escape(&place.name)
        );
        let _ = writeln!(
            out,
            "        <graphics><position x=\"{:?}\" y=\"{:?}\"/></graphics>",
            place.x_m * PNML_PIXELS_PER_M,
            -place.y_m * PNML_PIXELS_PER_M
        );
        if marked == Some(PlaceId(i as u32)) {
            out.push_str("        <initialMarking><text>1</text></initialMarking>\n");
        }
        let _ = writeln!(out, "        {TOOL}");
        let _ = write!(
            out,
            "          <fpnPlace x_m=\"{:?}\" y_m=\"{:?}\" heading_rad=\"{:?}\" kind=\"{}\" concave=\"{}\" visits=\"{}\"",
            place.x_m,
            place.y_m,
            place.heading_rad,
            place.kind.letter(),
            place.concave,
            place.visits
        );
        if let Some(p) = plan {
            let _ = write!(out, " alpha=\"{:?}\" reached=\"{}\"", p.alpha[i], p.reached[i]);
        }
        out.push_str("/>\n        </toolspecific>\n      </place>\n");
    }
    let names = pnml_transition_names(net);
    for (i, (t, name)) in net.transitions().iter().zip(&names).enumerate() {
        let _ = writeln!(out, "      <transition id=\"tr{i}\">");
        let _ = writeln!(out, "        <name><text>{}</text></name>", xml_escape(name));
        let _ = writeln!(out, "        {TOOL}");
        let _ = write!(
            out,
            "          <fpnTransition strategy=\"{}\" exit_turn=\"{}\" duration_s=\"{:?}\" cost=\"{:?}\" weighted_cost=\"{:?}\" lambda=\"{:?}\" attempts=\"{}\" failures=\"{}\"",
            t.strategy.name(),
            t.exit_turn.name(),
            t.duration_s,
            t.cost,
            net.weighted_cost(TransitionId(i as u32)),
            t.lambda,
            t.attempts,
            t.failures
        );
        if let Some(p) = plan {
            let _ = write!(
                out,
                " f=\"{:?}\" accepted=\"{}\" on_route=\"{}\"",
                p.f[i], p.accepted[i], on_route[i]
            );
        }
        out.push_str("/>\n        </toolspecific>\n      </transition>\n");
    }
    for (i, t) in net.transitions().iter().enumerate() {
        let _ = writeln!(
            out,
            "      <arc id=\"a{}\" source=\"pl{}\" target=\"tr{i}\"/>",
            2 * i,
            t.from.0
        );
        let _ = writeln!(
            out,
            "      <arc id=\"a{}\" source=\"tr{i}\" target=\"pl{}\"/>",
            2 * i + 1,
            t.to.0
        );
    }
    out.push_str("    </page>\n  </net>\n</pnml>\n");
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fpn::{Place, PlaceKind, Transition, Turn};
    use crate::{PlanMode, plan};

    fn small() -> FuzzyPetriNet {
        let mut net = FuzzyPetriNet::new();
        let mut p = Place::new(0.0, 0.0, 0.0, PlaceKind::A);
        p.name = "a \"quoted\" <place> & t0".into();
        net.add_place(p).unwrap();
        net.add_place(Place::new(2.0, 1.0, 0.5, PlaceKind::C)).unwrap();
        net.add_transition(Transition::new(
            PlaceId(0),
            PlaceId(1),
            Strategy::WallFollowLeft,
            Turn::Right,
            3.0,
        ))
        .unwrap();
        net.add_transition(Transition::new(
            PlaceId(1),
            PlaceId(0),
            Strategy::DetourRight,
            Turn::Left,
            4.0,
        ))
        .unwrap();
        net
    }

    #[test]
    fn dot_shows_strategies_and_the_route() {
        let net = small();
        let dot = to_dot(&net, None).unwrap();
        assert!(
            dot.contains("n0 -> n1 [label=\"t0 wall following left\\nC=0.3750\", color=\"blue\""),
            "{dot}"
        );
        assert!(dot.contains("a \\\"quoted\\\" <place> & t0\\n(a)"), "{dot}");
        assert!(dot.contains("pos=\"2.0,1.0!\""), "{dot}");
        let mut net = net;
        net.set_lambda(TransitionId(0), 0.9).unwrap();
        let p = plan(&net, PlaceId(1), &[PlaceId(0)], PlanMode::Optimal).unwrap();
        let dot = to_dot(&net, Some(&p)).unwrap();
        assert!(dot.contains("n1 -> n0 [label=\"t1 detour right\\nf=0.6250\", color=\"red\", fontcolor=\"red\", penwidth=3]"), "{dot}");
        // f(t0) = C(t0) + α(p2) = 1 > λ(t0) = 0.9: rejected.
        assert!(dot.contains("style=dashed"), "{dot}");
        assert!(dot.contains("shape=doublecircle"), "{dot}");
        let other = plan(&small_three(), PlaceId(0), &[PlaceId(2)], PlanMode::Optimal).unwrap();
        assert!(matches!(
            to_dot(&net, Some(&other)),
            Err(TopoError::PlanMismatch { .. })
        ));
    }

    fn small_three() -> FuzzyPetriNet {
        let mut net = small();
        net.add_place(Place::new(4.0, 0.0, 0.0, PlaceKind::B)).unwrap();
        net.add_transition(Transition::new(
            PlaceId(0),
            PlaceId(2),
            Strategy::FreeMovement,
            Turn::Right,
            1.0,
        ))
        .unwrap();
        net
    }

    #[test]
    fn transition_names_avoid_place_names() {
        let net = small();
        let mut renamed = net.clone();
        let mut p = Place::new(9.0, 9.0, 0.0, PlaceKind::A);
        p.name = "t1".into();
        renamed.add_place(p).unwrap();
        assert_eq!(pnml_transition_names(&net), ["t0", "t1"]);
        assert_eq!(pnml_transition_names(&renamed), ["t0", "t1'"]);
        assert!(matches!(
            to_pnml(&net, "x", Some(PlaceId(2)), None),
            Err(TopoError::NoSuchPlace { id: 2, .. })
        ));
        let text = to_pnml(&net, "x", Some(PlaceId(1)), None).unwrap();
        assert!(
            text.contains("<text>a &quot;quoted&quot; &lt;place&gt; &amp; t0</text>"),
            "{text}"
        );
        assert!(text.contains("kind=\"c\""), "{text}");
    }
}
