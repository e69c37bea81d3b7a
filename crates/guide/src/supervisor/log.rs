//! The mission log: what the guide robot keeps between missions, one JSON
//! line per calibration run or mission, appended and flushed, never
//! rewritten (docs/tour-guide.md, "Learning across missions").
//!
//! ```text
//! {"kind":"calibration","net":"…","behaviour":"automove","success":true,"duration_s":61.2,"path_m":21.8,"trajectory":[[8.1,6.4],…]}
//! {"kind":"mission","net":"…","mission":1,"success":true,"outcome":"goal","duration_s":70.4,"localizer":[…],"planner":[…],…}
//! ```
//!
//! Every line names the supervisor net it was learnt for (`net`,
//! [`super::Supervisor::net_id`]): a log of another net is refused, not
//! mixed. Reading ([`MissionLog::open`]) keeps every complete line; a last
//! line cut mid-write (a crash) is reported and cut off the file, so that
//! the next mission appends after the last complete one — nothing already
//! written is lost. Any other unreadable line is an error naming its line.
//! Every entry is checked as data too ([`check`]: durations,
//! outcomes, times within the run, mission numbers unique and in order):
//! an inconsistent one is an error naming its line and field, and the one
//! kind of entry that is skipped instead is reported
//! ([`MissionLog::skipped`]).

use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use super::Behaviour;

pub mod check;

/// One stretch of time in one state.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sojourn {
    /// The state: `success`/`warning` (localizer), `normal`/`abnormal`
    /// (planner).
    pub state: StateName,
    /// How long, seconds.
    pub duration_s: f64,
    /// It ended by a transition (not by the end of the mission).
    pub ended: bool,
}

/// The states whose sojourns are logged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StateName {
    /// Localizer: Success.
    Success,
    /// Localizer: Warning.
    Warning,
    /// Planner: Normal.
    Normal,
    /// Planner: Abnormal.
    Abnormal,
}

/// How a segment ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SegmentEnd {
    /// The localizer changed state.
    Localizer,
    /// The planner changed state.
    Planner,
    /// The behaviour changed.
    Behaviour,
    /// The crowd context changed.
    Context,
    /// The mission ended.
    Mission,
}

/// A stretch of a mission in one state: the crediting supervisor learns
/// from these ([`super::credit_learning`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Segment {
    /// The behaviour in control.
    pub behaviour: Behaviour,
    /// The localizer in Success.
    pub localized: bool,
    /// AutoMove's planner Normal (always true for contour tracking).
    pub normal: bool,
    /// The crowd context (0 quiet, 1 busy, 2 crowded).
    pub context: usize,
    /// Duration, seconds.
    pub duration_s: f64,
    /// Progress towards the goal along AutoMove's reference, metres
    /// (`None` where there was no reference to measure it on).
    pub progress_m: Option<f64>,
    /// How it ended.
    pub end: SegmentEnd,
}

/// A decision of the supervisor during a mission.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DecisionLog {
    /// When, seconds since the start of the mission.
    pub time_s: f64,
    /// Why it was taken: `start` or `recovered` (Warning → Success).
    pub reason: String,
    /// The rates used, λ1 first (eleven for the source's net, fifteen for
    /// the crediting one).
    pub rates: Vec<f64>,
    /// Throughput of AutoMove's completion under the AutoMove hypothesis.
    pub f_auto: f64,
    /// Throughput of Contour tracking's completion under its hypothesis.
    pub f_cont: f64,
    /// `P{#P5 = 1}`: localizer Success, under the chosen hypothesis.
    pub p_loc_succ: f64,
    /// `P{#P6 = 1}`: localizer Warning, under the chosen hypothesis.
    pub p_loc_warn: f64,
    /// The behaviour chosen.
    pub choice: Behaviour,
    /// The crowd context the rates were taken for (crediting supervisor).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub context: Option<usize>,
    /// The route the rates were taken for (crediting supervisor, where
    /// missions go between several places).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub route: Option<String>,
    /// λ1 first, the rates of the contour hypothesis where they differ from
    /// `rates` (crediting supervisor: λ3, λ4 are each behaviour's own).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub contour_rates: Vec<f64>,
    /// The supervisor net's places marked at the decision (crediting
    /// supervisor): `P0` (deciding), the localizer's and the planner's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub marking: Vec<String>,
    /// The choice explores: a behaviour never driven on the route, tried
    /// (crediting supervisor).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub explore: bool,
}

