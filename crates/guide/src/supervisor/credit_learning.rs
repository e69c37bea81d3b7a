//! Learning the crediting supervisor's rates ([`super::credit`]) from the
//! mission log: every failure credited to the behaviour responsible, every
//! rate learnt per context — the route and the crowd — and shrunk towards
//! the building's rates where a context has few observations
//! ([`super::shrinkage`]).
//!
//! **What a mission leaves.** The guide controller cuts its mission into
//! [`Segment`]s: stretches with one behaviour in control, one localizer
//! state (localized or not), one planner state and one crowd context, each
//! with its duration, how it ended and the progress made towards the goal
//! (the drop of the remaining length along AutoMove's route planned on the
//! static map at the mission's start). The mission names its route (`from →
//! to`, a leg of a tour; a log of one route has none).
//!
//! **Crowd context.** What the robot can see of the crowd: the unmapped
//! objects per scan (runs of beams ending short of the map,
//! [`localization::ScanConsistency::unmapped_objects`]), averaged
//! over about ten seconds ([`CrowdMeter`]), in three bins
//! ([`CROWD_BINS`]): *quiet* (< 2: nobody or a passer-by), *busy* (2–7:
//! a few people near), *crowded* (≥ 7). Measured on the museum's scans
//! with the true pose (`cargo run --release -p lab --example status_roc`):
//! median 5 objects with 25 visitors, 9 with 60.
//!
//! **Decision — who failed.** A mission that ended by a collision, by
//! arriving where the goal is not or by the lost watchdog failed in the
//! state it ended in: the failure is credited to the last segment's
//! behaviour, localizer state and context. A mission that ran out of time
//! failed because of all of it: one failure is shared among its segments
//! in proportion to their durations. The failure rate of a class is its
//! credited failures over its exposure time (the maximum-likelihood rate
//! of an exponential hazard).
//!
//! | rate | what, per behaviour where two are given |
//! |---|---|
//! | λ3, λ4 | leaving Success, leaving Warning (per unit time in it), with each behaviour: contour tracking earns credit for keeping the robot localized along walls |
//! | λ5, λ6 | leaving Normal, leaving Abnormal (AutoMove's time) |
//! | λ7, λ8 | progress speed of AutoMove, contour tracking while localized, over the remaining length |
//! | λ9 | AutoMove fails, planner Abnormal |
//! | λ13, λ14 | AutoMove, contour tracking fails while localized |
//! | λ12, λ10 | AutoMove, contour tracking fails while the localizer warns |
//!
//! **Decision — per route and crowd, shrunk.** Every rate is estimated per
//! behaviour, route and crowd context by the three-level estimator of
//! [`super::shrinkage`]: the building's rate per behaviour and crowd (the
//! crowd acts alike on both behaviours until their own data say otherwise:
//! on the museum day a supervisor that had seen contour tracking only in the
//! empty hall otherwise took its empty-hall speed for the crowd's, and
//! started missions in contour tracking among 60 visitors;
//! `crates/guide/EXPERIMENTS.md`), a route effect per behaviour, and the
//! context's own data, each level worth one observation — one event, or
//! one traversal of the route for the progress speeds. The model file's
//! rates are the building's prior (one pseudo-event each); the speeds'
//! prior is [`SPEED_PRIOR_MPS`] for [`SPEED_PRIOR_S`] seconds.
//!
//! **Decision — exploration: optimism, when quiet.** A behaviour never
//! driven on a route ([`CreditModel::tried`]) is tried at the next start of
//! a mission on that route that finds the building quiet
//! ([`CreditModel::explore`]; AutoMove first when neither has been): what
//! is never tried is never learnt, and a route where contour tracking
//! passes a door the planner refuses looks, to the building's rates, like
//! any other. Only when quiet, because exploring is paid for by the
//! missions it costs and a quiet building is where it costs least —
//! without visitors neither behaviour fails, it is only slower where it is
//! the wrong one — while in a crowd contour tracking fails most of its
//! missions in the museum; the crowd's effect on a behaviour then comes
//! from the building level. Rejected: exploring in any crowd (a mission
//! spent learning that contour tracking fails among 60 visitors is a failed
//! mission, and a museum day has six of them).

use super::Behaviour;
use super::credit::CreditRates;
use super::learning::LearnError;
use super::log::{Entry, Segment, SegmentEnd};
use super::reference::MIN_REMAINING_S;
use super::shrinkage::{self, RouteTable, Shrunk};

