//! The tour-guide robot's controller: the localizer, AutoMove and contour
//! tracking on one robot, with the behaviour chosen by a policy.
//!
//! Every cycle the localizer takes the odometry and the scan (a filter
//! iteration after the robot moved `update_min_d` or turned
//! `update_min_a`), the active behaviour drives from the localizer's
//! estimate, and the controller reports what happened as typed events:
//!
//! | event | when | payload |
//! |---|---|---|
//! | `warning` | the localizer goes from Success to Warning | `score_estimate`, `score_odometry` |
//! | `success` | back from Warning to Success | same |
//! | `abnormal` | AutoMove's exception has lasted `abnormal_after_s` | `exception` |
//! | `normal` | AutoMove is Normal again | — |
//! | `ask` | the robot starts asking people to step aside | `exception`: AutoMove's (`path_blocking`, `goal_occupation`) or `contour_blocked` (contour tracking held up, or stopped at a hit point) |
//! | `switch` | the active behaviour changes | `from`, `to`, `reason` |
//! | `decision` | the GSPN supervisor decides | `reason`, `f_auto`, `f_cont`, `choice`, `lambda3`…`lambda10`, `p_loc_succ`, `p_loc_warn` |
//! | `arrived` | the estimate is within `arrive_m` of the goal | — |
//!
//! It never sees the true pose: it declares the goal reached from its
//! estimate, and the simulator judges that by the truth.
//!
//! **Policies** (docs/tour-guide.md, the comparison): one behaviour throughout;
//! AutoMove until the first Warning and contour tracking from then on (the
//! rule added to AutoMove); the rule alone (contour tracking while the
//! localizer warns, AutoMove while it succeeds); and the GSPN supervisor:
//! the rule, plus a decision by `f_auto > f_cont` at the start of the
//! mission and whenever the localizer returns from Warning to Success — at
//! the start with the learnt λ7, λ8, on a return with λ7, λ8 from the
//! remaining part of each behaviour's reference trajectory
//! ([`crate::supervisor::reference`]).

use robot::{Command, Controller, Event, GridMap, LaserScan, Notes, Perception, Pose, Request, Step, Vec2};

use crate::supervisor::credit_learning::{CONTEXT_NAMES, ContextRates, CreditModel, CrowdMeter};
use crate::supervisor::log::{DecisionLog, Segment, SegmentEnd, Sojourn, StateName};
use crate::supervisor::plan::Planner;
use crate::supervisor::reference::Reference;
use crate::supervisor::{Rates, Supervisor};

use super::automove::{AutoMove, AutoMoveError, AutoMoveParams};
use super::contour::{ContourMode, ContourParams, ContourTracker, Side};
use crate::supervisor::Behaviour;
use localization::{
    LocalizationError, LocalizationStatus, Localizer, MclParams, RecoveryStage, ScanConsistency, UpdateInfo,
};

/// Parameters of the guide controller.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GuideParams {
    /// The localizer.
    pub mcl: MclParams,
    /// AutoMove.
    pub automove: AutoMoveParams,
    /// Contour tracking.
    pub contour: ContourParams,
    /// The goal counts as reached when the estimate is within this
    /// distance, metres. Default 0.2.
    pub arrive_m: f64,
    /// Spread of the initial particle cloud around the known start:
    /// position, metres. Default 0.1.
    pub initial_std_xy_m: f64,
    /// Spread of the initial particle cloud: heading, radians. Default 0.05.
    pub initial_std_theta_rad: f64,
}

impl Default for GuideParams {
    fn default() -> GuideParams {
        GuideParams {
            mcl: MclParams::default(),
            automove: AutoMoveParams::default(),
            contour: ContourParams::default(),
            arrive_m: 0.2,
            initial_std_xy_m: 0.1,
            initial_std_theta_rad: 0.05,
        }
    }
}

/// What the guide controller builds from a static map before a mission —
/// the localizer's likelihood field and free cells, AutoMove's whole-map
/// cost map, static cost layer and wall mask — built once with the
/// parameters and shared (immutable) by every mission on the map
/// ([`GuideController::on_map`]). In the museum, building it once saves
/// 8 % of an AutoMove mission without visitors (24 missions of
/// `museum_batch automove 0 24`: 1.91 → 1.75 s on one core; results the
/// same bit for bit).
#[derive(Debug, Clone)]
pub struct GuideMap {
    params: GuideParams,
    localizer: Localizer,
    automove: AutoMove,
}

