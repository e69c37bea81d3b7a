//! The README's test command, `scripts/test`: the README's first code block
//! names it, `.ci/run` calls it, and it checks what the tests need before
//! compiling anything.
//!
//! The behaviour tests run a copy of the script in a sandbox: a fresh
//! directory laid out as the repository (`scripts/test`, `crates/`) and a
//! `PATH` holding only fake `cargo`, `apt-get` or `chromium` that record
//! their calls, plus the few tools the script uses after its checks. No
//! real cargo, apt-get or browser is run.
#![cfg(unix)]

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(path)
}

/// The README's first ```sh block, its command lines without comments.
fn readme_commands() -> Vec<String> {
    let readme = std::fs::read_to_string(repo("README.md")).unwrap();
    let start = readme.find("```sh\n").expect("the README has a ```sh block") + "```sh\n".len();
    let end = start + readme[start..].find("```").unwrap();
    readme[start..end]
        .lines()
        .map(|l| l.split(" #").next().unwrap().trim().to_string())
        .filter(|l| !l.is_empty())
        .collect()
}

/// The README's test command: the second of the two commands at its top.
fn readme_test_command() -> String {
    let commands = readme_commands();
    assert_eq!(
        commands.len(),
        2,
        "the README opens with two commands, the main job and the tests: {commands:?}"
    );
    commands[1].clone()
}

#[test]
fn the_readme_opens_with_the_main_job_and_scripts_test() {
    let commands = readme_commands();
    assert!(commands[0].starts_with("cargo run --release -- "), "{commands:?}");
    assert_eq!(readme_test_command(), "scripts/test");
    let mode = std::fs::metadata(repo("scripts/test"))
        .unwrap()
        .permissions()
        .mode();
    assert!(mode & 0o111 != 0, "scripts/test is executable");
}

#[test]
fn ci_runs_the_readmes_test_command_and_no_tests_of_its_own() {
    let test_command = readme_test_command();
    let ci = std::fs::read_to_string(repo(".ci/run")).unwrap();
    let commands: Vec<&str> = ci
        .lines()
        .map(str::trim)
        .filter(|l| !l.starts_with('#') && !l.starts_with("echo "))
        .collect();
    assert!(
        commands.contains(&test_command.as_str()),
        ".ci/run does not run the README's test command `{test_command}`:\n{ci}"
    );
    assert!(
        !commands.iter().any(|l| l.contains("cargo test")),
        ".ci/run runs tests besides the README's test command:\n{ci}"
    );
}

/// A directory laid out as the repository with a copy of `scripts/test`,
/// and an empty `bin/` to serve as the whole `PATH`.
struct Sandbox {
    root: PathBuf,
}

