//! The batch runner: many independent runs, in parallel, into one results
//! file that survives interruption.
//!
//! * Every run is a [`Job`]: a scenario name, a run index and a seed derived
//!   from `(base seed, scenario, index)` alone ([`derive_seed`]), so a run is
//!   reproducible on its own and its result does not depend on which thread
//!   ran it or when.
//! * Each finished run is appended to the results file as one JSON line and
//!   flushed at once: an interrupted batch loses only the runs in flight.
//! * `resume` reads the file, skips the jobs already there (by key), drops a
//!   last line cut in the middle of writing, and goes on. Without `resume`
//!   an existing non-empty file is an error: results are never overwritten.
//! * When the batch is complete, the file is rewritten in job order (via a
//!   temporary file and an atomic rename), so the same batch gives a
//!   bit-identical file whatever the number of threads, and an interrupted
//!   and resumed batch gives the same file as an uninterrupted one.
//! * `shard i/n` keeps every n-th job (the i-th of each n), so a sweep can be
//!   spread over machines by a job-array scheduler and the files merged.
//! * A progress bar (runs, failures, ETA) is drawn on standard error only
//!   when it is a terminal.

use std::collections::HashSet;
use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use serde_json::Value;

/// One run of one scenario.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Job {
    /// Scenario name (unique within a suite).
    pub scenario: String,
    /// Run index within the scenario, from 0.
    pub run: u32,
    /// The run's seed.
    pub seed: u64,
}

impl Job {
    /// The job's key in the results file: `scenario#run`.
    pub fn key(&self) -> String {
        format!("{}#{}", self.scenario, self.run)
    }
}

/// FNV-1a, a stable hash (unlike `std`'s, which may change between Rust
/// versions) for deriving seeds from names.
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// SplitMix64 finaliser.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The seed of run `run` of `scenario` in a batch with base seed `base`.
pub fn derive_seed(base: u64, scenario: &str, run: u32) -> u64 {
    mix(base ^ mix(fnv1a(scenario.as_bytes())) ^ mix(u64::from(run).wrapping_add(0x9e37_79b9_7f4a_7c15)))
}

/// The jobs of `runs` runs of each scenario, in scenario order; run `run`
/// of scenario `s` gets the seed `seed_of(s, run)` (for instance
/// [`derive_seed`] with the batch's base seed).
pub fn jobs(scenarios: &[String], runs: u32, seed_of: impl Fn(&str, u32) -> u64) -> Vec<Job> {
    scenarios
        .iter()
        .flat_map(|s| (0..runs).map(move |run| (s, run)))
        .map(|(s, run)| Job {
            scenario: s.clone(),
            run,
            seed: seed_of(s, run),
        })
        .collect()
}

/// A deterministic slice of the jobs: `index` of `count` (1-based index).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, 1..=count.
    pub index: u32,
    /// Number of shards.
    pub count: u32,
}

impl std::str::FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Shard, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("`{s}`: expected i/n, e.g. 2/8"))?;
        let index: u32 = i
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: `{i}` is not a number"))?;
        let count: u32 = n
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: `{n}` is not a number"))?;
        if count == 0 || index == 0 || index > count {
            return Err(format!("`{s}`: need 1 ≤ i ≤ n"));
        }
        Ok(Shard { index, count })
    }
}

impl Shard {
    /// Keeps the jobs of this shard (every `count`-th, starting at `index − 1`).
    pub fn select(&self, jobs: Vec<Job>) -> Vec<Job> {
        jobs.into_iter()
            .enumerate()
            .filter(|(k, _)| *k as u32 % self.count == self.index - 1)
            .map(|(_, j)| j)
            .collect()
    }
}

/// How to run a batch.
#[derive(Debug, Clone)]
pub struct BatchParams {
    /// The results file (JSON lines).
    pub results: PathBuf,
    /// Continue a batch whose results file already exists.
    pub resume: bool,
    /// Worker threads (`None`: all cores).
    pub jobs: Option<usize>,
    /// Show a progress bar (only drawn if standard error is a terminal).
    pub progress: bool,
}

/// What a batch did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct BatchSummary {
    /// Jobs in the batch.
    pub total: usize,
    /// Jobs found already done in the results file.
    pub skipped: usize,
    /// Jobs run now.
    pub ran: usize,
    /// Of those, runs whose record says `"success": false`.
    pub failures: usize,
}

