//! The sensitivities to probabilities against a re-translation done here:
//! `bt analyze` re-solves the same chain where a probability only moves
//! rates (an action whose last stage draws the outcome, a persistent
//! condition), and must give what re-translating the moved sidecar gives.
//! The tree shares keys the ways the sidecar's lookup allows (a type key
//! that also reaches a named node without an entry of its own, a named one
//! with its own entry, two mean times, persistent conditions by type and by
//! name).

use bt::{AnalyzeOptions, ReadOptions, TreeParams};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data");

#[test]
fn probabilities_moved_by_rates_agree_with_a_re_translation() {
    let tree = bt::read_file(format!("{DATA}/shared_keys.xml"), &ReadOptions::default()).unwrap();
    let params = TreeParams::read_file(format!("{DATA}/shared_keys.toml")).unwrap();
    let plain = AnalyzeOptions {
        sensitivities: false,
        ..AnalyzeOptions::default()
    };
    let base = bt::analyze(&tree, &params, &plain).unwrap();
    let report = bt::analyze(&tree, &params, &AnalyzeOptions::default()).unwrap();
    let mut checked = 0;
    for s in report
        .sensitivities
        .iter()
        .filter(|s| s.parameter.starts_with('p'))
    {
        let h = if s.value + 1e-4 <= 1.0 { 1e-4 } else { -1e-4 };
        let mut moved = params.clone();
        let n = tree
            .preorder()
            .into_iter()
            .find(|&n| {
                let node = tree.node(n);
                matches!(node.kind, bt::Kind::Action | bt::Kind::Condition)
                    && params.condition_key(&tree, n) == s.key
            })
            .unwrap();
        if s.parameter == "p_success" {
            let mut a = params.action(&tree, n);
            a.p_success += h;
            moved.actions.insert(s.key.clone(), a);
        } else {
            let mut c = params.condition(&tree, n);
            c.p_true += h;
            moved.conditions.insert(s.key.clone(), c);
        }
        let r = bt::analyze(&tree, &moved, &plain).unwrap();
        let (dp, dt) = (
            (r.p_success - base.p_success) / h,
            (r.mean_time - base.mean_time) / h,
        );
        assert!(
            (dp - s.d_p_success).abs() < 1e-6,
            "{} {}: {dp} against {}",
            s.key,
            s.parameter,
            s.d_p_success
        );
        assert!(
            (dt - s.d_mean_time).abs() < 1e-5 * dt.abs().max(1.0),
            "{} {}: {dt} against {}",
            s.key,
            s.parameter,
            s.d_mean_time
        );
        checked += 1;
    }
    assert_eq!(checked, 5);
}