impl GuideMap {
    /// Prepares `map` for controllers with `params`. Fails on bad
    /// parameters or a map without free space.
    pub fn new(map: &GridMap, params: GuideParams) -> Result<GuideMap, GuideError> {
        params.contour.validate().map_err(GuideError::Params)?;
        for (name, v) in [
            ("arrive_m", params.arrive_m),
            ("initial_std_xy_m", params.initial_std_xy_m),
            ("initial_std_theta_rad", params.initial_std_theta_rad),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(GuideError::Params(format!(
                    "guide.{name} must be a finite number ≥ 0, got {v}"
                )));
            }
        }
        Ok(GuideMap {
            localizer: Localizer::new(map, params.mcl, 0)?,
            automove: AutoMove::new(map, params.automove)?,
            params,
        })
    }

    /// The parameters the controllers on this map get.
    pub fn params(&self) -> &GuideParams {
        &self.params
    }

    /// Whether this was prepared from `map` with `params` (`O(cells)`).
    pub fn is_for(&self, map: &GridMap, params: &GuideParams) -> bool {
        &self.params == params && self.automove.map() == map
    }
}

/// Why a guide controller cannot start.
#[derive(Debug, thiserror::Error)]
pub enum GuideError {
    /// Bad parameters.
    #[error("{0}")]
    Params(String),
    /// The localizer could not be built or started.
    #[error("localizer: {0}")]
    Localizer(#[from] LocalizationError),
    /// AutoMove found no route.
    #[error(transparent)]
    AutoMove(#[from] AutoMoveError),
}

/// How the controller picks the behaviour (module docs).
#[derive(Debug, Clone)]
pub enum Policy {
    /// One behaviour for the whole mission, whatever the localizer says.
    Fixed(Behaviour),
    /// AutoMove until the localizer first warns, contour tracking from
    /// then on.
    AutoMoveThenContour,
    /// Contour tracking while the localizer warns, AutoMove while it
    /// succeeds.
    Rule,
    /// Start with this behaviour, then the rule: contour tracking from
    /// every Warning on, AutoMove from every return to Success (what
    /// calibrate-then-commit runs on a route once it knows which behaviour
    /// was faster there).
    StartThenRule(Behaviour),
    /// The crediting GSPN supervisor ([`crate::supervisor::credit`]): the
    /// net decides at the start, at every Warning and at every return to
    /// Success, with rates learnt per behaviour and crowd context.
    Supervisor(Box<CreditPlan>),
    /// The source's GSPN supervisor: the rule, and `f_auto` against
    /// `f_cont` at the start and on every return to Success.
    SupervisorSource(Box<SupervisorPlan>),
}

impl Policy {
    /// The policy for a mission on `route` (`from → to`): the crediting
    /// supervisor takes its rates for that route; others are unchanged.
    pub fn on_route(self, route: &str) -> Policy {
        match self {
            Policy::Supervisor(mut plan) => {
                plan.route = route.to_string();
                Policy::Supervisor(plan)
            }
            other => other,
        }
    }

    /// A short name: `automove`, `contour`, `automove_then_contour`, `rule`,
    /// `automove_then_rule`, `contour_then_rule`, `supervisor`,
    /// `supervisor_source`.
    pub fn name(&self) -> &'static str {
        match self {
            Policy::Fixed(Behaviour::AutoMove) => "automove",
            Policy::Fixed(Behaviour::Contour) => "contour",
            Policy::AutoMoveThenContour => "automove_then_contour",
            Policy::Rule => "rule",
            Policy::StartThenRule(Behaviour::AutoMove) => "automove_then_rule",
            Policy::StartThenRule(Behaviour::Contour) => "contour_then_rule",
            Policy::Supervisor(_) => "supervisor",
            Policy::SupervisorSource(_) => "supervisor_source",
        }
    }
}

/// What the crediting supervisor decides with: its planner (the net
/// checked and compiled), what it learnt from the log, and the route the
/// mission drives.
#[derive(Debug, Clone)]
pub struct CreditPlan {
    /// Turns a context's rates into a choice ([`crate::supervisor::plan`]).
    pub planner: std::sync::Arc<dyn Planner>,
    /// The rates learnt per route, behaviour and crowd context.
    pub model: CreditModel,
    /// The mission's route (`from → to`; `""` for a log of one route):
    /// the context the rates are taken for.
    pub route: String,
}

/// What the source's supervisor decides with: the net compiled, the learnt
/// rates and the behaviours' references.
#[derive(Debug, Clone)]
pub struct SupervisorPlan {
    /// The supervisor.
    pub supervisor: Supervisor,
    /// λ1…λ11 as learnt (λ7, λ8 from the references' mean times).
    pub rates: Rates,
    /// AutoMove's reference.
    pub automove: Reference,
    /// Contour tracking's reference.
    pub contour: Reference,
}

/// What a mission leaves for the log: sojourns, time per behaviour,
/// decisions.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct GuideSummary {
    /// The localizer's sojourns in Success and Warning, in order (the last
    /// one open).
    pub localizer: Vec<Sojourn>,
    /// The planner's sojourns in Normal and Abnormal, in order.
    pub planner: Vec<Sojourn>,
    /// Time AutoMove drove, seconds.
    pub time_automove_s: f64,
    /// Time contour tracking drove, seconds.
    pub time_contour_s: f64,
    /// The supervisor's decisions.
    pub decisions: Vec<DecisionLog>,
    /// The mission in segments of one state each (crediting supervisor's
    /// learning, [`crate::supervisor::credit_learning`]).
    pub segments: Vec<Segment>,
}

