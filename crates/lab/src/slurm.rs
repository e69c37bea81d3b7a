//! A sharded batch as a Slurm job array: the scripts `petrinav lab slurm`
//! writes, and their submission.
//!
//! Two scripts go into `OUT/slurm/`:
//!
//! * `shards.sbatch`, a job array of `n` tasks: task `i` runs
//!   `lab run … --shard i/n --out OUT/part-i --resume`, so a task that
//!   failed, was cancelled or pre-empted continues where it stopped when it
//!   runs again;
//! * `merge.sbatch`, run after the whole array (`afterany`): `lab merge OUT
//!   OUT/part-*`, which refuses an incomplete batch and names the shards to
//!   run again.
//!
//! Every path in them is absolute (the binary, the output, the working
//! directory), since a compute node starts a job elsewhere than the login
//! node; the scripts are plain bash around `--shard`, so another scheduler
//! can run them by setting `SLURM_ARRAY_TASK_ID`. The choices are written
//! down in `docs/cluster.md`.
//!
//! ```
//! use lab::slurm::SlurmParams;
//!
//! let what = vec!["mysuite".to_string()];
//! let params = SlurmParams {
//!     runs: Some(4),
//!     shards: 4,
//!     partition: Some("batch".into()),
//!     time: Some("0:30:00".into()),
//!     ..SlurmParams::new("/opt/petrinav/bin/petrinav".into(), "/scratch/out".into(), what, "mysuite")
//! };
//! params.check()?;
//! let script = params.shards_script();
//! assert!(script.contains("#SBATCH --array=1-4\n"));
//! assert!(script.contains("--shard \"$task/$shards\" --out \"$out/part-$task\" --resume"));
//! assert!(params.merge_script().contains("lab merge \"$out\" \"${parts[@]}\""));
//! # Ok::<(), anyhow::Error>(())
//! ```

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

/// What `lab slurm` needs to write the scripts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SlurmParams {
    /// The `petrinav` binary the nodes run: an absolute path they see.
    pub petrinav: PathBuf,
    /// The suite, as `lab run` takes it: a name, or scenario files
    /// (absolute paths).
    pub what: Vec<String>,
    /// Runs per scenario (`None`: the suite's default).
    pub runs: Option<u32>,
    /// Shards, one array task each (at least 1).
    pub shards: u32,
    /// The merged results folder (absolute); the shards write
    /// `part-<i>` in it, the scripts and logs go to `slurm/`.
    pub out: PathBuf,
    /// CPUs per task (`--cpus-per-task`), also the task's worker threads
    /// (`lab run --jobs`). Default 1.
    pub cpus_per_task: u32,
    /// The partition (`--partition`), or the cluster's default.
    pub partition: Option<String>,
    /// The time limit of each task and of the merge (`--time`, Slurm's
    /// format: `MM`, `MM:SS`, `HH:MM:SS`, `D-HH`, `D-HH:MM`, `D-HH:MM:SS`),
    /// or the partition's default.
    pub time: Option<String>,
    /// The array's job name; the merge's is this with `-merge`.
    pub job_name: String,
    /// More `#SBATCH` options for both scripts, e.g. `--mem=2G`,
    /// `--account=lab`.
    pub sbatch_options: Vec<String>,
    /// Whether the merge draws the report's pictures.
    pub pictures: bool,
}

