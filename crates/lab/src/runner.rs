//! The batch runner: many runs, in parallel, into one results file that
//! survives interruption.
//!
//! * Every run is a [`Job`]: a scenario name, a run index and a seed, so a
//!   run is reproducible on its own and its result does not depend on which
//!   thread ran it or when ([`derive_seed`] derives seeds from names).
//! * Jobs come in [`Campaign`]s: runs in sequence whose state carries over
//!   from one to the next (a robot that learns across missions). The run
//!   function receives the records of the campaign's earlier runs, in
//!   order, and rebuilds its state from them; campaigns run in parallel, the
//!   runs of one campaign one after the other. Independent runs are
//!   campaigns of one run.
//! * Each finished run is appended to the results file as one JSON line and
//!   flushed at once: an interrupted batch loses only the runs in flight.
//! * `resume` reads the file, skips the jobs already there (by key), drops a
//!   last line cut in the middle of writing, and goes on: a campaign
//!   restarts at its first missing run with its earlier runs read back from
//!   the file — the same records the uninterrupted batch handed on. Without
//!   `resume` an existing non-empty file is an error: results are never
//!   overwritten.
//! * When the batch is complete, the file is rewritten in job order (via a
//!   temporary file and an atomic rename), so the same batch gives a
//!   bit-identical file whatever the number of threads, and an interrupted
//!   and resumed batch gives the same file as an uninterrupted one.
//! * `shard i/n` keeps every n-th campaign (the i-th of each n), so a sweep
//!   can be spread over machines by a job-array scheduler; [`gather`] reads
//!   the shards' files back in job order and [`Gathered::write`] writes
//!   them as one ([`merge`] does both); the same merge done twice leaves
//!   the file as it is.
//! * A progress bar (runs, how many did not reach the goal, ETA) is drawn
//!   on standard error only when it is a terminal.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

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

/// Runs in sequence: each run gets the records of the campaign's earlier
/// runs (its carried state).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Campaign {
    /// The runs, in the order they run.
    pub jobs: Vec<Job>,
}

impl Campaign {
    /// A campaign of one independent run.
    pub fn single(job: Job) -> Campaign {
        Campaign { jobs: vec![job] }
    }

    /// Independent runs, each its own campaign.
    pub fn independent(jobs: Vec<Job>) -> Vec<Campaign> {
        jobs.into_iter().map(Campaign::single).collect()
    }
}

/// The keys of all jobs of the campaigns, in order: the order of a complete
/// results file.
pub fn keys(campaigns: &[Campaign]) -> Vec<String> {
    campaigns.iter().flat_map(|c| &c.jobs).map(Job::key).collect()
}

/// A deterministic slice of a batch: `index` of `count` (1-based index).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
    /// Keeps the campaigns of this shard (every `count`-th, starting at
    /// `index − 1`): a campaign is never split between shards.
    pub fn select(&self, campaigns: Vec<Campaign>) -> Vec<Campaign> {
        campaigns
            .into_iter()
            .enumerate()
            .filter(|(k, _)| self.holds(*k))
            .map(|(_, c)| c)
            .collect()
    }

    /// Whether the campaign at position `campaign` (from 0, in the batch's
    /// order) belongs to this shard.
    pub fn holds(&self, campaign: usize) -> bool {
        campaign as u64 % u64::from(self.count) == u64::from(self.index - 1)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
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
    /// Stops the batch when raised (from another thread, e.g. on Ctrl-C):
    /// no run starts after it, the runs in flight finish and are written,
    /// and the batch ends with [`Stopped`]; `resume` continues it.
    pub stop: Option<Arc<AtomicBool>>,
}

/// A batch stopped through [`BatchParams::stop`]: the results file holds
/// the runs finished so far, complete lines only.
#[derive(Debug, thiserror::Error)]
#[error("the batch was stopped on request; the runs finished so far are in {}: resume to continue", .results.display())]
pub struct Stopped {
    /// The results file.
    pub results: PathBuf,
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
    /// Of those, the runs that did not reach the goal (`"success": false`),
    /// counted by their record's `outcome` (`time_limit`, `collision`,
    /// `lost`, …; `unknown` when a record has none).
    pub not_reached: BTreeMap<String, usize>,
}