/// What the controller counted over its mission.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct GuideStats {
    /// Times the localizer went to Warning.
    pub warnings: u32,
    /// Time in Warning, seconds.
    pub time_in_warning_s: f64,
    /// Times AutoMove became Abnormal.
    pub abnormal_episodes: u32,
    /// Time AutoMove was Abnormal, seconds.
    pub time_abnormal_s: f64,
    /// Time AutoMove drove, seconds.
    pub time_automove_s: f64,
    /// Time contour tracking drove, seconds.
    pub time_contour_s: f64,
    /// Control cycles in which the robot asked people to step aside.
    pub asking_cycles: u32,
    /// Filter iterations of the localizer.
    pub filter_iterations: u64,
}

/// The name of the particle cloud the controller notes at every filter
/// iteration ([`robot::Notes::cloud`]).
pub const PARTICLES_CLOUD: &str = "particles";

/// The tour-guide controller (module docs).
///
/// Its notes (traces, the run viewer, MCAP): the behaviour in control;
/// every tick the localizer's estimate (`estimate_x_m`, `_y_m`,
/// `_theta_rad`), `warning` (0/1) and the last filter iteration's
/// `score_estimate`, `score_odometry`, `effective_sample_size`; contour
/// tracking's `contour_mode`, `contour_m`, `contour_centred`, `contour_gap`;
/// at each filter iteration the particle cloud (`particles`); events for
/// status changes (`warning`, `success` with both scores), switches,
/// supervisor decisions (`decision` with `f_auto`, `f_cont`, the choice,
/// `p_loc_succ`, `p_loc_warn` and the rates λ3…λ10), requests and
/// arrival.
pub struct GuideController {
    p: GuideParams,
    localizer: Localizer,
    automove: AutoMove,
    contour: ContourTracker,
    policy: Policy,
    active: Behaviour,
    goal: Vec2,
    last_time_s: Option<f64>,
    status: LocalizationStatus,
    /// The scores of the last filter iteration (estimate, odometry) and
    /// its effective sample size, for the notes.
    last_scores: Option<[f64; 3]>,
    /// The scan's consistency at the last judgement (contradiction rule).
    last_consistency: Option<ScanConsistency>,
    abnormal: bool,
    asking: bool,
    request: Option<Request>,
    stats: GuideStats,
    /// Whether the first step has been taken.
    started: bool,
    /// When the localizer's and the planner's current states began.
    loc_since_s: f64,
    plan_since_s: f64,
    sojourns_loc: Vec<Sojourn>,
    sojourns_plan: Vec<Sojourn>,
    decisions: Vec<DecisionLog>,
    /// The crowd seen (unmapped objects per scan, ~10 s mean).
    crowd: CrowdMeter,
    /// Closed segments, and the open one with its state.
    segments: Vec<Segment>,
    open: Option<(SegmentKey, Segment)>,
    /// Remaining length along the crediting supervisor's reference at the
    /// last step, metres.
    last_remaining_m: Option<f64>,
    /// The crediting supervisor's reference: AutoMove's route planned on
    /// the static map at the start (progress and remaining length are
    /// measured along it).
    reference: Option<Reference>,
}

/// The state a segment is in: behaviour, localized, planner Normal,
/// crowd context.
type SegmentKey = (Behaviour, bool, bool, usize);

/// Seconds over which the crowd is averaged for the context.
pub const CROWD_WINDOW_S: f64 = 10.0;

impl GuideController {
    /// A controller on `map`, starting from the known pose `start` (the
    /// particle cloud spread around it) towards `goal`, with `policy`; the
    /// localizer's randomness comes from `seed`. Fails on bad parameters or
    /// when AutoMove finds no route from `start` to `goal`.
    pub fn new(
        map: &GridMap,
        params: GuideParams,
        start: Pose,
        goal: Vec2,
        policy: Policy,
        seed: u64,
    ) -> Result<GuideController, GuideError> {
        GuideController::on_map(&GuideMap::new(map, params)?, start, goal, policy, seed)
    }

