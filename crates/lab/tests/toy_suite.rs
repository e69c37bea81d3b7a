//! A suite defined only here, in test code — a toy controller, a toy
//! metric, campaigns of two runs whose second run learns from the first —
//! run through the real runner and report: what a new suite needs is its
//! own folder, nothing in the core.

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use lab::experiment::{Prepared, RunSeeds};
use lab::page::Block;
use lab::pictures::{EventMarker, Replay};
use lab::record::RunRecord;
use lab::runner::{BatchParams, Campaign, Job, derive_seed};
use lab::scenario::Scenario;
use lab::suite::{ReportContext, Suite, SuiteInfo, SuiteReport};
use lab::tables::{self, MetricColumn};
use robot::{Command, Controller, Event, Notes, Perception, Step, Vec2};
use sim::TraceParams;

/// Drives straight at the goal at a set speed, and says "mark" every metre
/// it has driven (by odometry).
struct Marker {
    speed_mps: f64,
    last_mark: Option<Vec2>,
}

impl Controller for Marker {
    fn step(&mut self, p: &Perception, notes: &mut Notes) -> Step {
        let here = p.odometry.position();
        let last = *self.last_mark.get_or_insert(here);
        if here.dist(last) >= 1.0 {
            notes.event(
                Event::new("mark", p.time_s)
                    .at(here)
                    .with("speed_mps", self.speed_mps),
            );
            self.last_mark = Some(here);
        }
        let Some(goal) = p.goal else {
            return Step::Done(Command::Stop);
        };
        if goal.dist(here) < 0.1 {
            return Step::Done(Command::Stop);
        }
        let error = robot::wrap_angle((goal - here).angle() - p.odometry.theta_rad);
        notes.behaviour("marching");
        Step::Run(Command::Twist {
            v_mps: self.speed_mps,
            omega_radps: 2.0 * error,
        })
    }
}

const CORRIDOR: &str = "
name = \"corridor\"
time_limit_s = 60
[world]
width_m = 8.0
height_m = 2.0
walls = true
[start]
x = 0.5
y = 1.0
jitter_m = 0.05
[goal]
x = 7.0
y = 1.0
";

/// Three campaigns of two runs in the same corridor. The first run of a
/// campaign drives at 0.2 m/s; the next one learns: 0.1 m/s faster per
/// earlier success of its campaign. The metric `marks` counts the
/// controller's `mark` events; records keep them.
struct ToySuite {
    info: SuiteInfo,
    corridor: Prepared,
    /// Fails this run, as a kill would leave the batch.
    kill_at: Option<String>,
}

impl ToySuite {
    fn new(kill_at: Option<&str>) -> ToySuite {
        let scenario = Scenario::parse(CORRIDOR, "corridor.toml", None).unwrap();
        ToySuite {
            info: SuiteInfo {
                name: "toy".into(),
                suite: "toy".into(),
                runs: 2,
                seed: 5,
                scenarios: vec!["a".into(), "b".into(), "c".into()],
                sources: BTreeMap::new(),
            },
            corridor: Prepared::new(scenario).unwrap(),
            kill_at: kill_at.map(str::to_string),
        }
    }

    fn seeds(&self, job: &Job) -> RunSeeds {
        RunSeeds {
            sim: job.seed,
            variation: derive_seed(self.info.seed, "variation", job.run),
        }
    }

    fn speed(earlier: &[RunRecord]) -> f64 {
        0.2 + 0.1 * earlier.iter().filter(|r| r.success).count() as f64
    }

    fn simulate(
        &self,
        job: &Job,
        earlier: &[RunRecord],
        trace: TraceParams,
    ) -> Result<(RunRecord, lab::experiment::RunOutput)> {
        let speed = ToySuite::speed(earlier);
        let controller = Marker {
            speed_mps: speed,
            last_mark: None,
        };
        let out = self
            .corridor
            .run_with(self.seeds(job), trace, Box::new(controller))?;
        let mut record = out.record.clone();
        let marks: Vec<Event> = out.events.iter().filter(|e| e.kind == "mark").cloned().collect();
        record.set_metric("marks", marks.len() as f64)?;
        record.set_metric("speed_mps", speed)?;
        record.events = marks;
        Ok((record, out))
    }
}

const MARKERS: [EventMarker; 0] = [];

impl Suite for ToySuite {
    fn info(&self) -> &SuiteInfo {
        &self.info
    }

    fn campaigns(&self) -> Vec<Campaign> {
        self.info
            .scenarios
            .iter()
            .map(|s| Campaign {
                jobs: (0..2)
                    .map(|run| Job {
                        scenario: s.clone(),
                        run,
                        seed: derive_seed(self.info.seed, s, run),
                    })
                    .collect(),
            })
            .collect()
    }

    fn run(&self, job: &Job, earlier: &[RunRecord]) -> Result<RunRecord> {
        if self.kill_at.as_deref() == Some(job.key().as_str()) {
            bail!("killed");
        }
        Ok(self.simulate(job, earlier, TraceParams::default())?.0)
    }