impl BatchSummary {
    /// Runs done now that did not reach the goal.
    pub fn not_reached_total(&self) -> usize {
        self.not_reached.values().sum()
    }

    /// The runs done now in words: `"3031 reached the goal, 469 did not
    /// (312 time limits, 140 collisions, 17 lost)"`.
    pub fn outcomes_in_words(&self) -> String {
        let missed = self.not_reached_total();
        let reached = self.ran - missed;
        if missed == 0 {
            return format!("{reached} reached the goal");
        }
        let causes: Vec<String> = self
            .not_reached
            .iter()
            .map(|(outcome, &n)| crate::tables::outcome_in_words(outcome, n))
            .collect();
        format!(
            "{reached} reached the goal, {missed} did not ({})",
            causes.join(", ")
        )
    }
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
        if !record.is_object() {
            bail!("{}:{number}: not a JSON object", path.display());
        }
        records.push(record);
        good += n as u64;
    }
    Ok((records, good))
}

/// The `key` of a results line.
fn key_of(record: &Value) -> Option<&str> {
    record.get("key").and_then(Value::as_str)
}

/// Checks that no key appears twice.
fn unique_keys(keys: &[String]) -> Result<()> {
    let mut unique = HashSet::new();
    for k in keys {
        if !unique.insert(k.as_str()) {
            bail!("job `{k}` appears twice in the batch");
        }
    }
    Ok(())
}

/// The runs already in the results file, by key (empty for a new file).
/// Refuses a file that holds results unless `--resume` was given, drops a
/// line cut mid-write, and refuses a campaign whose runs on file do not
/// form a prefix of it.
fn runs_on_file(campaigns: &[Campaign], params: &BatchParams) -> Result<HashMap<String, Value>> {
    let exists = params.results.exists() && std::fs::metadata(&params.results)?.len() > 0;
    let mut done: HashMap<String, Value> = HashMap::new();
    if exists {
        if !params.resume {
            bail!(
                "{} already holds results: pass --resume to continue that batch, or choose another output",
                params.results.display()
            );
        }
        let (records, good) = read_results(&params.results)?;
        for r in records {
            if let Some(k) = key_of(&r) {
                done.insert(k.to_string(), r);
            }
        }
        // Drop a line cut mid-write.
        let f = OpenOptions::new().write(true).open(&params.results)?;
        f.set_len(good)?;
    }
    // A campaign resumes at its first missing run; a run on file after a
    // missing one was not computed from the state this batch hands on.
    for c in campaigns {
        let first_missing = c.jobs.iter().position(|j| !done.contains_key(&j.key()));
        if let Some(m) = first_missing
            && let Some(later) = c.jobs[m..].iter().find(|j| done.contains_key(&j.key()))
        {
            bail!(
                "{}: run `{}` is there but the earlier run `{}` of its campaign is not; the file was edited or mixes batches",
                params.results.display(),
                later.key(),
                c.jobs[m].key()
            );
        }
    }
    Ok(done)
}