/// A calibration run: one behaviour alone from the start to the goal.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CalibrationRun {
    /// The behaviour.
    pub behaviour: Behaviour,
    /// Reached the goal.
    pub success: bool,
    /// Travel time, seconds.
    pub duration_s: f64,
    /// Path length, metres.
    pub path_m: f64,
    /// The trajectory as the robot estimated it, world frame, every 0.5 m.
    pub trajectory: Vec<[f64; 2]>,
    /// How it ended (`goal`, `collision`, …); empty in the source's logs.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub outcome: String,
    /// Its segments, for the crediting supervisor ([`super::credit_learning`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub segments: Vec<Segment>,
    /// The route it drove (`from → to`), where the log's missions go
    /// between several places; `None`: the log's one route.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub route: Option<String>,
}

/// A mission: what the supervisor learns from.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MissionRecord {
    /// Mission number in the log, from 1.
    pub mission: u32,
    /// Reached the goal.
    pub success: bool,
    /// How it ended (`goal`, `collision`, `time_limit`, `lost`…).
    pub outcome: String,
    /// Duration, seconds.
    pub duration_s: f64,
    /// The localizer's sojourns in Success and Warning, in order.
    pub localizer: Vec<Sojourn>,
    /// The planner's sojourns in Normal and Abnormal, in order.
    pub planner: Vec<Sojourn>,
    /// Time AutoMove drove, seconds.
    pub time_automove_s: f64,
    /// Time contour tracking drove, seconds.
    pub time_contour_s: f64,
    /// The supervisor's decisions.
    pub decisions: Vec<DecisionLog>,
    /// Its segments, for the crediting supervisor ([`super::credit_learning`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub segments: Vec<Segment>,
    /// The route it drove (`from → to`, a leg of a tour), where missions go
    /// between several places; `None`: the log's one route.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub route: Option<String>,
}

/// One line of the log.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Entry {
    /// A calibration run.
    Calibration(CalibrationRun),
    /// A mission.
    Mission(MissionRecord),
}

/// A log's calibration runs and missions, each in log order.
pub fn split_entries(entries: &[Entry]) -> (Vec<&CalibrationRun>, Vec<&MissionRecord>) {
    let mut calibration = Vec::new();
    let mut missions = Vec::new();
    for e in entries {
        match e {
            Entry::Calibration(c) => calibration.push(c),
            Entry::Mission(m) => missions.push(m),
        }
    }
    (calibration, missions)
}

/// A line as written: the net it belongs to, and the entry.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Line {
    /// The supervisor net's id.
    pub net: String,
    /// The entry.
    #[serde(flatten)]
    pub entry: Entry,
}

/// What can go wrong with a log.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// A complete line that is not a log entry.
    #[error("{path}:{line}: not a mission log entry: {message}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Its line, from 1.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A complete entry that does not hold together ([`check`]).
    #[error("{path}:{line}: `{field}`: {message}")]
    Inconsistent {
        /// The file.
        path: PathBuf,
        /// Its line, from 1.
        line: usize,
        /// The field at fault.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A mission whose number does not follow the log's previous one.
    #[error(
        "{path}:{line}: mission {number} follows mission {previous} (line {previous_line}): mission numbers are unique and in order"
    )]
    MissionOrder {
        /// The file.
        path: PathBuf,
        /// Its line.
        line: usize,
        /// Its number.
        number: u32,
        /// The previous mission's number.
        previous: u32,
        /// The previous mission's line.
        previous_line: usize,
    },
    /// A line of another supervisor net.
    #[error(
        "{path}:{line}: this entry was logged for the supervisor net `{found}`, not `{expected}`: keep one log per net"
    )]
    OtherNet {
        /// The file.
        path: PathBuf,
        /// Its line.
        line: usize,
        /// The net of the line.
        found: String,
        /// The net of this log.
        expected: String,
    },
}