pub use super::shrinkage::CONTEXTS;

/// Unmapped objects per scan separating the crowd contexts: quiet below
/// the first, busy below the second, crowded from it on.
pub const CROWD_BINS: [f64; 2] = [2.0, 7.0];

/// The contexts' names, in bin order.
pub const CONTEXT_NAMES: [&str; CONTEXTS] = ["quiet", "busy", "crowded"];

/// Pseudo-exposure of the speed prior at the building level, seconds.
pub const SPEED_PRIOR_S: f64 = 30.0;

/// Prior progress speeds along AutoMove's planned route, m/s: AutoMove,
/// contour tracking. Their cruise speeds are 0.5 and 0.4 m/s; in the empty
/// museum hall AutoMove takes about 60 s over a route of 25 m and contour
/// tracking, round the exhibits, 1.6 times as long.
pub const SPEED_PRIOR_MPS: [f64; 2] = [0.4, 0.25];

/// The context of a crowd measure (unmapped objects per scan).
pub fn crowd_context(objects: f64) -> usize {
    CROWD_BINS.iter().filter(|&&b| objects >= b).count()
}

/// A running mean of the unmapped objects per scan, over about
/// `window_s` seconds (an exponential average in time).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrowdMeter {
    window_s: f64,
    mean: Option<f64>,
    last_s: f64,
}

impl CrowdMeter {
    /// A meter averaging over `window_s` seconds (> 0).
    pub fn new(window_s: f64) -> CrowdMeter {
        CrowdMeter {
            window_s: window_s.max(1e-3),
            mean: None,
            last_s: 0.0,
        }
    }

    /// Takes the objects counted on a scan at `time_s`.
    pub fn observe(&mut self, time_s: f64, objects: f64) {
        self.mean = Some(match self.mean {
            None => objects,
            Some(m) => {
                let a = 1.0 - (-(time_s - self.last_s).max(0.0) / self.window_s).exp();
                m + a * (objects - m)
            }
        });
        self.last_s = time_s;
    }

    /// The mean so far (0 before any scan).
    pub fn mean(&self) -> f64 {
        self.mean.unwrap_or(0.0)
    }

    /// The context of the mean.
    pub fn context(&self) -> usize {
        crowd_context(self.mean())
    }
}

fn behaviour_index(b: Behaviour) -> usize {
    match b {
        Behaviour::AutoMove => 0,
        Behaviour::Contour => 1,
    }
}

/// What the crediting supervisor learnt from a log: per kind of rate, the
/// events over the exposure per route, behaviour and crowd context.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct CreditModel {
    /// Localized time and exits to Warning, per behaviour (λ3).
    pub leave_success: RouteTable,
    /// Warning time and exits to Success, per behaviour (λ4).
    pub leave_warning: RouteTable,
    /// AutoMove's Normal time and exits to Abnormal (λ5).
    pub leave_normal: RouteTable,
    /// AutoMove's Abnormal time and exits to Normal (λ6).
    pub leave_abnormal: RouteTable,
    /// AutoMove's failures while Abnormal (λ9).
    pub fail_abnormal: RouteTable,
    /// Failures while localized (and Normal): AutoMove λ13, contour λ14.
    pub fail_localized: RouteTable,
    /// Failures while the localizer warns: AutoMove λ12, contour λ10.
    pub fail_warning: RouteTable,
    /// Progress along the route (metres) over localized time, per
    /// behaviour (λ7, λ8).
    pub progress: RouteTable,
    /// Missions in the log.
    pub missions: usize,
    /// Of which reached the goal.
    pub successes: usize,
}

/// The rates of a decision in one context, per hypothesis, with the
/// estimates behind them (for the logs).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ContextRates {
    /// The rates under the AutoMove hypothesis (λ3, λ4 AutoMove's).
    pub automove: CreditRates,
    /// The rates under the contour hypothesis (λ3, λ4 contour tracking's).
    pub contour: CreditRates,
    /// The progress speeds (AutoMove, contour), m/s, at each level.
    pub speeds: [Shrunk; 2],
}

fn check(what: &str, v: f64) -> Result<f64, LearnError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(LearnError::BadValue {
            what: what.to_string(),
            value: v,
        })
    }
}