/// Runs `run` on every job not yet in the results file, appending one JSON
/// record per finished run (the record gets `key`, `scenario`, `run` and
/// `seed` fields added), then rewrites the file in job order.
///
/// `run(job, earlier)` gets the complete results lines of the campaign's
/// earlier runs, in order — the lines as written to the file and parsed
/// back, whether they were run now or read on resume, so a campaign's state
/// is the same either way, to the last bit.
pub fn run_batch<F>(campaigns: &[Campaign], params: &BatchParams, run: F) -> Result<BatchSummary>
where
    F: Fn(&Job, &[Value]) -> Result<Value> + Sync,
{
    let keys = keys(campaigns);
    unique_keys(&keys)?;
    if let Some(dir) = params.results.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let done = runs_on_file(campaigns, params)?;
    let todo = keys.iter().filter(|k| !done.contains_key(*k)).count();
    let skipped = keys.len() - todo;
    let file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(&params.results)
        .with_context(|| format!("opening {}", params.results.display()))?;
    let sink = Mutex::new(file);
    let not_reached: Mutex<BTreeMap<String, usize>> = Mutex::new(BTreeMap::new());
    let bar = (params.progress && std::io::stderr().is_terminal()).then(|| {
        let b = indicatif::ProgressBar::new(todo as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} runs  {msg}  ETA {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let one = |job: &Job, earlier: &[Value]| -> Result<Value> {
        let mut record = run(job, earlier).with_context(|| format!("run {}", job.key()))?;
        if let Value::Object(map) = &mut record {
            map.insert("key".into(), Value::from(job.key()));
            map.insert("scenario".into(), Value::from(job.scenario.clone()));
            map.insert("run".into(), Value::from(job.run));
            map.insert("seed".into(), Value::from(job.seed));
        } else {
            bail!("run {} returned a record that is not a JSON object", job.key());
        }
        let missed = if record.get("success") == Some(&Value::Bool(false)) {
            let outcome = record.get("outcome").and_then(Value::as_str).unwrap_or("unknown");
            let mut counts = not_reached
                .lock()
                .map_err(|_| anyhow::anyhow!("outcome counts lock poisoned"))?;
            *counts.entry(outcome.to_string()).or_default() += 1;
            Some(counts.values().sum::<usize>())
        } else {
            None
        };
        let mut line = serde_json::to_string(&record)?;
        // Hand on what the file holds, parsed back, so that a campaign's
        // later runs see the same numbers whether they follow now or after
        // a resume (serde_json's `float_roundtrip` makes the two equal).
        let record: Value = serde_json::from_str(&line)?;
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
            if let Some(n) = missed {
                b.set_message(format!("{n} did not reach the goal"));
            }
        }
        Ok(record)
    };
    let stopped = || params.stop.as_ref().is_some_and(|s| s.load(Ordering::Relaxed));
    let campaign = |c: &Campaign| -> Result<()> {
        let mut earlier: Vec<Value> = Vec::with_capacity(c.jobs.len());
        for job in &c.jobs {
            let record = match done.get(&job.key()) {
                Some(r) => r.clone(),
                None if stopped() => {
                    return Err(Stopped {
                        results: params.results.clone(),
                    }
                    .into());
                }
                None => one(job, &earlier)?,
            };
            earlier.push(record);
        }
        Ok(())
    };
    let outcome = match params.jobs {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .context("starting worker threads")?
            .install(|| campaigns.par_iter().try_for_each(campaign)),
        None => campaigns.par_iter().try_for_each(campaign),
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    outcome?;
    drop(sink);
    canonicalise(&params.results, &keys)?;
    Ok(BatchSummary {
        total: keys.len(),
        skipped,
        ran: todo,
        not_reached: not_reached
            .into_inner()
            .map_err(|_| anyhow::anyhow!("outcome counts lock poisoned"))?,
    })
}

/// Writes records to `path` in the order of `keys` (records of other keys —
/// e.g. from an older batch definition — at the end, in their order), via a
/// temporary file and an atomic rename.
fn write_ordered(path: &Path, records: &[Value], keys: &[String]) -> Result<()> {
    let index: HashMap<&str, usize> = keys.iter().enumerate().map(|(i, k)| (k.as_str(), i)).collect();
    let mut ordered: Vec<(usize, usize, &Value)> = records
        .iter()
        .enumerate()
        .map(|(pos, r)| {
            let k = key_of(r).and_then(|k| index.get(k).copied());
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

/// Rewrites the results file with its records in job order.
fn canonicalise(path: &Path, keys: &[String]) -> Result<()> {
    let (records, _) = read_results(path)?;
    write_ordered(path, &records, keys)
}

/// What [`merge`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct MergeSummary {
    /// Runs in the merged file.
    pub merged: usize,
    /// Runs found in more than one part, identical in each (kept once).
    pub duplicates: usize,
    /// Keys of the batch found in no part, in job order.
    pub missing: Vec<String>,
    /// The output already held exactly this merge (a merge run twice):
    /// nothing was written.
    pub unchanged: bool,
}

/// The runs of a sharded batch gathered from its parts' results files, in
/// job order, before anything is written ([`Gathered::write`]).
#[derive(Debug, Clone)]
pub struct Gathered {
    /// The records found, in job order.
    records: Vec<Value>,
    /// Runs found in more than one part, identical in each.
    pub duplicates: usize,
    /// Keys of the batch found in no part, in job order.
    pub missing: Vec<String>,
}

/// Reads the results files of the shards of one batch (`keys`, see
/// [`keys`]): every run once, in job order.
///
/// A run found in two parts must be identical in both; a record whose key
/// is not a job of the batch is an error (the parts belong to another
/// batch); a last line cut mid-write in a part is not a finished run and is
/// left out. Runs in no part are listed in [`Gathered::missing`].
pub fn gather(parts: &[PathBuf], keys: &[String]) -> Result<Gathered> {
    unique_keys(keys)?;
    let wanted: HashSet<&str> = keys.iter().map(String::as_str).collect();
    let mut found: HashMap<String, (Value, &Path)> = HashMap::new();
    let mut duplicates = 0;
    for part in parts {
        let (records, _) = read_results(part)?;
        for r in records {
            let k = key_of(&r)
                .with_context(|| format!("{}: a record without a key", part.display()))?
                .to_string();
            if !wanted.contains(k.as_str()) {
                bail!(
                    "{}: run `{k}` is not a job of this batch (the parts come from different batches?)",
                    part.display()
                );
            }
            match found.get(&k) {
                Some((same, _)) if *same == r => duplicates += 1,
                Some((_, first)) => bail!(
                    "run `{k}` differs between {} and {}: they come from different batches or versions",
                    first.display(),
                    part.display()
                ),
                None => {
                    found.insert(k, (r, part));
                }
            }
        }
    }
    let missing: Vec<String> = keys.iter().filter(|k| !found.contains_key(*k)).cloned().collect();
    let records: Vec<Value> = keys
        .iter()
        .filter_map(|k| found.remove(k))
        .map(|(r, _)| r)
        .collect();
    Ok(Gathered {
        records,
        duplicates,
        missing,
    })
}

impl Gathered {
    /// Runs found.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// Whether no run was found.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Writes the runs to `out` (via a temporary file and an atomic
    /// rename): the file an unsharded batch writes. An `out` that already
    /// holds results is refused, unless it holds exactly these (the same
    /// merge done before), which is left as it is.
    pub fn write(self, out: &Path) -> Result<MergeSummary> {
        let mut text = Vec::new();
        for r in &self.records {
            serde_json::to_writer(&mut text, r)?;
            text.push(b'\n');
        }
        let summary = |unchanged| MergeSummary {
            merged: self.records.len(),
            duplicates: self.duplicates,
            missing: self.missing.clone(),
            unchanged,
        };
        if out.exists() && std::fs::metadata(out)?.len() > 0 {
            if std::fs::read(out).with_context(|| format!("reading {}", out.display()))? == text {
                return Ok(summary(true));
            }
            bail!(
                "{} already holds other results: merge into a new folder",
                out.display()
            );
        }
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        // A temporary file of this process's own: two merges of the same
        // parts at once each rename a whole file into place.
        let tmp = out.with_extension(format!("jsonl.tmp{}", std::process::id()));
        std::fs::write(&tmp, &text).with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, out).with_context(|| format!("replacing {}", out.display()))?;
        Ok(summary(false))
    }
}

/// Merges the results files of the shards of one batch into `out`, in job
/// order (`keys`, see [`keys`]): the file an unsharded batch writes
/// ([`gather`], then [`Gathered::write`]). Runs in no part are listed in
/// the summary: resuming the batch in the merged folder completes it.
pub fn merge(parts: &[PathBuf], keys: &[String], out: &Path) -> Result<MergeSummary> {
    gather(parts, keys)?.write(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_says_how_many_runs_did_not_reach_the_goal_and_why() {
        let mut s = BatchSummary {
            total: 10,
            skipped: 2,
            ran: 8,
            not_reached: BTreeMap::new(),
        };
        assert_eq!(s.outcomes_in_words(), "8 reached the goal");
        s.not_reached = [("time_limit", 2), ("collision", 1), ("gave_up", 1)]
            .map(|(k, n)| (k.to_string(), n))
            .into();
        assert_eq!(
            s.outcomes_in_words(),
            "4 reached the goal, 4 did not (1 collision, 1 gave up, 2 time limits)"
        );
        assert!(!s.outcomes_in_words().contains("fail"));
    }

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
            stop: None,
        };
        run_batch(&Campaign::independent(js.clone()), &p(&a, 1), |j, _| fake_run(j)).unwrap();
        let s = run_batch(&Campaign::independent(js.clone()), &p(&b, 2), |j, _| fake_run(j)).unwrap();
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
            stop: None,
        };
        run_batch(&Campaign::independent(js.clone()), &p(&full, false), |j, _| {
            fake_run(j)
        })
        .unwrap();
        // "Kill" half-way: the first half of the jobs finished, in some order,
        // and the last line was cut mid-write.
        let half: Vec<Job> = js.iter().rev().skip(50).cloned().collect();
        run_batch(&Campaign::independent(half), &p(&part, false), |j, _| fake_run(j)).unwrap();
        let mut f = OpenOptions::new().append(true).open(&part).unwrap();
        f.write_all(b"{\"key\":\"field5#19\",\"succ").unwrap();
        drop(f);
        // Without --resume the existing results are protected.
        assert!(
            run_batch(&Campaign::independent(js.clone()), &p(&part, false), |j, _| {
                fake_run(j)
            })
            .is_err()
        );
        let s = run_batch(&Campaign::independent(js.clone()), &p(&part, true), |j, _| {
            fake_run(j)
        })
        .unwrap();
        assert_eq!((s.skipped, s.ran), (50, 50));
        assert_eq!(std::fs::read(&full).unwrap(), std::fs::read(&part).unwrap());
    }

    #[test]
    fn shards_partition_the_jobs() {
        let js = jobs(&scenarios(), 7, |s, r| derive_seed(1, s, r));
        let shards: Vec<Shard> = (1..=3).map(|i| format!("{i}/3").parse().unwrap()).collect();
        let mut all: Vec<String> = shards
            .iter()
            .flat_map(|s| s.select(Campaign::independent(js.clone())))
            .flat_map(|c| c.jobs)
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
            stop: None,
        };
        let err = run_batch(&Campaign::independent(js), &p, |j, _| {
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

    #[test]
    fn a_stopped_batch_keeps_complete_lines_and_resumes_to_the_same_file() {
        let js = jobs(&scenarios(), 10, |s, r| derive_seed(13, s, r));
        let (full, cut) = (temp("stop-full"), temp("stop-cut"));
        let p = |path: &Path, resume, stop| BatchParams {
            results: path.to_path_buf(),
            resume,
            jobs: Some(1),
            progress: false,
            stop,
        };
        run_batch(
            &Campaign::independent(js.clone()),
            &p(&full, false, None),
            |j, _| fake_run(j),
        )
        .unwrap();
        // Raised by the seventh run, as another thread would: no run starts after it.
        let flag = Arc::new(AtomicBool::new(false));
        let err = run_batch(
            &Campaign::independent(js.clone()),
            &p(&cut, false, Some(flag.clone())),
            |j, _| {
                if j.scenario == "field2" && j.run == 1 {
                    flag.store(true, Ordering::Relaxed);
                }
                fake_run(j)
            },
        )
        .unwrap_err();
        assert!(err.downcast_ref::<Stopped>().is_some(), "{err:#}");
        let text = std::fs::read_to_string(&cut).unwrap();
        assert!(text.ends_with('\n'));
        assert_eq!(text.lines().count(), 12);
        let s = run_batch(&Campaign::independent(js), &p(&cut, true, None), |j, _| {
            fake_run(j)
        })
        .unwrap();
        assert_eq!((s.skipped, s.ran), (12, 38));
        assert_eq!(std::fs::read(&full).unwrap(), std::fs::read(&cut).unwrap());
    }

    /// Three campaigns of four runs; each run's value is the previous one's
    /// plus a draw from its own seed: state carried from run to run.
    fn campaigns() -> Vec<Campaign> {
        (0..3)
            .map(|c| Campaign {
                jobs: (0..4)
                    .map(|run| Job {
                        scenario: format!("campaign{c}"),
                        run,
                        seed: derive_seed(9, &format!("campaign{c}"), run),
                    })
                    .collect(),
            })
            .collect()
    }

    fn learning_run(job: &Job, earlier: &[Value]) -> Result<Value> {
        assert_eq!(earlier.len(), job.run as usize, "earlier runs of {}", job.key());
        let before = earlier.last().map_or(0.0, |r| r["value"].as_f64().unwrap());
        Ok(serde_json::json!({ "success": true, "value": before + (job.seed % 100) as f64 }))
    }

    #[test]
    fn campaigns_carry_state_and_resume_at_their_first_missing_run() {
        let cs = campaigns();
        let p = |path: &Path, resume, jobs| BatchParams {
            results: path.to_path_buf(),
            resume,
            jobs: Some(jobs),
            progress: false,
            stop: None,
        };
        let full = temp("campaign-full");
        run_batch(&cs, &p(&full, false, 2), learning_run).unwrap();
        let (records, _) = read_results(&full).unwrap();
        let value = |k: &str| {
            records.iter().find(|r| r["key"] == k).unwrap()["value"]
                .as_f64()
                .unwrap()
        };
        assert_eq!(
            value("campaign1#3") - value("campaign1#2"),
            (derive_seed(9, "campaign1", 3) % 100) as f64
        );
        // Killed in the middle of campaign 1 (its run 2 failed), campaign 0
        // finished, campaign 2 not started (one worker).
        let cut = temp("campaign-cut");
        let err = run_batch(&cs, &p(&cut, false, 1), |j, e| {
            if j.key() == "campaign1#2" {
                bail!("killed")
            }
            learning_run(j, e)
        })
        .unwrap_err();
        assert!(format!("{err:#}").contains("campaign1#2"));
        let s = run_batch(&cs, &p(&cut, true, 2), learning_run).unwrap();
        assert_eq!((s.skipped, s.ran), (6, 6));
        assert_eq!(std::fs::read(&full).unwrap(), std::fs::read(&cut).unwrap());
        // A file with a hole inside a campaign is refused on resume.
        let holed = temp("campaign-hole");
        let text = std::fs::read_to_string(&full).unwrap();
        let kept: String = text
            .lines()
            .filter(|l| !l.contains("\"campaign2#1\""))
            .map(|l| format!("{l}\n"))
            .collect();
        std::fs::write(&holed, kept).unwrap();
        let err = format!(
            "{:#}",
            run_batch(&cs, &p(&holed, true, 1), learning_run).unwrap_err()
        );
        assert!(
            err.contains("campaign2#2") && err.contains("campaign2#1"),
            "{err}"
        );
    }

    #[test]
    fn merged_shards_equal_the_unsharded_batch() {
        let cs = campaigns();
        let p = |path: &Path| BatchParams {
            results: path.to_path_buf(),
            resume: false,
            jobs: Some(2),
            progress: false,
            stop: None,
        };
        let whole = temp("merge-whole");
        run_batch(&cs, &p(&whole), learning_run).unwrap();
        let mut parts = Vec::new();
        for i in 1..=3 {
            let shard = Shard { index: i, count: 3 };
            let part = temp(&format!("merge-part{i}"));
            run_batch(&shard.select(cs.clone()), &p(&part), learning_run).unwrap();
            parts.push(part);
        }
        let merged = temp("merge-out");
        std::fs::remove_file(&merged).ok();
        let s = merge(&parts, &keys(&cs), &merged).unwrap();
        assert_eq!(
            (s.merged, s.duplicates, s.missing.len(), s.unchanged),
            (12, 0, 0, false)
        );
        assert_eq!(std::fs::read(&whole).unwrap(), std::fs::read(&merged).unwrap());
        // The same merge again leaves the file as it is; merging other runs
        // into a file that holds results, or a part twice with a changed
        // record, is refused.
        let s = merge(&parts, &keys(&cs), &merged).unwrap();
        assert_eq!((s.merged, s.unchanged), (12, true));
        assert!(merge(&parts[..2], &keys(&cs), &merged).is_err());
        assert_eq!(std::fs::read(&whole).unwrap(), std::fs::read(&merged).unwrap());
        let changed = temp("merge-changed");
        let text = std::fs::read_to_string(&parts[0]).unwrap();
        std::fs::write(
            &changed,
            text.replacen("\"success\":true", "\"success\":false", 1),
        )
        .unwrap();
        let again = temp("merge-again");
        std::fs::remove_file(&again).ok();
        let err = format!(
            "{:#}",
            merge(&[parts[0].clone(), changed], &keys(&cs), &again).unwrap_err()
        );
        assert!(err.contains("differs"), "{err}");
        // Two shards of three: the third's runs are listed as missing.
        let partial = temp("merge-partial");
        std::fs::remove_file(&partial).ok();
        let s = merge(&parts[..2], &keys(&cs), &partial).unwrap();
        assert_eq!(
            s.missing,
            ["campaign2#0", "campaign2#1", "campaign2#2", "campaign2#3"]
        );
    }
}