    fn replay(&self, job: &Job, earlier: &[RunRecord], trace: TraceParams) -> Result<Replay> {
        let (record, out) = self.simulate(job, earlier, trace)?;
        Ok(Replay {
            record,
            trace: out.trace.context("no trace")?,
            grid: out.grid.context("no grid")?,
            goal: Some(Vec2::new(7.0, 1.0)),
            robot_radius_m: 0.15,
            control_period_s: 0.1,
            net: None,
        })
    }

    fn markers(&self) -> &[EventMarker] {
        &MARKERS
    }

    fn report(&self, ctx: &ReportContext<'_>) -> Result<SuiteReport> {
        let (text, table) = tables::generic_table(
            ctx.summaries,
            &[MetricColumn {
                metric: "marks",
                heading: "marks/run",
                short: "marks",
                decimals: 1,
            }],
        );
        Ok(SuiteReport {
            text,
            intro: Some("Three campaigns of two runs: the second learns from the first.".into()),
            blocks: vec![Block::Table(table)],
            files: Vec::new(),
        })
    }
}

fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("petrinav-toy-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn params(dir: &Path, resume: bool, jobs: usize) -> BatchParams {
    BatchParams {
        results: dir.join("results.jsonl"),
        resume,
        jobs: Some(jobs),
        progress: false,
        stop: None,
    }
}

#[test]
fn a_suite_from_test_code_runs_learns_resumes_and_reports_its_metric() {
    let whole = folder("whole");
    let suite = ToySuite::new(None);
    let s = lab::suite::run(&suite, &params(&whole, false, 2), None).unwrap();
    assert_eq!((s.total, s.ran, s.not_reached_total()), (6, 6, 0));

    // The second run of each campaign learnt from the first.
    let (lines, _) = lab::runner::read_results(&whole.join("results.jsonl")).unwrap();
    let runs = lab::record::group(&lines).unwrap();
    for name in ["a", "b", "c"] {
        let (first, second) = (&runs[name][0].1, &runs[name][1].1);
        assert!(first.success && second.success, "{name}");
        assert_eq!(first.metric("speed_mps"), Some(0.2));
        assert_eq!(second.metric("speed_mps"), Some(0.30000000000000004));
        assert!(
            second.time_s < first.time_s * 0.75,
            "{name}: faster after learning"
        );
        // 6.5 m at one mark per metre; the events are kept, typed.
        assert_eq!(first.metric("marks"), Some(6.0), "{name}");
        assert_eq!(first.events.len(), 6);
        assert_eq!(first.events[0].number("speed_mps"), Some(0.2));
    }
    let line = std::fs::read_to_string(whole.join("results.jsonl")).unwrap();
    assert!(
        line.lines()
            .next()
            .unwrap()
            .contains("\"events\":[{\"kind\":\"mark\""),
        "events are JSON objects in the records"
    );

    // Killed in the middle of campaign b (its first run written, a line
    // torn mid-write), then resumed: the same file, byte for byte.
    let cut = folder("cut");
    let err = lab::suite::run(&ToySuite::new(Some("b#1")), &params(&cut, false, 1), None).unwrap_err();
    assert!(format!("{err:#}").contains("b#1"), "{err:#}");
    let (done, _) = lab::runner::read_results(&cut.join("results.jsonl")).unwrap();
    assert!(done.iter().any(|l| l["key"] == "b#0") && !done.iter().any(|l| l["key"] == "b#1"));
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(cut.join("results.jsonl"))
        .unwrap();
    f.write_all(b"{\"key\":\"c#0\",\"succ").unwrap();
    drop(f);
    let s = lab::suite::run(&suite, &params(&cut, true, 2), None).unwrap();
    assert_eq!(s.skipped + s.ran, 6);
    assert!(s.ran >= 1 && s.skipped >= 3, "{s:?}");
    assert_eq!(
        std::fs::read(cut.join("results.jsonl")).unwrap(),
        std::fs::read(whole.join("results.jsonl")).unwrap()
    );

    // A replay of the second run rebuilds its state from the file.
    let replay = lab::suite::replay_key(&suite, &whole, "c#1", TraceParams::poses()).unwrap();
    assert_eq!(replay.record, runs["c"][1].1);

    // The generic report shows the suite's metric in the suite's column.
    let written = lab::report::write(&whole, &suite, false).unwrap();
    assert!(written.text.contains("marks"), "{}", written.text);
    let md = std::fs::read_to_string(whole.join("tables.md")).unwrap();
    assert!(md.contains("marks/run") && md.contains("| 6.0 |"), "{md}");
    let csv = std::fs::read_to_string(whole.join("summary.csv")).unwrap();
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains("marks_mean,marks_half_width,speed_mps_mean")
    );
    let html = std::fs::read_to_string(whole.join("index.html")).unwrap();
    assert!(html.contains("<th>marks/run</th>"));
    assert!(
        md.contains("Three campaigns of two runs"),
        "the suite's own introduction"
    );
}
