//! The bad-input corpus (`tests/bad_inputs/` at the repository root; its
//! README says how a case is written): every case's command run on its
//! files, its exit code and messages checked, all cases in one test so
//! that a failure lists every broken case at once.
//!
//! A case is one TOML file: the files it writes into a fresh folder
//! (inline text, or a repository file with edits), the command, the exit
//! code, and substrings its standard error (and, optionally, its standard
//! output) must hold; a case passing means the command ended with that
//! code, within its time limit, without a panic, saying what it must.
//! Adding a case is adding a file.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// At least this many cases (issue 51): the corpus may grow, not shrink
/// by accident.
const MIN_CASES: usize = 100;

/// A case's time limit when it sets none (a debug build, a shared
/// machine: generous; the release binary takes a fraction of it).
const DEFAULT_TIMEOUT_S: u64 = 60;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// One file a case writes.
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct FileSpec {
    /// Repository files whose bytes start the file, concatenated.
    #[serde(default)]
    from: Vec<String>,
    /// Text after them.
    #[serde(default)]
    text: String,
    /// Lines appended `times` times, `{i}` replaced by 0, 1, …
    #[serde(default)]
    repeat: String,
    #[serde(default)]
    times: usize,
    /// Text after the repeated lines.
    #[serde(default)]
    tail: String,
    /// `[old, new]` replacements, in order, each of which must match.
    #[serde(default)]
    replace: Vec<[String; 2]>,
    /// Keep only the first this many bytes.
    truncate: Option<usize>,
    /// Make a folder of this name instead of a file.
    #[serde(default)]
    folder: bool,
}

/// A case (README of the corpus).
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Case {
    /// What the case is about.
    about: String,
    /// The command's arguments, after `petrinav`; `{NAME}` is the path of
    /// the case's file NAME, `{dir}` its folder, `{repo}` the repository.
    args: Vec<String>,
    /// The exit code.
    exit: i32,
    /// Substrings standard error must hold.
    #[serde(default)]
    stderr: Vec<String>,
    /// Substrings standard output must hold.
    #[serde(default)]
    stdout: Vec<String>,
    /// Seconds the command may take.
    timeout_s: Option<u64>,
    /// The files, by name (relative to the case's folder).
    #[serde(default)]
    files: BTreeMap<String, FileSpec>,
}

fn cases(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            if p.file_name().is_some_and(|n| n != "fixtures") {
                cases(&p, out);
            }
        } else if p.extension().is_some_and(|e| e == "toml") {
            out.push(p);
        }
    }
}

fn write_file(root: &Path, dir: &Path, name: &str, spec: &FileSpec) -> Result<(), String> {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
    }
    if spec.folder {
        return std::fs::create_dir_all(&path).map_err(|e| format!("{}: {e}", path.display()));
    }
    let mut bytes = Vec::new();
    for f in &spec.from {
        let src = root.join(f);
        bytes.extend(std::fs::read(&src).map_err(|e| format!("`from` {}: {e}", src.display()))?);
    }
    bytes.extend(spec.text.as_bytes());
    for i in 0..spec.times {
        bytes.extend(spec.repeat.replace("{i}", &i.to_string()).as_bytes());
    }
    bytes.extend(spec.tail.as_bytes());
    if !spec.replace.is_empty() {
        let mut text = String::from_utf8(bytes).map_err(|_| format!("{name}: `replace` in a binary file"))?;
        for [old, new] in &spec.replace {
            if !text.contains(old.as_str()) {
                return Err(format!("{name}: `replace`: `{old}` is not in the file"));
            }
            text = text.replace(old.as_str(), new);
        }
        bytes = text.into_bytes();
    }
    if let Ok(text) = std::str::from_utf8(&bytes)
        && text.contains("_net}")
    {
        bytes = with_net_ids(text).into_bytes();
    }
    if let Some(n) = spec.truncate {
        bytes.truncate(n);
    }
    std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// `{source_net}` and `{credit_net}` replaced by the shipped supervisor
/// nets' ids, which mission logs name (so that the corpus's logs follow
/// the nets when they change).
fn with_net_ids(text: &str) -> String {
    use std::sync::OnceLock;
    static IDS: OnceLock<(String, String)> = OnceLock::new();
    let (source, credit) = IDS.get_or_init(|| {
        (
            guide::supervisor::Supervisor::new().unwrap().net_id().to_string(),
            guide::supervisor::credit::CreditSupervisor::new()
                .unwrap()
                .net_id()
                .to_string(),
        )
    });
    text.replace("{source_net}", source)
        .replace("{credit_net}", credit)
}

