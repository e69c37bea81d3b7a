//! `petrinav lab slurm`: a batch as a Slurm job array of shards and a
//! merge job after it (the scripts and their submission in `lab::slurm`;
//! here the options, absolute paths and what is printed).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use lab::slurm::SlurmParams;

use crate::outln;

#[derive(Args, Debug)]
pub struct SlurmArgs {
    /// A suite (see `lab list`) or scenario files (.toml), as for `lab run`.
    #[arg(required = true)]
    what: Vec<String>,
    /// Shards, one task of the job array each (campaigns are never split).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    shards: u32,
    /// Runs per scenario (default: the suite's or the file's), as for `lab run`.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(lab::scenario::MAX_RUNS)))]
    runs: Option<u32>,
    /// The merged results folder (default: `out/<suite name>`); the shards write
    /// `part-<i>` in it, the scripts and logs go to its `slurm/`. It must be on a
    /// filesystem the nodes share.
    #[arg(long, short = 'o')]
    out: Option<PathBuf>,
    /// The partition (default: the cluster's).
    #[arg(long)]
    partition: Option<String>,
    /// The time limit of each task and of the merge, in Slurm's format (e.g. 30,
    /// 2:00:00, 1-12; default: the partition's).
    #[arg(long)]
    time: Option<String>,
    /// CPUs per task, also each task's worker threads.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    cpus_per_task: u32,
    /// The array's job name (default: `petrinav-<suite name>`); the merge's adds `-merge`.
    #[arg(long)]
    job_name: Option<String>,
    /// Another #SBATCH option for both scripts, in long form (repeatable), e.g.
    /// --sbatch-option=--mem=2G --sbatch-option=--account=lab.
    #[arg(long = "sbatch-option", value_name = "OPTION", allow_hyphen_values = true)]
    sbatch_options: Vec<String>,
    /// The petrinav binary the nodes run (default: this one). It must be where
    /// the nodes see it, at the same path.
    #[arg(long, value_name = "PATH")]
    petrinav: Option<PathBuf>,
    /// The merge skips the report's pictures.
    #[arg(long)]
    no_pictures: bool,
    /// Submit the scripts with `sbatch` (the array, then the merge after it)
    /// and print the job ids.
    #[arg(long)]
    submit: bool,
    /// With --submit: only these tasks of the array, in sbatch's --array syntax
    /// (e.g. 2, or 1,3-4), to run shards again that failed or were cut short;
    /// they continue where they stopped, and a new merge job follows them.
    #[arg(long, value_name = "TASKS", requires = "submit")]
    array: Option<String>,
}

/// `path` made absolute against the working directory (`..` and `.` left
/// as they are; the nodes resolve them the same way).
fn absolute(path: &Path) -> Result<PathBuf> {
    if path.is_absolute() {
        return Ok(path.to_path_buf());
    }
    Ok(std::env::current_dir()
        .context("reading the working directory")?
        .join(path))
}

/// Refuses an output folder that holds another batch, or parts of this
/// one cut into another number of shards: the tasks would refuse to
/// resume them only once queued.
fn check_out(out: &Path, info: &lab::suite::SuiteInfo, shards: u32) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(out) else {
        return Ok(()); // a new folder
    };
    let mut folders = vec![out.to_path_buf()];
    folders.extend(entries.flatten().map(|e| e.path()).filter(|p| {
        p.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with("part-"))
    }));
    for dir in folders.iter().filter(|d| d.join("suite.json").exists()) {
        if !lab::batch::read_info(dir)?.same_batch(info) {
            bail!(
                "{} holds another batch (suite, scenarios, runs or seed differ): choose another -o",
                dir.display()
            );
        }
        if let Some(shard) = lab::batch::read_shard(dir)?
            && shard.count != shards
        {
            bail!(
                "{} holds shard {shard} of this batch: give --shards {} as before, or choose another -o",
                dir.display(),
                shard.count
            );
        }
    }
    Ok(())
}

pub fn run(a: &SlurmArgs) -> Result<()> {
    // The suite is built here, once, to catch a wrong name, file or run
    // count before anything is queued.
    let suite = lab::suites::load(&a.what, a.runs)?;
    let info = suite.info();
    let campaigns = suite.campaigns().len();
    if a.shards as usize > campaigns {
        bail!(
            "{} shards for {campaigns} campaigns: some tasks would have nothing to run (at most --shards {campaigns})",
            a.shards
        );
    }
    // Scenario files by absolute path: the nodes start elsewhere.
    let what = if a.what.iter().all(|w| w.ends_with(".toml")) {
        a.what
            .iter()
            .map(|w| {
                std::fs::canonicalize(w)
                    .with_context(|| format!("finding {w}"))
                    .map(|p| p.display().to_string())
            })
            .collect::<Result<Vec<_>>>()?
    } else {
        a.what.clone()
    };
    let out = absolute(
        &a.out
            .clone()
            .unwrap_or_else(|| PathBuf::from("out").join(info.name.replace('/', "-"))),
    )?;
    let petrinav = match &a.petrinav {
        Some(p) => absolute(p)?,
        None => std::env::current_exe().context("finding this petrinav binary")?,
    };
    let mut params = SlurmParams {
        runs: a.runs,
        shards: a.shards,
        cpus_per_task: a.cpus_per_task,
        partition: a.partition.clone(),
        time: a.time.clone(),
        sbatch_options: a.sbatch_options.clone(),
        pictures: !a.no_pictures,
        ..SlurmParams::new(petrinav, out, what, &info.name)
    };
    if let Some(name) = &a.job_name {
        params.job_name = name.clone();
    }
    params.check()?;
    check_out(&params.out, info, a.shards)?;
    let scripts = params.write()?;
    outln!("{}", scripts.shards.display())?;
    outln!("{}", scripts.merge.display())?;
    if !a.submit {
        eprintln!(
            "wrote the job array ({} tasks) and its merge; submit them with --submit, or by hand:\n  jobid=$(sbatch --parsable {})\n  sbatch --dependency=afterany:\"${{jobid%%;*}}\" {}",
            a.shards,
            scripts.shards.display(),
            scripts.merge.display()
        );
        return Ok(());
    }
    let submitted = lab::slurm::submit(&scripts, a.shards, a.array.as_deref(), "sbatch".as_ref())?;
    outln!(
        "array job {} (tasks {} of {})",
        submitted.array_job,
        submitted.tasks,
        a.shards
    )?;
    outln!(
        "merge job {} (after job {})",
        submitted.merge_job,
        submitted.array_job
    )?;
    eprintln!(
        "logs: {}/shard-<task>.log and merge.log; results: {}",
        params.dir().display(),
        params.out.display()
    );
    Ok(())
}
