//! `petrinav lab slurm` without a cluster: the scripts it writes run as
//! plain shell (as another scheduler would run them), a merge of an
//! incomplete batch names the shards and writes nothing, a part cut short
//! or never started is continued, and `--submit` calls `sbatch` (a fake
//! one here) for the array and then the merge after it. The same against
//! real Slurm daemons: `slurm_cluster.rs`.
#![cfg(unix)]

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn fresh(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("lab_slurm_{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn petrinav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

fn ok(out: Output) -> Output {
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs a written script with bash, as task `task` of the array if given.
fn bash(script: &Path, task: Option<u32>) -> Output {
    let mut cmd = Command::new("bash");
    cmd.arg(script).env_remove("SLURM_ARRAY_TASK_ID");
    if let Some(t) = task {
        cmd.env("SLURM_ARRAY_TASK_ID", t.to_string());
    }
    cmd.output().expect("bash runs")
}

/// Complete lines of a file.
fn lines(path: &Path) -> usize {
    std::fs::read(path).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count())
}

#[test]
fn the_scripts_run_as_plain_shell_and_an_incomplete_batch_is_named_then_completed() {
    let dir = fresh("shell");
    let whole = dir.join("whole");
    ok(petrinav(&[
        "lab",
        "run",
        "voting",
        "--runs",
        "2",
        "--no-pictures",
        "--out",
        whole.to_str().unwrap(),
    ]));
    let out = dir.join("campaign");
    let o = out.to_str().unwrap();
    let written = ok(petrinav(&[
        "lab",
        "slurm",
        "voting",
        "--runs",
        "2",
        "--shards",
        "3",
        "--no-pictures",
        "-o",
        o,
    ]));
    let (shards, merge) = (out.join("slurm/shards.sbatch"), out.join("slurm/merge.sbatch"));
    assert_eq!(
        String::from_utf8_lossy(&written.stdout),
        format!("{}\n{}\n", shards.display(), merge.display())
    );
    assert!(stderr(&written).contains("jobid=$(sbatch --parsable"));
    // Outside an array the script says what it needs.
    let alone = bash(&shards, None);
    assert!(!alone.status.success());
    assert!(stderr(&alone).contains("not an array task"), "{}", stderr(&alone));
    // Tasks 1 and 3; task 2 never started, then started and cut short.
    for task in [1, 3] {
        ok(bash(&shards, Some(task)));
    }
    let refused = |says: &str| {
        let m = bash(&merge, None);
        assert!(!m.status.success(), "merged an incomplete batch");
        let err = stderr(&m);
        assert!(err.contains(says), "{err}");
        assert!(err.contains("resubmit the array tasks 2)"), "{err}");
        assert!(err.contains("merge.sbatch: not merged"), "{err}");
        assert!(!out.join("results.jsonl").exists());
    };
    let per_shard = 47; // of shard 2: 140 campaigns make shards of 47, 47 and 46
    refused(&format!(
        "shard 2/3: 0 of {per_shard} runs done, no part holds it"
    ));
    std::fs::create_dir_all(out.join("part-2")).unwrap();
    refused("part-2: no results yet (no suite.json), left out");
    ok(bash(&shards, Some(2)));
    let part = out.join("part-2/results.jsonl");
    let text = std::fs::read_to_string(&part).unwrap();
    let kept: Vec<&str> = text.lines().take(10).collect();
    std::fs::write(
        &part,
        format!("{}\n{}", kept.join("\n"), &text.lines().nth(10).unwrap()[..20]),
    )
    .unwrap();
    refused(&format!("shard 2/3: 10 of {per_shard} runs done, in {o}/part-2"));
    // The wrong shard in a part's folder is refused; the right one continues.
    let wrong = petrinav(&[
        "lab",
        "run",
        "voting",
        "--runs",
        "2",
        "--shard",
        "3/3",
        "--resume",
        "--out",
        out.join("part-2").to_str().unwrap(),
    ]);
    assert!(!wrong.status.success());
    assert!(
        stderr(&wrong).contains("holds shard 2/3 of this batch, not shard 3/3"),
        "{}",
        stderr(&wrong)
    );
    let again = ok(bash(&shards, Some(2)));
    assert!(
        stderr(&again).contains(&format!(
            "{per_shard} runs (10 already done, {} now",
            per_shard - 10
        )),
        "{}",
        stderr(&again)
    );
    assert_eq!(lines(&part), per_shard);
    let merged = ok(bash(&merge, None));
    assert!(
        stderr(&merged).contains("140 runs merged from 3 folders"),
        "{}",
        stderr(&merged)
    );
    let results = std::fs::read(out.join("results.jsonl")).unwrap();
    assert!(
        results == std::fs::read(whole.join("results.jsonl")).unwrap(),
        "merged ≠ unsharded"
    );
    assert!(out.join("index.html").exists());
    // The merge again: nothing to do, the file as it was.
    let twice = ok(bash(&merge, None));
    assert!(
        stderr(&twice).contains("already holds these 140 runs"),
        "{}",
        stderr(&twice)
    );
    assert!(std::fs::read(out.join("results.jsonl")).unwrap() == results);
}

/// A fake `sbatch` in a folder of its own: it appends its arguments to
/// `calls` and prints a job id (40 + its call's number), or fails with
/// `fail` on its standard error.
fn fake_sbatch(dir: &Path, fail: Option<&str>) -> PathBuf {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let calls = dir.join("calls");
    let body = match fail {
        Some(message) => format!("echo '{message}' >&2\nexit 1"),
        None => "n=$(wc -l < \"$calls\")\ncase \"$*\" in *--dependency*) echo \"$((40 + n));cluster\" ;; *) echo \"$((40 + n))\" ;; esac".into(),
    };
    let path = bin.join("sbatch");
    std::fs::write(
        &path,
        format!(
            "#!/bin/sh\ncalls='{}'\necho \"$@\" >> \"$calls\"\n{body}\n",
            calls.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    bin
}

fn slurm_with(path: &Path, args: &[&str]) -> Output {
    let mut all = vec!["lab", "slurm", "voting", "--runs", "1"];
    all.extend_from_slice(args);
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(all)
        .env("PATH", format!("{}:/usr/bin:/bin", path.display()))
        .output()
        .unwrap()
}

#[test]
fn submit_queues_the_array_then_the_merge_after_it() {
    let dir = fresh("submit");
    let bin = fake_sbatch(&dir, None);
    let out = dir.join("o");
    let o = out.to_str().unwrap();
    let shards = out.join("slurm/shards.sbatch").display().to_string();
    let merge = out.join("slurm/merge.sbatch").display().to_string();
    let first = ok(slurm_with(&bin, &["--shards", "2", "-o", o, "--submit"]));
    let stdout = String::from_utf8_lossy(&first.stdout);
    assert!(
        stdout.contains("array job 41 (tasks 1-2 of 2)\nmerge job 42 (after job 41)\n"),
        "{stdout}"
    );
    let again = ok(slurm_with(
        &bin,
        &["--shards", "2", "-o", o, "--submit", "--array", "2"],
    ));
    assert!(String::from_utf8_lossy(&again.stdout).contains("array job 43 (tasks 2 of 2)"));
    // A task that is not in the array: refused before sbatch is called.
    let bad = slurm_with(&bin, &["--shards", "2", "-o", o, "--submit", "--array", "3"]);
    assert!(!bad.status.success());
    assert!(stderr(&bad).contains("there is no task 3"), "{}", stderr(&bad));
    let calls = std::fs::read_to_string(dir.join("calls")).unwrap();
    assert_eq!(
        calls,
        format!(
            "--parsable --array=1-2 {shards}\n--parsable --dependency=afterany:41 {merge}\n\
             --parsable --array=2 {shards}\n--parsable --dependency=afterany:43 {merge}\n"
        )
    );
    // --array only with --submit.
    let alone = slurm_with(&bin, &["--shards", "2", "-o", o, "--array", "2"]);
    assert!(
        !alone.status.success() && stderr(&alone).contains("--submit"),
        "{}",
        stderr(&alone)
    );
    // sbatch's own refusal is passed on; no sbatch at all is explained.
    let failing = fresh("submit_fails");
    let bin = fake_sbatch(&failing, Some("sbatch: error: invalid partition specified: nope"));
    let refused = slurm_with(
        &bin,
        &["--shards", "2", "-o", o, "--submit", "--partition", "nope"],
    );
    assert!(!refused.status.success());
    assert!(
        stderr(&refused).contains("invalid partition specified: nope"),
        "{}",
        stderr(&refused)
    );
    let nowhere = Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args([
            "lab", "slurm", "voting", "--runs", "1", "--shards", "2", "-o", o, "--submit",
        ])
        .env("PATH", failing.join("nothing"))
        .output()
        .unwrap();
    assert!(!nowhere.status.success());
    assert!(
        stderr(&nowhere).contains("is this a Slurm login node?"),
        "{}",
        stderr(&nowhere)
    );
}

#[test]
fn bad_options_are_refused_before_anything_is_written() {
    let dir = fresh("refused");
    let out = dir.join("o");
    let o = out.to_str().unwrap();
    let spaced = dir.join("o u t");
    for (args, says) in [
        (vec!["--shards", "2", "-o", o, "--time", "1h"], "Slurm's formats"),
        (vec!["--shards", "71", "-o", o], "at most --shards 70"),
        (
            vec!["--shards", "2", "-o", o, "--sbatch-option=--array=1"],
            "set --array themselves",
        ),
        (
            vec!["--shards", "2", "-o", o, "--sbatch-option=--time=5"],
            "use lab slurm --time",
        ),
        (
            vec!["--shards", "2", "-o", o, "--partition", "a b"],
            "a partition name",
        ),
        (
            vec!["--shards", "2", "-o", spaced.to_str().unwrap()],
            "cannot hold spaces",
        ),
        (vec!["--shards", "0", "-o", o], "0 is not in 1..="),
    ] {
        let mut all = vec!["lab", "slurm", "voting", "--runs", "1"];
        all.extend(args.iter().copied());
        let run = petrinav(&all);
        assert!(!run.status.success(), "{args:?}");
        assert!(stderr(&run).contains(says), "{args:?}: {}", stderr(&run));
        assert!(!stderr(&run).contains("panicked"));
    }
    assert!(!out.exists() && !spaced.exists());
    // A folder holding another batch, or this one in other shards.
    ok(petrinav(&[
        "lab", "slurm", "voting", "--runs", "1", "--shards", "2", "-o", o,
    ]));
    ok(petrinav(&[
        "lab",
        "run",
        "voting",
        "--runs",
        "1",
        "--shard",
        "1/2",
        "--out",
        out.join("part-1").to_str().unwrap(),
    ]));
    for (args, says) in [
        (vec!["--runs", "2", "--shards", "2"], "part-1 holds another batch"),
        (
            vec!["--runs", "1", "--shards", "3"],
            "part-1 holds shard 1/2 of this batch: give --shards 2",
        ),
    ] {
        let mut all = vec!["lab", "slurm", "voting", "-o", o];
        all.extend(args.iter().copied());
        let run = petrinav(&all);
        assert!(!run.status.success(), "{args:?}");
        assert!(stderr(&run).contains(says), "{args:?}: {}", stderr(&run));
    }
    ok(petrinav(&[
        "lab", "slurm", "voting", "--runs", "1", "--shards", "2", "-o", o,
    ]));
    let unknown = petrinav(&["lab", "slurm", "no_such_suite", "--shards", "2", "-o", o]);
    assert!(stderr(&unknown).contains("unknown suite"), "{}", stderr(&unknown));
}

#[test]
fn scenario_files_and_the_output_go_into_the_script_as_absolute_paths() {
    let dir = std::fs::canonicalize(fresh("paths")).unwrap();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    std::fs::create_dir_all(dir.join("mine")).unwrap();
    std::fs::copy(
        repo.join("crates/lab/src/suites/voting/scenarios/field03.toml"),
        dir.join("mine/field03.toml"),
    )
    .unwrap();
    ok(Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args([
            "lab",
            "slurm",
            "mine/field03.toml",
            "--runs",
            "2",
            "--shards",
            "1",
            "-o",
            "rel/out",
            "--cpus-per-task",
            "2",
        ])
        .current_dir(&dir)
        .output()
        .unwrap());
    let out = dir.join("rel/out");
    let script = std::fs::read_to_string(out.join("slurm/shards.sbatch")).unwrap();
    let file = dir.join("mine/field03.toml");
    let binary = std::fs::canonicalize(env!("CARGO_BIN_EXE_petrinav")).unwrap();
    for line in [
        format!(
            "lab run {} --runs 2 --jobs \"${{SLURM_CPUS_PER_TASK:-2}}\"",
            file.display()
        ),
        format!("\nout={}\n", out.display()),
        format!("#SBATCH --chdir={}\n", out.display()),
        format!("\npetrinav={}\n", binary.display()),
        "#SBATCH --cpus-per-task=2\n".into(),
        "#SBATCH --job-name=petrinav-".into(),
    ] {
        assert!(script.contains(&line), "no {line:?} in\n{script}");
    }
    // The task runs from anywhere: the paths in it are absolute.
    let task = Command::new("bash")
        .arg(out.join("slurm/shards.sbatch"))
        .env("SLURM_ARRAY_TASK_ID", "1")
        .current_dir("/")
        .output()
        .unwrap();
    let task = ok(task);
    assert!(
        stderr(&task).contains("2 runs (0 already done, 2 now"),
        "{}",
        stderr(&task)
    );
    assert_eq!(lines(&out.join("part-1/results.jsonl")), 2);
}