impl CreditModel {
    /// Learns from the entries of a log (module docs): its missions and
    /// the calibration runs that have segments. Fails on a value that is
    /// not a finite number ≥ 0.
    pub fn learn(entries: &[Entry]) -> Result<CreditModel, LearnError> {
        let (calibration, missions) = super::log::split_entries(entries);
        let mut m = CreditModel::default();
        for c in &calibration {
            m.credit(
                c.route.as_deref().unwrap_or(""),
                &c.segments,
                &c.outcome,
                c.success,
            )?;
        }
        for r in &missions {
            m.credit(
                r.route.as_deref().unwrap_or(""),
                &r.segments,
                &r.outcome,
                r.success,
            )?;
        }
        m.missions = missions.len();
        m.successes = missions.iter().filter(|r| r.success).count();
        Ok(m)
    }

    /// Whether `behaviour` has driven on `route` while localized.
    pub fn tried(&self, route: &str, behaviour: Behaviour) -> bool {
        let b = behaviour_index(behaviour);
        self.progress.route(route)[b].iter().any(|e| e.time_s > 0.0)
    }

    /// The behaviour to explore at the start of a mission on `route` in
    /// crowd context `context` (module docs): one never driven there, when
    /// the context is quiet (AutoMove first); `None` otherwise.
    pub fn explore(&self, route: &str, context: usize) -> Option<Behaviour> {
        if context != 0 {
            return None;
        }
        [Behaviour::AutoMove, Behaviour::Contour]
            .into_iter()
            .find(|&b| !self.tried(route, b))
    }

    /// The rates for a decision on `route` (its reference `length_m` long)
    /// in crowd context `context`, `remaining_m` metres from the goal
    /// along the reference.
    pub fn rates(&self, route: &str, context: usize, remaining_m: f64, length_m: f64) -> ContextRates {
        let prior = CreditRates::initial();
        let c = context.min(CONTEXTS - 1);
        let pair = |t: &RouteTable, i: [usize; 2], b: usize| {
            let p = i.map(|i| prior.get(i));
            shrinkage::shrink(t, p.map(|r| (1.0, 1.0 / r)), route, b, c, 1.0).rate
        };
        let mut r = prior;
        let mut set = |i: usize, v: f64| {
            // Learnt rates are finite and > 0 by construction; keep the
            // prior should one not be.
            let _ = r.try_set(i, v);
        };
        set(5, pair(&self.leave_normal, [5, 5], 0));
        set(6, pair(&self.leave_abnormal, [6, 6], 0));
        set(9, pair(&self.fail_abnormal, [9, 9], 0));
        set(13, pair(&self.fail_localized, [13, 14], 0));
        set(14, pair(&self.fail_localized, [13, 14], 1));
        set(12, pair(&self.fail_warning, [12, 10], 0));
        set(10, pair(&self.fail_warning, [12, 10], 1));
        let length = length_m.max(1.0);
        let speeds: [Shrunk; 2] = std::array::from_fn(|b| {
            shrinkage::shrink(
                &self.progress,
                SPEED_PRIOR_MPS.map(|v| (v * SPEED_PRIOR_S, SPEED_PRIOR_S)),
                route,
                b,
                c,
                length,
            )
        });
        let remaining = remaining_m.max(0.0);
        for (b, i) in [(0usize, 7usize), (1, 8)] {
            let v = speeds[b].rate.max(1e-3);
            set(i, 1.0 / (remaining / v).max(MIN_REMAINING_S));
        }
        // λ15 (the failure cost) stays the model's.
        let with_localizer = |b: usize| {
            let mut x = r;
            let _ = x.try_set(3, pair(&self.leave_success, [3, 3], b));
            let _ = x.try_set(4, pair(&self.leave_warning, [4, 4], b));
            x
        };
        ContextRates {
            automove: with_localizer(0),
            contour: with_localizer(1),
            speeds,
        }
    }

