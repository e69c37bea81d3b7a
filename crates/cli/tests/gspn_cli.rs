//! The `petrinav gspn` commands, run as a user would.

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

fn petrinav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn data(path: &str) -> String {
    format!("{}/../petri/tests/data/{path}", env!("CARGO_MANIFEST_DIR"))
}

fn json(args: &[&str]) -> Value {
    let out = petrinav(args);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

/// Runs a command that must fail; returns its error message.
fn fails(args: &[&str]) -> String {
    let out = petrinav(args);
    assert!(!out.status.success(), "{args:?} should fail");
    assert_ne!(out.status.code(), Some(101), "{args:?} panicked");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(err.starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

fn temp_file(name: &str, text: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn select_gives_the_published_decision() {
    let v = json(&[
        "gspn",
        "select",
        "--set",
        "lambda7=1/122.33",
        "--set",
        "lambda8=1/186.98",
        "--json",
    ]);
    assert_eq!(v["tangible_markings"], 13);
    assert_eq!(format!("{:.3e}", v["f_cont"].as_f64().unwrap()), "5.348e-3");
    assert_eq!(v["choice"], "automove");
    for key in [
        "f_auto",
        "u_auto",
        "u_cont",
        "p_loc_succ",
        "p_loc_warn",
        "p_pp_norm",
        "p_pp_abno",
    ] {
        assert!(v[key].is_number(), "{key}");
    }
    let err = fails(&["gspn", "select", "--set", "lambda12=1"]);
    assert!(err.contains("λ12"), "{err}");
    let err = fails(&["gspn", "select", "--set", "mu=1"]);
    assert!(err.contains("lambda1"), "{err}");
}

#[test]
fn info_counts_the_mcc_reachability_sets() {
    for (file, count) in [
        ("mcc/TokenRing-PT-005.pnml", 166),
        ("mcc/Philosophers-PT-000005.pnml", 243),
        ("mcc/FMS-PT-00002.pnml", 3444),
    ] {
        let v = json(&["gspn", "info", &data(file), "--json"]);
        assert_eq!(v["reachable_markings"], count, "{file}");
        for key in [
            "places",
            "transitions",
            "tangible_markings",
            "vanishing_markings",
            "dead_markings",
            "bounded",
        ] {
            assert!(!v[key].is_null(), "{file}: {key}");
        }
    }
    let v = json(&[
        "gspn",
        "info",
        &data("greatspn/FlexibleManufacturingSystem.PNPRO"),
        "--param",
        "N=2",
        "--json",
    ]);
    assert_eq!(
        v["vanishing_markings"].as_u64().unwrap() + v["tangible_markings"].as_u64().unwrap(),
        v["reachable_markings"].as_u64().unwrap()
    );
    assert_eq!(v["live"], true);
}

#[test]
fn state_limit_is_an_error_naming_the_limit() {
    let err = fails(&[
        "gspn",
        "info",
        &data("mcc/Philosophers-PT-000010.pnml"),
        "--max-states",
        "1000",
    ]);
    assert!(err.contains("1000"), "{err}");
    let unbounded = temp_file(
        "unbounded.toml",
        "[[place]]\nname = \"q\"\n[[transition]]\nname = \"arrive\"\nrate = 1\noutputs = [\"q\"]\n",
    );
    let err = fails(&["gspn", "info", unbounded.to_str().unwrap(), "--max-states", "500"]);
    assert!(err.contains("500") && err.contains("`q`"), "{err}");
}

#[test]
fn solve_reports_places_transitions_and_measures() {
    let v = json(&[
        "gspn",
        "solve",
        &data("mcc/Philosophers-PT-000005.pnml"),
        "--default-rate",
        "1",
        "--json",
    ]);
    assert_eq!(v["tangible_markings"], 243);
    assert!(v["residual"].as_f64().unwrap() <= 1e-10);
    // The MCC philosophers deadlock: every long-run throughput is 0.
    for (_, t) in v["transitions"].as_object().unwrap() {
        assert_eq!(t["throughput"], 0.0);
    }
    let supervisor = format!("{}/../../models/supervisor.toml", env!("CARGO_MANIFEST_DIR"));
    let v = json(&[
        "gspn",
        "solve",
        &supervisor,
        "--measure",
        "#P1 = 1 and #P7 = 1",
        "--json",
    ]);
    assert_eq!(v["tangible_markings"], 13);
    let m = v["measures"]["#P1 = 1 and #P7 = 1"].as_f64().unwrap();
    let x9 = v["transitions"]["t9"]["throughput"].as_f64().unwrap();
    // t9 fires at λ7 = 0.0082 whenever P1 and P7 are marked.
    assert!((x9 - 0.0082 * m).abs() < 1e-15, "{x9} vs {m}");
    assert!(v["places"]["P0"]["prob_nonempty"].is_number());
    assert!(v["places"]["P0"]["mean_tokens"].is_number());
    assert!(v["solver"].is_string());
}

#[test]
fn plain_nets_need_a_default_rate() {
    let err = fails(&["gspn", "solve", &data("mcc/TokenRing-PT-005.pnml")]);
    assert!(err.contains("--default-rate"), "{err}");
}

#[test]
fn bad_input_gets_clear_errors() {
    let malformed = temp_file(
        "malformed.pnml",
        "<pnml><net id=\"n\"><page id=\"p\">\n<place id=\"a\">\n</net></pnml>",
    );
    let err = fails(&["gspn", "info", malformed.to_str().unwrap()]);
    assert!(err.contains("malformed XML") && err.contains(":3:"), "{err}");

    let unknown = temp_file(
        "unknown_arc.toml",
        "[[place]]\nname = \"a\"\n[[transition]]\nname = \"t\"\ninputs = [\"b\"]\n",
    );
    let err = fails(&["gspn", "info", unknown.to_str().unwrap()]);
    assert!(err.contains("`b`"), "{err}");

    let duplicate = temp_file(
        "duplicate.toml",
        "[[place]]\nname = \"a\"\n[[place]]\nname = \"a\"\n",
    );
    let err = fails(&["gspn", "info", duplicate.to_str().unwrap()]);
    assert!(err.contains("duplicate") && err.contains("`a`"), "{err}");

    let err = fails(&[
        "gspn",
        "info",
        &data("greatspn/FlexibleManufacturingSystem.PNPRO"),
    ]);
    assert!(err.contains("`N`") && err.contains("--param N="), "{err}");

    for rate in ["0", "-2"] {
        let err = fails(&[
            "gspn",
            "solve",
            &data("greatspn/Philosophers4.PNPRO"),
            "--param",
            &format!("lambda={rate}"),
        ]);
        assert!(err.contains("rate") && err.contains("> 0"), "{err}");
    }
    let weight = temp_file(
        "zero_weight.toml",
        "[[place]]\nname = \"a\"\ninitial = 1\n[[transition]]\nname = \"t\"\nkind = \"immediate\"\nweight = 0\ninputs = [\"a\"]\noutputs = [\"a\"]\n",
    );
    let err = fails(&["gspn", "info", weight.to_str().unwrap()]);
    assert!(err.contains("weight"), "{err}");

    let trap = temp_file(
        "trap.toml",
        "[[place]]\nname = \"a\"\ninitial = 1\n[[place]]\nname = \"b\"\n[[place]]\nname = \"c\"\n\
         [[transition]]\nname = \"go\"\nrate = 1\ninputs = [\"a\"]\noutputs = [\"b\"]\n\
         [[transition]]\nname = \"ping\"\nkind = \"immediate\"\ninputs = [\"b\"]\noutputs = [\"c\"]\n\
         [[transition]]\nname = \"pong\"\nkind = \"immediate\"\ninputs = [\"c\"]\noutputs = [\"b\"]\n",
    );
    let err = fails(&["gspn", "solve", trap.to_str().unwrap()]);
    assert!(err.contains("timeless trap"), "{err}");

    let err = fails(&["gspn", "info", "no/such/file.pnpro"]);
    assert!(err.contains("no/such/file.pnpro"), "{err}");
    let err = fails(&["gspn", "info", "model.xyz"]);
    assert!(err.contains("extension"), "{err}");
    let err = fails(&[
        "gspn",
        "solve",
        &data("greatspn/Philosophers4.PNPRO"),
        "--measure",
        "#nowhere > 0",
    ]);
    assert!(err.contains("nowhere"), "{err}");
}

#[test]
fn convert_round_trips_and_dot_draws() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let toml = dir.join("rw.toml");
    let pnpro = dir.join("rw.pnpro");
    let src = data("greatspn/ReaderWriter.PNPRO");
    assert!(
        petrinav(&["gspn", "convert", &src, toml.to_str().unwrap()])
            .status
            .success()
    );
    assert!(
        petrinav(&["gspn", "convert", toml.to_str().unwrap(), pnpro.to_str().unwrap()])
            .status
            .success()
    );
    let a = json(&["gspn", "solve", &src, "--param", "K=2", "--json"]);
    let b = json(&[
        "gspn",
        "solve",
        pnpro.to_str().unwrap(),
        "--param",
        "K=2",
        "--json",
    ]);
    assert_eq!(a["places"], b["places"]);
    assert_eq!(a["transitions"], b["transitions"]);
    for graph in ["net", "rg", "trg"] {
        let out = petrinav(&["gspn", "dot", &src, "--param", "K=2", "--graph", graph]);
        assert!(out.status.success(), "{graph}");
        assert!(
            String::from_utf8_lossy(&out.stdout).starts_with("digraph"),
            "{graph}"
        );
    }
}

#[test]
fn simulate_is_reproducible_and_agrees_with_solve() {
    let supervisor = format!("{}/../../models/supervisor.toml", env!("CARGO_MANIFEST_DIR"));
    let file = data("greatspn/Cycle_of_Four_Seasons.PNPRO");
    let run = || {
        json(&[
            "gspn", "simulate", &file, "--time", "20000", "--seed", "7", "--json",
        ])
    };
    assert_eq!(run(), run());
    let sim = run();
    let exact = json(&["gspn", "solve", &file, "--json"]);
    let names = sim["place_names"].as_array().unwrap();
    for (i, name) in names.iter().enumerate() {
        let est = &sim["places"][i];
        let mean = est["mean"].as_f64().unwrap();
        let hw = est["half_width"].as_f64().unwrap();
        let want = exact["places"][name.as_str().unwrap()]["mean_tokens"]
            .as_f64()
            .unwrap();
        assert!(
            (mean - want).abs() <= 4.0 * hw.max(1e-3),
            "{name}: {mean} ± {hw} vs {want}"
        );
    }
    let err = fails(&["gspn", "simulate", &supervisor, "--time=-1", "--seed", "1"]);
    assert!(err.contains("end"), "{err}");
}

#[test]
fn family_writes_a_model_that_solves() {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("kanban1.toml");
    assert!(
        petrinav(&["gspn", "family", "kanban", "1", "-o", path.to_str().unwrap()])
            .status
            .success()
    );
    let v = json(&["gspn", "solve", path.to_str().unwrap(), "--json"]);
    assert_eq!(v["tangible_markings"], 160);
}

/// The progress line of `gspn solve` is for terminals only: with standard
/// error piped, nothing is written to it, and the output is the same.
#[test]
fn solve_prints_no_progress_when_not_on_a_terminal() {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("kanban2-progress.pnpro");
    let f = path.to_str().unwrap();
    assert!(
        petrinav(&["gspn", "family", "kanban", "2", "-o", f])
            .status
            .success()
    );
    for args in [vec!["gspn", "solve", f, "--json"], vec!["gspn", "solve", f]] {
        let out = petrinav(&args);
        assert!(out.status.success(), "{args:?}");
        assert!(
            out.stderr.is_empty(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(!text.contains('\r') && !text.contains('\u{1b}'), "{text}");
        assert!(
            !text.contains("generating") && !text.contains("iteration "),
            "{text}"
        );
    }
    let v = json(&["gspn", "solve", f, "--json"]);
    assert_eq!(v["tangible_markings"], 4600);
}

/// Issue 17: `select --set lambda3=1e200` printed `f_auto NaN` and decided
/// on it. The answer exists: the localizer leaves Success at once, so
/// AutoMove never completes and Contour tracking is chosen.
#[test]
fn select_with_a_warning_rate_of_1e200_decides_on_finite_numbers() {
    let v = json(&["gspn", "select", "--set", "lambda3=1e200", "--json"]);
    for key in [
        "f_auto",
        "f_cont",
        "u_auto",
        "u_cont",
        "p_loc_succ",
        "p_loc_warn",
        "p_pp_norm",
        "p_pp_abno",
    ] {
        let x = v[key].as_f64().unwrap_or_else(|| panic!("{key} is {}", v[key]));
        assert!(x.is_finite() && (0.0..=1.0).contains(&x), "{key} = {x}");
    }
    assert_eq!(v["choice"], "contour");
    assert!(v["f_cont"].as_f64().unwrap() > 5e-3);
    assert!(v["p_loc_succ"].as_f64().unwrap() < 1e-190);
    let out = petrinav(&["gspn", "select", "--set", "lambda3=1e200"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        !text.contains("NaN") && text.contains("Contour tracking"),
        "{text}"
    );
    // What double precision cannot hold is an error naming the ratio.
    let err = fails(&["gspn", "select", "--set", "lambda3=1e300"]);
    assert!(err.contains("too far apart") && err.contains("1.0e303"), "{err}");
}

/// Issue 17: `solve models/supervisor.toml -p lambda3=1e200` printed all-NaN
/// probabilities.
#[test]
fn solve_with_rates_1e200_apart_gives_finite_probabilities() {
    let supervisor = format!("{}/../../models/supervisor.toml", env!("CARGO_MANIFEST_DIR"));
    let v = json(&["gspn", "solve", &supervisor, "-p", "lambda3=1e200", "--json"]);
    let places = v["places"].as_object().unwrap();
    assert_eq!(places.len(), 9);
    for (name, p) in places {
        for key in ["prob_nonempty", "mean_tokens"] {
            let x = p[key]
                .as_f64()
                .unwrap_or_else(|| panic!("{name}.{key} is {}", p[key]));
            assert!(x.is_finite() && x >= 0.0, "{name}.{key} = {x}");
        }
    }
    assert!((places["P6"]["prob_nonempty"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    for (name, t) in v["transitions"].as_object().unwrap() {
        assert!(t["throughput"].as_f64().is_some_and(f64::is_finite), "{name}");
    }
    assert!(v["residual"].as_f64().is_some_and(|r| r < 1e-12));
    let out = petrinav(&["gspn", "solve", &supervisor, "-p", "lambda3=1e200"]);
    assert!(out.status.success() && !String::from_utf8_lossy(&out.stdout).contains("NaN"));
    let err = fails(&["gspn", "solve", &supervisor, "-p", "lambda3=1e-300"]);
    assert!(err.contains("too far apart"), "{err}");
    let err = fails(&["gspn", "solve", &supervisor, "-m", "1 / #P0"]);
    assert!(err.contains("not a finite number"), "{err}");
}

/// Issue 17: `family philosophers 100000000` aborted on a failed allocation
/// of 3.7 GB (exit 134).
#[test]
fn a_family_too_large_is_refused_before_allocating() {
    let err = fails(&["gspn", "family", "philosophers", "100000000"]);
    assert!(
        err.contains("1000000000 places and transitions") && err.contains("limit of 1000000"),
        "{err}"
    );
    let err = fails(&["gspn", "family", "philosophers", "0"]);
    assert!(err.contains("at least 1"), "{err}");
    // The largest member accepted is written.
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("philosophers1000.pnml");
    assert!(
        petrinav(&[
            "gspn",
            "family",
            "philosophers",
            "1000",
            "-o",
            path.to_str().unwrap()
        ])
        .status
        .success()
    );
}

/// Issue 17: `simulate models/supervisor.toml --time 1e300` ran with no end
/// in sight: the event and wall-time bounds end it with a clear message.
#[test]
fn an_endless_simulation_stops_at_its_bounds() {
    let supervisor = format!("{}/../../models/supervisor.toml", env!("CARGO_MANIFEST_DIR"));
    let base = [
        "gspn",
        "simulate",
        supervisor.as_str(),
        "--time",
        "1e300",
        "--seed",
        "1",
    ];
    let start = std::time::Instant::now();
    let err = fails(&[&base[..], &["--max-events", "200000"]].concat());
    assert!(
        err.contains("200000 transitions, its limit") && err.contains("--max-events"),
        "{err}"
    );
    let err = fails(&[&base[..], &["--max-wall", "0.2"]].concat());
    assert!(
        err.contains("0.2 s of wall-clock time") && err.contains("--max-wall"),
        "{err}"
    );
    assert!(err.contains("firings would be needed"), "{err}");
    assert!(start.elapsed().as_secs_f64() < 30.0);
    let err = fails(&[&base[..], &["--max-wall", "0"]].concat());
    assert!(err.contains("max_wall_s"), "{err}");
}

#[test]
fn solve_stats_accounts_for_the_memory_in_the_table_and_in_json() {
    let dir = std::env::temp_dir().join(format!("petrinav-stats-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("kanban2.pnpro");
    let f = file.to_str().unwrap();
    assert!(
        petrinav(&["gspn", "family", "kanban", "2", "-o", f])
            .status
            .success()
    );
    let plain = json(&["gspn", "solve", f, "--json"]);
    assert!(
        plain.get("memory").is_none(),
        "--json without --stats stays as it was"
    );
    let v = json(&["gspn", "solve", f, "--json", "--stats"]);
    let m = &v["memory"];
    assert_eq!(m["tangible_markings"], 4600);
    let parts = m["parts"].as_array().unwrap();
    let sum = |stages: &[&str]| -> u64 {
        parts
            .iter()
            .filter(|p| stages.contains(&p["stage"].as_str().unwrap()))
            .map(|p| p["bytes"].as_u64().unwrap())
            .sum()
    };
    assert_eq!(m["solve_bytes"].as_u64().unwrap(), sum(&["chain", "solve"]));
    assert!(m["peak_bytes"].as_u64().unwrap() >= m["solve_bytes"].as_u64().unwrap());
    assert!(m["guard_estimate_bytes"].as_u64().unwrap() > 0);
    let table = petrinav(&["gspn", "solve", f, "--stats"]);
    assert!(table.status.success());
    let text = String::from_utf8_lossy(&table.stdout);
    assert!(
        text.contains("B/marking") && text.contains("incoming rows: column indices"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
