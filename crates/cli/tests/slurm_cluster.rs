//! `petrinav lab slurm` against a real Slurm: a one-node cluster on
//! localhost (Debian's `munge` and `slurm-wlm`: munged as the `munge` user,
//! slurmctld and slurmd with a slurm.conf written here), on which
//!
//! 1. a 4-task array of `lab run voting --runs 4` and its merge job give
//!    the `results.jsonl` of the unsharded run, byte for byte;
//! 2. a task cancelled mid-run (`scancel` of one array element) leaves the
//!    merge job failing with the shard named, and that task submitted again
//!    (`--array 2`) continues its part: the merged file is again the
//!    unsharded one (of `voting --runs 20`, whose tasks run long enough to
//!    be cut); a task requeued mid-run (`scontrol requeue`, as pre-emption
//!    does) continues its part on its own;
//! 3. the scripts written with `--partition` and `--time` (and a relative
//!    `-o`) run as written on a partition that is not the default, with
//!    that time limit and working directory, and pass `shellcheck`.
//!
//! It needs root (munged runs as `munge`, slurmd as root) and the daemons;
//! as root with apt-get it installs `slurm-wlm`, `munge` and `shellcheck`
//! first (CI's fresh Debian machine). Elsewhere it is skipped, and says why
//! on the terminal (past the test harness's capture) in a line that
//! `scripts/test` repeats in its summary. The daemons listen on free ports
//! and keep their files, with the batches' results, in a folder of the
//! test process's own under the temporary directory, so runs of this test
//! in other checkouts do not meet; a guard stops them (jobs cancelled,
//! then SIGTERM, then SIGKILL) however the test ends, and removes the
//! folder unless the test failed. A later run kills what a test process
//! killed before its guard could left running, by the pid files and the
//! command lines that name its folder. Its time is in
//! `crates/lab/BENCHMARKS.md`.
#![cfg(unix)]

use std::collections::HashMap;
use std::io::Write as _;
use std::os::unix::fs::PermissionsExt;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Debian's packages the test installs when a tool is missing.
const PACKAGES: [&str; 3] = ["slurm-wlm", "munge", "shellcheck"];
/// The programs it runs.
const TOOLS: [&str; 9] = [
    "munged",
    "slurmctld",
    "slurmd",
    "sbatch",
    "scontrol",
    "scancel",
    "squeue",
    "sinfo",
    "shellcheck",
];
/// Where the clusters' folders go: `<temp>/PREFIX<test pid>`.
const PREFIX: &str = "petrinav-slurm-";
/// Runs of outcome 1's batch (`voting --runs 4`): 5 teams × 14 fields ×
/// 4 runs, one campaign each.
const RUNS: usize = 5 * 14 * 4;
/// Runs per scenario of outcome 2's batch, five times outcome 1's: a
/// task's 350 runs take long enough (about 2 s of one core here) to be
/// cancelled mid-run.
const LONG_RUNS: usize = 20;

/// Says on the terminal, past the harness's capture, that the test did not
/// run and why; `scripts/test` lists these lines in its summary.
fn skip(reason: &str) {
    let _ = writeln!(
        std::io::stderr(),
        "\nskipped: slurm_cluster (a real Slurm cluster): {reason}"
    );
}

fn note(text: &str) {
    let _ = writeln!(std::io::stderr(), "\nslurm_cluster: {text}");
}

