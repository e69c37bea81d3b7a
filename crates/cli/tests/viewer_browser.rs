//! The run viewer (`lab replay --html`) in a real browser: headless
//! Chromium opens the page, the page reports its state in the DOM
//! (`<body data-ready data-tick data-robot-…>`, script errors counted in
//! `<html data-errors>`), the URL hash moves the slider, and two
//! screenshots differ where the robot moved.
//!
//! Needs Chromium: Debian's `chromium` package (`apt-get install
//! chromium`), or `PETRINAV_CHROMIUM=/path/to/chrome`. Without it these
//! tests fail, saying so; `scripts/test` (the README's test command, which
//! `.ci/run` calls) looks for it the same way and installs it, as root, or
//! stops before compiling.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn petrinav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("viewer_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The browser, or a failure that says how to get one.
fn chromium() -> PathBuf {
    let candidates: Vec<PathBuf> = match std::env::var_os("PETRINAV_CHROMIUM") {
        Some(p) => vec![PathBuf::from(p)],
        None => ["chromium", "chromium-browser", "google-chrome"]
            .iter()
            .map(PathBuf::from)
            .collect(),
    };
    for c in &candidates {
        if Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
        {
            return c.clone();
        }
    }
    panic!(
        "the viewer's browser tests need Chromium and found none ({}): install Debian's `chromium` package \
         (`apt-get install -y chromium`) or set PETRINAV_CHROMIUM to a Chromium or Chrome binary; \
         `scripts/test` installs it when run as root",
        candidates
            .iter()
            .map(|c| c.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
}

/// Runs headless Chromium on `url` with `extra` (`--dump-dom`,
/// `--screenshot=…`) after `budget_ms` of virtual time; its stdout.
fn headless(profile: &Path, url: &str, budget_ms: u32, extra: &[String]) -> String {
    let out = Command::new(chromium())
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
            "--window-size=1200,900",
            "--no-first-run",
            "--disable-extensions",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--virtual-time-budget={budget_ms}"))
        .args(extra)
        .arg(url)
        .output()
        .expect("chromium runs");
    assert!(
        out.status.success(),
        "chromium failed on {url}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("the DOM is UTF-8")
}

/// The attributes of the first `<tag …>` in `dom`.
fn attributes(dom: &str, tag: &str) -> BTreeMap<String, String> {
    let open = format!("<{tag} ");
    let start = dom.find(&open).unwrap_or_else(|| panic!("no <{tag}> in the DOM")) + open.len();
    let end = start + dom[start..].find('>').unwrap();
    let mut out = BTreeMap::new();
    let mut rest = &dom[start..end];
    while let Some(eq) = rest.find("=\"") {
        let name = rest[..eq].trim().to_string();
        let value_end = rest[eq + 2..].find('"').unwrap();
        out.insert(name, rest[eq + 2..eq + 2 + value_end].to_string());
        rest = &rest[eq + 2 + value_end + 1..];
    }
    out
}

/// What the page says after `budget_ms` at `url`: `<html>`'s and
/// `<body>`'s attributes merged, and the errors listed.
fn page_state(profile: &Path, url: &str, budget_ms: u32) -> (BTreeMap<String, String>, String) {
    let dom = headless(profile, url, budget_ms, &["--dump-dom".to_string()]);
    let mut state = attributes(&dom, "html");
    state.extend(attributes(&dom, "body"));
    let errors = dom
        .find("<ol id=\"errors\"")
        .map(|k| dom[k..k + dom[k..].find("</ol>").unwrap()].to_string())
        .unwrap_or_default();
    (state, errors)
}

fn number(state: &BTreeMap<String, String>, key: &str) -> f64 {
    state
        .get(key)
        .unwrap_or_else(|| panic!("the page has no {key}: {state:?}"))
        .parse()
        .unwrap_or_else(|_| panic!("{key} is not a number: {state:?}"))
}

/// A voting batch of one run per scenario and the viewer page of
/// `e4/field12#0` in `dir`.
fn voting_page(dir: &Path) -> PathBuf {
    let results = dir.join("voting");
    let out = petrinav(&[
        "lab",
        "run",
        "voting",
        "--runs",
        "1",
        "--no-pictures",
        "--out",
        results.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let html = dir.join("run.html");
    let out = petrinav(&[
        "lab",
        "replay",
        results.to_str().unwrap(),
        "e4/field12#0",
        "--html",
        html.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    html
}

/// A voting batch of three runs per scenario with its report, and the
/// viewer page of `e4/field12`'s three pictured runs in it.
fn voting_runs_page(dir: &Path) -> PathBuf {
    let results = dir.join("voting");
    let out = petrinav(&[
        "lab",
        "run",
        "voting",
        "--runs",
        "3",
        "--out",
        results.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    results.join("viewer/e4-field12.html")
}

/// A copy of the page at `html` that runs `script` once the viewer is
/// ready (the DOM says so), to act as a user would.
fn with_script(html: &Path, script: &str, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(html).unwrap();
    let act = format!(
        "<script>(function wait(){{if(document.body.dataset.ready!==\"1\")return setTimeout(wait,50);{script}}})();</script>\n</body>"
    );
    let out = html.with_file_name(name);
    std::fs::write(&out, text.replacen("</body>", &act, 1)).unwrap();
    out
}

fn url(path: &Path, hash: &str) -> String {
    format!("file://{}#{hash}", path.canonicalize().unwrap().display())
}

#[test]
fn the_viewer_loads_without_errors_and_the_slider_moves_the_robot() {
    let dir = fresh("slider");
    let html = voting_page(&dir);
    let profile = dir.join("profile");
    let (at0, errors0) = page_state(&profile, &url(&html, "t=0"), 2000);
    assert_eq!(at0.get("data-errors").map(String::as_str), Some("0"), "{errors0}");
    assert_eq!(at0.get("data-ready").map(String::as_str), Some("1"), "{at0:?}");
    assert_eq!(number(&at0, "data-tick"), 0.0);
    // One run on the page: `lab replay --html` shows the run asked for.
    assert_eq!(number(&at0, "data-runs"), 1.0);
    assert_eq!(at0.get("data-run-key").map(String::as_str), Some("e4/field12#0"));
    let (at20, errors20) = page_state(&profile, &url(&html, "t=20"), 2000);
    assert_eq!(
        at20.get("data-errors").map(String::as_str),
        Some("0"),
        "{errors20}"
    );
    assert_eq!(number(&at20, "data-tick"), 200.0, "{at20:?}");
    assert_eq!(number(&at20, "data-time"), 20.0);
    let moved_m = (number(&at20, "data-robot-x") - number(&at0, "data-robot-x"))
        .hypot(number(&at20, "data-robot-y") - number(&at0, "data-robot-y"));
    assert!(moved_m > 1.0, "the robot moved {moved_m} m in 20 s");
    let moved_px = (number(&at20, "data-robot-page-x") - number(&at0, "data-robot-page-x"))
        .hypot(number(&at20, "data-robot-page-y") - number(&at0, "data-robot-page-y"));
    assert!(moved_px > 30.0, "the robot was drawn {moved_px} px away");
}

#[test]
fn the_viewer_plays_from_the_url() {
    let dir = fresh("play");
    let html = voting_page(&dir);
    // 3 s of virtual time at 5× is 150 ticks of 0.1 s (timers are not exact
    // under a virtual time budget: at least a third of them).
    let (state, errors) = page_state(&dir.join("profile"), &url(&html, "t=0&play=1&speed=5"), 3000);
    assert_eq!(
        state.get("data-errors").map(String::as_str),
        Some("0"),
        "{errors}"
    );
    assert_eq!(
        state.get("data-playing").map(String::as_str),
        Some("1"),
        "{state:?}"
    );
    let tick = number(&state, "data-tick");
    assert!((50.0..=160.0).contains(&tick), "played to tick {tick}");
}

#[test]
fn screenshots_at_two_times_differ_where_the_robot_moved() {
    let dir = fresh("screenshots");
    let html = voting_page(&dir);
    let profile = dir.join("profile");
    let shots: Vec<(image::RgbImage, BTreeMap<String, String>)> = ["t=0", "t=20"]
        .iter()
        .map(|hash| {
            let png = dir.join(format!("{}.png", hash.replace('=', "")));
            headless(
                &profile,
                &url(&html, hash),
                2000,
                &[format!("--screenshot={}", png.display())],
            );
            let (state, _) = page_state(&profile, &url(&html, hash), 2000);
            (image::open(&png).expect("a screenshot").to_rgb8(), state)
        })
        .collect();
    let [(a, sa), (b, sb)] = &shots[..] else {
        unreachable!()
    };
    assert_eq!(a.dimensions(), (1200, 900));
    // Pixels that differ within 6 px of where the robot is drawn.
    let differing = |x: f64, y: f64| {
        let mut n = 0;
        for dy in -6i64..=6 {
            for dx in -6i64..=6 {
                let (px, py) = ((x as i64 + dx) as u32, (y as i64 + dy) as u32);
                if a.get_pixel(px, py) != b.get_pixel(px, py) {
                    n += 1;
                }
            }
        }
        n
    };
    for (s, when) in [(sa, "at 0 s"), (sb, "at 20 s")] {
        let n = differing(number(s, "data-robot-page-x"), number(s, "data-robot-page-y"));
        assert!(n > 40, "only {n} pixels differ around the robot {when}");
    }
    // The rest of the page stays: the map, the layout.
    let changed = a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count();
    assert!(
        changed < (1200 * 900) / 10,
        "{changed} pixels changed: more than the robot, its path and the panel"
    );
}

#[test]
fn a_script_error_is_reported_in_the_page() {
    // The check above can fail: a page whose data breaks the script says so.
    let dir = fresh("broken");
    let html = voting_page(&dir);
    let text = std::fs::read_to_string(&html).unwrap();
    let (good, bad) = ("T = D.ticks;", "T = D.no_such_thing.ticks;");
    assert!(text.contains(good));
    let broken = dir.join("broken.html");
    std::fs::write(&broken, text.replacen(good, bad, 1)).unwrap();
    let (state, errors) = page_state(&dir.join("profile"), &url(&broken, "t=0"), 2000);
    let n: u32 = state.get("data-errors").and_then(|n| n.parse().ok()).unwrap_or(0);
    assert!(n >= 1, "no error reported: {state:?}");
    assert!(errors.contains("<li>the viewer failed: "), "{errors}");
    assert_ne!(state.get("data-ready").map(String::as_str), Some("1"));
}

#[test]
fn a_page_of_several_runs_draws_the_run_its_url_names() {
    let dir = fresh("runs");
    let html = voting_runs_page(&dir);
    let profile = dir.join("profile");
    // Every run at its end: the whole trajectory drawn.
    let shots: Vec<(image::RgbImage, BTreeMap<String, String>)> = (0..3)
        .map(|k| {
            let hash = format!("run={k}&tick=100000");
            let png = dir.join(format!("run{k}.png"));
            headless(
                &profile,
                &url(&html, &hash),
                2000,
                &[format!("--screenshot={}", png.display())],
            );
            let (state, errors) = page_state(&profile, &url(&html, &hash), 2000);
            assert_eq!(
                state.get("data-errors").map(String::as_str),
                Some("0"),
                "{errors}"
            );
            assert_eq!(
                state.get("data-ready").map(String::as_str),
                Some("1"),
                "{state:?}"
            );
            (image::open(&png).expect("a screenshot").to_rgb8(), state)
        })
        .collect();
    for (k, (_, state)) in shots.iter().enumerate() {
        assert_eq!(number(state, "data-runs"), 3.0);
        assert_eq!(number(state, "data-run"), k as f64);
        assert_eq!(
            state.get("data-run-key").map(String::as_str),
            Some(format!("e4/field12#{k}").as_str())
        );
        assert!(number(state, "data-tick") > 100.0, "{state:?}");
    }
    // The runs' trajectories differ on the map (the canvas: left of the
    // panel, under the header).
    for k in 1..3 {
        let (a, b) = (&shots[0].0, &shots[k].0);
        let mut differ = 0;
        for y in 70..640 {
            for x in 15..810 {
                if a.get_pixel(x, y) != b.get_pixel(x, y) {
                    differ += 1;
                }
            }
        }
        assert!(differ > 300, "run {k} is drawn as run 0 ({differ} pixels differ)");
    }
}

#[test]
fn another_run_chosen_by_its_hash_or_the_selector_starts_at_its_first_tick() {
    let dir = fresh("switch");
    let html = voting_runs_page(&dir);
    let profile = dir.join("profile");
    // The URL's hash changes on the open page.
    let by_hash = with_script(&html, "location.hash=\"run=2\";", "by_hash.html");
    let (state, errors) = page_state(&profile, &url(&by_hash, "run=1&t=20"), 3000);
    assert_eq!(
        state.get("data-errors").map(String::as_str),
        Some("0"),
        "{errors}"
    );
    assert_eq!(
        state.get("data-run-key").map(String::as_str),
        Some("e4/field12#2"),
        "{state:?}"
    );
    assert_eq!(
        number(&state, "data-tick"),
        0.0,
        "the slider was not reset: {state:?}"
    );
    // The selector.
    let by_select = with_script(
        &html,
        "var s=document.getElementById(\"run\");s.value=\"1\";s.dispatchEvent(new Event(\"change\"));",
        "by_select.html",
    );
    let (state, errors) = page_state(&profile, &url(&by_select, "run=0&t=20"), 3000);
    assert_eq!(
        state.get("data-errors").map(String::as_str),
        Some("0"),
        "{errors}"
    );
    assert_eq!(
        state.get("data-run-key").map(String::as_str),
        Some("e4/field12#1"),
        "{state:?}"
    );
    assert_eq!(
        number(&state, "data-tick"),
        0.0,
        "the slider was not reset: {state:?}"
    );
    // Without a switch the page stays where its URL put it.
    let (state, _) = page_state(&profile, &url(&html, "run=1&t=20"), 3000);
    assert_eq!(
        state.get("data-run-key").map(String::as_str),
        Some("e4/field12#1")
    );
    assert_eq!(number(&state, "data-tick"), 200.0, "{state:?}");
}

/// The museum of the tour-guide suite.
const MUSEUM: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../lab/src/suites/tourguide/museum.toml"
);

/// A short leg the crediting supervisor drives in the museum from an empty
/// mission log (`nav go --behaviour supervisor --html`): its page.
fn supervisor_page(dir: &Path) -> PathBuf {
    let log = dir.join("missions.jsonl");
    std::fs::write(&log, "").unwrap();
    let html = dir.join("supervisor.html");
    let out = petrinav(&[
        "nav",
        "go",
        MUSEUM,
        "--from",
        "8.1,6.4,1.5708",
        "--to",
        "8.1,9.6,1.5708",
        "--behaviour",
        "supervisor",
        "--log",
        log.to_str().unwrap(),
        "--html",
        html.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    html
}

#[test]
fn the_supervisor_net_is_drawn_with_its_marking_and_the_last_decision() {
    let dir = fresh("net");
    let html = supervisor_page(&dir);
    let profile = dir.join("profile");
    let dom = headless(&profile, &url(&html, "t=1"), 2000, &["--dump-dom".to_string()]);
    let mut state = attributes(&dom, "html");
    state.extend(attributes(&dom, "body"));
    assert_eq!(state.get("data-errors").map(String::as_str), Some("0"), "{dom}");
    // Running AutoMove (P1), localized (P5), the planner Normal (P7).
    assert_eq!(
        state.get("data-net-marking").map(String::as_str),
        Some("P1 P5 P7"),
        "{state:?}"
    );
    // The start decision, at tick 0, with the value of each choice and
    // the marking it was taken in.
    assert_eq!(state.get("data-net-event-tick").map(String::as_str), Some("0"));
    let panel = &dom[dom.find("<div id=\"net-box\"").expect("the net's panel")..];
    let panel = &panel[..panel.find("</div>").unwrap()];
    assert!(!panel.contains(" hidden"), "{panel}");
    for shown in [
        "supervisor_credit",
        "time_auto_s",
        "time_cont_s",
        "P0 P5 P7",
        "route",
        "context",
    ] {
        assert!(panel.contains(shown), "`{shown}` not in the panel: {panel}");
    }
    assert_eq!(panel.matches("class=\"place").count(), 10, "{panel}");
}