impl SlurmParams {
    /// The defaults for a binary, an output folder, the suite as `lab run`
    /// takes it, and the suite's name (the job name is `petrinav-<name>`,
    /// with characters other than letters, digits, `.`, `_` and `-`
    /// replaced by `-`).
    pub fn new(petrinav: PathBuf, out: PathBuf, what: Vec<String>, name: &str) -> SlurmParams {
        let name: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "._-".contains(c) {
                    c
                } else {
                    '-'
                }
            })
            .collect();
        SlurmParams {
            petrinav,
            what,
            runs: None,
            shards: 1,
            out,
            cpus_per_task: 1,
            partition: None,
            time: None,
            job_name: format!("petrinav-{name}"),
            sbatch_options: Vec::new(),
            pictures: true,
        }
    }

    /// The folder of the scripts and logs: `OUT/slurm`.
    pub fn dir(&self) -> PathBuf {
        self.out.join("slurm")
    }

    /// Checks what goes into the scripts: absolute paths that an `#SBATCH`
    /// line can hold, a time limit and a partition in Slurm's syntax, and
    /// options that the scripts do not set themselves.
    pub fn check(&self) -> Result<()> {
        for (what, path) in [
            ("the petrinav binary", &self.petrinav),
            ("the output folder", &self.out),
        ] {
            if !path.is_absolute() {
                bail!(
                    "{what} must be an absolute path for the nodes, not {}",
                    path.display()
                );
            }
            sbatch_word(what, &path.to_string_lossy())?;
        }
        if self.shards == 0 || self.cpus_per_task == 0 {
            bail!("--shards and --cpus-per-task must be at least 1");
        }
        if self.what.is_empty() {
            bail!("no suite to run");
        }
        if let Some(w) = self.what.iter().find(|w| w.chars().any(char::is_control)) {
            bail!("{w:?}: a suite name or scenario file with a control character cannot go into a script");
        }
        if let Some(p) = &self.partition
            && (p.is_empty() || !p.chars().all(|c| c.is_ascii_alphanumeric() || "._-,".contains(c)))
        {
            bail!(
                "--partition `{p}`: a partition name (letters, digits, `._-`; several separated by commas)"
            );
        }
        if let Some(t) = &self.time {
            check_time(t)?;
        }
        sbatch_word("--job-name", &self.job_name)?;
        for o in &self.sbatch_options {
            check_option(o)?;
        }
        Ok(())
    }

    /// The `#SBATCH` lines both scripts share, after the job name and
    /// before the log.
    fn common_options(&self) -> Vec<String> {
        let mut lines = vec![format!("--cpus-per-task={}", self.cpus_per_task)];
        if let Some(p) = &self.partition {
            lines.push(format!("--partition={p}"));
        }
        if let Some(t) = &self.time {
            lines.push(format!("--time={t}"));
        }
        lines.extend(self.sbatch_options.iter().cloned());
        lines.push(format!("--chdir={}", self.out.display()));
        lines
    }

    /// The lines every script starts its commands with: strict mode, the
    /// binary and output folder, and a check that the binary is there.
    fn prelude(&self, script: &str) -> String {
        format!(
            "set -euo pipefail\n\
             petrinav={petrinav}\n\
             out={out}\n\
             if [ ! -x \"$petrinav\" ]; then\n  \
             echo \"{script}: no petrinav binary at $petrinav on $(uname -n): install it where the nodes see it, or write the scripts again with lab slurm --petrinav PATH\" >&2\n  \
             exit 1\n\
             fi\n",
            petrinav = quote(&self.petrinav.to_string_lossy()),
            out = quote(&self.out.to_string_lossy()),
        )
    }

    /// `lab run`'s arguments for the batch, quoted for the shell.
    fn batch_args(&self) -> String {
        let mut args: Vec<String> = self.what.iter().map(|w| quote(w)).collect();
        if let Some(r) = self.runs {
            args.push(format!("--runs {r}"));
        }
        args.join(" ")
    }

    /// The job array: one shard per task.
    pub fn shards_script(&self) -> String {
        let dir = self.dir();
        let script = dir.join("shards.sbatch");
        let merge = dir.join("merge.sbatch");
        let n = self.shards;
        let mut text = format!(
            "#!/bin/bash\n\
             # One shard of a petrinav batch per task of a Slurm job array, written by\n\
             # `petrinav lab slurm`; docs/cluster.md explains it.\n\
             #\n\
             #   batch:   petrinav lab run {batch}, in {n} shards\n\
             #   results: {out}/part-<task>, merged into {out} by merge.sbatch\n\
             #\n\
             # Submit it, then the merge after it (`lab slurm … --submit` does both):\n\
             #   jobid=$(sbatch --parsable {script})\n\
             #   sbatch --dependency=afterany:\"${{jobid%%;*}}\" {merge}\n\
             # A task that failed or was cut short continues where it stopped when\n\
             # submitted again, e.g. task 2: sbatch --array=2 {script}\n\
             # (then the merge again, after that job).\n\
             #\n\
             # Without Slurm the tasks are plain shell, e.g. one after the other:\n\
             #   for i in $(seq {n}); do SLURM_ARRAY_TASK_ID=$i bash {script}; done\n",
            batch = self.batch_args(),
            out = self.out.display(),
            script = script.display(),
            merge = merge.display(),
        );
        text += &format!("#SBATCH --job-name={}\n", self.job_name);
        text += &format!("#SBATCH --array=1-{n}\n");
        for o in self.common_options() {
            text += &format!("#SBATCH {o}\n");
        }
        text += &format!(
            "#SBATCH --output={}\n",
            slurm_pattern(&dir.join("shard-")) + "%a.log"
        );
        text += "#SBATCH --open-mode=append\n";
        text += &self.prelude("shards.sbatch");
        text += &format!(
            "shards={n}\n\
             task=${{SLURM_ARRAY_TASK_ID:?not an array task: submit this script with sbatch, or set SLURM_ARRAY_TASK_ID to a shard from 1 to {n}}}\n\
             echo \"== shard $task/$shards, job ${{SLURM_JOB_ID:-none}} on $(uname -n), $(date -u +%Y-%m-%dT%H:%M:%SZ)\"\n\
             exec \"$petrinav\" lab run {batch} --jobs \"${{SLURM_CPUS_PER_TASK:-{cpus}}}\" \\\n  \
             --shard \"$task/$shards\" --out \"$out/part-$task\" --resume\n",
            batch = self.batch_args(),
            cpus = self.cpus_per_task,
        );
        text
    }

    /// The merge, to run after the whole array.
    pub fn merge_script(&self) -> String {
        let dir = self.dir();
        let shards = dir.join("shards.sbatch");
        let mut text = format!(
            "#!/bin/bash\n\
             # The merge of the shards of a petrinav batch, to run after the job array\n\
             # of shards.sbatch has ended (`sbatch --dependency=afterany:ARRAY_JOB`);\n\
             # written by `petrinav lab slurm`, docs/cluster.md explains it.\n\
             #\n\
             # It writes {out}/results.jsonl (the file an unsharded batch writes) and\n\
             # the report, or, when a shard is incomplete, says which and writes nothing:\n\
             # submit those tasks again (sbatch --array=TASKS {shards}), then this\n\
             # script after them.\n",
            out = self.out.display(),
            shards = shards.display(),
        );
        text += &format!("#SBATCH --job-name={}-merge\n", self.job_name);
        for o in self.common_options() {
            text += &format!("#SBATCH {o}\n");
        }
        text += &format!("#SBATCH --output={}\n", slurm_pattern(&dir.join("merge.log")));
        text += "#SBATCH --open-mode=append\n";
        text += &self.prelude("merge.sbatch");
        text += &format!(
            "shopt -s nullglob\n\
             parts=(\"$out\"/part-*)\n\
             if [ ${{#parts[@]}} -eq 0 ]; then\n  \
             echo \"merge.sbatch: no part folder in $out: no shard has started\" >&2\n  \
             exit 1\n\
             fi\n\
             echo \"== merge of ${{#parts[@]}} parts, job ${{SLURM_JOB_ID:-none}} on $(uname -n), $(date -u +%Y-%m-%dT%H:%M:%SZ)\"\n\
             if ! \"$petrinav\" lab merge \"$out\" \"${{parts[@]}}\"{pictures}; then\n  \
             echo \"merge.sbatch: not merged. Submit the array tasks named above again: sbatch --array=TASKS $out/slurm/shards.sbatch, then this script after them; or add --array TASKS --submit to your lab slurm command.\" >&2\n  \
             exit 1\n\
             fi\n",
            pictures = if self.pictures { "" } else { " --no-pictures" },
        );
        text
    }

    /// Writes `shards.sbatch` and `merge.sbatch` into `OUT/slurm/`
    /// (replacing earlier ones: jobs already submitted keep the copy
    /// `sbatch` took).
    pub fn write(&self) -> Result<Scripts> {
        self.check()?;
        let dir = self.dir();
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        let scripts = Scripts {
            shards: dir.join("shards.sbatch"),
            merge: dir.join("merge.sbatch"),
        };
        for (path, text) in [
            (&scripts.shards, self.shards_script()),
            (&scripts.merge, self.merge_script()),
        ] {
            std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755))
                    .with_context(|| format!("making {} executable", path.display()))?;
            }
        }
        Ok(scripts)
    }
}