impl Sandbox {
    fn new(name: &str) -> Sandbox {
        let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("test_command_{name}"));
        let _ = std::fs::remove_dir_all(&root);
        for dir in ["scripts", "crates", "bin"] {
            std::fs::create_dir_all(root.join(dir)).unwrap();
        }
        std::fs::copy(repo("scripts/test"), root.join("scripts/test")).unwrap();
        Sandbox { root }
    }

    /// A fake `name` on the PATH: it appends its arguments to `name.called`
    /// and then runs `body` (sh).
    fn fake(&self, name: &str, body: &str) {
        let path = self.root.join("bin").join(name);
        let called = self.root.join(format!("{name}.called"));
        std::fs::write(
            &path,
            format!("#!/bin/sh\necho \"$@\" >> '{}'\n{body}\n", called.display()),
        )
        .unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    }

    /// The real `tool` on the PATH too.
    fn real(&self, tool: &str) {
        std::os::unix::fs::symlink(on_path(tool), self.root.join("bin").join(tool)).unwrap();
    }

    /// The real tools the script runs once its checks pass (the checks
    /// themselves need none).
    fn real_tools_after_the_checks(&self) {
        for tool in ["mktemp", "tee", "awk", "sed", "rm", "grep"] {
            self.real(tool);
        }
    }

    /// A fake `mdbook` of the version the script pins.
    fn fake_pinned_mdbook(&self) {
        self.fake("mdbook", &format!("echo mdbook v{}", mdbook_version()));
    }

    /// What a fake was called with, one line a call; `None` if never.
    fn calls(&self, name: &str) -> Option<String> {
        std::fs::read_to_string(self.root.join(format!("{name}.called"))).ok()
    }

    /// Runs the script with `args` and nothing in its environment but the
    /// sandbox's PATH and `env`; its exit status, stdout, stderr and time.
    fn run(&self, args: &[&str], env: &[(&str, &str)]) -> (ExitStatus, String, String, Duration) {
        let started = Instant::now();
        let mut child = Command::new(on_path("bash"))
            .arg(self.root.join("scripts/test"))
            .args(args)
            .env_clear()
            .env("PATH", self.root.join("bin"))
            .envs(env.iter().copied())
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let status = loop {
            if let Some(status) = child.try_wait().unwrap() {
                break status;
            }
            if started.elapsed() > Duration::from_secs(60) {
                let _ = child.kill();
                panic!("scripts/test still runs after 60 s");
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        let elapsed = started.elapsed();
        let out = child.wait_with_output().unwrap();
        (
            status,
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
            elapsed,
        )
    }
}

/// `tool`'s path on this process's PATH.
fn on_path(tool: &str) -> PathBuf {
    std::env::split_paths(&std::env::var_os("PATH").unwrap())
        .map(|dir| dir.join(tool))
        .find(|p| p.is_file())
        .unwrap_or_else(|| panic!("no {tool} on PATH"))
}

/// The mdBook version `scripts/test` pins (its `MDBOOK_VERSION=` line).
fn mdbook_version() -> String {
    let script = std::fs::read_to_string(repo("scripts/test")).unwrap();
    script
        .lines()
        .find_map(|l| l.strip_prefix("MDBOOK_VERSION="))
        .expect("scripts/test pins MDBOOK_VERSION")
        .trim()
        .to_string()
}

fn is_root() -> bool {
    let out = Command::new("id").arg("-u").output().unwrap();
    String::from_utf8_lossy(&out.stdout).trim() == "0"
}

/// The message of a check that stopped the script: fast, before cargo.
fn assert_stopped_before_cargo(sandbox: &Sandbox, run: &(ExitStatus, String, String, Duration)) {
    let (status, _, stderr, elapsed) = run;
    assert!(!status.success(), "scripts/test succeeded: {stderr}");
    assert_eq!(sandbox.calls("cargo"), None, "scripts/test ran cargo: {stderr}");
    assert!(
        *elapsed < Duration::from_secs(10),
        "scripts/test took {elapsed:?} to stop"
    );
}

#[test]
fn without_chromium_nor_apt_get_it_stops_at_once_saying_what_to_install() {
    let sandbox = Sandbox::new("no_chromium");
    sandbox.fake("cargo", "");
    let run = sandbox.run(&[], &[]);
    assert_stopped_before_cargo(&sandbox, &run);
    let stderr = &run.2;
    assert!(stderr.contains("sudo apt-get install chromium"), "{stderr}");
    assert!(stderr.contains("PETRINAV_CHROMIUM=/path/to/chrome"), "{stderr}");
}

#[test]
fn without_chromium_it_installs_it_with_apt_get_as_root_only() {
    let sandbox = Sandbox::new("apt_get");
    sandbox.fake("cargo", "");
    // An apt-get that installs nothing: as root the script calls it, finds
    // no chromium still, and stops.
    sandbox.fake("apt-get", "");
    let run = sandbox.run(&[], &[]);
    assert_stopped_before_cargo(&sandbox, &run);
    let (_, _, stderr, _) = &run;
    if is_root() {
        let calls = sandbox.calls("apt-get").unwrap_or_default();
        assert!(calls.lines().any(|l| l.starts_with("update")), "{calls}");
        assert!(
            calls
                .lines()
                .any(|l| l.starts_with("install -y") && l.ends_with(" chromium")),
            "{calls}"
        );
        assert!(stderr.contains("still fails"), "{stderr}");
    } else {
        assert_eq!(sandbox.calls("apt-get"), None);
        assert!(stderr.contains("sudo apt-get install chromium"), "{stderr}");
    }
}

#[test]
fn a_petrinav_chromium_that_does_not_run_stops_it_and_installs_nothing() {
    let sandbox = Sandbox::new("bad_env");
    sandbox.fake("cargo", "");
    sandbox.fake("apt-get", "");
    sandbox.fake("chromium", "echo Chromium 1.0");
    let run = sandbox.run(&[], &[("PETRINAV_CHROMIUM", "/no/such/chrome")]);
    assert_stopped_before_cargo(&sandbox, &run);
    assert!(
        run.2.contains("PETRINAV_CHROMIUM=/no/such/chrome does not run"),
        "{}",
        run.2
    );
    assert_eq!(sandbox.calls("apt-get"), None);
}

#[test]
fn with_a_python_package_and_no_python_it_names_python3_venv_too() {
    let sandbox = Sandbox::new("python");
    sandbox.fake("cargo", "");
    std::fs::create_dir_all(sandbox.root.join("crates/py")).unwrap();
    std::fs::write(sandbox.root.join("crates/py/pyproject.toml"), "").unwrap();
    let run = sandbox.run(&[], &[]);
    assert_stopped_before_cargo(&sandbox, &run);
    assert!(
        run.2
            .contains("sudo apt-get install chromium python3 python3-venv"),
        "{}",
        run.2
    );
}

#[test]
fn with_chromium_it_runs_cargo_test_on_the_workspace_and_sums_up() {
    let sandbox = Sandbox::new("runs");
    sandbox.fake("chromium", "echo Chromium 1.0");
    sandbox.fake(
        "cargo",
        "echo 'test result: ok. 3 passed; 0 failed; 1 ignored; 0 measured; 0 filtered out; finished in 0.01s'\n\
         echo 'test a_real_cluster ... '\n\
         echo 'skipped: slurm_cluster (a real Slurm cluster): needs root'\n\
         echo 'ok'\n\
         echo 'test result: ok. 2 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 0.01s'",
    );
    sandbox.fake_pinned_mdbook();
    sandbox.real_tools_after_the_checks();
    let (status, stdout, stderr, _) = sandbox.run(&["--", "--nocapture"], &[]);
    assert!(status.success(), "{stdout}\n{stderr}");
    let calls = sandbox.calls("cargo").unwrap();
    assert_eq!(calls.trim(), "test --workspace --no-fail-fast -- --nocapture");
    let book = sandbox.calls("mdbook").unwrap();
    assert!(book.lines().any(|l| l == "build docs"), "{book}");
    assert!(stdout.contains("book     ok"), "{stdout}");
    assert!(stdout.contains("Chromium 1.0"), "{stdout}");
    assert!(
        stdout.contains("rust     ok  5 passed, 0 failed, 1 ignored"),
        "{stdout}"
    );
    assert!(stdout.contains("python   none"), "{stdout}");
    // A test skipped here (it printed why, past the harness's capture) is
    // named in the summary.
    let summary = &stdout[stdout.find("== summary").expect("a summary")..];
    assert!(
        summary.contains("rust     skipped: slurm_cluster (a real Slurm cluster): needs root"),
        "{summary}"
    );
}

#[test]
fn a_failing_cargo_test_fails_it_and_says_so_in_the_summary() {
    let sandbox = Sandbox::new("fails");
    sandbox.fake("chromium", "echo Chromium 1.0");
    sandbox.fake(
        "cargo",
        "echo 'test result: FAILED. 3 passed; 1 failed; 0 ignored; 0 measured; 0 filtered out; finished in 0.01s'\n\
         exit 101",
    );
    sandbox.fake_pinned_mdbook();
    sandbox.real_tools_after_the_checks();
    let (status, stdout, stderr, _) = sandbox.run(&[], &[]);
    assert_eq!(status.code(), Some(1), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("rust     FAILED  3 passed, 1 failed, 0 ignored"),
        "{stdout}"
    );
}

#[test]
fn without_the_pinned_mdbook_it_installs_it_with_cargo_before_the_tests() {
    let sandbox = Sandbox::new("mdbook");
    sandbox.fake("chromium", "echo Chromium 1.0");
    // An older mdbook on the PATH; `cargo install` puts the pinned one there.
    sandbox.fake("mdbook", "echo mdbook v0.4.0");
    let pinned = sandbox.root.join("bin/mdbook");
    sandbox.fake(
        "cargo",
        &format!(
            "if [ \"$1\" = install ]; then printf '#!/bin/sh\\necho mdbook v{}\\n' > '{}'; fi",
            mdbook_version(),
            pinned.display()
        ),
    );
    sandbox.real_tools_after_the_checks();
    let (status, stdout, stderr, _) = sandbox.run(&[], &[]);
    assert!(status.success(), "{stdout}\n{stderr}");
    let calls = sandbox.calls("cargo").unwrap();
    let lines: Vec<&str> = calls.lines().collect();
    assert!(
        lines[0].starts_with(&format!("install mdbook --locked --version {}", mdbook_version())),
        "{calls}"
    );
    assert!(lines[1].starts_with("test --workspace"), "{calls}");
    assert!(stdout.contains("installing mdBook"), "{stdout}");
}