/// `name` on the PATH or in the system's sbin folders.
fn find_tool(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin", "/usr/bin", "/sbin", "/bin"].map(PathBuf::from))
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

/// The tools, installed now if missing (as root with apt-get); otherwise
/// why the test cannot run here.
fn tools() -> Result<HashMap<&'static str, PathBuf>, String> {
    if !is_root() {
        return Err(
            "needs root, to start munged as the munge user and slurmd (run the tests as root, e.g. on CI)"
                .into(),
        );
    }
    let found = || -> HashMap<&'static str, PathBuf> {
        TOOLS
            .iter()
            .filter_map(|t| find_tool(t).map(|p| (*t, p)))
            .collect()
    };
    let mut tools = found();
    if tools.len() < TOOLS.len() {
        let missing: Vec<&str> = TOOLS
            .iter()
            .filter(|t| !tools.contains_key(*t))
            .copied()
            .collect();
        let Some(apt) = find_tool("apt-get") else {
            return Err(format!(
                "{} missing and no apt-get to install them (Debian's packages: {})",
                missing.join(", "),
                PACKAGES.join(" ")
            ));
        };
        let started = Instant::now();
        let apt_get = |args: &[&str]| {
            let out = Command::new(&apt)
                .args(["-o", "DPkg::Lock::Timeout=300", "-qq"])
                .args(args)
                .env("DEBIAN_FRONTEND", "noninteractive")
                .stdin(Stdio::null())
                .output()
                .expect("apt-get runs");
            assert!(
                out.status.success(),
                "apt-get {args:?} failed:\n{}\n{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
        };
        apt_get(&["update"]);
        let mut install = vec!["install", "-y", "--no-install-recommends"];
        install.extend(PACKAGES);
        apt_get(&install);
        note(&format!(
            "installed {} with apt-get in {:.1} s",
            PACKAGES.join(", "),
            started.elapsed().as_secs_f64()
        ));
        tools = found();
        let missing: Vec<&str> = TOOLS
            .iter()
            .filter(|t| !tools.contains_key(*t))
            .copied()
            .collect();
        assert!(missing.is_empty(), "still missing after apt-get: {missing:?}");
    }
    Ok(tools)
}

/// The uid and gid of a user in /etc/passwd.
fn user_ids(name: &str) -> (u32, u32) {
    let passwd = std::fs::read_to_string("/etc/passwd").unwrap();
    passwd
        .lines()
        .map(|l| l.split(':').collect::<Vec<_>>())
        .find(|f| f.len() > 3 && f[0] == name)
        .map(|f| (f[2].parse().unwrap(), f[3].parse().unwrap()))
        .unwrap_or_else(|| panic!("no user {name} (the munge package makes it)"))
}

/// Two distinct free TCP ports on the loopback (free when asked, both
/// held until both are chosen; the daemons take them a moment later).
fn free_ports() -> (u16, u16) {
    let bind = || std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let (a, b) = (bind(), bind());
    (a.local_addr().unwrap().port(), b.local_addr().unwrap().port())
}

fn alive(pid: u32) -> bool {
    Path::new(&format!("/proc/{pid}")).exists()
}

/// The command line of a process, if it runs.
fn cmdline(pid: u32) -> Option<String> {
    std::fs::read(format!("/proc/{pid}/cmdline"))
        .ok()
        .map(|b| String::from_utf8_lossy(&b).replace('\0', " "))
}

/// Sends `signal` to `pid`.
fn signal(pid: u32, signal: &str) {
    let _ = Command::new("kill")
        .args([&format!("-{signal}"), &pid.to_string()])
        .stderr(Stdio::null())
        .status();
}

