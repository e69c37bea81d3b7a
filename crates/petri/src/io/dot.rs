//! Graphviz DOT export of a net, to draw it (`dot -Tsvg net.dot -o net.svg`).
//!
//! - Places are circles labelled with their name and, when not 0, their
//!   initial marking (a number, or the marking expression).
//! - Timed transitions are white boxes labelled with their name and rate
//!   (and `∞-server` or `k-server` when not single-server).
//! - Immediate transitions are thin black bars, with their name, weight and
//!   priority as an outside label.
//! - Arcs are drawn from place to transition (input, inhibitor) or from
//!   transition to place (output); inhibitor arcs end in a circle
//!   (`arrowhead=odot`); multiplicities other than 1 label the arc.
//! - Node ids are the names, quoted (names are unique across places and
//!   transitions); the output is valid DOT whatever the names contain.
//!
//! [`write_reachability_dot`] and [`write_tangible_dot`] draw the
//! reachability graph (tangible markings as ellipses, vanishing ones as
//! dashed boxes, the initial marking bold, dead markings red; edges labelled
//! with the transition and its probability or server factor) and the
//! tangible reachability graph (the CTMC: edges labelled with the transition
//! and the rate, or the symbolic coefficient when no rates are given).
//! Markings are labelled with their marked places (`P1 P5 Q(2)`). Graphs
//! larger than the given limit are refused: nobody reads a drawing of a
//! million states.
//!
//! DOT is an export format: it cannot be read back.

use std::fmt::Write as _;

use crate::ctmc::CompiledGspn;
use crate::error::{Error, Result};
use crate::expr::{Expr, fmt_number};
use crate::gspn::Gspn;
use crate::net::{ArcKind, Net, Servers, TransitionKind};
use crate::reachability::{MarkingId, ReachabilityGraph};

/// A DOT double-quoted string.
fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => {}
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn too_large(what: &str, n: usize, limit: usize) -> Result<()> {
    if n > limit {
        return Err(Error::Invalid(format!(
            "the {what} has {n} markings, more than the {limit} a drawing may have (raise the limit if you really want it)"
        )));
    }
    Ok(())
}

fn graph_header(out: &mut String, name: &str) {
    let _ = writeln!(out, "digraph {} {{", quote(name));
    out.push_str("  node [fontname=\"Helvetica\", fontsize=10];\n");
    out.push_str("  edge [fontname=\"Helvetica\", fontsize=9];\n");
}

/// Writes the reachability graph (tangible and vanishing markings) as DOT;
/// fails if it has more than `max_markings` markings.
pub fn write_reachability_dot(gspn: &Gspn, rg: &ReachabilityGraph, max_markings: usize) -> Result<String> {
    too_large("reachability graph", rg.num_markings(), max_markings)?;
    let mut out = String::new();
    graph_header(&mut out, &format!("{} RG", gspn.name()));
    let names = gspn.transition_names();
    for i in 0..rg.num_markings() {
        let id = MarkingId(i as u32);
        let label = format!("M{i}\n{}", gspn.format_marking(&rg.marking(id)));
        let mut style = if rg.is_vanishing(id) {
            "shape=box, style=dashed".to_string()
        } else {
            "shape=ellipse".to_string()
        };
        if i == 0 {
            style.push_str(", penwidth=2");
        }
        if rg.edges(id).next().is_none() {
            style.push_str(", color=red");
        }
        let _ = writeln!(out, "  m{i} [{style}, label={}];", quote(&label));
    }
    for i in 0..rg.num_markings() {
        for e in rg.edges(MarkingId(i as u32)) {
            let t = &names[e.transition.index()];
            let label = if e.coeff == 1.0 {
                t.clone()
            } else {
                format!("{t} ×{}", fmt_number(e.coeff))
            };
            let _ = writeln!(out, "  m{i} -> m{} [label={}];", e.target.0, quote(&label));
        }
    }
    out.push_str("}\n");
    Ok(out)
}

/// Writes the tangible reachability graph (the CTMC after vanishing
/// markings are eliminated) as DOT, edges labelled with their rate when
/// `rates` (by transition) are given; fails beyond `max_markings` states.
pub fn write_tangible_dot(
    compiled: &CompiledGspn,
    rates: Option<&[f64]>,
    max_markings: usize,
) -> Result<String> {
    let n = compiled.num_tangible();
    too_large("tangible reachability graph", n, max_markings)?;
    let gspn = compiled.gspn();
    let mut out = String::new();
    graph_header(&mut out, &format!("{} TRG", gspn.name()));
    for s in 0..n {
        let label = format!("T{s}\n{}", gspn.format_marking(&compiled.tangible_marking(s)));
        let _ = writeln!(out, "  s{s} [shape=ellipse, label={}];", quote(&label));
    }
    for (s, p) in compiled.initial_distribution() {
        let _ = writeln!(
            out,
            "  s{s} [penwidth=2, xlabel={}];",
            quote(&format!("M0 p={}", fmt_number(*p)))
        );
    }
    let names = gspn.transition_names();
    for s in 0..n {
        for (d, t, c) in compiled.entries_from(s) {
            let name = &names[t.index()];
            let label = match rates {
                Some(r) => format!("{name} {:.4e}", r[t.index()] * c),
                None if c == 1.0 => name.clone(),
                None => format!("{name} ×{}", fmt_number(c)),
            };
            let _ = writeln!(out, "  s{s} -> s{d} [label={}];", quote(&label));
        }
    }
    out.push_str("}\n");
    Ok(out)
}