    /// A controller as [`GuideController::new`] makes it, on a map
    /// prepared beforehand (with its parameters): the same controller, bit
    /// for bit, without building the map's likelihood field and cost maps
    /// again.
    pub fn on_map(
        map: &GuideMap,
        start: Pose,
        goal: Vec2,
        policy: Policy,
        seed: u64,
    ) -> Result<GuideController, GuideError> {
        let params = map.params.clone();
        let mut localizer = map.localizer.on_same_map(seed);
        localizer.init_pose(start, params.initial_std_xy_m, params.initial_std_theta_rad)?;
        let mut automove = map.automove.on_same_map();
        let route = automove.set_goal(start.position(), goal)?;
        let reference = matches!(policy, Policy::Supervisor(_)).then(|| Reference {
            mean_time_s: 0.0,
            mean_speed_mps: 0.0,
            trajectory: route.path.clone(),
        });
        let contour = ContourTracker::new(params.contour).map_err(GuideError::Params)?;
        let active = match &policy {
            Policy::Fixed(b) | Policy::StartThenRule(b) => *b,
            Policy::AutoMoveThenContour
            | Policy::Rule
            | Policy::Supervisor(_)
            | Policy::SupervisorSource(_) => Behaviour::AutoMove,
        };
        Ok(GuideController {
            p: params,
            localizer,
            automove,
            contour,
            policy,
            active,
            goal,
            last_time_s: None,
            status: LocalizationStatus::Success,
            last_scores: None,
            last_consistency: None,
            abnormal: false,
            asking: false,
            request: None,
            stats: GuideStats::default(),
            started: false,
            loc_since_s: 0.0,
            plan_since_s: 0.0,
            sojourns_loc: Vec::new(),
            sojourns_plan: Vec::new(),
            decisions: Vec::new(),
            crowd: CrowdMeter::new(CROWD_WINDOW_S),
            segments: Vec::new(),
            open: None,
            last_remaining_m: None,
            reference,
        })
    }

    /// The localizer.
    pub fn localizer(&self) -> &Localizer {
        &self.localizer
    }

    /// AutoMove (its route, its last path).
    pub fn automove(&self) -> &AutoMove {
        &self.automove
    }

    /// The pose estimate now.
    pub fn estimate(&self) -> Pose {
        self.localizer.estimate()
    }

    /// The behaviour driving.
    pub fn active(&self) -> Behaviour {
        self.active
    }

    /// The policy.
    pub fn policy(&self) -> &Policy {
        &self.policy
    }

    /// What the mission leaves for the log, the open sojourns closed at
    /// `end_s` (the time the mission ended).
    pub fn summary(&self, end_s: f64) -> GuideSummary {
        let mut localizer = self.sojourns_loc.clone();
        localizer.push(Sojourn {
            state: match self.status {
                LocalizationStatus::Success => StateName::Success,
                LocalizationStatus::Warning => StateName::Warning,
            },
            duration_s: (end_s - self.loc_since_s).max(0.0),
            ended: false,
        });
        let mut planner = self.sojourns_plan.clone();
        planner.push(Sojourn {
            state: if self.abnormal {
                StateName::Abnormal
            } else {
                StateName::Normal
            },
            duration_s: (end_s - self.plan_since_s).max(0.0),
            ended: false,
        });
        let mut segments = self.segments.clone();
        if let Some((_, open)) = self.open {
            segments.push(Segment {
                end: SegmentEnd::Mission,
                ..open
            });
        }
        GuideSummary {
            localizer,
            planner,
            time_automove_s: self.stats.time_automove_s,
            time_contour_s: self.stats.time_contour_s,
            decisions: self.decisions.clone(),
            segments,
        }
    }

    /// Makes `to` the active behaviour (an event when it changes).
    fn switch(&mut self, to: Behaviour, reason: &str, t: f64, at: Vec2, notes: &mut Notes) {
        if to == self.active {
            return;
        }
        notes.event(
            Event::new("switch", t)
                .at(at)
                .with("from", behaviour_name(self.active))
                .with("to", behaviour_name(to))
                .with("reason", reason),
        );
        match to {
            Behaviour::AutoMove => self.automove.resume(0.0, 0.0),
            Behaviour::Contour => self.contour.reset(),
        }
        self.active = to;
    }

