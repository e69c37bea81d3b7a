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
//! DOT is an export format: it cannot be read back.

use std::fmt::Write as _;

use crate::error::Result;
use crate::expr::Expr;
use crate::net::{ArcKind, Net, Servers, TransitionKind};

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