/// Writes the net as a DOT digraph.
pub fn write_dot(net: &Net) -> Result<String> {
    net.validate()?;
    let mut out = String::new();
    let _ = writeln!(out, "digraph {} {{", quote(&net.name));
    out.push_str("  rankdir=LR;\n");
    out.push_str("  node [fontname=\"Helvetica\", fontsize=11];\n");
    out.push_str("  edge [fontname=\"Helvetica\", fontsize=10];\n");
    for p in &net.places {
        let label = if p.initial == Expr::Num(0.0) {
            p.name.clone()
        } else {
            format!("{}\n{}", p.name, p.initial)
        };
        let label = match p.capacity {
            Some(c) => format!("{label}\n≤ {c}"),
            None => label,
        };
        let _ = writeln!(
            out,
            "  {} [shape=circle, width=0.6, label={}];",
            quote(&p.name),
            quote(&label)
        );
    }
    for t in &net.transitions {
        match &t.kind {
            TransitionKind::Timed { rate, servers } => {
                let mut label = t.name.clone();
                if let Some(r) = rate {
                    let _ = write!(label, "\nλ = {r}");
                }
                match servers {
                    Servers::Single => {}
                    Servers::Infinite => label.push_str("\n∞-server"),
                    Servers::K(k) => {
                        let _ = write!(label, "\n{k}-server");
                    }
                }
                let _ = writeln!(
                    out,
                    "  {} [shape=box, style=filled, fillcolor=white, label={}];",
                    quote(&t.name),
                    quote(&label)
                );
            }
            TransitionKind::Immediate { weight, priority } => {
                let label = format!("{}\nw = {weight}, π = {priority}", t.name);
                let _ = writeln!(
                    out,
                    "  {} [shape=box, style=filled, fillcolor=black, width=0.08, height=0.5, fixedsize=true, label=\"\", xlabel={}];",
                    quote(&t.name),
                    quote(&label)
                );
            }
        }
    }
    for a in &net.arcs {
        let (Some(p), Some(t)) = (
            net.places.get(a.place.index()),
            net.transitions.get(a.transition.index()),
        ) else {
            continue;
        };
        let (from, to) = match a.kind {
            ArcKind::Input | ArcKind::Inhibitor => (&p.name, &t.name),
            ArcKind::Output => (&t.name, &p.name),
        };
        let mut attrs = Vec::new();
        if a.kind == ArcKind::Inhibitor {
            attrs.push("arrowhead=odot".to_string());
        }
        if a.multiplicity != Expr::Num(1.0) {
            attrs.push(format!("label={}", quote(&a.multiplicity.to_string())));
        }
        let attrs = if attrs.is_empty() {
            String::new()
        } else {
            format!(" [{}]", attrs.join(", "))
        };
        let _ = writeln!(out, "  {} -> {}{attrs};", quote(from), quote(to));
    }
    out.push_str("}\n");
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::Servers;

    #[test]
    fn draws_every_element() {
        let mut net = Net::new("a \"net\"");
        let p = net.add_place("P\\0", Expr::param("N"));
        let q = net.add_place("q", 0u32);
        let t = net.add_timed("t", Expr::param("lambda"));
        net.set_servers(t, Servers::K(3));
        let u = net.add_immediate("u", 0.5, 2);
        net.add_arc(ArcKind::Input, p, t, 2u32);
        net.output(t, q);
        net.inhibitor(q, u);
        let dot = write_dot(&net).unwrap();
        assert!(dot.starts_with("digraph \"a \\\"net\\\"\" {"), "{dot}");
        assert!(
            dot.contains("\"P\\\\0\" [shape=circle, width=0.6, label=\"P\\\\0\\nN\"]"),
            "{dot}"
        );
        assert!(dot.contains("label=\"t\\nλ = lambda\\n3-server\""), "{dot}");
        assert!(dot.contains("fillcolor=black"), "{dot}");
        assert!(dot.contains("xlabel=\"u\\nw = 0.5, π = 2\""), "{dot}");
        assert!(dot.contains("\"P\\\\0\" -> \"t\" [label=\"2\"];"), "{dot}");
        assert!(dot.contains("\"t\" -> \"q\";"), "{dot}");
        assert!(dot.contains("\"q\" -> \"u\" [arrowhead=odot];"), "{dot}");
        assert!(dot.ends_with("}\n"));
    }
}

#[cfg(test)]
mod graph_tests {
    use super::*;
    use crate::net::Params;
    use crate::reachability::ExploreParams;

    #[test]
    fn reachability_and_tangible_graphs_draw() {
        let g = crate::families::robots_corridors(2, 2)
            .instantiate(&Params::new())
            .unwrap();
        let rg = ReachabilityGraph::explore(&g, &ExploreParams::default()).unwrap();
        let dot = write_reachability_dot(&g, &rg, 1000).unwrap();
        assert!(dot.starts_with("digraph") && dot.contains("style=dashed") && dot.contains("-> m"));
        assert_eq!(dot.matches(" -> ").count(), rg.num_edges());
        let c = CompiledGspn::from_graph(g.clone(), rg.clone()).unwrap();
        let rates = g.rates(&Params::new(), None).unwrap();
        let trg = write_tangible_dot(&c, Some(&rates), 1000).unwrap();
        assert!(trg.contains("-> s") && !trg.contains("dashed"));
        assert!(write_reachability_dot(&g, &rg, 3).is_err());
    }
}