    /// The supervisor's decision at `t` (`reason`: `start` or `recovered`):
    /// the behaviour it chooses, or the active one when it cannot decide
    /// (an event says why).
    fn decide(&mut self, reason: &str, t: f64, estimate: Pose, notes: &mut Notes) -> Behaviour {
        let Policy::SupervisorSource(plan) = &self.policy else {
            return self.active;
        };
        let mut rates = plan.rates;
        if reason != "start" {
            rates.set(7, plan.automove.rate_from(estimate.position()));
            rates.set(8, plan.contour.rate_from(estimate.position()));
        }
        match plan.supervisor.decide(&rates) {
            Ok(d) => {
                let mut e = Event::new("decision", t)
                    .at(estimate.position())
                    .with("reason", reason)
                    .with("f_auto", d.f_auto)
                    .with("f_cont", d.f_cont)
                    .with("choice", behaviour_name(d.choice))
                    .with("p_loc_succ", d.p_loc_succ)
                    .with("p_loc_warn", d.p_loc_warn);
                for i in 3..=10 {
                    e = e.with(format!("lambda{i}"), rates.get(i));
                }
                notes.event(e);
                self.decisions.push(DecisionLog {
                    time_s: t,
                    reason: reason.to_string(),
                    rates: rates.as_array().to_vec(),
                    f_auto: d.f_auto,
                    f_cont: d.f_cont,
                    p_loc_succ: d.p_loc_succ,
                    p_loc_warn: d.p_loc_warn,
                    choice: d.choice,
                    context: None,
                    route: None,
                    contour_rates: Vec::new(),
                    marking: Vec::new(),
                    explore: false,
                });
                d.choice
            }
            Err(err) => {
                notes.event(Event::new("decision_error", t).with("error", err.to_string()));
                self.active
            }
        }
    }

    /// The crediting supervisor's decision at `t` (`reason`: `start`,
    /// `warning` or `recovered`), the localizer `localized` or not: the
    /// behaviour it chooses — at the start, the one to explore if the model
    /// says so ([`CreditModel::explore`]) — or the active one when it
    /// cannot decide (an event says why).
    fn decide_credit(
        &mut self,
        reason: &str,
        t: f64,
        estimate: Pose,
        localized: bool,
        notes: &mut Notes,
    ) -> Behaviour {
        let Policy::Supervisor(plan) = &self.policy else {
            return self.active;
        };
        let context = self.crowd.context();
        let (remaining, length) = self
            .reference
            .as_ref()
            .map_or((0.0, 0.0), |r| (r.remaining_m(estimate.position()), r.length_m()));
        let rates = plan.model.rates(&plan.route, context, remaining, length);
        let explore = if reason == "start" {
            plan.model.explore(&plan.route, context)
        } else {
            None
        };
        match plan.planner.decide(&rates.automove, &rates.contour, localized) {
            Ok(d) => {
                let choice = explore.unwrap_or(d.choice);
                let marking = decision_marking(localized, self.abnormal);
                let route = plan.route.clone();
                let planner = plan.planner.name();
                notes.event(
                    decision_event(t, estimate, reason, &d, choice, &rates, &marking)
                        .with("context", CONTEXT_NAMES[context])
                        .with("crowd", self.crowd.mean())
                        .with("remaining_m", remaining)
                        .with("route", route.clone())
                        .with("planner", planner)
                        .with("explore", f64::from(u8::from(explore.is_some()))),
                );
                self.decisions.push(DecisionLog {
                    time_s: t,
                    reason: reason.to_string(),
                    rates: rates.automove.as_array().to_vec(),
                    f_auto: d.f_auto,
                    f_cont: d.f_cont,
                    p_loc_succ: 1.0 - d.p_loc_warn,
                    p_loc_warn: d.p_loc_warn,
                    choice,
                    context: Some(context),
                    route: (!route.is_empty()).then_some(route),
                    contour_rates: rates.contour.as_array().to_vec(),
                    marking: marking.iter().map(|p| p.to_string()).collect(),
                    explore: explore.is_some(),
                });
                choice
            }
            Err(err) => {
                notes.event(Event::new("decision_error", t).with("error", err.to_string()));
                self.active
            }
        }
    }

    /// Accounts the control cycle that just ended (`dt` seconds, in the
    /// state the controller is in now) to the segments, with the progress
    /// made along the crediting supervisor's reference to `estimate`.
    fn account_segment(&mut self, dt: f64, estimate: Pose) {
        let remaining = self
            .reference
            .as_ref()
            .map(|r| r.remaining_m(estimate.position()));
        let progress = match (self.last_remaining_m, remaining) {
            (Some(a), Some(b)) => Some(a - b),
            _ => None,
        };
        self.last_remaining_m = remaining;
        let key: SegmentKey = (
            self.active,
            self.status == LocalizationStatus::Success,
            !self.abnormal || self.active == Behaviour::Contour,
            self.crowd.context(),
        );
        if let Some((k, seg)) = self.open
            && k != key
        {
            let end = if k.1 != key.1 {
                SegmentEnd::Localizer
            } else if k.2 != key.2 {
                SegmentEnd::Planner
            } else if k.0 != key.0 {
                SegmentEnd::Behaviour
            } else {
                SegmentEnd::Context
            };
            self.segments.push(Segment { end, ..seg });
            self.open = None;
        }
        let (_, seg) = self.open.get_or_insert((
            key,
            Segment {
                behaviour: key.0,
                localized: key.1,
                normal: key.2,
                context: key.3,
                duration_s: 0.0,
                progress_m: remaining.map(|_| 0.0),
                end: SegmentEnd::Mission,
            },
        ));
        seg.duration_s += dt;
        if let (Some(p), Some(acc)) = (progress, seg.progress_m.as_mut()) {
            *acc += p;
        }
    }

