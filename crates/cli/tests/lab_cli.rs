//! `petrinav lab`, run as a user would: determinism across thread counts,
//! resuming a killed batch, replays, and bad scenario files.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn petrinav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("lab_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn run_voting(out: &Path, runs: &str, jobs: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "lab",
        "run",
        "voting",
        "--runs",
        runs,
        "--jobs",
        jobs,
        "--no-pictures",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    petrinav(&args)
}

fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |s| s.lines().count())
}

#[test]
fn one_thread_and_two_threads_write_the_same_results_file() {
    let (a, b) = (fresh("jobs1"), fresh("jobs2"));
    let out_a = run_voting(&a, "2", "1", &[]);
    assert!(
        out_a.status.success(),
        "{}",
        String::from_utf8_lossy(&out_a.stderr)
    );
    let out_b = run_voting(&b, "2", "2", &[]);
    assert!(
        out_b.status.success(),
        "{}",
        String::from_utf8_lossy(&out_b.stderr)
    );
    let ra = std::fs::read(a.join("results.jsonl")).unwrap();
    let rb = std::fs::read(b.join("results.jsonl")).unwrap();
    assert_eq!(lines(&a.join("results.jsonl")), 5 * 14 * 2);
    assert!(ra == rb, "results differ between --jobs 1 and --jobs 2");
    // The printed tables and the report's tables are the same too.
    let tables_only = |o: &std::process::Output| {
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter(|l| !l.starts_with("report:"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(tables_only(&out_a), tables_only(&out_b));
    assert_eq!(
        std::fs::read(a.join("tables.md")).unwrap(),
        std::fs::read(b.join("tables.md")).unwrap()
    );
    let tables = String::from_utf8_lossy(&out_a.stdout);
    assert!(tables.contains("field14") && tables.contains("e4"), "{tables}");
}

#[test]
fn a_killed_batch_resumes_to_the_uninterrupted_results() {
    let (whole, cut) = (fresh("whole"), fresh("cut"));
    let out = run_voting(&whole, "3", "1", &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let total = lines(&whole.join("results.jsonl"));
    assert_eq!(total, 5 * 14 * 3);

    let mut child = Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args([
            "lab",
            "run",
            "voting",
            "--runs",
            "3",
            "--jobs",
            "1",
            "--no-pictures",
            "--out",
            cut.to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("the petrinav binary runs");
    let results = cut.join("results.jsonl");
    let start = Instant::now();
    while lines(&results) < total / 4 && start.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().expect("kill the batch");
    child.wait().unwrap();
    let done = lines(&results);
    assert!(
        done > 0 && done < total,
        "the batch should be cut half-way, has {done} of {total} runs"
    );

    let out = run_voting(&cut, "3", "2", &["--resume"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("already done"), "{stderr}");
    assert_eq!(
        std::fs::read(&results).unwrap(),
        std::fs::read(whole.join("results.jsonl")).unwrap(),
        "resumed results differ from an uninterrupted batch"
    );
    // Resuming with other arguments is refused.
    let out = run_voting(&cut, "4", "1", &["--resume"]);
    assert!(!out.status.success());
    // And a second run without --resume does not overwrite anything.
    let out = run_voting(&cut, "3", "1", &[]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--resume"));
}

#[test]
fn a_run_is_replayed_with_its_picture_and_trace() {
    let dir = fresh("replay");
    let out = run_voting(&dir, "1", "2", &[]);
    assert!(out.status.success());
    let png = dir.join("run.png");
    let trace = dir.join("run.jsonl");
    let out = petrinav(&[
        "lab",
        "replay",
        dir.to_str().unwrap(),
        "e4/field12#0",
        "-o",
        png.to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let replayed: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let results = std::fs::read_to_string(dir.join("results.jsonl")).unwrap();
    let original: serde_json::Value = results
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .find(|r| r["key"] == "e4/field12#0")
        .unwrap();
    for k in ["outcome", "time_s", "path_length_m", "ticks"] {
        assert_eq!(replayed[k], original[k], "{k}");
    }
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    assert_eq!(lines(&trace) as u64, original["ticks"].as_u64().unwrap());
    let bad = petrinav(&["lab", "replay", dir.to_str().unwrap(), "e9/field99#0"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("no scenario"));
}

#[test]
fn a_replay_explains_an_unknown_run_another_suites_folder_and_an_unwritable_output() {
    let voting = fresh("replay_bad_voting");
    assert!(run_voting(&voting, "1", "2", &[]).status.success());
    let deadlock = fresh("replay_bad_deadlock");
    let out = petrinav(&[
        "lab",
        "run",
        "deadlock",
        "--runs",
        "1",
        "--no-pictures",
        "--out",
        deadlock.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let html = voting.join("run.html");
    let fails = |dir: &Path, run: &str, extra: &[&str], says: &str| {
        let mut args = vec!["lab", "replay", dir.to_str().unwrap(), run];
        args.extend_from_slice(extra);
        let out = petrinav(&args);
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.starts_with("error: ") && !err.contains("panicked"), "{err}");
        assert!(err.contains(says), "{args:?}: {err}");
    };
    let h = html.to_str().unwrap();
    // Unknown runs.
    fails(
        &voting,
        "e4/field12#99",
        &["--html", h],
        "no run `99` of `e4/field12` in this batch (it has 1 runs",
    );
    fails(
        &voting,
        "e4/field99#0",
        &["--html", h],
        "no scenario `e4/field99` in this batch of the `voting` suite",
    );
    fails(&voting, "field12", &["--html", h], "a run is SCENARIO#INDEX");
    // A results folder of another suite, and a folder that is none.
    fails(
        &deadlock,
        "e4/field12#0",
        &["--html", h],
        "no scenario `e4/field12` in this batch of the `deadlock` suite; it has: priority",
    );
    fails(
        &voting.join("pictures-none"),
        "e4/field12#0",
        &["--html", h],
        "is not a results folder",
    );
    // Outputs that cannot be written, refused before the replay.
    let missing = voting.join("no/such/folder/run.html");
    fails(
        &voting,
        "e4/field12#0",
        &["--html", missing.to_str().unwrap()],
        "there is no folder",
    );
    let under_a_file = voting.join("results.jsonl").join("run.mcap");
    fails(
        &voting,
        "e4/field12#0",
        &["--mcap", under_a_file.to_str().unwrap()],
        "there is no folder",
    );
    fails(
        &voting,
        "e4/field12#0",
        &["--mcap", voting.to_str().unwrap()],
        "it is a folder",
    );
    assert!(!html.exists());
    // And what works after all that.
    let out = petrinav(&[
        "lab",
        "replay",
        voting.to_str().unwrap(),
        "e4/field12#0",
        "--html",
        h,
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::read_to_string(&html).unwrap().contains("e4/field12#0"));
}

/// The value of `name="…"` in `tag` (an opening tag's text).
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let open = format!(" {name}=\"");
    let start = tag.find(&open)? + open.len();
    Some(&tag[start..start + tag[start..].find('"')?])
}

/// The run blocks of a viewer page: (`data-run`, `data-key`, the block's
/// text), in the page's order.
fn run_blocks(page: &str) -> Vec<(String, String, String)> {
    page.split("<script ")
        .skip(1)
        .filter(|s| s.starts_with("type=\"application/octet-stream\" class=\"run-data\""))
        .map(|s| {
            let (tag, rest) = s.split_once('>').unwrap();
            (
                attr(tag, "data-run").unwrap().to_string(),
                attr(tag, "data-key").unwrap().to_string(),
                rest[..rest.find("</script>").unwrap()].to_string(),
            )
        })
        .collect()
}

/// A viewer page's block (zlib-compressed JSON in base64) as JSON.
fn inflate(block: &str) -> serde_json::Value {
    use std::io::Read as _;
    let digit = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let digits: Vec<u8> = block.trim().bytes().filter(|&c| c != b'=').map(digit).collect();
    let mut bytes = Vec::new();
    for chunk in digits.chunks(4) {
        let n = chunk
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &d)| n | u32::from(d) << (18 - 6 * i));
        bytes.extend_from_slice(&n.to_be_bytes()[1..chunk.len()]);
    }
    let mut json = String::new();
    flate2::read::ZlibDecoder::new(&bytes[..])
        .read_to_string(&mut json)
        .expect("a zlib stream");
    serde_json::from_str(&json).expect("JSON")
}

/// The `k`th run of a viewer page as the page shows it: its data with its
/// map and its behaviours' labels in place of their indices into what the
/// page's runs share.
fn shown_run(page: &str, k: usize) -> serde_json::Value {
    let shared_start = page.find("id=\"page-data\"").expect("page data");
    let shared = &page[shared_start..];
    let shared = &shared[shared.find('>').unwrap() + 1..shared.find("</script>").unwrap()];
    let shared = inflate(shared);
    let mut run = inflate(&run_blocks(page)[k].2);
    let map = run["map"].as_u64().unwrap() as usize;
    run["map"] = shared["maps"][map].clone();
    let labels: Vec<serde_json::Value> = run["ticks"]["behaviour"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| match b.as_i64().unwrap() {
            -1 => serde_json::Value::Null,
            b => shared["behaviours"][b as usize].clone(),
        })
        .collect();
    run["ticks"]["behaviour"] = labels.into();
    run
}

#[test]
fn the_report_links_each_pictured_run_to_its_viewer_page() {
    let dir = fresh("report_viewer");
    let out = petrinav(&[
        "lab",
        "run",
        "voting",
        "--runs",
        "3",
        "--jobs",
        "2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let index = std::fs::read_to_string(dir.join("index.html")).unwrap();
    let mut links = 0;
    for figure in index.split("<figure>").skip(1) {
        let figure = &figure[..figure.find("</figure>").unwrap()];
        let scenario = attr(figure, "alt").unwrap();
        let hrefs: Vec<&str> = figure
            .split("<a ")
            .skip(1)
            .filter_map(|a| a.strip_prefix("href=\"")?.split('"').next())
            .collect();
        // The picture opens its page at the first run; the caption links
        // each of the three runs it draws.
        let page_href = format!("viewer/{}.html", scenario.replace('/', "-"));
        let runs: Vec<String> = (0..3).map(|k| format!("{page_href}#run={k}")).collect();
        assert_eq!(hrefs[0], runs[0], "{figure}");
        assert_eq!(&hrefs[1..], &runs[..], "{figure}");
        let page = std::fs::read_to_string(dir.join(&page_href)).unwrap();
        let blocks = run_blocks(&page);
        for (k, href) in runs.iter().enumerate() {
            let (_, fragment) = href.split_once('#').unwrap();
            let run = fragment.strip_prefix("run=").unwrap();
            let block = blocks.iter().find(|b| b.0 == run);
            assert_eq!(
                block.map(|b| b.1.as_str()),
                Some(format!("{scenario}#{k}").as_str()),
                "{href}: no run {scenario}#{k} at data-run={run}"
            );
            links += 1;
        }
        assert_eq!(blocks.len(), 3, "{page_href}");
    }
    assert_eq!(links, 5 * 14 * 3);
    // Each run on the report's page is the one `lab replay --html` writes
    // (the first byte for byte; the others' behaviours and maps are
    // numbered among the page's).
    let report_page = std::fs::read_to_string(dir.join("viewer/e4-field12.html")).unwrap();
    let report_blocks = run_blocks(&report_page);
    assert_eq!(report_blocks.len(), 3);
    for (k, (_, _, report_block)) in report_blocks.iter().enumerate() {
        let key = format!("e4/field12#{k}");
        let replayed = dir.join(format!("replayed{k}.html"));
        let out = petrinav(&[
            "lab",
            "replay",
            dir.to_str().unwrap(),
            &key,
            "--html",
            replayed.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let replayed = std::fs::read_to_string(&replayed).unwrap();
        let single = run_blocks(&replayed);
        assert_eq!(single.len(), 1);
        assert_eq!((single[0].0.as_str(), single[0].1.as_str()), ("0", key.as_str()));
        if k == 0 {
            assert!(
                single[0].2 == *report_block,
                "the report's page and the replayed one differ on {key}"
            );
        }
        assert!(
            shown_run(&replayed, 0) == shown_run(&report_page, k),
            "the report's page and the replayed one show {key} differently"
        );
    }
}

#[test]
fn a_malformed_scenario_names_the_key_and_line() {
    let dir = fresh("bad_scenario");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.toml");
    std::fs::write(
        &file,
        "name = \"bad\"\nruns = 3\n\n[start]\nx = 1.0\ny = 1.0\nspeed = 2\n\n[goal]\nx = 3.0\ny = 1.0\n",
    )
    .unwrap();
    let out = petrinav(&[
        "lab",
        "run",
        file.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("speed") && err.contains("line 7"), "{err}");
    std::fs::write(&file, "name = \"bad\"\nruns = -3\n").unwrap();
    let out = petrinav(&[
        "lab",
        "run",
        file.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("runs") && err.contains("line 2"), "{err}");
}

#[test]
fn three_merged_shards_equal_the_unsharded_batch() {
    let whole = fresh("merge_whole");
    let out = run_voting(&whole, "2", "2", &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut parts = Vec::new();
    for i in 1..=3 {
        let part = fresh(&format!("merge_part{i}"));
        let out = run_voting(&part, "2", "1", &["--shard", &format!("{i}/3")]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert!(lines(&part.join("results.jsonl")) < 5 * 14 * 2);
        parts.push(part);
    }
    let merged = fresh("merge_out");
    let mut args = vec!["lab", "merge", merged.to_str().unwrap()];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    args.push("--no-pictures");
    let out = petrinav(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(
        std::fs::read(merged.join("results.jsonl")).unwrap(),
        std::fs::read(whole.join("results.jsonl")).unwrap(),
        "merged shards differ from the unsharded batch"
    );
    assert_eq!(
        std::fs::read(merged.join("tables.md")).unwrap(),
        std::fs::read(whole.join("tables.md")).unwrap()
    );
    // Two shards only: refused, the missing shard named, nothing written;
    // with --partial the missing runs are named, and resuming in the
    // merged folder completes the batch to the same file.
    let partial = fresh("merge_partial");
    let mut args = vec![
        "lab",
        "merge",
        partial.to_str().unwrap(),
        parts[0].to_str().unwrap(),
        parts[2].to_str().unwrap(),
        "--no-pictures",
    ];
    let out = petrinav(&args);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("shard 2/3: 0 of 47 runs done, no part holds it"),
        "{err}"
    );
    assert!(!partial.join("results.jsonl").exists());
    args.push("--partial");
    let out = petrinav(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("47 runs are in no part (shard 2/3: 0 of 47 done)"),
        "{err}"
    );
    let out = run_voting(&partial, "2", "2", &["--resume"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(
        std::fs::read(partial.join("results.jsonl")).unwrap(),
        std::fs::read(whole.join("results.jsonl")).unwrap()
    );
    // Parts of different batches are refused.
    let other = fresh("merge_other");
    assert!(run_voting(&other, "1", "2", &["--shard", "2/3"]).status.success());
    let out = petrinav(&[
        "lab",
        "merge",
        fresh("merge_refused").to_str().unwrap(),
        parts[0].to_str().unwrap(),
        other.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("not parts of the same batch"));
}