    /// Adds a run on `route` — its segments and its credited failure.
    fn credit(
        &mut self,
        route: &str,
        segments: &[Segment],
        outcome: &str,
        success: bool,
    ) -> Result<(), LearnError> {
        for (k, s) in segments.iter().enumerate() {
            let d = check(&format!("segment {k} duration_s"), s.duration_s)?;
            let (b, c) = (behaviour_index(s.behaviour), s.context.min(CONTEXTS - 1));
            let last = k + 1 == segments.len();
            let next = segments.get(k + 1);
            let changed_loc =
                s.end == SegmentEnd::Localizer || next.is_some_and(|n| n.localized != s.localized);
            let changed_plan = s.end == SegmentEnd::Planner || next.is_some_and(|n| n.normal != s.normal);
            let left = |changed: bool| f64::from(u8::from(!last && changed));
            let loc = if s.localized {
                &mut self.leave_success
            } else {
                &mut self.leave_warning
            };
            loc.add(route, b, c, left(changed_loc), d);
            if s.behaviour == Behaviour::AutoMove {
                let plan = if s.normal {
                    &mut self.leave_normal
                } else {
                    &mut self.leave_abnormal
                };
                plan.add(route, 0, c, left(changed_plan), d);
            }
            self.failures_of(s).add(route, b, c, 0.0, d);
            if let (true, Some(p)) = (s.localized, s.progress_m)
                && p.is_finite()
            {
                self.progress.add(route, b, c, p, d);
            }
        }
        if success || segments.is_empty() {
            return Ok(());
        }
        if outcome == "time_limit" {
            let total: f64 = segments.iter().map(|s| s.duration_s).sum();
            if total > 0.0 {
                for s in segments {
                    let (b, c) = (behaviour_index(s.behaviour), s.context.min(CONTEXTS - 1));
                    self.failures_of(s).add(route, b, c, s.duration_s / total, 0.0);
                }
            }
        } else if let Some(s) = segments.last() {
            let (b, c) = (behaviour_index(s.behaviour), s.context.min(CONTEXTS - 1));
            self.failures_of(s).add(route, b, c, 1.0, 0.0);
        }
        Ok(())
    }