    /// The localizer's state.
    pub fn status(&self) -> LocalizationStatus {
        self.status
    }

    /// Whether AutoMove is Abnormal.
    pub fn abnormal(&self) -> bool {
        self.abnormal
    }

    /// What the controller counted so far.
    pub fn stats(&self) -> GuideStats {
        self.stats
    }
}

/// The name of a behaviour in traces.
fn behaviour_name(b: Behaviour) -> &'static str {
    match b {
        Behaviour::AutoMove => "automove",
        Behaviour::Contour => "contour",
    }
}

/// The supervisor net's places marked at a decision: `P0` (choosing the
/// behaviour), the localizer's (`P5` Success, `P6` Warning) and the
/// planner's (`P7` Normal, `P8` Abnormal).
fn decision_marking(localized: bool, abnormal: bool) -> [&'static str; 3] {
    [
        "P0",
        if localized { "P5" } else { "P6" },
        if abnormal { "P8" } else { "P7" },
    ]
}

/// The values the controller notes every cycle under a supervisor: the
/// supervisor net's marking (`net.P1` … `net.P8`, 0 or 1) as the robot's
/// state puts it — the behaviour running (`P1` AutoMove, `P2` contour
/// tracking), the localizer's state, the planner's.
pub const NET_MARKING_VALUES: [&str; 6] = ["net.P1", "net.P2", "net.P5", "net.P6", "net.P7", "net.P8"];

/// The `decision` event of the crediting supervisor: the choice, the value
/// of each (`f_auto`, `f_cont`: completion throughputs; `time_auto_s`,
/// `time_cont_s`: their inverses, the expected time per completed mission
/// with a failure costing the time limit), the rates of each hypothesis
/// (λ3…λ15 the AutoMove hypothesis's, `lambda3_cont`, `lambda4_cont`
/// contour tracking's, `speed_auto_mps`, `speed_cont_mps`) and the net's
/// marking.
fn decision_event(
    t: f64,
    estimate: Pose,
    reason: &str,
    d: &crate::supervisor::credit::CreditDecision,
    choice: Behaviour,
    rates: &ContextRates,
    marking: &[&str],
) -> Event {
    let mut e = Event::new("decision", t)
        .at(estimate.position())
        .with("reason", reason)
        .with("f_auto", d.f_auto)
        .with("f_cont", d.f_cont);
    for (key, f) in [("time_auto_s", d.f_auto), ("time_cont_s", d.f_cont)] {
        if f > 0.0 {
            e = e.with(key, 1.0 / f);
        }
    }
    e = e
        .with("choice", behaviour_name(choice))
        .with("p_success", d.p_success)
        .with("p_loc_warn", d.p_loc_warn)
        .with("marking", marking.join(" "))
        .with("speed_auto_mps", rates.speeds[0].rate)
        .with("speed_cont_mps", rates.speeds[1].rate)
        .with("lambda3_cont", rates.contour.get(3))
        .with("lambda4_cont", rates.contour.get(4));
    for i in 3..=15 {
        e = e.with(format!("lambda{i}"), rates.automove.get(i));
    }
    e
}

impl GuideController {
    /// Adds the cycle that just ended (`dt` seconds) to the time spent in
    /// the localizer's, the planner's and the behaviours' states and to
    /// the current segment.
    fn account_time(&mut self, dt: f64) {
        if self.status == LocalizationStatus::Warning {
            self.stats.time_in_warning_s += dt;
        }
        if self.abnormal {
            self.stats.time_abnormal_s += dt;
        }
        match self.active {
            Behaviour::AutoMove => self.stats.time_automove_s += dt,
            Behaviour::Contour => self.stats.time_contour_s += dt,
        }
        let estimate = self.localizer.estimate();
        self.account_segment(dt, estimate);
    }