fn expand(arg: &str, dir: &Path, root: &Path, files: &BTreeMap<String, FileSpec>) -> String {
    let mut a = arg
        .replace("{dir}", &dir.display().to_string())
        .replace("{repo}", &root.display().to_string());
    for name in files.keys() {
        a = a.replace(&format!("{{{name}}}"), &dir.join(name).display().to_string());
    }
    a
}

/// Runs one case; `Err` says what went wrong.
fn run(path: &Path, root: &Path, scratch: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let case: Case = toml::from_str(&text).map_err(|e| format!("not a case: {e}"))?;
    if case.about.trim().is_empty() || (case.stderr.is_empty() && case.stdout.is_empty()) {
        return Err("a case says what it is about and what the command must say".into());
    }
    let rel = path.strip_prefix(root).unwrap_or(path);
    let dir = scratch.join(rel.with_extension("").to_string_lossy().replace('/', "__"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    for (name, spec) in &case.files {
        write_file(root, &dir, name, spec)?;
    }
    let args: Vec<String> = case
        .args
        .iter()
        .map(|a| expand(a, &dir, root, &case.files))
        .collect();
    let mut child = Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(&args)
        .current_dir(&dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot run petrinav: {e}"))?;
    // Read both pipes while waiting, so that a chatty command cannot block.
    let (mut out, mut err) = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let out_reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        std::io::Read::read_to_end(&mut out, &mut s).ok();
        s
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        std::io::Read::read_to_end(&mut err, &mut s).ok();
        s
    });
    let limit = Duration::from_secs(case.timeout_s.unwrap_or(DEFAULT_TIMEOUT_S));
    let started = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().map_err(|e| e.to_string())? {
            break s;
        }
        if started.elapsed() > limit {
            child.kill().ok();
            child.wait().ok();
            return Err(format!(
                "petrinav {} ran for more than {} s",
                args.join(" "),
                limit.as_secs()
            ));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stdout = String::from_utf8_lossy(&out_reader.join().unwrap()).into_owned();
    let stderr = String::from_utf8_lossy(&err_reader.join().unwrap()).into_owned();
    let mut wrong = Vec::new();
    if status.code() != Some(case.exit) {
        wrong.push(format!("exit code {:?}, expected {}", status.code(), case.exit));
    }
    if stderr.contains("panicked") || stderr.contains("RUST_BACKTRACE") {
        wrong.push("it panicked".into());
    }
    for s in &case.stderr {
        if !stderr.contains(s.as_str()) {
            wrong.push(format!("standard error lacks `{s}`"));
        }
    }
    for s in &case.stdout {
        if !stdout.contains(s.as_str()) {
            wrong.push(format!("standard output lacks `{s}`"));
        }
    }
    if wrong.is_empty() {
        // Keep only what failed for a look afterwards.
        let _ = std::fs::remove_dir_all(&dir);
        Ok(())
    } else {
        Err(format!(
            "{}\n    petrinav {}\n    stderr: {}\n    stdout: {}",
            wrong.join("; "),
            args.join(" "),
            stderr.trim_end().replace('\n', "\n            "),
            stdout
                .chars()
                .take(400)
                .collect::<String>()
                .trim_end()
                .replace('\n', "\n            ")
        ))
    }
}

#[test]
fn every_bad_input_of_the_corpus_gets_its_error() {
    let root = repo_root();
    let mut all = Vec::new();
    cases(&root.join("tests/bad_inputs"), &mut all);
    assert!(
        all.len() >= MIN_CASES,
        "{} cases in tests/bad_inputs, fewer than {MIN_CASES}",
        all.len()
    );
    let scratch = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bad_inputs");
    let queue = Mutex::new(all.iter());
    let failures = Mutex::new(Vec::new());
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get()).min(4);
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| {
                loop {
                    let Some(path) = queue.lock().unwrap().next() else {
                        break;
                    };
                    if let Err(why) = run(path, &root, &scratch) {
                        let rel = path.strip_prefix(&root).unwrap_or(path).display().to_string();
                        failures.lock().unwrap().push(format!("{rel}: {why}"));
                    }
                }
            });
        }
    });
    let mut failures = failures.into_inner().unwrap();
    failures.sort();
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        all.len(),
        failures.join("\n")
    );
}