/// The two scripts written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Scripts {
    /// The job array.
    pub shards: PathBuf,
    /// The merge.
    pub merge: PathBuf,
}

/// The jobs [`submit`] queued.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Submitted {
    /// The array job's id.
    pub array_job: String,
    /// The array's tasks submitted (`1-n`, or the `--array` asked for).
    pub tasks: String,
    /// The merge job's id.
    pub merge_job: String,
}

/// Submits the array (all `shards` tasks, or those of `array`, in Slurm's
/// `--array` syntax) with `sbatch --parsable`, then the merge with a
/// dependency `afterany` on it.
pub fn submit(scripts: &Scripts, shards: u32, array: Option<&str>, sbatch: &OsStr) -> Result<Submitted> {
    let tasks = match array {
        Some(a) => {
            check_array(a, shards)?;
            a.to_string()
        }
        None => format!("1-{shards}"),
    };
    let array_job = sbatch_parsable(sbatch, &[format!("--array={tasks}")], &scripts.shards)?;
    let merge_job = sbatch_parsable(sbatch, &[format!("--dependency=afterany:{array_job}")], &scripts.merge)
        .with_context(|| {
            format!(
                "the array job {array_job} is queued but not its merge: submit it with `sbatch --dependency=afterany:{array_job} {}`",
                scripts.merge.display()
            )
        })?;
    Ok(Submitted {
        array_job,
        tasks,
        merge_job,
    })
}