    /// The failure class of a segment: AutoMove while Abnormal (λ9), while
    /// the localizer warns (λ12, λ10), otherwise (λ13, λ14).
    fn failures_of(&mut self, s: &Segment) -> &mut RouteTable {
        match (s.behaviour, s.localized, s.normal) {
            (_, false, _) => &mut self.fail_warning,
            (Behaviour::AutoMove, true, false) => &mut self.fail_abnormal,
            _ => &mut self.fail_localized,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::supervisor::log::MissionRecord;

    fn seg(b: Behaviour, localized: bool, context: usize, d: f64, progress: f64, end: SegmentEnd) -> Segment {
        Segment {
            behaviour: b,
            localized,
            normal: true,
            context,
            duration_s: d,
            progress_m: Some(progress),
            end,
        }
    }

    fn mission(k: u32, route: &str, outcome: &str, segments: Vec<Segment>) -> Entry {
        Entry::Mission(MissionRecord {
            mission: k,
            success: outcome == "goal",
            outcome: outcome.into(),
            duration_s: segments.iter().map(|s| s.duration_s).sum(),
            localizer: Vec::new(),
            planner: Vec::new(),
            time_automove_s: 0.0,
            time_contour_s: 0.0,
            decisions: Vec::new(),
            segments,
            route: (!route.is_empty()).then(|| route.to_string()),
        })
    }

    #[test]
    fn contexts_and_the_meter() {
        assert_eq!(crowd_context(0.0), 0);
        assert_eq!(crowd_context(1.99), 0);
        assert_eq!(crowd_context(2.0), 1);
        assert_eq!(crowd_context(7.0), 2);
        let mut m = CrowdMeter::new(10.0);
        m.observe(0.0, 10.0);
        assert_eq!(m.mean(), 10.0);
        m.observe(10.0, 0.0);
        assert!((m.mean() - 10.0 * (-1.0f64).exp()).abs() < 1e-12);
    }

    #[test]
    fn failures_are_credited_to_the_behaviour_state_and_route_responsible() {
        use SegmentEnd::{Behaviour as SwitchedBehaviour, Localizer, Mission};
        let (a, c) = (Behaviour::AutoMove, Behaviour::Contour);
        let log = vec![
            // A collision while AutoMove drove, lost, in a crowd.
            mission(
                1,
                "",
                "collision",
                vec![
                    seg(a, true, 2, 30.0, 10.0, Localizer),
                    seg(a, false, 2, 5.0, 1.0, Mission),
                ],
            ),
            // A time limit on route r: shared 3 : 1 between AutoMove and
            // contour.
            mission(
                2,
                "r",
                "time_limit",
                vec![
                    seg(a, true, 1, 225.0, 10.0, SwitchedBehaviour),
                    seg(c, true, 1, 75.0, 5.0, Mission),
                ],
            ),
            mission(3, "", "goal", vec![seg(a, true, 0, 40.0, 20.0, Mission)]),
        ];
        let m = CreditModel::learn(&log).unwrap();
        assert_eq!((m.missions, m.successes), (3, 1));
        let lost = m.fail_warning.route("");
        assert_eq!((lost[0][2].events, lost[0][2].time_s), (1.0, 5.0));
        assert_eq!(m.fail_localized.route("")[0][2].events, 0.0);
        assert_eq!(m.leave_success.route("")[0][2].events, 1.0);
        let r = m.fail_localized.route("r");
        assert!((r[0][1].events - 0.75).abs() < 1e-12 && (r[1][1].events - 0.25).abs() < 1e-12);
        assert!(m.tried("r", c) && !m.tried("", c) && m.tried("", a));
        // Rates are finite and > 0 everywhere, known routes or not.
        for route in ["", "r", "elsewhere"] {
            for ctx in 0..CONTEXTS {
                let x = m.rates(route, ctx, 10.0, 30.0);
                for i in 1..=15 {
                    for v in [x.automove.get(i), x.contour.get(i)] {
                        assert!(v.is_finite() && v > 0.0, "λ{i} {route} {ctx}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_route_where_contour_tracking_is_the_faster_is_learnt_as_such() {
        use SegmentEnd::Mission;
        let (a, c) = (Behaviour::AutoMove, Behaviour::Contour);
        let mut log = Vec::new();
        // The door route: 36 m of AutoMove's route, AutoMove 80 s, contour
        // 35 s (it passes the door: the remaining length drops at once).
        // Another route: AutoMove 45 s, contour 150 s.
        let runs = [
            ("door", a, 80.0, 36.0),
            ("door", c, 35.0, 36.0),
            ("hall", a, 45.0, 20.0),
            ("hall", c, 150.0, 20.0),
        ];
        for k in 0..3 {
            for (route, b, time_s, length_m) in runs {
                let segments = vec![seg(b, true, 0, time_s, length_m, Mission)];
                log.push(mission(k, route, "goal", segments));
            }
        }
        let m = CreditModel::learn(&log).unwrap();
        let door = m.rates("door", 0, 36.0, 36.0);
        assert!(door.automove.get(8) > 1.5 * door.automove.get(7), "{door:?}");
        let hall = m.rates("hall", 0, 20.0, 20.0);
        assert!(hall.automove.get(7) > 2.0 * hall.automove.get(8), "{hall:?}");
        // λ3, λ4 differ by hypothesis only through each behaviour's data.
        assert_eq!(door.automove.get(7), door.contour.get(7));
    }

    #[test]
    fn exploration_tries_each_behaviour_once_per_route_and_only_when_quiet() {
        use SegmentEnd::Mission;
        let a = Behaviour::AutoMove;
        let empty = CreditModel::learn(&[]).unwrap();
        assert_eq!(empty.explore("r", 0), Some(a));
        assert_eq!(empty.explore("r", 1), None);
        let log = vec![mission(
            1,
            "r",
            "goal",
            vec![seg(a, true, 1, 40.0, 20.0, Mission)],
        )];
        let m = CreditModel::learn(&log).unwrap();
        assert_eq!(m.explore("r", 0), Some(Behaviour::Contour));
        assert_eq!(m.explore("r", 2), None);
        assert_eq!(m.explore("other", 0), Some(a));
        let log = [
            log,
            vec![mission(
                2,
                "r",
                "goal",
                vec![seg(Behaviour::Contour, true, 0, 90.0, 20.0, Mission)],
            )],
        ]
        .concat();
        assert_eq!(CreditModel::learn(&log).unwrap().explore("r", 0), None);
    }

    #[test]
    fn without_missions_the_rates_are_the_prior() {
        let m = CreditModel::learn(&[]).unwrap();
        let r = m.rates("", 1, 20.0, 20.0);
        let prior = CreditRates::initial();
        for i in [3, 4, 5, 6, 9, 10, 12, 13, 14] {
            assert!(
                (r.automove.get(i) - prior.get(i)).abs() / prior.get(i) < 1e-12,
                "λ{i}"
            );
        }
        assert!((r.automove.get(7) - SPEED_PRIOR_MPS[0] / 20.0).abs() < 1e-12);
        assert!((r.automove.get(8) - SPEED_PRIOR_MPS[1] / 20.0).abs() < 1e-12);
    }
}