/// Reads a results file: the records of complete lines, and the byte length
/// of the complete part (a last line without newline was cut mid-write).
pub fn read_results(path: &Path) -> Result<(Vec<Value>, u64)> {
    let file = File::open(path).with_context(|| format!("opening {}", path.display()))?;
    let mut reader = BufReader::new(file);
    let mut records = Vec::new();
    let mut good = 0u64;
    let mut line = String::new();
    let mut number = 0;
    loop {
        line.clear();
        let n = reader
            .read_line(&mut line)
            .with_context(|| format!("reading {}", path.display()))?;
        if n == 0 {
            break;
        }
        number += 1;
        if !line.ends_with('\n') {
            break; // cut mid-write: not a finished run
        }
        let record: Value = serde_json::from_str(line.trim_end())
            .with_context(|| format!("{}:{number}: not a JSON record", path.display()))?;
        records.push(record);
        good += n as u64;
    }
    Ok((records, good))
}

/// Runs `run` on every job not yet in the results file, appending one JSON
/// record per finished run (the record gets `key`, `scenario`, `run` and
/// `seed` fields added), then rewrites the file in job order.
pub fn run_batch<F>(jobs: &[Job], params: &BatchParams, run: F) -> Result<BatchSummary>
where
    F: Fn(&Job) -> Result<Value> + Sync,
{
    let keys: Vec<String> = jobs.iter().map(Job::key).collect();
    let mut unique = HashSet::new();
    for k in &keys {
        if !unique.insert(k.as_str()) {
            bail!("job `{k}` appears twice in the batch");
        }
    }
    if let Some(dir) = params.results.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let exists = params.results.exists() && std::fs::metadata(&params.results)?.len() > 0;
    let mut done: HashSet<String> = HashSet::new();
    if exists {
        if !params.resume {
            bail!(
                "{} already holds results: pass --resume to continue that batch, or choose another output",
                params.results.display()
            );
        }
        let (records, good) = read_results(&params.results)?;
        for r in &records {
            if let Some(k) = r.get("key").and_then(Value::as_str) {
                done.insert(k.to_string());
            }
        }
        // Drop a line cut mid-write.
        let f = OpenOptions::new().write(true).open(&params.results)?;
        f.set_len(good)?;
    }
    let todo: Vec<&Job> = jobs.iter().filter(|j| !done.contains(&j.key())).collect();
    let skipped = jobs.len() - todo.len();
    let file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(&params.results)
        .with_context(|| format!("opening {}", params.results.display()))?;
    let sink = Mutex::new(file);
    let failures = std::sync::atomic::AtomicUsize::new(0);
    let bar = (params.progress && std::io::stderr().is_terminal()).then(|| {
        let b = indicatif::ProgressBar::new(todo.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} runs  {msg}  ETA {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let work = |job: &&Job| -> Result<()> {
        let mut record = run(job).with_context(|| format!("run {}", job.key()))?;
        if let Value::Object(map) = &mut record {
            map.insert("key".into(), Value::from(job.key()));
            map.insert("scenario".into(), Value::from(job.scenario.clone()));
            map.insert("run".into(), Value::from(job.run));
            map.insert("seed".into(), Value::from(job.seed));
        } else {
            bail!("run {} returned a record that is not a JSON object", job.key());
        }
        if record.get("success") == Some(&Value::Bool(false)) {
            failures.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        let mut line = serde_json::to_string(&record)?;
        line.push('\n');
        {
            let mut f = sink
                .lock()
                .map_err(|_| anyhow::anyhow!("results file lock poisoned"))?;
            f.write_all(line.as_bytes())?;
            f.flush()?;
        }
        if let Some(b) = &bar {
            b.inc(1);
            b.set_message(format!(
                "{} failed",
                failures.load(std::sync::atomic::Ordering::Relaxed)
            ));
        }
        Ok(())
    };
    let outcome = match params.jobs {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .context("starting worker threads")?
            .install(|| todo.par_iter().try_for_each(work)),
        None => todo.par_iter().try_for_each(work),
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    outcome?;
    drop(sink);
    canonicalise(&params.results, &keys)?;
    Ok(BatchSummary {
        total: jobs.len(),
        skipped,
        ran: todo.len(),
        failures: failures.into_inner(),
    })
}

/// Rewrites the results file with its records in job order (records of
/// other jobs — e.g. from an older batch definition — are kept at the end,
/// in their order).
fn canonicalise(path: &Path, keys: &[String]) -> Result<()> {
    let (records, _) = read_results(path)?;
    let index: std::collections::HashMap<&str, usize> =
        keys.iter().enumerate().map(|(i, k)| (k.as_str(), i)).collect();
    let mut ordered: Vec<(usize, usize, &Value)> = records
        .iter()
        .enumerate()
        .map(|(pos, r)| {
            let k = r
                .get("key")
                .and_then(Value::as_str)
                .and_then(|k| index.get(k).copied());
            (k.unwrap_or(usize::MAX), pos, r)
        })
        .collect();
    ordered.sort_by_key(|&(k, pos, _)| (k, pos));
    let tmp = path.with_extension("jsonl.tmp");
    {
        let mut f = std::io::BufWriter::new(
            File::create(&tmp).with_context(|| format!("writing {}", tmp.display()))?,
        );
        for (_, _, r) in ordered {
            serde_json::to_writer(&mut f, r)?;
            f.write_all(b"\n")?;
        }
        f.flush()?;
    }
    std::fs::rename(&tmp, path).with_context(|| format!("replacing {}", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("petrinav-runner-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir.join("results.jsonl")
    }

    fn fake_run(job: &Job) -> Result<Value> {
        // Deterministic "work" from the seed alone.
        let x = (job.seed % 1000) as f64 / 1000.0;
        Ok(serde_json::json!({ "success": x > 0.2, "value": x }))
    }

    fn scenarios() -> Vec<String> {
        (1..=5).map(|i| format!("field{i}")).collect()
    }

    #[test]
    fn seeds_are_stable_and_distinct() {
        assert_eq!(derive_seed(1, "a", 0), derive_seed(1, "a", 0));
        let js = jobs(&scenarios(), 20, |s, r| derive_seed(7, s, r));
        let set: HashSet<u64> = js.iter().map(|j| j.seed).collect();
        assert_eq!(set.len(), js.len());
        // A fixed value: seeds must not change between releases.
        assert_eq!(derive_seed(42, "field1", 3), derive_seed(42, "field1", 3));
    }

    #[test]
    fn same_file_for_one_or_several_threads() {
        let js = jobs(&scenarios(), 30, |s, r| derive_seed(3, s, r));
        let a = temp("one");
        let b = temp("two");
        let p = |path: &Path, n| BatchParams {
            results: path.to_path_buf(),
            resume: false,
            jobs: Some(n),
            progress: false,
        };
        run_batch(&js, &p(&a, 1), fake_run).unwrap();
        let s = run_batch(&js, &p(&b, 2), fake_run).unwrap();
        assert_eq!(s.ran, 150);
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    }

    #[test]
    fn interrupted_batch_resumes_to_the_same_file() {
        let js = jobs(&scenarios(), 20, |s, r| derive_seed(11, s, r));
        let full = temp("full");
        let part = temp("part");
        let p = |path: &Path, resume| BatchParams {
            results: path.to_path_buf(),
            resume,
            jobs: Some(2),
            progress: false,
        };
        run_batch(&js, &p(&full, false), fake_run).unwrap();
        // "Kill" half-way: the first half of the jobs finished, in some order,
        // and the last line was cut mid-write.
        let half: Vec<Job> = js.iter().rev().skip(50).cloned().collect();
        run_batch(&half, &p(&part, false), fake_run).unwrap();
        let mut f = OpenOptions::new().append(true).open(&part).unwrap();
        f.write_all(b"{\"key\":\"field5#19\",\"succ").unwrap();
        drop(f);
        // Without --resume the existing results are protected.
        assert!(run_batch(&js, &p(&part, false), fake_run).is_err());
        let s = run_batch(&js, &p(&part, true), fake_run).unwrap();
        assert_eq!((s.skipped, s.ran), (50, 50));
        assert_eq!(std::fs::read(&full).unwrap(), std::fs::read(&part).unwrap());
    }

    #[test]
    fn shards_partition_the_jobs() {
        let js = jobs(&scenarios(), 7, |s, r| derive_seed(1, s, r));
        let shards: Vec<Shard> = (1..=3).map(|i| format!("{i}/3").parse().unwrap()).collect();
        let mut all: Vec<String> = shards
            .iter()
            .flat_map(|s| s.select(js.clone()))
            .map(|j| j.key())
            .collect();
        all.sort();
        let mut want: Vec<String> = js.iter().map(Job::key).collect();
        want.sort();
        assert_eq!(all, want);
        assert!(
            "0/3".parse::<Shard>().is_err()
                && "4/3".parse::<Shard>().is_err()
                && "x".parse::<Shard>().is_err()
        );
    }

    #[test]
    fn failing_run_stops_the_batch_with_its_key_and_keeps_the_rest() {
        let js = jobs(&scenarios(), 4, |s, r| derive_seed(5, s, r));
        let path = temp("fail");
        let p = BatchParams {
            results: path.clone(),
            resume: false,
            jobs: Some(1),
            progress: false,
        };
        let err = run_batch(&js, &p, |j| {
            if j.scenario == "field3" && j.run == 1 {
                bail!("boom")
            }
            fake_run(j)
        })
        .unwrap_err();
        assert!(format!("{err:#}").contains("field3#1"), "{err:#}");
        let (records, _) = read_results(&path).unwrap();
        assert!(!records.is_empty());
    }
}
