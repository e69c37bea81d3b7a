//! The tree drawn as SVG: one box per node, laid out by depth (rows) and
//! leaf order (columns); the fill is the probability of finding the node
//! active at a random instant of a run (white → blue), the bar under each
//! box its share of the tree's failures (red, full width = all of them).

use std::fmt::Write as _;

use crate::analyze::Report;
use crate::tree::{NodeId, Tree};

const W: f64 = 150.0;
const H: f64 = 34.0;
const GAP_X: f64 = 12.0;
const GAP_Y: f64 = 36.0;

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Column (in box widths) of each node's centre.
fn layout(tree: &Tree) -> (Vec<f64>, Vec<usize>) {
    let mut x = vec![0.0; tree.len()];
    let mut depth = vec![0usize; tree.len()];
    let mut next_leaf = 0.0;
    for n in tree.preorder() {
        if let Some(p) = tree.node(n).parent {
            depth[n.index()] = depth[p.index()] + 1;
        }
    }
    // Post-order: leaves take the next column, parents centre over children.
    let order: Vec<NodeId> = tree.preorder().into_iter().rev().collect();
    let mut leaf_x = vec![None; tree.len()];
    for n in tree.preorder() {
        if tree.node(n).children.is_empty() {
            leaf_x[n.index()] = Some(next_leaf);
            next_leaf += 1.0;
        }
    }
    for n in order {
        let node = tree.node(n);
        x[n.index()] = match leaf_x[n.index()] {
            Some(v) => v,
            None => {
                let xs: Vec<f64> = node.children.iter().map(|c| x[c.index()]).collect();
                (xs[0] + xs[xs.len() - 1]) / 2.0
            }
        };
    }
    (x, depth)
}

/// The tree as an SVG document, coloured by `report` (plain without one).
pub fn render(tree: &Tree, report: Option<&Report>) -> String {
    let (x, depth) = layout(tree);
    let cols = x.iter().copied().fold(0.0, f64::max) + 1.0;
    let rows = depth.iter().copied().max().unwrap_or(0) + 1;
    let width = cols * (W + GAP_X) + GAP_X;
    let height = rows as f64 * (H + GAP_Y) + GAP_Y + 30.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="11">"#
    );
    let title = match report {
        Some(r) => format!(
            "{} — P(success) {:.4}, mean time {:.2} s; fill: share of the run active; red bar: share of failures",
            tree.main, r.p_success, r.mean_time
        ),
        None => tree.main.clone(),
    };
    let _ = writeln!(
        s,
        r#"<text x="{GAP_X}" y="18" font-size="13">{}</text>"#,
        escape(&title)
    );
    let pos = |n: NodeId| -> (f64, f64) {
        (
            GAP_X + x[n.index()] * (W + GAP_X),
            30.0 + GAP_Y / 2.0 + depth[n.index()] as f64 * (H + GAP_Y),
        )
    };
    for n in tree.preorder() {
        let (px, py) = pos(n);
        for &c in &tree.node(n).children {
            let (cx, cy) = pos(c);
            let _ = writeln!(
                s,
                r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#888"/>"##,
                px + W / 2.0,
                py + H,
                cx + W / 2.0,
                cy
            );
        }
    }
    for n in tree.preorder() {
        let node = tree.node(n);
        let (px, py) = pos(n);
        let (activity, share) = report
            .and_then(|r| r.nodes.iter().find(|s| s.node == n))
            .map_or((0.0, 0.0), |st| {
                (st.activity.clamp(0.0, 1.0), st.failure_share.clamp(0.0, 1.0))
            });
        // White (0) to a strong blue (1).
        let shade = |c0: f64, c1: f64| (c0 + (c1 - c0) * activity).round() as u8;
        let fill = format!(
            "#{:02x}{:02x}{:02x}",
            shade(255.0, 40.0),
            shade(255.0, 110.0),
            shade(255.0, 220.0)
        );
        let text = if activity > 0.55 { "#fff" } else { "#000" };
        let _ = writeln!(
            s,
            r##"<g><title>{}&#10;{}:{}&#10;active {:.3}, failures {:.3}</title><rect x="{px:.1}" y="{py:.1}" width="{W}" height="{H}" rx="4" fill="{fill}" stroke="#333"/>"##,
            escape(&node.path),
            escape(&tree.files[node.file]),
            node.line,
            activity,
            share
        );
        let mut label = node.label();
        if label.chars().count() > 24 {
            label = label.chars().take(23).collect::<String>() + "…";
        }
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" fill="{text}">{}</text>"#,
            px + W / 2.0,
            py + H / 2.0 + 4.0,
            escape(&label)
        );
        if share > 0.0 {
            let _ = writeln!(
                s,
                r##"<rect x="{px:.1}" y="{:.1}" width="{:.1}" height="4" fill="#d62728"/>"##,
                py + H + 2.0,
                W * share
            );
        }
        let _ = writeln!(s, "</g>");
    }
    s.push_str("</svg>\n");
    s
}