    /// Takes in what a localizer update did: its scores and consistency,
    /// and on a change of status the event, the sojourn and the policy's
    /// switch.
    fn observe_update(&mut self, info: &UpdateInfo, t: f64, notes: &mut Notes) {
        self.stats.filter_iterations += u64::from(info.filtered);
        if let Some(c) = info.consistency {
            self.last_consistency = Some(c);
            self.crowd.observe(t, c.unmapped_objects as f64);
        }
        self.last_scores = Some([
            info.score_estimate,
            info.score_odometry,
            info.effective_sample_size,
        ]);
        if notes.is_enabled() && info.filtered {
            notes.cloud(PARTICLES_CLOUD, self.localizer.particles().map(|p| p.pose));
        }
        if info.status != self.status {
            let kind = match info.status {
                LocalizationStatus::Warning => {
                    self.stats.warnings += 1;
                    "warning"
                }
                LocalizationStatus::Success => "success",
            };
            notes.event(
                Event::new(kind, t)
                    .at(info.estimate.position())
                    .with("score_estimate", info.score_estimate)
                    .with("score_odometry", info.score_odometry),
            );
            self.sojourns_loc.push(Sojourn {
                state: match self.status {
                    LocalizationStatus::Success => StateName::Success,
                    LocalizationStatus::Warning => StateName::Warning,
                },
                duration_s: t - self.loc_since_s,
                ended: true,
            });
            self.loc_since_s = t;
            self.status = info.status;
            self.on_status_change(info.status, t, info.estimate, notes);
        }
    }

    /// The policy's answer to the localizer's new `status`: a decision of
    /// the supervisor, or the rule's switch.
    fn on_status_change(&mut self, status: LocalizationStatus, t: f64, at: Pose, notes: &mut Notes) {
        match (&self.policy, status) {
            (Policy::Fixed(_), _) => {}
            (Policy::Supervisor(_), status) => {
                let localized = status == LocalizationStatus::Success;
                let reason = if localized { "recovered" } else { "warning" };
                let choice = self.decide_credit(reason, t, at, localized, notes);
                self.switch(choice, "decision", t, at.position(), notes);
            }
            (_, LocalizationStatus::Warning) => {
                self.switch(Behaviour::Contour, "warning", t, at.position(), notes)
            }
            (Policy::AutoMoveThenContour, LocalizationStatus::Success) => {}
            (Policy::Rule | Policy::StartThenRule(_), LocalizationStatus::Success) => {
                self.switch(Behaviour::AutoMove, "success", t, at.position(), notes)
            }
            (Policy::SupervisorSource(_), LocalizationStatus::Success) => {
                let choice = self.decide("recovered", t, at, notes);
                self.switch(choice, "decision", t, at.position(), notes);
            }
        }
    }

    /// The first cycle: the sojourns start, and a supervisor makes its
    /// first decision.
    fn start(&mut self, t: f64, estimate: Pose, notes: &mut Notes) {
        self.started = true;
        self.loc_since_s = t;
        self.plan_since_s = t;
        match self.policy {
            Policy::SupervisorSource(_) => {
                let choice = self.decide("start", t, estimate, notes);
                self.switch(choice, "decision", t, estimate.position(), notes);
            }
            Policy::Supervisor(_) => {
                let localized = self.status == LocalizationStatus::Success;
                let choice = self.decide_credit("start", t, estimate, localized, notes);
                self.switch(choice, "decision", t, estimate.position(), notes);
            }
            _ => {}
        }
        if let Some(r) = &self.reference {
            self.last_remaining_m = Some(r.remaining_m(estimate.position()));
        }
    }

    /// The supervisor net's marking as the robot's state puts it
    /// ([`NET_MARKING_VALUES`]), for traces and replays.
    fn note_marking(&self, notes: &mut Notes) {
        let warning = self.status == LocalizationStatus::Warning;
        let marked = [
            self.active == Behaviour::AutoMove,
            self.active == Behaviour::Contour,
            !warning,
            warning,
            !self.abnormal,
            self.abnormal,
        ];
        for (name, on) in NET_MARKING_VALUES.iter().zip(marked) {
            notes.value(name, f64::from(u8::from(on)));
        }
    }

    /// The localizer's values of this cycle, for traces and replays.
    fn note_localization(&self, estimate: Pose, notes: &mut Notes) {
        notes.value("estimate_x_m", estimate.x_m);
        notes.value("estimate_y_m", estimate.y_m);
        notes.value("estimate_theta_rad", estimate.theta_rad);
        notes.value(
            "warning",
            f64::from(u8::from(self.status == LocalizationStatus::Warning)),
        );
        if let Some([estimate, odometry, ess]) = self.last_scores {
            notes.value("score_estimate", estimate);
            notes.value("score_odometry", odometry);
            notes.value("effective_sample_size", ess);
        }
        if let Some(c) = self.last_consistency {
            notes.value("contradiction", c.contradiction());
            notes.value("evidence_beams", c.evidence() as f64);
            notes.value("unmapped_objects", c.unmapped_objects as f64);
        }
        notes.value(
            "recovering",
            match self.localizer.recovery_stage() {
                RecoveryStage::Idle => 0.0,
                RecoveryStage::Scattered => 1.0,
                RecoveryStage::Global => 2.0,
            },
        );
    }