/// Runs `sbatch --parsable ARGS SCRIPT` and reads the job id it prints
/// (`id` or `id;cluster`).
fn sbatch_parsable(sbatch: &OsStr, args: &[String], script: &Path) -> Result<String> {
    let shown = Path::new(sbatch).display().to_string();
    let out = Command::new(sbatch)
        .arg("--parsable")
        .args(args)
        .arg(script)
        .output()
        .with_context(|| {
            format!(
                "running `{shown}`: is this a Slurm login node? The scripts are written; submit them by hand"
            )
        })?;
    if !out.status.success() {
        bail!(
            "`{shown} {} {}` failed ({}): {}",
            args.join(" "),
            script.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    parse_job_id(&String::from_utf8_lossy(&out.stdout))
}

/// The job id in what `sbatch --parsable` printed: `id` or `id;cluster`.
pub fn parse_job_id(printed: &str) -> Result<String> {
    let line = printed
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("");
    let id = line.split(';').next().unwrap_or("");
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        bail!("sbatch --parsable printed `{}`, not a job id", printed.trim());
    }
    Ok(id.to_string())
}

/// Checks an `--array` value against `shards`: indices, ranges `a-b`
/// (with an optional step `:s`) separated by commas, an optional `%k` (at
/// most `k` tasks at once); every index from 1 to `shards`.
pub fn check_array(spec: &str, shards: u32) -> Result<()> {
    let bad =
        |why: String| anyhow::anyhow!("--array `{spec}`: {why}; e.g. 2, 1,3 or 2-4 (tasks 1 to {shards})");
    let (list, limit) = spec.split_once('%').map_or((spec, None), |(l, k)| (l, Some(k)));
    if let Some(k) = limit
        && !matches!(k.parse::<u32>(), Ok(k) if k > 0)
    {
        return Err(bad(format!("`%{k}` is not a positive number of tasks")));
    }
    let index = |s: &str| -> Result<u32> {
        let i: u32 = s
            .parse()
            .map_err(|_| bad(format!("`{s}` is not a task number")))?;
        if i == 0 || i > shards {
            return Err(bad(format!("there is no task {i}")));
        }
        Ok(i)
    };
    for item in list.split(',') {
        let (range, step) = item.split_once(':').map_or((item, None), |(r, s)| (r, Some(s)));
        match range.split_once('-') {
            Some((a, b)) => {
                if index(a)? > index(b)? {
                    return Err(bad(format!("`{range}` is an empty range")));
                }
            }
            None => {
                index(range)?;
            }
        }
        if let Some(s) = step
            && !matches!(s.parse::<u32>(), Ok(s) if s > 0)
        {
            return Err(bad(format!("`:{s}` is not a positive step")));
        }
    }
    Ok(())
}

/// Checks a time limit in Slurm's formats: `MM`, `MM:SS`, `HH:MM:SS`,
/// `D-HH`, `D-HH:MM`, `D-HH:MM:SS`, or `UNLIMITED`/`INFINITE`.
pub fn check_time(t: &str) -> Result<()> {
    if t.eq_ignore_ascii_case("unlimited") || t.eq_ignore_ascii_case("infinite") {
        return Ok(());
    }
    let numbers = |s: &str| {
        !s.is_empty()
            && s.split(':')
                .all(|n| !n.is_empty() && n.chars().all(|c| c.is_ascii_digit()))
    };
    let ok = match t.split_once('-') {
        Some((days, rest)) => {
            !days.is_empty()
                && days.chars().all(|c| c.is_ascii_digit())
                && numbers(rest)
                && rest.split(':').count() <= 3
        }
        None => numbers(t) && t.split(':').count() <= 3,
    };
    if !ok {
        bail!(
            "--time `{t}`: Slurm's formats are MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM and D-HH:MM:SS (e.g. 30, 2:00:00, 1-12)"
        );
    }
    Ok(())
}

/// The options the scripts set themselves, which `sbatch_options` may not
/// repeat.
const OWN_OPTIONS: [&str; 10] = [
    "--array",
    "--output",
    "--error",
    "--chdir",
    "--job-name",
    "--dependency",
    "--open-mode",
    "--partition",
    "--time",
    "--cpus-per-task",
];

fn check_option(o: &str) -> Result<()> {
    sbatch_word("an sbatch option", o)?;
    if !o.starts_with("--") || o.len() < 3 {
        bail!("sbatch option `{o}`: give it in long form, e.g. --mem=2G or --account=lab");
    }
    let name = o.split('=').next().unwrap_or(o);
    if OWN_OPTIONS.contains(&name) {
        bail!(
            "sbatch option `{o}`: the scripts set {name} themselves{}",
            match name {
                "--partition" | "--time" | "--job-name" | "--cpus-per-task" =>
                    format!(" (use lab slurm {name})"),
                _ => String::new(),
            }
        );
    }
    Ok(())
}

/// Refuses what an `#SBATCH` line cannot hold as one word.
fn sbatch_word(what: &str, s: &str) -> Result<()> {
    if s.is_empty()
        || s.chars()
            .any(|c| c.is_whitespace() || c.is_control() || "\"'\\".contains(c))
    {
        bail!("{what} `{s}`: an #SBATCH line cannot hold spaces, quotes or backslashes");
    }
    Ok(())
}

/// A path for `--output`, whose `%` Slurm reads as a pattern (`%%` is a
/// `%`).
fn slurm_pattern(path: &Path) -> String {
    path.to_string_lossy().replace('%', "%%")
}

/// `s` as one shell word: as it is when it holds only safe characters,
/// else in single quotes.
pub fn quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-./:=+,@%".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> SlurmParams {
        SlurmParams {
            runs: Some(3),
            shards: 5,
            ..SlurmParams::new(
                "/opt/bin/petrinav".into(),
                "/scratch/o u t".into(),
                vec!["mine".into()],
                "mine",
            )
        }
    }

    #[test]
    fn quoting_keeps_safe_words_and_single_quotes_the_rest() {
        assert_eq!(quote("e4/field12"), "e4/field12");
        assert_eq!(quote("/a b/c.toml"), "'/a b/c.toml'");
        assert_eq!(quote("it's"), "'it'\\''s'");
        assert_eq!(quote(""), "''");
    }

    #[test]
    fn paths_with_spaces_are_refused_and_relative_ones_too() {
        let err = params().check().unwrap_err().to_string();
        assert!(err.contains("cannot hold spaces"), "{err}");
        let p = SlurmParams {
            out: "out".into(),
            ..params()
        };
        assert!(p.check().unwrap_err().to_string().contains("absolute"));
    }

    #[test]
    fn the_scripts_hold_the_array_the_options_and_the_shard_per_task() {
        let p = SlurmParams {
            out: "/scratch/o%ut".into(),
            partition: Some("long".into()),
            time: Some("1-00:00".into()),
            cpus_per_task: 2,
            sbatch_options: vec!["--mem=2G".into()],
            what: vec!["/home/me/my scenario.toml".into()],
            pictures: false,
            ..params()
        };
        p.check().unwrap();
        let s = p.shards_script();
        for line in [
            "#SBATCH --array=1-5\n",
            "#SBATCH --job-name=petrinav-mine\n",
            "#SBATCH --partition=long\n",
            "#SBATCH --time=1-00:00\n",
            "#SBATCH --cpus-per-task=2\n",
            "#SBATCH --mem=2G\n",
            "#SBATCH --chdir=/scratch/o%ut\n",
            "#SBATCH --output=/scratch/o%%ut/slurm/shard-%a.log\n",
            "petrinav=/opt/bin/petrinav\n",
            "exec \"$petrinav\" lab run '/home/me/my scenario.toml' --runs 3 --jobs \"${SLURM_CPUS_PER_TASK:-2}\"",
        ] {
            assert!(s.contains(line), "no {line:?} in\n{s}");
        }
        // sbatch reads #SBATCH lines only before the first command.
        let first_command = s.find("\nset -euo").unwrap();
        assert!(s.rfind("#SBATCH").unwrap() < first_command);
        let m = p.merge_script();
        assert!(m.contains("#SBATCH --job-name=petrinav-mine-merge\n"), "{m}");
        assert!(
            m.contains("lab merge \"$out\" \"${parts[@]}\" --no-pictures;"),
            "{m}"
        );
        assert!(!m.contains("#SBATCH --array"), "{m}");
    }

    #[test]
    fn time_limits_arrays_and_options_in_slurms_syntax() {
        for t in [
            "30",
            "30:00",
            "2:00:00",
            "1-12",
            "1-12:30",
            "1-12:30:00",
            "UNLIMITED",
        ] {
            check_time(t).unwrap();
        }
        for t in ["", "1h", "1:2:3:4", "-1", "1-", "1-1:2:3:4", "1 h"] {
            assert!(check_time(t).is_err(), "{t}");
        }
        for a in ["2", "1,3", "2-4", "1-5:2", "1-5%2", "5"] {
            check_array(a, 5).unwrap();
        }
        for a in ["0", "6", "2-1", "x", "1,,2", "1%0", "1-5:0", ""] {
            assert!(check_array(a, 5).is_err(), "{a}");
        }
        check_option("--mem=2G").unwrap();
        for o in ["-n1", "--array=1-3", "--time=5", "--output=x", "--mem=2 G"] {
            assert!(check_option(o).is_err(), "{o}");
        }
    }

    #[test]
    fn job_ids_from_sbatch_parsable() {
        assert_eq!(parse_job_id("1234\n").unwrap(), "1234");
        assert_eq!(parse_job_id("1234;cluster\n").unwrap(), "1234");
        assert!(parse_job_id("Submitted batch job 1234\n").is_err());
        assert!(parse_job_id("").is_err());
    }
}
