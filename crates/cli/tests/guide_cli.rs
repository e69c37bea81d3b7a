//! The tour-guide robot's mission log from the command line: calibrating,
//! learning, a crash mid-write, the supervisor's learnt decision checked
//! against `gspn select`, and bad logs as clear errors.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::{Command, Output};

use guide::supervisor::{Behaviour, Rates, Supervisor};

fn petrinav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("guide_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const MUSEUM: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../lab/src/suites/tourguide/museum.toml"
);

/// A hand-made log line for the shipped net.
fn line(entry: &str) -> String {
    let net = Supervisor::new().unwrap().net_id().to_string();
    format!("{{\"net\":\"{net}\",{entry}}}\n")
}

fn calibration(behaviour: &str, t: f64, len: f64) -> String {
    line(&format!(
        "\"kind\":\"calibration\",\"behaviour\":\"{behaviour}\",\"success\":true,\"duration_s\":{t},\"path_m\":{len},\"trajectory\":[[8.1,6.4],[8.5,27.5]]"
    ))
}

fn mission(k: u32, success: bool, warn_s: f64) -> String {
    let outcome = if success { "goal" } else { "time_limit" };
    line(&format!(
        "\"kind\":\"mission\",\"mission\":{k},\"success\":{success},\"outcome\":\"{outcome}\",\"duration_s\":100.0,\"localizer\":[{{\"state\":\"success\",\"duration_s\":{},\"ended\":true}},{{\"state\":\"warning\",\"duration_s\":{warn_s},\"ended\":false}}],\"planner\":[{{\"state\":\"normal\",\"duration_s\":100.0,\"ended\":false}}],\"time_automove_s\":100.0,\"time_contour_s\":0.0,\"decisions\":[]",
        100.0 - warn_s
    ))
}