/// Kills what clusters whose test process died before its guard stopped
/// them left running: the daemons named in their pid files, then any
/// process whose command line names their folder (munged in the
/// foreground writes no pid file; a job's `petrinav` writes into the
/// folder); then removes those folders.
fn clean_up_stale_clusters() {
    let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(owner) = name.strip_prefix(PREFIX).and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        if alive(owner) {
            continue;
        }
        let dir = entry.path();
        let named = |pid: u32| cmdline(pid).is_some_and(|c| c.contains(&dir.display().to_string()));
        let mut killed = Vec::new();
        for file in ["slurmd.pid", "slurmctld.pid", "munged.pid"] {
            let pid = std::fs::read_to_string(dir.join(file))
                .ok()
                .and_then(|p| p.trim().parse::<u32>().ok());
            if let Some(pid) = pid
                && named(pid)
            {
                note(&format!("killing {file} {pid} left by test process {owner}"));
                signal(pid, "KILL");
                killed.push(pid);
            }
        }
        let others: Vec<u32> = std::fs::read_dir("/proc")
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
            .filter(|&pid| !killed.contains(&pid) && named(pid))
            .collect();
        for pid in others {
            note(&format!(
                "killing {pid} ({}) left by test process {owner}",
                cmdline(pid).unwrap_or_default().trim()
            ));
            signal(pid, "KILL");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// This test process's folder: the cluster's files and the batches'
/// results (kept after a failure, for a look).
fn own_dir() -> PathBuf {
    clean_up_stale_clusters();
    let dir = std::env::temp_dir().join(format!("{PREFIX}{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("results")).unwrap();
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    dir
}

/// A one-node Slurm cluster on localhost; stopped on drop.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    tools: HashMap<&'static str, PathBuf>,
    daemons: Vec<(&'static str, Child)>,
}

impl Cluster {
    /// Starts the daemons, their files in `dir` ([`own_dir`]).
    fn start(dir: PathBuf, tools: HashMap<&'static str, PathBuf>) -> Cluster {
        for sub in ["munge", "state", "spool", "log"] {
            std::fs::create_dir_all(dir.join(sub)).unwrap();
        }
        let mut cluster = Cluster {
            conf: dir.join("slurm.conf"),
            dir,
            tools,
            daemons: Vec::new(),
        };
        cluster.start_munged();
        std::fs::write(&cluster.conf, cluster.slurm_conf()).unwrap();
        let conf = cluster.conf.display().to_string();
        let ctld = cluster.spawn("slurmctld", &["-D", "-i", "-f", &conf]);
        cluster.daemons.push(("slurmctld", ctld));
        let slurmd = cluster.spawn("slurmd", &["-D", "-f", &conf, "-N", "localhost"]);
        cluster.daemons.push(("slurmd", slurmd));
        cluster.wait_for_the_node();
        cluster
    }

    /// munged with a key of its own, as the `munge` user, its socket in
    /// the cluster's folder.
    fn start_munged(&mut self) {
        let (uid, gid) = user_ids("munge");
        let munge = self.dir.join("munge");
        let key = munge.join("key");
        let mut bytes = vec![0u8; 1024];
        std::io::Read::read_exact(&mut std::fs::File::open("/dev/urandom").unwrap(), &mut bytes).unwrap();
        std::fs::write(&key, bytes).unwrap();
        std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o400)).unwrap();
        // munged wants its folder and key its own, the socket's folder
        // open to all (execute only).
        std::os::unix::fs::chown(&key, Some(uid), Some(gid)).unwrap();
        std::os::unix::fs::chown(&munge, Some(uid), Some(gid)).unwrap();
        std::fs::set_permissions(&munge, std::fs::Permissions::from_mode(0o711)).unwrap();
        let path = |f: &str| format!("{}", munge.join(f).display());
        let child = Command::new(&self.tools["munged"])
            .args([
                "-F",
                &format!("--socket={}", path("socket")),
                &format!("--key-file={}", path("key")),
                &format!("--pid-file={}", self.dir.join("munged.pid").display()),
                &format!("--log-file={}", path("munged.log")),
                &format!("--seed-file={}", path("seed")),
            ])
            .uid(uid)
            .gid(gid)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(self.dir.join("log/munged.stderr")).unwrap())
            .spawn()
            .expect("munged starts");
        self.daemons.push(("munged", child));
        self.wait("munged's socket", Duration::from_secs(20), |c| {
            c.dir.join("munge/socket").exists()
        });
    }

    fn slurm_conf(&self) -> String {
        let d = self.dir.display();
        let (ctld, slurmd) = free_ports();
        format!(
            "ClusterName=petrinavtest\n\
             SlurmctldHost=localhost(127.0.0.1)\n\
             SlurmctldPort={ctld}\n\
             SlurmdPort={slurmd}\n\
             SlurmUser=root\n\
             SlurmdUser=root\n\
             AuthType=auth/munge\n\
             CredType=cred/munge\n\
             AuthInfo=socket={d}/munge/socket,cred_expire=10\n\
             StateSaveLocation={d}/state\n\
             SlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\n\
             SlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldLogFile={d}/log/slurmctld.log\n\
             SlurmdLogFile={d}/log/slurmd.log\n\
             ProctrackType=proctrack/linuxproc\n\
             TaskPlugin=task/none\n\
             JobAcctGatherType=jobacct_gather/none\n\
             AccountingStorageType=accounting_storage/none\n\
             JobCompType=jobcomp/none\n\
             MpiDefault=none\n\
             SwitchType=switch/none\n\
             SelectType=select/cons_tres\n\
             SelectTypeParameters=CR_CPU\n\
             SlurmdParameters=config_overrides\n\
             ReturnToService=2\n\
             KillWait=5\n\
             MinJobAge=3600\n\
             NodeName=localhost NodeAddr=127.0.0.1 CPUs=4 State=UNKNOWN\n\
             PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP\n\
             PartitionName=campaign Nodes=localhost MaxTime=10 State=UP\n",
        )
    }

    /// A daemon in the foreground, its output in the cluster's log folder.
    fn spawn(&self, tool: &str, args: &[&str]) -> Child {
        let log = |ext: &str| std::fs::File::create(self.dir.join(format!("log/{tool}.{ext}"))).unwrap();
        Command::new(&self.tools[tool])
            .args(args)
            .env("SLURM_CONF", &self.conf)
            .stdin(Stdio::null())
            .stdout(log("stdout"))
            .stderr(log("stderr"))
            .spawn()
            .unwrap_or_else(|e| panic!("{tool} starts: {e}"))
    }

    fn wait_for_the_node(&self) {
        self.wait("the node to be idle", Duration::from_secs(60), |c| {
            let out = c.slurm("sinfo", &["-h", "-o", "%T"]);
            String::from_utf8_lossy(&out.stdout)
                .lines()
                .any(|l| l.trim() == "idle")
        });
    }

    /// Waits until `ready`, failing with the daemons' logs after `limit`.
    fn wait(&self, what: &str, limit: Duration, ready: impl Fn(&Cluster) -> bool) {
        let started = Instant::now();
        while !ready(self) {
            for (name, child) in &self.daemons {
                // A daemon that ended is an error whatever we wait for.
                let pid = child.id();
                assert!(
                    alive(pid),
                    "{name} ended while waiting for {what}\n{}",
                    self.logs()
                );
            }
            assert!(
                started.elapsed() < limit,
                "no {what} after {limit:?}\n{}",
                self.logs()
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Runs a Slurm client command against this cluster.
    fn slurm(&self, tool: &str, args: &[&str]) -> Output {
        Command::new(&self.tools[tool])
            .args(args)
            .env("SLURM_CONF", &self.conf)
            .stdin(Stdio::null())
            .output()
            .unwrap_or_else(|e| panic!("{tool} runs: {e}"))
    }

    /// `petrinav` as a user on the login node: an environment holding
    /// only the PATH to Slurm's commands and the cluster's configuration
    /// (the jobs inherit it: no HOME, no cargo variables).
    fn petrinav(&self, cwd: &Path, args: &[&str]) -> Output {
        let sbatch_dir = self.tools["sbatch"].parent().unwrap().display().to_string();
        Command::new(env!("CARGO_BIN_EXE_petrinav"))
            .args(args)
            .current_dir(cwd)
            .env_clear()
            .env("PATH", format!("{sbatch_dir}:/usr/bin:/bin"))
            .env("SLURM_CONF", &self.conf)
            .stdin(Stdio::null())
            .output()
            .expect("petrinav runs")
    }

    /// Every record `scontrol show job` has for `id` (an array's tasks
    /// each), as key → value.
    fn jobs(&self, id: &str) -> Vec<HashMap<String, String>> {
        let out = self.slurm("scontrol", &["-o", "show", "job", id]);
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter(|l| l.starts_with("JobId="))
            .map(|l| {
                l.split_whitespace()
                    .filter_map(|kv| kv.split_once('='))
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect()
            })
            .collect()
    }

    /// Waits for every task of job `id` to end; its records.
    fn wait_ended(&self, id: &str, limit: Duration) -> Vec<HashMap<String, String>> {
        const ENDED: [&str; 9] = [
            "COMPLETED",
            "FAILED",
            "CANCELLED",
            "TIMEOUT",
            "NODE_FAIL",
            "OUT_OF_MEMORY",
            "PREEMPTED",
            "BOOT_FAIL",
            "DEADLINE",
        ];
        self.wait(&format!("end of job {id}"), limit, |c| {
            let jobs = c.jobs(id);
            !jobs.is_empty() && jobs.iter().all(|j| ENDED.contains(&j["JobState"].as_str()))
        });
        self.jobs(id)
    }

    /// The end of each daemon's log, for a failure's message.
    fn logs(&self) -> String {
        let mut text = String::new();
        for f in [
            "log/slurmctld.log",
            "log/slurmd.log",
            "log/slurmctld.stderr",
            "log/slurmd.stderr",
            "munge/munged.log",
        ] {
            let body = std::fs::read_to_string(self.dir.join(f)).unwrap_or_default();
            let tail: Vec<&str> = body.lines().rev().take(15).collect();
            text += &format!(
                "--- {f} (end)\n{}\n",
                tail.into_iter().rev().collect::<Vec<_>>().join("\n")
            );
        }
        text
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // The jobs first (their processes are slurmstepd's, not slurmd's).
        if self.daemons.len() == 3 {
            self.slurm("scancel", &["--user=root"]);
            let started = Instant::now();
            while started.elapsed() < Duration::from_secs(20)
                && !String::from_utf8_lossy(&self.slurm("squeue", &["-h"]).stdout)
                    .trim()
                    .is_empty()
            {
                std::thread::sleep(Duration::from_millis(200));
            }
        }
        for (name, child) in self.daemons.iter_mut().rev() {
            signal(child.id(), "TERM");
            let started = Instant::now();
            while child.try_wait().ok().flatten().is_none() && started.elapsed() < Duration::from_secs(10) {
                std::thread::sleep(Duration::from_millis(50));
            }
            if child.try_wait().ok().flatten().is_none() {
                note(&format!("{name} did not stop on SIGTERM: killed"));
                let _ = child.kill();
                let _ = child.wait();
            }
        }
        if std::thread::panicking() {
            note(&format!("the cluster's files are kept in {}", self.dir.display()));
        } else {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

fn ok(out: &Output, what: &str) -> String {
    assert!(
        out.status.success(),
        "{what} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The array's and the merge's job ids in what `lab slurm --submit` printed.
fn job_ids(stdout: &str) -> (String, String) {
    let id = |prefix: &str| {
        stdout
            .lines()
            .find_map(|l| l.strip_prefix(prefix))
            .and_then(|rest| rest.split_whitespace().next())
            .unwrap_or_else(|| panic!("no `{prefix}` in {stdout}"))
            .to_string()
    };
    (id("array job "), id("merge job "))
}

/// Complete lines of a file (a last line cut mid-write not counted).
fn lines(path: &Path) -> usize {
    std::fs::read(path).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count())
}

/// (array task, state) of each record, by task.
fn state(jobs: &[HashMap<String, String>]) -> Vec<(String, String)> {
    let mut states: Vec<(String, String)> = jobs
        .iter()
        .map(|j| {
            (
                j.get("ArrayTaskId").cloned().unwrap_or_default(),
                j["JobState"].clone(),
            )
        })
        .collect();
    states.sort_by_key(|(task, _)| (task.parse::<u32>().unwrap_or(u32::MAX), task.clone()));
    states
}

const BATCH: [&str; 6] = ["lab", "slurm", "voting", "--runs", "4", "--no-pictures"];

#[test]
fn a_job_array_on_a_real_slurm_merges_to_the_unsharded_batch() {
    let started = Instant::now();
    let tools = match tools() {
        Ok(t) => t,
        Err(reason) => return skip(&reason),
    };
    let installed = started.elapsed();
    let dir = own_dir();
    let base = dir.join("results");
    // The unsharded batches, beside the cluster's start.
    let reference = |runs: usize| {
        let whole = base.join(format!("whole-{runs}"));
        let child = Command::new(env!("CARGO_BIN_EXE_petrinav"))
            .args([
                "lab",
                "run",
                "voting",
                "--runs",
                &runs.to_string(),
                "--no-pictures",
                "--out",
            ])
            .arg(&whole)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        move || {
            let out = child.wait_with_output().unwrap();
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            let results = std::fs::read(whole.join("results.jsonl")).unwrap();
            assert_eq!(lines(&whole.join("results.jsonl")), RUNS / 4 * runs);
            results
        }
    };
    let (short, long) = (reference(4), reference(LONG_RUNS));
    let cluster = Cluster::start(dir, tools);
    let up = started.elapsed();
    let whole = short();

    outcome_1_the_array_and_its_merge(&cluster, &base, &whole);
    let one = started.elapsed();
    outcome_2_a_task_cancelled_and_submitted_again(&cluster, &base, &long());
    let two = started.elapsed();
    outcome_3_partition_time_and_shellcheck(&cluster, &base, &whole);
    let three = started.elapsed();
    drop(cluster);
    note(&format!(
        "tools ready after {:.1} s, cluster up after {:.1} s, outcome 1 done after {:.1} s, 2 after {:.1} s, 3 after {:.1} s, stopped after {:.1} s",
        installed.as_secs_f64(),
        up.as_secs_f64(),
        one.as_secs_f64(),
        two.as_secs_f64(),
        three.as_secs_f64(),
        started.elapsed().as_secs_f64()
    ));
}

/// Outcome 1: 4 tasks and the merge after them give the unsharded file.
fn outcome_1_the_array_and_its_merge(cluster: &Cluster, base: &Path, whole: &[u8]) {
    let out = base.join("o1");
    let o = out.to_str().unwrap();
    let mut args = BATCH.to_vec();
    args.extend(["--shards", "4", "-o", o, "--submit"]);
    let printed = ok(&cluster.petrinav(base, &args), "lab slurm --submit");
    let (array, merge) = job_ids(&printed);
    let merged = cluster.wait_ended(&merge, Duration::from_secs(240));
    let tasks = cluster.jobs(&array);
    assert_eq!(
        state(&tasks),
        (1..=4)
            .map(|i| (i.to_string(), "COMPLETED".to_string()))
            .collect::<Vec<_>>(),
        "{}",
        cluster.logs()
    );
    assert_eq!(
        state(&merged),
        [(String::new(), "COMPLETED".into())],
        "{}",
        log(&out, "merge.log")
    );
    assert!(
        std::fs::read(out.join("results.jsonl")).unwrap() == whole,
        "the merged results differ from the unsharded batch"
    );
    for i in 1..=4 {
        let part = out.join(format!("part-{i}/results.jsonl"));
        assert_eq!(lines(&part), RUNS / 4, "{}", part.display());
    }
}

fn log(out: &Path, name: &str) -> String {
    std::fs::read_to_string(out.join("slurm").join(name)).unwrap_or_default()
}

/// Outcome 2: task 2 cancelled mid-run and task 3 requeued mid-run; task
/// 3 continues on its own, the merge fails naming shard 2; task 2
/// submitted again continues and the new merge gives the unsharded file.
fn outcome_2_a_task_cancelled_and_submitted_again(cluster: &Cluster, base: &Path, whole: &[u8]) {
    let out = base.join("o2");
    let o = out.to_str().unwrap();
    let runs = LONG_RUNS.to_string();
    let per_task = RUNS / 4 * LONG_RUNS / 4;
    let mut args = vec!["lab", "slurm", "voting", "--runs", &runs, "--no-pictures"];
    args.extend(["--shards", "4", "-o", o, "--submit"]);
    let (array, merge) = job_ids(&ok(&cluster.petrinav(base, &args), "lab slurm --submit"));
    let part = out.join("part-2/results.jsonl");
    let started = Instant::now();
    while lines(&part) == 0 || lines(&out.join("part-3/results.jsonl")) == 0 {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "tasks 2 and 3 wrote nothing\n{}",
            cluster.logs()
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    ok(&cluster.slurm("scancel", &[&format!("{array}_2")]), "scancel");
    // Task 3 pre-empted as Slurm does it: killed and queued again.
    ok(
        &cluster.slurm("scontrol", &["requeue", &format!("{array}_3")]),
        "scontrol requeue",
    );
    let merged = cluster.wait_ended(&merge, Duration::from_secs(240));
    let tasks = cluster.jobs(&array);
    let cut = lines(&part);
    assert!(
        cut > 0 && cut < per_task,
        "task 2 should have been cut mid-run, has {cut} of {} runs",
        per_task
    );
    assert_eq!(
        state(&tasks),
        [
            ("1", "COMPLETED"),
            ("2", "CANCELLED"),
            ("3", "COMPLETED"),
            ("4", "COMPLETED")
        ]
        .map(|(a, b)| (a.to_string(), b.to_string())),
        "{}",
        cluster.logs()
    );
    assert_eq!(state(&merged), [(String::new(), "FAILED".into())]);
    let merge_log = log(&out, "merge.log");
    assert!(
        merge_log.contains(&format!(
            "shard 2/4: {cut} of {} runs done, in {o}/part-2",
            per_task
        )) && merge_log.contains("resubmit the array tasks 2)"),
        "{merge_log}"
    );
    assert!(
        !out.join("results.jsonl").exists(),
        "an incomplete merge wrote results"
    );
    // The requeued task ran again and continued its part.
    let requeued = log(&out, "shard-3.log");
    assert_eq!(requeued.matches("== shard 3/4").count(), 2, "{requeued}");
    let continued = requeued
        .split(&format!("{per_task} runs ("))
        .nth(1)
        .and_then(|rest| rest.split(' ').next()?.parse::<usize>().ok());
    assert!(
        continued.is_some_and(|done| done > 0 && done < per_task),
        "task 3 requeued mid-run should continue its part:\n{requeued}"
    );
    // Task 2 again, and a merge after it.
    args.extend(["--array", "2"]);
    let (again, merge) = job_ids(&ok(
        &cluster.petrinav(base, &args),
        "lab slurm --submit --array 2",
    ));
    let merged = cluster.wait_ended(&merge, Duration::from_secs(240));
    assert_eq!(state(&cluster.jobs(&again)), [("2".into(), "COMPLETED".into())]);
    assert_eq!(
        state(&merged),
        [(String::new(), "COMPLETED".into())],
        "{}",
        log(&out, "merge.log")
    );
    let shard_log = log(&out, "shard-2.log");
    assert_eq!(shard_log.matches("== shard 2/4").count(), 2, "{shard_log}");
    assert!(
        shard_log.contains(&format!("{} runs ({cut} already done", per_task)),
        "the second task did not continue the first's {cut} runs:\n{shard_log}"
    );
    assert!(
        std::fs::read(out.join("results.jsonl")).unwrap() == whole,
        "the merged results differ from the unsharded batch"
    );
}

/// Outcome 3: written with a partition, a time limit and a relative -o,
/// the scripts pass shellcheck and run as written.
fn outcome_3_partition_time_and_shellcheck(cluster: &Cluster, base: &Path, whole: &[u8]) {
    let out = base.join("o3");
    let mut args = BATCH.to_vec();
    args.extend([
        "--shards",
        "4",
        "-o",
        "o3",
        "--partition",
        "campaign",
        "--time",
        "5:00",
        "--submit",
    ]);
    let (array, merge) = job_ids(&ok(&cluster.petrinav(base, &args), "lab slurm --submit"));
    let merged = cluster.wait_ended(&merge, Duration::from_secs(240));
    let tasks = cluster.jobs(&array);
    for job in tasks.iter().chain(&merged) {
        assert_eq!(
            job["JobState"],
            "COMPLETED",
            "{job:?}\n{}",
            log(&out, "merge.log")
        );
        assert_eq!(job["Partition"], "campaign");
        assert_eq!(job["TimeLimit"], "00:05:00");
        assert_eq!(Path::new(&job["WorkDir"]), out);
    }
    assert_eq!(tasks.len(), 4);
    assert!(
        std::fs::read(out.join("results.jsonl")).unwrap() == whole,
        "the merged results differ from the unsharded batch"
    );
    for o in [base.join("o1"), out] {
        for script in ["shards.sbatch", "merge.sbatch"] {
            let path = o.join("slurm").join(script);
            let check = Command::new(&cluster.tools["shellcheck"])
                .arg(&path)
                .output()
                .unwrap();
            assert!(
                check.status.success(),
                "shellcheck {}:\n{}",
                path.display(),
                String::from_utf8_lossy(&check.stdout)
            );
        }
    }
}