/// A last line cut mid-write, found and cut off the file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TornLine {
    /// Its line number.
    pub line: usize,
    /// Its bytes (what was cut off).
    pub bytes: usize,
}

/// An entry read but left out of the learning ([`check`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SkippedLine {
    /// Its line number.
    pub line: usize,
    /// Why.
    pub why: String,
}

/// An open mission log.
#[derive(Debug)]
pub struct MissionLog {
    path: PathBuf,
    net: String,
    entries: Vec<Entry>,
    torn: Option<TornLine>,
    skipped: Vec<SkippedLine>,
    /// The last mission's number and line.
    last_mission: Option<(u32, usize)>,
    /// Lines in the file (complete ones).
    lines: usize,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> LogError + '_ {
    move |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl MissionLog {
    /// Opens (or creates) the log at `path` for the net `net`: reads every
    /// entry ([`MissionLog::read`]), and cuts a last line cut mid-write
    /// off the file (it stays reported in [`MissionLog::torn`]), so that
    /// the next entry starts a line of its own.
    pub fn open(path: &Path, net: &str) -> Result<MissionLog, LogError> {
        let (log, good) = MissionLog::load(path, net)?;
        if log.torn.is_some() {
            OpenOptions::new()
                .write(true)
                .open(path)
                .and_then(|f| f.set_len(good))
                .map_err(io(path))?;
        }
        Ok(log)
    }

    /// Reads the log at `path` for the net `net` without changing the file:
    /// every complete entry, and a last line cut mid-write reported in
    /// [`MissionLog::torn`]. Errors: unreadable file, a complete line that
    /// is not an entry (its line), a line of another net. A missing file is
    /// an empty log.
    pub fn read(path: &Path, net: &str) -> Result<MissionLog, LogError> {
        Ok(MissionLog::load(path, net)?.0)
    }

    fn load(path: &Path, net: &str) -> Result<(MissionLog, u64), LogError> {
        let mut log = MissionLog {
            path: path.to_path_buf(),
            net: net.to_string(),
            entries: Vec::new(),
            torn: None,
            skipped: Vec::new(),
            last_mission: None,
            lines: 0,
        };
        if !path.exists() {
            return Ok((log, 0));
        }
        let file = File::open(path).map_err(io(path))?;
        let mut reader = BufReader::new(file);
        let mut good = 0u64;
        let mut number = 0;
        let mut text = String::new();
        loop {
            text.clear();
            let n = reader.read_line(&mut text).map_err(io(path))?;
            if n == 0 {
                break;
            }
            number += 1;
            if !text.ends_with('\n') {
                log.torn = Some(TornLine {
                    line: number,
                    bytes: n,
                });
                break;
            }
            let trimmed = text.trim();
            if !trimmed.is_empty() {
                let line: Line = serde_json::from_str(trimmed).map_err(|e| LogError::Malformed {
                    path: path.to_path_buf(),
                    line: number,
                    message: e.to_string(),
                })?;
                if line.net != net {
                    return Err(LogError::OtherNet {
                        path: path.to_path_buf(),
                        line: number,
                        found: line.net,
                        expected: net.to_string(),
                    });
                }
                let skipped = log.admit(&line.entry, number)?;
                log.keep(line.entry, number, skipped);
            }
            good += n as u64;
            log.lines = number;
        }
        Ok((log, good))
    }

    /// Checks an entry that would be line `line` ([`check`],
    /// mission numbers in order): `Ok` with the reason it is skipped, if
    /// it is.
    fn admit(&self, entry: &Entry, line: usize) -> Result<Option<SkippedLine>, LogError> {
        let verdict = check::check(entry).map_err(|e| LogError::Inconsistent {
            path: self.path.clone(),
            line,
            field: e.field,
            message: e.message,
        })?;
        if let Entry::Mission(m) = entry
            && let Some((previous, previous_line)) = self.last_mission
            && m.mission <= previous
        {
            return Err(LogError::MissionOrder {
                path: self.path.clone(),
                line,
                number: m.mission,
                previous,
                previous_line,
            });
        }
        Ok(match verdict {
            check::Verdict::Kept => None,
            check::Verdict::Skipped(why) => Some(SkippedLine { line, why }),
        })
    }

    /// Keeps an admitted entry of line `line`.
    fn keep(&mut self, entry: Entry, line: usize, skipped: Option<SkippedLine>) {
        if let Entry::Mission(m) = &entry {
            self.last_mission = Some((m.mission, line));
        }
        self.skipped.extend(skipped);
        self.entries.push(entry);
        self.lines = line;
    }

    /// The entries read but left out of the learning, with their lines.
    pub fn skipped(&self) -> &[SkippedLine] {
        &self.skipped
    }

    /// What a reader should be told of the file beyond its entries: the
    /// last line cut mid-write, the entries skipped; one sentence each,
    /// naming the file and line.
    pub fn notices(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(t) = &self.torn {
            out.push(format!(
                "{}:{}: the last line was cut mid-write ({} bytes); it is not an entry and is left out",
                self.path.display(),
                t.line,
                t.bytes
            ));
        }
        for s in &self.skipped {
            out.push(format!("{}:{}: {}", self.path.display(), s.line, s.why));
        }
        out
    }

    /// The number the next mission gets: one more than the last one's (1
    /// in a log without missions).
    pub fn next_mission(&self) -> u32 {
        self.last_mission.map_or(1, |(k, _)| k.saturating_add(1))
    }

    /// The entries, in the file's order.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// The last line cut mid-write found on opening (and cut off).
    pub fn torn(&self) -> Option<&TornLine> {
        self.torn.as_ref()
    }

    /// The missions logged so far.
    pub fn missions(&self) -> u32 {
        self.entries
            .iter()
            .filter(|e| matches!(e, Entry::Mission(_)))
            .count() as u32
    }

    /// Appends an entry: one line, written and flushed to the disk before
    /// returning. An entry that would not read back (inconsistent, or a
    /// mission numbered out of order) is refused before anything is
    /// written.
    pub fn append(&mut self, entry: Entry) -> Result<(), LogError> {
        let path = self.path.clone();
        let number = self.lines + 1;
        let skipped = self.admit(&entry, number)?;
        let line = Line {
            net: self.net.clone(),
            entry,
        };
        let mut text = serde_json::to_string(&line).map_err(|e| LogError::Malformed {
            path: path.clone(),
            line: 0,
            message: e.to_string(),
        })?;
        text.push('\n');
        let mut f = OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .map_err(io(&path))?;
        f.write_all(text.as_bytes()).map_err(io(&path))?;
        f.sync_data().map_err(io(&path))?;
        self.keep(line.entry, number, skipped);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("petrinav-log-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir.join("missions.jsonl")
    }

    fn mission(k: u32) -> Entry {
        Entry::Mission(MissionRecord {
            mission: k,
            success: true,
            outcome: "goal".into(),
            duration_s: 60.0 + f64::from(k),
            localizer: vec![Sojourn {
                state: StateName::Success,
                duration_s: 60.0,
                ended: false,
            }],
            planner: Vec::new(),
            time_automove_s: 60.0,
            time_contour_s: 0.0,
            decisions: Vec::new(),
            segments: Vec::new(),
            route: None,
        })
    }

    #[test]
    fn a_crash_mid_write_loses_nothing_written_and_is_reported() {
        let path = temp("torn");
        let mut log = MissionLog::open(&path, "net-a").unwrap();
        log.append(mission(1)).unwrap();
        log.append(mission(2)).unwrap();
        // The process dies while writing mission 3.
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(br#"{"net":"net-a","kind":"mission","miss"#).unwrap();
        drop(f);
        // Reading leaves the file as it is.
        let before = std::fs::read(&path).unwrap();
        assert!(MissionLog::read(&path, "net-a").unwrap().torn().is_some());
        assert_eq!(std::fs::read(&path).unwrap(), before);
        let mut log = MissionLog::open(&path, "net-a").unwrap();
        assert_eq!(log.missions(), 2);
        assert_eq!(log.torn(), Some(&TornLine { line: 3, bytes: 37 }));
        // The next mission goes on from there.
        log.append(mission(3)).unwrap();
        let log = MissionLog::open(&path, "net-a").unwrap();
        assert_eq!(log.missions(), 3);
        assert!(log.torn().is_none());
        assert_eq!(log.entries()[2], mission(3));
    }

    /// Regression (issue 51): duplicate mission numbers were read.
    #[test]
    fn missions_out_of_order_or_inconsistent_are_errors_naming_the_line() {
        let path = temp("order");
        let mut log = MissionLog::open(&path, "net-a").unwrap();
        log.append(mission(1)).unwrap();
        log.append(mission(2)).unwrap();
        assert_eq!(log.next_mission(), 3);
        // Appending a mission out of order is refused before writing.
        let before = std::fs::read(&path).unwrap();
        assert!(matches!(
            log.append(mission(2)),
            Err(LogError::MissionOrder { line: 3, .. })
        ));
        assert_eq!(std::fs::read(&path).unwrap(), before);
        // Written by hand, it is an error on reading.
        let line = serde_json::to_string(&Line {
            net: "net-a".into(),
            entry: mission(2),
        })
        .unwrap();
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(format!("{line}\n").as_bytes()).unwrap();
        drop(f);
        let e = MissionLog::read(&path, "net-a").unwrap_err().to_string();
        assert!(e.contains(":3: mission 2 follows mission 2 (line 2)"), "{e}");
        // A negative duration names the line and the field.
        let path = temp("negative");
        let text =
            before_text(&path, "net-a", &[mission(1)]).replace("\"duration_s\":61.0", "\"duration_s\":-61.0");
        std::fs::write(&path, text).unwrap();
        let e = MissionLog::read(&path, "net-a").unwrap_err().to_string();
        assert!(e.contains(":1: `duration_s`: -61 s"), "{e}");
    }

    /// The text a log of `entries` holds.
    fn before_text(path: &Path, net: &str, entries: &[Entry]) -> String {
        let _ = std::fs::remove_file(path);
        let mut log = MissionLog::open(path, net).unwrap();
        for e in entries {
            log.append(e.clone()).unwrap();
        }
        std::fs::read_to_string(path).unwrap()
    }

    #[test]
    fn a_successful_calibration_run_of_no_time_is_read_and_reported() {
        let path = temp("skipped");
        let run = Entry::Calibration(CalibrationRun {
            behaviour: Behaviour::AutoMove,
            success: true,
            duration_s: 0.0,
            path_m: 0.0,
            trajectory: Vec::new(),
            outcome: String::new(),
            segments: Vec::new(),
            route: None,
        });
        let mut log = MissionLog::open(&path, "net-a").unwrap();
        log.append(run).unwrap();
        log.append(mission(1)).unwrap();
        let log = MissionLog::read(&path, "net-a").unwrap();
        assert_eq!(log.entries().len(), 2);
        assert_eq!(log.skipped().len(), 1);
        assert_eq!(log.skipped()[0].line, 1);
        let notices = log.notices();
        assert!(
            notices[0].contains(":1: a successful calibration run of 0 s"),
            "{notices:?}"
        );
    }

    #[test]
    fn foreign_lines_and_other_nets_are_errors_naming_the_line() {
        let path = temp("foreign");
        let mut log = MissionLog::open(&path, "net-a").unwrap();
        log.append(mission(1)).unwrap();
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(b"{\"net\":\"net-a\",\"kind\":\"lunch\"}\n").unwrap();
        drop(f);
        let e = MissionLog::open(&path, "net-a").unwrap_err().to_string();
        assert!(e.contains(":2:") && e.contains("lunch"), "{e}");
        let path = temp("other");
        MissionLog::open(&path, "net-b")
            .unwrap()
            .append(mission(1))
            .unwrap();
        let e = MissionLog::open(&path, "net-a").unwrap_err().to_string();
        assert!(e.contains(":1:") && e.contains("net-b"), "{e}");
        let path = temp("garbage");
        std::fs::write(&path, "not json\n").unwrap();
        assert!(matches!(
            MissionLog::open(&path, "net-a"),
            Err(LogError::Malformed { line: 1, .. })
        ));
    }
}
