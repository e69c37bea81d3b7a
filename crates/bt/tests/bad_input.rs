//! Bad input (issue 49): malformed and truncated XML, unknown node kinds,
//! subtree cycles, out-of-range parameters, a 50 MB file and a deeply
//! nested one — each a clear error with the line and the node's path,
//! never a panic. Logs: FileLogger2 read back and fitted.

// Reading the trees here returns `bt::Error` as the library does.
#![allow(clippy::result_large_err)]

use bt::{ReadOptions, TreeParams};

fn read(text: &str) -> Result<bt::Tree, bt::Error> {
    bt::read_str(text, "t.xml", None, &ReadOptions::default())
}

#[test]
fn a_50_mb_file_is_refused_at_the_node_that_crosses_the_limit() {
    let mut text = String::from("<root BTCPP_format=\"4\"><BehaviorTree ID=\"Big\"><Sequence>\n");
    while text.len() < 50 << 20 {
        text.push_str("<AlwaysSuccess/>\n");
    }
    text.push_str("</Sequence></BehaviorTree></root>\n");
    let e = read(&text).unwrap_err().to_string();
    assert!(e.contains("more than 100000 nodes"), "{e}");
    assert!(
        e.starts_with("t.xml:100001: Big/Sequence#0/AlwaysSuccess#99999"),
        "{e}"
    );
}

#[test]
fn deep_nesting_is_refused_with_the_path() {
    let depth = 5_000;
    let text = format!(
        "<root BTCPP_format=\"4\"><BehaviorTree ID=\"Deep\">{}<AlwaysSuccess/>{}</BehaviorTree></root>",
        "<Inverter>".repeat(depth),
        "</Inverter>".repeat(depth)
    );
    let e = read(&text).unwrap_err().to_string();
    assert!(e.contains("nested deeper than 256 levels"), "{e}");
}

#[test]
fn wrong_child_counts_name_the_node() {
    let e = read(
        r#"<root BTCPP_format="4"><BehaviorTree ID="A"><Inverter><A/><B/></Inverter></BehaviorTree></root>"#,
    )
    .unwrap_err()
    .to_string();
    assert_eq!(
        e,
        "t.xml:1: A/Inverter#0: `Inverter` is a decorator: one child, found 2 children"
    );
}

#[test]
fn non_numeric_attribute_names_it() {
    let e = read(r#"<root BTCPP_format="4"><BehaviorTree ID="A"><RecoveryNode number_of_retries="many"><A/><B/></RecoveryNode></BehaviorTree></root>"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("`number_of_retries` = `many`: a number"), "{e}");
}

#[test]
fn missing_subtree_is_an_error_unless_checking() {
    let text = r#"<root BTCPP_format="4"><BehaviorTree ID="A"><SubTree ID="Nowhere"/></BehaviorTree></root>"#;
    let e = read(text).unwrap_err().to_string();
    assert!(e.contains("the subtree `Nowhere` is not defined"), "{e}");
    let keep = ReadOptions {
        keep_missing: true,
        ..ReadOptions::default()
    };
    let t = bt::read_str(text, "t.xml", None, &keep).unwrap();
    assert_eq!(t.missing.len(), 1);
}

#[test]
fn unsupported_node_says_why() {
    let e =
        read(r#"<root BTCPP_format="4"><BehaviorTree ID="A"><RunOnce><A/></RunOnce></BehaviorTree></root>"#)
            .unwrap_err()
            .to_string();
    assert!(e.contains("`RunOnce` is not supported"), "{e}");
}

#[test]
fn zero_time_endless_loop_is_an_analysis_error_not_a_hang() {
    let tree = read(
        r#"<root BTCPP_format="4"><BehaviorTree ID="A"><RetryUntilSuccessful num_attempts="-1"><AlwaysFailure/></RetryUntilSuccessful></BehaviorTree></root>"#,
    )
    .unwrap();
    let e = bt::analyze(&tree, &TreeParams::default(), &bt::AnalyzeOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("loops in zero time") || e.contains("never ends"),
        "{e}"
    );
}

#[test]
fn btlog_read_and_fitted() {
    let bytes = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fuzz/regressions/bt_log/small.btlog"
    ))
    .unwrap();
    let t = bt::logs::read_btlog(&bytes, "small.btlog", 0).unwrap();
    assert_eq!(t.len(), 7);
    let tree = read(
        r#"<root BTCPP_format="4"><BehaviorTree ID="T"><ReactiveSequence><IsOk/><Fallback><A/><RetryUntilSuccessful num_attempts="3"><B/></RetryUntilSuccessful></Fallback></ReactiveSequence></BehaviorTree></root>"#,
    )
    .unwrap();
    let fit = bt::logs::fit(&tree, &t);
    let a = &fit.actions["A"];
    assert_eq!((a.successes, a.failures, a.halted), (0, 1, 0));
    assert!((a.time_failure - 1.5).abs() < 1e-9);
    assert_eq!(fit.actions["B"].successes, 1);
    let c = &fit.conditions["IsOk"];
    assert_eq!((c.holds, c.fails, c.changes), (1, 1, 1));
    TreeParams::parse(&fit.to_toml(), "fit.toml").unwrap();
}