    /// One cycle of AutoMove: its command, with the Normal/Abnormal
    /// sojourns and events and the requests it makes.
    fn automove_cycle(
        &mut self,
        p: &Perception,
        scan: &LaserScan,
        estimate: Pose,
        dt: f64,
        notes: &mut Notes,
    ) -> Command {
        let t = p.time_s;
        let s = self.automove.step(estimate, scan, p.odometry, dt, t);
        if s.abnormal != self.abnormal {
            self.sojourns_plan.push(Sojourn {
                state: if self.abnormal {
                    StateName::Abnormal
                } else {
                    StateName::Normal
                },
                duration_s: t - self.plan_since_s,
                ended: true,
            });
            self.plan_since_s = t;
            let mut e = Event::new(if s.abnormal { "abnormal" } else { "normal" }, t).at(estimate.position());
            if let Some(x) = s.exception {
                e = e.with("exception", x.name());
            }
            if s.abnormal {
                self.stats.abnormal_episodes += 1;
            }
            notes.event(e);
            self.abnormal = s.abnormal;
        }
        let asking = s.request.is_some();
        if asking {
            self.stats.asking_cycles += 1;
            if !self.asking {
                let mut e = Event::new("ask", t).at(estimate.position());
                if let Some(x) = s.exception {
                    e = e.with("exception", x.name());
                }
                notes.event(e);
            }
        }
        self.asking = asking;
        self.request = s.request;
        s.command
    }

    /// One cycle of contour tracking: its command, with the end of an
    /// Abnormal sojourn, the tracker's values and the requests it makes.
    fn contour_cycle(
        &mut self,
        p: &Perception,
        scan: &LaserScan,
        estimate: Pose,
        notes: &mut Notes,
    ) -> Command {
        let t = p.time_s;
        if self.abnormal {
            self.sojourns_plan.push(Sojourn {
                state: StateName::Abnormal,
                duration_s: t - self.plan_since_s,
                ended: true,
            });
            self.plan_since_s = t;
            self.abnormal = false;
            notes.event(Event::new("normal", t).at(estimate.position()));
        }
        let s = self.contour.step(scan, p.odometry, estimate, self.goal, t);
        if notes.is_enabled() {
            // What the tracker does, for traces and replays: mode
            // (0 seek, −1 following on the right, +1 on the left),
            // distance to the contour, centred, passing a gap.
            let mode = match s.mode {
                ContourMode::Seek => 0.0,
                ContourMode::Follow { side, .. } => match side {
                    Side::Left => 1.0,
                    Side::Right => -1.0,
                },
            };
            notes.value("contour_mode", mode);
            notes.value("contour_m", s.contour_m);
            notes.value("contour_centred", f64::from(u8::from(s.centred)));
            notes.value("contour_gap", f64::from(u8::from(s.gap)));
        }
        let asking = s.request.is_some();
        if asking {
            self.stats.asking_cycles += 1;
            if !self.asking {
                notes.event(
                    Event::new("ask", t)
                        .at(estimate.position())
                        .with("exception", "contour_blocked"),
                );
            }
        }
        self.asking = asking;
        self.request = s.request;
        s.command
    }
}

impl Controller for GuideController {
    fn step(&mut self, p: &Perception, notes: &mut Notes) -> Step {
        let t = p.time_s;
        let dt = self.last_time_s.map_or(0.1, |t0| (t - t0).max(1e-3));
        // Time spent in the states of the cycle that just ended.
        if self.last_time_s.is_some() {
            self.account_time(dt);
        }
        self.last_time_s = Some(t);
        self.request = None;
        let Some(scan) = p.lasers.first() else {
            notes.event(Event::new("no_laser", t));
            return Step::GiveUp;
        };
        match self.localizer.update_at(t, p.odometry, scan) {
            Ok(Some(info)) => self.observe_update(&info, t, notes),
            Ok(None) => {}
            Err(e) => {
                notes.event(Event::new("localizer_error", t).with("error", e.to_string()));
                return Step::GiveUp;
            }
        }
        let estimate = self.localizer.estimate();
        if !self.started {
            self.start(t, estimate, notes);
        }
        if notes.is_enabled() {
            self.note_localization(estimate, notes);
            if matches!(self.policy, Policy::Supervisor(_)) {
                self.note_marking(notes);
            }
        }
        if estimate.position().dist(self.goal) <= self.p.arrive_m {
            notes.event(Event::new("arrived", t).at(estimate.position()));
            notes.behaviour(behaviour_name(self.active));
            return Step::Done(Command::Stop);
        }
        notes.behaviour(behaviour_name(self.active));
        let command = match self.active {
            Behaviour::AutoMove => self.automove_cycle(p, scan, estimate, dt, notes),
            Behaviour::Contour => self.contour_cycle(p, scan, estimate, notes),
        };
        Step::Run(command)
    }

    fn request(&self) -> Option<Request> {
        self.request
    }
}