#[test]
fn learnt_rates_decide_as_gspn_select_does() {
    let dir = fresh("select");
    let log = dir.join("missions.jsonl");
    let mut text = calibration("automove", 60.0, 24.0) + &calibration("contour", 130.0, 40.0);
    for k in 1..=6 {
        text += &mission(k, k != 3, 10.0 * f64::from(k));
    }
    std::fs::write(&log, text).unwrap();
    let out = petrinav(&["guide", "learn", log.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let learned: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let lambda: Vec<f64> = learned["rates"]["lambda"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(lambda.len(), 11);
    assert!((lambda[6] - 1.0 / 60.0).abs() < 1e-12, "λ7 from the calibration");
    // The same rates through `gspn select`.
    let sets: Vec<String> = lambda
        .iter()
        .enumerate()
        .skip(2)
        .take(8)
        .map(|(i, v)| format!("lambda{}={v:e}", i + 1))
        .collect();
    let mut args = vec!["gspn", "select", "--json"];
    for s in &sets {
        args.push("--set");
        args.push(s);
    }
    let out = petrinav(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let select: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // And through the supervisor the guide robot runs.
    let mut rates = Rates::initial();
    for (i, &v) in lambda.iter().enumerate() {
        rates.set(i + 1, v);
    }
    let d = Supervisor::new().unwrap().decide(&rates).unwrap();
    let choice = match d.choice {
        Behaviour::AutoMove => "automove",
        Behaviour::Contour => "contour",
    };
    assert_eq!(select["choice"], choice, "{select}");
    let f_auto = select["f_auto"].as_f64().unwrap();
    assert!(
        (f_auto - d.f_auto).abs() <= 1e-12 * d.f_auto,
        "{f_auto} vs {}",
        d.f_auto
    );
}

#[test]
fn calibrate_run_crash_and_go_on_learning() {
    let dir = fresh("campaign");
    let log = dir.join("missions.jsonl");
    let l = log.to_str().unwrap();
    let go = |extra: &[&str]| {
        let mut args = vec![
            "nav",
            "go",
            MUSEUM,
            "--from",
            "8.1,6.4,1.5708",
            "--to",
            "8.5,27.5,0",
            "--log",
            l,
            "--json",
        ];
        args.extend_from_slice(extra);
        petrinav(&args)
    };
    // Calibration: each behaviour alone (once here; the source did five).
    for b in ["automove", "contour"] {
        let out = go(&["--behaviour", b, "--calibration"]);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    // A supervised mission learns from the calibration.
    let out = go(&["--behaviour", "supervisor", "--seed", "2"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&log).unwrap();
    assert_eq!(text.lines().count(), 3);
    assert!(
        text.lines().last().unwrap().contains("\"decisions\":[{"),
        "a decision logged: {text}"
    );
    // The robot dies while writing the next mission.
    let mut f = std::fs::OpenOptions::new().append(true).open(&log).unwrap();
    f.write_all(b"{\"net\":\"supervisor-").unwrap();
    drop(f);
    let shown = petrinav(&["guide", "log", "show", l]);
    assert!(shown.status.success());
    assert!(
        stderr(&shown).contains("cut mid-write"),
        "reported: {}",
        stderr(&shown)
    );
    assert!(String::from_utf8_lossy(&shown.stdout).contains("mission 1"));
    // Restarted, the next mission goes on from the log: nothing lost.
    let out = go(&["--behaviour", "supervisor", "--seed", "3"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("dropped"), "{}", stderr(&out));
    let after = std::fs::read_to_string(&log).unwrap();
    assert!(after.starts_with(&text), "the entries before the crash are kept");
    assert_eq!(after.lines().count(), 4);
    assert!(after.lines().last().unwrap().contains("\"mission\":2"));
    let out = petrinav(&["guide", "learn", l, "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let learned: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(learned["missions"], 2);
}

#[test]
fn bad_logs_are_clear_errors() {
    let dir = fresh("bad");
    let check = |text: &str, args: &[&str], expect: &[&str]| {
        let path = dir.join("log.jsonl");
        std::fs::write(&path, text).unwrap();
        let mut full: Vec<&str> = args.to_vec();
        full.push(path.to_str().unwrap());
        let out = petrinav(&full);
        assert!(!out.status.success(), "{args:?} on {text:?} should fail");
        let err = stderr(&out);
        for e in expect {
            assert!(err.contains(e), "`{e}` not in: {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
    };
    let good = calibration("automove", 60.0, 24.0);
    // A foreign line, a malformed line: named by their line.
    check(
        &(good.clone() + "{\"kind\":\"lunch\"}\n"),
        &["guide", "log", "show"],
        &["log.jsonl:2"],
    );
    check(
        &(good.clone() + "no json\n"),
        &["guide", "learn"],
        &["log.jsonl:2"],
    );
    // Another net's log.
    let other = good.replace("\"net\":\"supervisor", "\"net\":\"another");
    check(&other, &["guide", "learn"], &["log.jsonl:1", "another"]);
    // No calibration of contour tracking: learning says so.
    check(&good, &["guide", "learn"], &["calibration", "Contour"]);
    // A negative duration in a mission.
    let bad = good.clone() + &calibration("contour", 130.0, 40.0) + &mission(1, true, -5.0);
    check(
        &bad,
        &["guide", "learn"],
        &["log.jsonl:3", "localizer[1].duration_s", "-5 s"],
    );
    // The supervisor without a log.
    let out = petrinav(&[
        "nav",
        "go",
        MUSEUM,
        "--from",
        "8.1,6.4,0",
        "--to",
        "8.5,27.5,0",
        "--behaviour",
        "supervisor",
    ]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--log"), "{}", stderr(&out));
    // A missing log.
    let out = petrinav(&["guide", "learn", dir.join("none.jsonl").to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("no such mission log"));
}

#[test]
fn guide_check_accepts_the_shipped_nets_and_refuses_a_broken_one_naming_the_property() {
    let o = petrinav(&["guide", "check"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(out.matches("verdict: accepted").count(), 2, "{out}");
    for variant in [
        "AutoMove hypothesis",
        "contour hypothesis",
        "AutoMove, lost",
        "contour, localized",
    ] {
        assert!(out.contains(variant), "{variant}: {out}");
    }
    // The crediting net without its way back after a failure: failed
    // missions are dead ends.
    let dir = fresh("check");
    let net = dir.join("broken.toml");
    let text = guide::supervisor::credit::CREDIT_MODEL;
    let start = text.find("[[transition]]\nname = \"t14\"").unwrap();
    let end = start + text[start..].find("\n\n").unwrap();
    std::fs::write(&net, format!("{}{}", &text[..start], &text[end..])).unwrap();
    let o = petrinav(&["guide", "check", net.to_str().unwrap()]);
    assert!(!o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("verdict: REFUSED"), "{out}");
    assert!(stderr(&o).contains("dead marking"), "{}", stderr(&o));
    // JSON for machines.
    let o = petrinav(&["guide", "check", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v.as_array().unwrap().len(), 2);
    assert_eq!(v[1]["supervisor"], "credit");
    assert_eq!(v[1]["accepted"], true);
}
