//! `petrinav bt` from the command line: a shipped Nav2 tree checked and
//! analysed, and a sidecar whose fields do not fit the leaf refused by
//! every command that reads parameters, naming the node and both files.

use std::path::PathBuf;
use std::process::{Command, Output};

fn petrinav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn nav2(file: &str) -> String {
    format!("{}/../../models/bt/nav2/{file}", env!("CARGO_MANIFEST_DIR"))
}

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("bt_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn shipped_tree_checks_clean_and_analyses() {
    let tree = nav2("navigate_w_replanning_time.xml");
    let o = petrinav(&["bt", "check", &tree]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("no finding"));
    let params = nav2("nominal.toml");
    let o = petrinav(&["bt", "analyze", &tree, "--params", &params, "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let p = r["p_success"].as_f64().unwrap();
    assert!(p > 0.0 && p <= 1.0, "{p}");
}

/// Condition fields on an action (`p_true` for `FollowPath`) were silently
/// replaced by the defaults.
#[test]
fn condition_fields_on_an_action_are_refused_naming_node_and_files() {
    let dir = fresh("kinds");
    let sidecar = dir.join("p.toml");
    std::fs::write(&sidecar, "[leaf.FollowPath]\np_true = 0.5\n").unwrap();
    let sidecar = sidecar.to_str().unwrap();
    let tree = nav2("navigate_w_replanning_time.xml");
    for cmd in ["check", "analyze", "simulate"] {
        let o = petrinav(&["bt", cmd, &tree, "--params", sidecar]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{cmd}: {err}");
        assert!(err.contains("navigate_w_replanning_time.xml:"), "{cmd}: {err}");
        assert!(err.contains("/FollowPath"), "{cmd}: {err}");
        assert!(
            err.contains(&format!("[leaf.FollowPath] of {sidecar}")),
            "{cmd}: {err}"
        );
        assert!(err.contains("is an action"), "{cmd}: {err}");
    }
}
