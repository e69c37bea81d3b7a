//! Reports speak plainly (issue 50, outcome 3): every suite of `petrinav lab
//! list` is run small and its report — `tables.md` and the text of
//! `index.html` — is scanned for
//!
//! - a run's outcome called a failure (`failed`, `failure`, `failures` as
//!   whole words): a run that does not reach the goal is said so, with its
//!   cause (a collision, the time limit, lost);
//! - a number printed with more than six significant digits
//!   (`0.0000666666666667`): rates and probabilities go through
//!   `lab::tables::sig`. Whole numbers are counts and are left alone.
//!
//! The heavy suites run one shard of one campaign set (`--shard`), then
//! `lab report` writes the report from that part: the same report code on
//! fewer runs.

use std::path::{Path, PathBuf};
use std::process::Command;

fn petrinav(args: &[&str]) -> std::process::Output {
    let out = Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs");
    assert!(
        out.status.success(),
        "petrinav {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("plain_reports_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The arguments that run `suite` small: a few runs, or for the suites
/// whose every run is a long mission, one shard of their campaigns.
fn small_run(suite: &str) -> Vec<&'static str> {
    match suite {
        "voting" | "deadlock" => vec!["--runs", "2"],
        "topo" => vec!["--runs", "1", "--shard", "1/3"],
        "maps" => vec!["--runs", "1", "--shard", "1/4"],
        "tourguide" => vec!["--runs", "1", "--shard", "1/12"],
        // A suite added later runs with one run per scenario.
        _ => vec!["--runs", "1"],
    }
}

/// The text of an HTML page: tags, scripts and styles removed, entities
/// of the few kinds the reports write decoded.
fn html_text(html: &str) -> String {
    let mut out = String::new();
    let mut rest = html;
    while let Some(k) = rest.find('<') {
        out.push_str(&rest[..k]);
        rest = &rest[k..];
        let skip_to = ["script", "style"].iter().find_map(|tag| {
            rest.get(1..=tag.len())
                .filter(|t| t.eq_ignore_ascii_case(tag))
                .map(|_| format!("</{tag}>"))
        });
        let end = match skip_to {
            Some(close) => rest.find(&close).map_or(rest.len(), |e| e + close.len()),
            None => rest.find('>').map_or(rest.len(), |e| e + 1),
        };
        out.push(' ');
        rest = &rest[end..];
    }
    out.push_str(rest);
    out.replace("&amp;", "&")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&#39;", "'")
}

/// Numbers in `text` with more than six significant digits: a run of
/// digits with a decimal point (and an optional exponent), its leading
/// zeros not counted. Whole numbers are counts and are skipped.
fn overlong_numbers(text: &str) -> Vec<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let starts = bytes[i].is_ascii_digit() && (i == 0 || !is_word(bytes[i - 1]));
        if !starts {
            i += 1;
            continue;
        }
        let start = i;
        while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
            i += 1;
        }
        // A sentence's full stop after a number is not a decimal point.
        let number = text[start..i].trim_end_matches('.');
        let in_word = i < bytes.len() && bytes[i].is_ascii_alphabetic() && bytes[i] != b'e';
        if number.contains('.') && !in_word {
            let significant = number
                .chars()
                .filter(char::is_ascii_digit)
                .skip_while(|&c| c == '0')
                .count();
            if significant > 6 {
                out.push(number.to_string());
            }
        }
    }
    out
}

fn is_word(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b'.'
}

/// Whole-word, case-insensitive `failed`, `failure` and `failures` in
/// `text`, each with some context.
fn outcomes_called_failures(text: &str) -> Vec<String> {
    let lower = text.to_lowercase();
    let word = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
    let mut out = Vec::new();
    for needle in ["failed", "failures", "failure"] {
        for (i, _) in lower.match_indices(needle) {
            let before = lower[..i].chars().next_back();
            let after = lower[i + needle.len()..].chars().next();
            if !word(before) && !word(after) {
                let from = lower[..i].char_indices().rev().nth(40).map_or(0, |(k, _)| k);
                let to = lower[i..]
                    .char_indices()
                    .nth(60)
                    .map_or(lower.len(), |(k, _)| i + k);
                out.push(text[from..to].to_string());
            }
        }
    }
    out
}

/// What a report's files say that they should not.
fn scan(dir: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    for (file, text) in [
        (
            "tables.md",
            std::fs::read_to_string(dir.join("tables.md")).unwrap(),
        ),
        (
            "index.html",
            html_text(&std::fs::read_to_string(dir.join("index.html")).unwrap()),
        ),
    ] {
        for n in overlong_numbers(&text) {
            problems.push(format!("{file}: {n} has more than 6 significant digits"));
        }
        for context in outcomes_called_failures(&text) {
            problems.push(format!("{file}: a run outcome called a failure: …{context}…"));
        }
    }
    problems
}

#[test]
fn every_suites_report_speaks_plainly() {
    let list = String::from_utf8(petrinav(&["lab", "list"]).stdout).unwrap();
    let suites: Vec<&str> = list.lines().filter_map(|l| l.split_whitespace().next()).collect();
    for expected in ["voting", "deadlock", "maps", "tourguide", "topo"] {
        assert!(suites.contains(&expected), "{list}");
    }
    let mut problems = Vec::new();
    for suite in suites {
        let dir = fresh(suite);
        let dir_s = dir.to_str().unwrap();
        let args = small_run(suite);
        // The `files` suite runs scenario files: one of the shipped ones.
        let field = format!(
            "{}/../lab/src/suites/voting/scenarios/field01.toml",
            env!("CARGO_MANIFEST_DIR")
        );
        let what = if suite == "files" { field.as_str() } else { suite };
        let mut run = vec!["lab", "run", what, "--no-pictures", "--out", dir_s];
        run.extend(&args);
        let out = petrinav(&run);
        let summary = String::from_utf8_lossy(&out.stderr);
        if !summary.contains("already done") || summary.contains("failed") {
            problems.push(format!("{suite}: run summary `{summary}`"));
        }
        if args.contains(&"--shard") {
            petrinav(&["lab", "report", dir_s, "--no-pictures"]);
        }
        problems.extend(scan(&dir).into_iter().map(|p| format!("{suite}: {p}")));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_scanner_finds_long_numbers_and_failures_and_leaves_the_rest() {
    assert_eq!(
        overlong_numbers("(0.0000666666666667 per visitor-second), 0.00817451, 1234567, v1.2345678x"),
        ["0.0000666666666667"]
    );
    assert!(overlong_numbers("12.5. Then 3.1415926.").len() == 1);
    assert!(overlong_numbers("at 6.67e-5 and 1.5e9, 2026-12-06").is_empty());
    assert_eq!(
        outcomes_called_failures("469 failed; failed_legs; Failures: 3; unfailing").len(),
        2
    );
    let text = html_text("<p>a &amp; b</p><script>var x = 0.123456789;</script><svg><text>0.5</text></svg>");
    assert_eq!(
        text.split_whitespace().collect::<Vec<_>>(),
        ["a", "&", "b", "0.5"]
    );
}
