//! The analysis generates a tree's state space with the conditions' places
//! as the context its memory of forced hops may leave out
//! (`petri::ExploreParams::forced_context`, `Translation::world`). That
//! must change nothing but the work: on every shipped Nav2 tree with both
//! parameter sets, the graph — every marking in order, every edge — is the
//! one generated without it, and fewer forced markings are evaluated where
//! the tree has persistent conditions.

use bt::{ReadOptions, TreeParams};
use petri::{ExploreParams, MarkingId, Params, ReachabilityGraph};

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/bt/nav2");

fn graph(tr: &bt::translate::Translation, context: bool) -> ReachabilityGraph {
    let gspn = tr.net.instantiate(&Params::new()).expect("a net");
    let params = ExploreParams {
        skip_forced: true,
        forced_context: if context { tr.world() } else { Vec::new() },
        ..ExploreParams::default()
    };
    ReachabilityGraph::explore(&gspn, &params).expect("a graph")
}

#[test]
fn the_world_as_context_leaves_every_nav2_graph_unchanged() {
    let mut trees: Vec<_> = std::fs::read_dir(DIR)
        .expect("the shipped trees")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml") && !p.ends_with("nav2_tree_nodes.xml"))
        .collect();
    trees.sort();
    assert!(trees.len() >= 10);
    let mut saved = 0;
    for path in &trees {
        let tree = bt::read_file(path, &ReadOptions::default()).expect("a shipped tree");
        for set in ["nominal", "degraded"] {
            let params = TreeParams::read_file(format!("{DIR}/{set}.toml")).expect("a parameter set");
            let tr = bt::translate::translate(&tree, &params).expect("a translation");
            let (a, b) = (graph(&tr, false), graph(&tr, true));
            let tag = format!("{} [{set}]", path.display());
            assert_eq!(a.num_markings(), b.num_markings(), "{tag}");
            for i in 0..a.num_markings() as u32 {
                let m = MarkingId(i);
                assert_eq!(a.marking(m), b.marking(m), "{tag}: marking {i}");
                assert_eq!(a.is_vanishing(m), b.is_vanishing(m), "{tag}: marking {i}");
                assert!(a.edges(m).eq(b.edges(m)), "{tag}: edges of {i}");
            }
            assert_eq!(a.place_bounds(), b.place_bounds(), "{tag}");
            let (ea, eb) = (a.stats().forced_evaluated, b.stats().forced_evaluated);
            assert!(eb <= ea, "{tag}: {eb} evaluations with the context, {ea} without");
            if eb < ea {
                saved += 1;
            }
        }
    }
    // The trees with persistent conditions in the shipped sets.
    assert!(saved >= 6, "work saved on {saved} trees and sets");
}
