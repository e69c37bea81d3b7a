//! Dynamic weighted voting (docs/voting.md; Amin, Mamat & Kwong 2005): a
//! reactive controller for a robot with IR detectors, sonars and odometry
//! that heads for a goal round the obstacles it senses.
//!
//! ```
//! use robot::{Controller, Notes, Perception, Step, Vec2};
//! use voting::{VotingController, VotingParams};
//!
//! let mut controller = VotingController::new(VotingParams::default()).unwrap();
//! // Nothing sensed, the goal 5 m ahead: the robot drives towards it.
//! let open = Perception { goal: Some(Vec2::new(5.0, 0.0)), ..Perception::default() };
//! let Step::Run(command) = controller.step(&open, &mut Notes::enabled()) else {
//!     panic!("the goal is not reached yet")
//! };
//! assert!(controller.ballot().goal_bearing_rad.abs() < 1e-9);
//! println!("{command:?}: action {}", controller.ballot().chosen);
//! ```
//!
//! Every behaviour votes in [0, 1] for every action of a small discrete set;
//! a weight manager sets the behaviours' weights from the situation; the
//! arbiter picks `argmax_m V(m)` with
//! `V(m) = W_obs · Σ_obstacle-team w_b b(m) + W_goal · Σ_goal-team w_b b(m)`.
//!
//! | weight | value |
//! |---|---|
//! | `W_IR`, `W_sonar` | 0.5 each (1 for a team of one) |
//! | `W_plan` | `(mark_sum − mark_min)/(mark_max − mark_min)` clamped to [0, 1] |
//! | `W_odo` | `1 − W_plan` (1 without planning) |
//! | `W_obs` | `0.6 + 0.3 · N/N_total`, N = IR detectors triggered |
//! | `W_goal` | `1 − W_obs` |
//!
//! **Decisions** where the source is silent: the centre weight uses the IR
//! detectors whenever the robot has them, even in the sonar-only
//! combination (they are the robot's clutter sensor); ties between actions go
//! to the one whose heading is nearest Forward (Escape last); Escape turns
//! towards the side whose IR detectors are less triggered, then towards the
//! goal, then left. Behaviour details: [`behaviours`], [`memory`].
#![warn(missing_docs)]

pub mod actions;
pub mod behaviours;
pub mod memory;
pub mod trace_layer;

use robot::{Controller, Notes, Perception, Step, Vec2, wrap_angle};

use actions::{ActionKind, ActionSet};
use memory::{MemoryParams, SpatialMemory};

/// Which behaviours take part (the source's four experiments).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Teams {
    /// `b_IR` in the obstacle team.
    pub ir: bool,
    /// `b_sonar` in the obstacle team.
    pub sonar: bool,
    /// `b_odo` in the goal team.
    pub odometry: bool,
    /// `b_plan` in the goal team.
    pub planning: bool,
}

impl Teams {
    /// Experiment `k` of the source (1: IR + odometry; 2: sonar + odometry;
    /// 3: IR + sonar + odometry; 4: IR + sonar + odometry + planning).
    pub fn experiment(k: u32) -> Option<Teams> {
        let t = |ir, sonar, planning| Teams {
            ir,
            sonar,
            odometry: true,
            planning,
        };
        match k {
            1 => Some(t(true, false, false)),
            2 => Some(t(false, true, false)),
            3 => Some(t(true, true, false)),
            4 => Some(t(true, true, true)),
            _ => None,
        }
    }

    /// A short label, e.g. "IR+sonar / odo+plan".
    pub fn label(&self) -> String {
        let mut obs = Vec::new();
        if self.ir {
            obs.push("IR");
        }
        if self.sonar {
            obs.push("sonar");
        }
        let mut goal = Vec::new();
        if self.odometry {
            goal.push("odo");
        }
        if self.planning {
            goal.push("plan");
        }
        format!("{} / {}", obs.join("+"), goal.join("+"))
    }
}

/// Parameters of the voting controller, with documented defaults.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VotingParams {
    /// The behaviours taking part. Default: experiment 4 (all).
    pub teams: Teams,
    /// The action set. Default: [`ActionSet::default`].
    pub actions: ActionSet,
    /// Window width β of the Π-function, radians. Default 60° (1.0472).
    ///
    /// **Decision** (the source gives no value): β sets how hard goal
    /// seeking resists a detour. One triggered detector in an action's
    /// cover lowers its IR vote from 1.0 to 0.7, worth `0.3 · W_obs ≥ 0.19`
    /// at the centre; the goal's preference for Forward over a 60° turn is
    /// `(1 − Π(60°)) · W_goal ≤ 0.36 · (1 − Π(60°))`. With β ≥ 55° a single
    /// detection straight ahead is enough to turn the robot; with a narrow
    /// β (30°) the robot drives on into a pole that only one beam sees.
    pub beta_rad: f64,
    /// Sonar: distance below which an action gets 0, metres. Default 0.25.
    pub sonar_d_min_m: f64,
    /// Sonar: distance above which an action gets 1, metres. Default 1.0.
    pub sonar_d_max_m: f64,
    /// `mark_sum` at which planning starts to weigh in. Default 25.
    ///
    /// **Decision**: the sum over the default 5 × 5 neighbourhood
    /// ([`MemoryParams::neighbourhood`] 2) that a path without any revisit
    /// can reach — each cell entered once — so that, by the pigeonhole
    /// rule, a sum above it proves the robot came back to a cell: the
    /// source's "belief of being trapped" starts with evidence, not on the
    /// first turn at a wall. With a different radius `r` the same rule
    /// gives `(2r + 1)²`. Measured in the voting suite against the earlier
    /// 6 / 20 (below one pass's count): field 11 (the narrowest passage,
    /// where the robot lingers at the wall) 0.96 against 0.86, within
    /// IR + sonar's interval, fields 1–10 unchanged; the traps 0.98 / 0.64
    /// / 0.94 against 0.96 / 0.94 / 0.94, planning starting later — the
    /// deep trap runs out of time more often, and the traps take longer.
    pub mark_min: f64,
    /// `mark_sum` at which planning takes over. Default 50: every cell of
    /// the neighbourhood entered twice on average (twice `mark_min`).
    pub mark_max: f64,
    /// The spatial memory of `b_plan`.
    pub memory: MemoryParams,
    /// Stop (done) within this distance of the goal by odometry, metres.
    /// Default 0.05: the run is judged by the true position within the
    /// task's tolerance (0.3 m in the lab), so aiming at the goal point
    /// leaves the whole tolerance to dead-reckoning error (as
    /// [`activity::PriorityParams::arrive_m`]).
    pub arrive_m: f64,
    /// Half-width of the ground an action sweeps, for the sonar's
    /// `D_obs`: the robot's radius plus a margin, metres. Default 0.2
    /// (AIBOT: 0.15 + 0.05).
    pub swept_half_width_m: f64,
    /// How far the robot drives (by odometry) before `b_sonar` forgets an
    /// echo, metres; 0 keeps only the current reading. Default 1.0
    /// (`D_max`).
    ///
    /// **Decision** (the source votes on the current reading only): three
    /// 25° cones at 0°, ±30° cover ±42.5°; an obstacle beside the robot is
    /// in none of them. An inner corner of a bend, or the edge of an
    /// opening the robot slides past, is heard while it is ahead and lost
    /// as it comes abeam — just when the goal's pull turns the robot into
    /// it (every sonar-only run cut the corner of the bent corridor without
    /// this). So `b_sonar` keeps the echoes it heard, carried along by
    /// odometry into the robot's frame, until the robot has driven `D_max`
    /// past them: beyond that an echo can no longer be on the ground an
    /// action sweeps before a fresh reading would see it, and odometry
    /// drift over 1 m (about 1 %) stays far below the footprint's margin.
    /// A short-term local map of this kind is the usual companion of a
    /// sparse sonar ring.
    pub sonar_memory_m: f64,
}

impl Default for VotingParams {
    fn default() -> Self {
        VotingParams {
            teams: Teams::experiment(4).unwrap_or(Teams {
                ir: true,
                sonar: true,
                odometry: true,
                planning: true,
            }),
            actions: ActionSet::default(),
            beta_rad: 60f64.to_radians(),
            sonar_d_min_m: 0.25,
            sonar_d_max_m: 1.0,
            mark_min: 25.0,
            mark_max: 50.0,
            memory: MemoryParams::default(),
            arrive_m: 0.05,
            swept_half_width_m: 0.2,
            sonar_memory_m: 1.0,
        }
    }
}

impl VotingParams {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), String> {
        self.actions.validate()?;
        if !(self.beta_rad.is_finite() && self.beta_rad > 0.0) {
            return Err(format!("beta_rad must be > 0, got {}", self.beta_rad));
        }
        if !(self.sonar_d_min_m >= 0.0 && self.sonar_d_max_m > self.sonar_d_min_m) {
            return Err(format!(
                "need 0 ≤ sonar_d_min_m < sonar_d_max_m, got {} and {}",
                self.sonar_d_min_m, self.sonar_d_max_m
            ));
        }
        if self.mark_max.partial_cmp(&self.mark_min) != Some(std::cmp::Ordering::Greater) {
            return Err(format!(
                "need mark_min < mark_max, got {} and {}",
                self.mark_min, self.mark_max
            ));
        }
        if !(self.teams.ir || self.teams.sonar) || !(self.teams.odometry || self.teams.planning) {
            return Err("each team needs at least one behaviour".into());
        }
        if !(self.swept_half_width_m.is_finite() && self.swept_half_width_m > 0.0) {
            return Err(format!(
                "swept_half_width_m must be > 0, got {}",
                self.swept_half_width_m
            ));
        }
        if !(self.sonar_memory_m.is_finite() && self.sonar_memory_m >= 0.0) {
            return Err(format!(
                "sonar_memory_m must be a finite number ≥ 0, got {}",
                self.sonar_memory_m
            ));
        }
        if !(self.memory.cell_m > 0.0 && self.memory.size > 0) {
            return Err("the spatial memory needs cell_m > 0 and size > 0".into());
        }
        Ok(())
    }
}

/// The weights of one tick.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Weights {
    /// IR within the obstacle team.
    pub ir: f64,
    /// Sonar within the obstacle team.
    pub sonar: f64,
    /// Odometry goal seeking within the goal team.
    pub odo: f64,
    /// Planning within the goal team.
    pub plan: f64,
    /// Obstacle team at the centre.
    pub obs: f64,
    /// Goal team at the centre.
    pub goal: f64,
}

/// `W_plan = (mark_sum − mark_min)/(mark_max − mark_min)`, clamped to [0, 1].
pub fn plan_weight(mark_sum: f64, mark_min: f64, mark_max: f64) -> f64 {
    ((mark_sum - mark_min) / (mark_max - mark_min)).clamp(0.0, 1.0)
}

/// `W_obs = 0.6 + 0.3 · N/N_total` (0.6 without detectors).
pub fn obstacle_weight(triggered: usize, total: usize) -> f64 {
    if total == 0 {
        0.6
    } else {
        0.6 + 0.3 * triggered as f64 / total as f64
    }
}

/// Everything the controller computed in one tick (for traces and tests).
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct Ballot {
    /// Votes of each behaviour, by action (empty if not in a team).
    pub ir: Vec<f64>,
    /// Sonar votes.
    pub sonar: Vec<f64>,
    /// Odometry goal-seeking votes.
    pub odo: Vec<f64>,
    /// Planning votes.
    pub plan: Vec<f64>,
    /// Weights.
    pub weights: Weights,
    /// Fused votes.
    pub fused: Vec<f64>,
    /// Index of the chosen action.
    pub chosen: usize,
    /// Bearing of the goal relative to the heading, radians.
    pub goal_bearing_rad: f64,
    /// Bearing of the planning behaviour's temporary goal, radians.
    pub temp_bearing_rad: f64,
    /// `mark_sum` around the robot.
    pub mark_sum: f64,
}

/// The dynamic weighted voting controller.
#[derive(Debug, Clone)]
pub struct VotingController {
    p: VotingParams,
    memory: Option<SpatialMemory>,
    ir_covers: Vec<Vec<usize>>,
    ir_layout: usize,
    swept: behaviours::SweptPaths,
    ballot: Ballot,
    steer: Option<f64>,
    heard: EchoMemory,
}

/// Echoes `b_sonar` remembers ([`VotingParams::sonar_memory_m`]): points in
/// the odometry frame with the odometer reading when they were heard.
#[derive(Debug, Clone, Default)]
struct EchoMemory {
    /// (point in the odometry frame, odometer when heard).
    points: Vec<(Vec2, f64)>,
    /// Distance driven by odometry, metres.
    odometer_m: f64,
    /// Where the robot was at the last tick (odometry).
    last: Option<Vec2>,
    /// Pose (odometry) and odometer at the last reading remembered.
    heard_at: Option<(robot::Pose, f64)>,
    /// The remembered echoes in the robot frame, for this tick's votes.
    in_robot: Vec<behaviours::Echo>,
}

impl EchoMemory {
    /// Most points remembered: 1 m of travel at one reading per 2 cm, three
    /// transducers.
    const MOST: usize = 150;

    /// Advances the odometer to `pose`, forgets echoes heard more than
    /// `keep_m` ago, and lays the others out in the robot frame — those
    /// that can lie on a swept path: within `d_max_m` of the transducers
    /// (beyond, the ramp votes 1 anyway) and not behind the robot by more
    /// than `half_width_m` (every path runs forward of the robot's axle).
    fn update(
        &mut self,
        pose: &robot::Pose,
        keep_m: f64,
        mount_radius_m: f64,
        d_max_m: f64,
        half_width_m: f64,
    ) {
        let at = pose.position();
        if let Some(last) = self.last {
            self.odometer_m += (at - last).norm();
        }
        self.last = Some(at);
        let now = self.odometer_m;
        self.points.retain(|&(_, heard)| now - heard <= keep_m);
        self.in_robot.clear();
        for &(p, _) in &self.points {
            let q = pose.inverse_transform(p);
            let distance_m = (q.norm() - mount_radius_m).max(0.0);
            if distance_m <= d_max_m && q.x >= -half_width_m {
                self.in_robot.push(behaviours::Echo {
                    x_m: q.x,
                    y_m: q.y,
                    distance_m,
                });
            }
        }
    }

    /// Remembers this reading's echoes (robot frame → odometry frame),
    /// unless the robot has moved less than 2 cm and turned less than 5°
    /// since the last reading it remembered (the echoes would repeat it:
    /// a robot turning on the spot would otherwise pile them up), and at
    /// most [`Self::MOST`] points, the oldest forgotten first.
    fn hear(&mut self, pose: &robot::Pose, sonar: &[robot::SonarReading], d_max_m: f64) {
        if let Some((at, odo)) = self.heard_at {
            let turned = wrap_angle(pose.theta_rad - at.theta_rad).abs();
            if self.odometer_m - odo < 0.02 && turned < 5f64.to_radians() {
                return;
            }
        }
        self.heard_at = Some((*pose, self.odometer_m));
        if self.points.len() + sonar.len() > Self::MOST {
            let drop = (self.points.len() + sonar.len() - Self::MOST).min(self.points.len());
            self.points.drain(..drop);
        }
        for e in behaviours::echoes(sonar, d_max_m) {
            let p = pose.transform(Vec2::new(e.x_m, e.y_m));
            self.points.push((p, self.odometer_m));
        }
    }
}

impl VotingController {
    /// A controller with these parameters.
    pub fn new(p: VotingParams) -> Result<VotingController, String> {
        p.validate()?;
        let m = p.actions.len();
        let ballot = Ballot {
            fused: vec![0.0; m],
            ..Ballot::default()
        };
        let swept = behaviours::SweptPaths::new(&p.actions, p.sonar_d_max_m, p.swept_half_width_m);
        Ok(VotingController {
            swept,
            p,
            memory: None,
            ir_covers: Vec::new(),
            ir_layout: usize::MAX,
            ballot,
            steer: None,
            heard: EchoMemory::default(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &VotingParams {
        &self.p
    }

    /// What the last tick computed.
    pub fn ballot(&self) -> &Ballot {
        &self.ballot
    }

    /// Makes goal seeking steer towards this heading (odometry frame,
    /// radians) instead of the goal's bearing, or back to the goal with
    /// `None` (used by the activity-trace layer's recovery).
    pub fn steer_towards(&mut self, heading_rad: Option<f64>) {
        self.steer = heading_rad;
    }

    /// The index of the action whose heading is nearest Forward among those
    /// tied at the maximum (Escape last).
    fn argmax(&self, fused: &[f64]) -> usize {
        let max = fused.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let key = |m: usize| {
            let a = &self.p.actions.actions[m];
            match a.kind {
                ActionKind::Escape => f64::INFINITY,
                ActionKind::Arc => a.heading_rad.abs(),
            }
        };
        (0..fused.len())
            .filter(|&m| fused[m] >= max - 1e-12)
            .min_by(|&a, &b| key(a).total_cmp(&key(b)).then(a.cmp(&b)))
            .unwrap_or(0)
    }
}

/// Two teams' weighted votes for action `m` (a team without votes adds
/// nothing).
fn team_sum(w1: f64, v1: &[f64], w2: f64, v2: &[f64], m: usize) -> f64 {
    let a = if v1.is_empty() { 0.0 } else { w1 * v1[m] };
    let b = if v2.is_empty() { 0.0 } else { w2 * v2[m] };
    a + b
}

impl VotingController {
    /// Each team's votes into the ballot (a team switched off gets none):
    /// IR and sonar avoid obstacles (the sonar with the echoes it heard),
    /// odometry votes for the goal's bearing, planning for the freest
    /// bearing `temp_bearing`.
    fn cast_votes(&mut self, perception: &Perception, goal_bearing: f64, temp_bearing: f64) {
        let n_actions = self.p.actions.len();
        let pose = perception.odometry;
        let t = self.p.teams;
        let b = &mut self.ballot;
        let resize = |v: &mut Vec<f64>, on: bool| {
            v.clear();
            if on {
                v.resize(n_actions, 0.0);
            }
        };
        resize(&mut b.ir, t.ir);
        resize(&mut b.sonar, t.sonar);
        resize(&mut b.odo, t.odometry);
        resize(&mut b.plan, t.planning);
        if t.ir {
            if self.ir_layout != perception.ir.len() {
                self.ir_covers = behaviours::ir_covers(&self.p.actions, &perception.ir);
                self.ir_layout = perception.ir.len();
            }
            behaviours::ir_votes(&self.p.actions, &perception.ir, &self.ir_covers, &mut b.ir);
        }
        if t.sonar {
            let keep = self.p.sonar_memory_m;
            if keep > 0.0 {
                let mount_r = perception
                    .sonar
                    .first()
                    .map_or(0.0, |s| s.mount.x_m.hypot(s.mount.y_m));
                self.heard.update(
                    &pose,
                    keep,
                    mount_r,
                    self.p.sonar_d_max_m,
                    self.p.swept_half_width_m,
                );
            }
            behaviours::sonar_votes(
                &self.p.actions,
                &perception.sonar,
                &self.heard.in_robot,
                &self.swept,
                self.p.sonar_d_min_m,
                self.p.sonar_d_max_m,
                &mut b.sonar,
            );
            if keep > 0.0 {
                self.heard.hear(&pose, &perception.sonar, self.p.sonar_d_max_m);
            }
        }
        if t.odometry {
            behaviours::goal_votes(&self.p.actions, goal_bearing, self.p.beta_rad, &mut b.odo);
        }
        if t.planning {
            behaviours::goal_votes(&self.p.actions, temp_bearing, self.p.beta_rad, &mut b.plan);
        }
    }

    /// Fuses the teams' votes with the weights of the moment (obstacle
    /// teams by the IR triggered, goal teams by the marks around) and
    /// chooses the action; the ballot keeps it all.
    fn fuse(
        &mut self,
        perception: &Perception,
        mark_sum: f64,
        goal_bearing: f64,
        temp_bearing: f64,
    ) -> usize {
        let n_actions = self.p.actions.len();
        let t = self.p.teams;
        let b = &mut self.ballot;
        let triggered = perception.ir.iter().filter(|d| d.triggered).count();
        let obs = obstacle_weight(triggered, perception.ir.len());
        let (w_ir, w_sonar) = match (t.ir, t.sonar) {
            (true, true) => (0.5, 0.5),
            (true, false) => (1.0, 0.0),
            _ => (0.0, 1.0),
        };
        let (w_odo, w_plan) = match (t.odometry, t.planning) {
            (true, true) => {
                let wp = plan_weight(mark_sum, self.p.mark_min, self.p.mark_max);
                (1.0 - wp, wp)
            }
            (true, false) => (1.0, 0.0),
            _ => (0.0, 1.0),
        };
        b.weights = Weights {
            ir: w_ir,
            sonar: w_sonar,
            odo: w_odo,
            plan: w_plan,
            obs,
            goal: 1.0 - obs,
        };
        b.fused.resize(n_actions, 0.0);
        for m in 0..n_actions {
            b.fused[m] = obs * team_sum(w_ir, &b.ir, w_sonar, &b.sonar, m)
                + (1.0 - obs) * team_sum(w_odo, &b.odo, w_plan, &b.plan, m);
        }
        b.goal_bearing_rad = goal_bearing;
        b.temp_bearing_rad = temp_bearing;
        b.mark_sum = mark_sum;
        let fused = std::mem::take(&mut b.fused);
        let chosen = self.argmax(&fused);
        let b = &mut self.ballot;
        b.fused = fused;
        b.chosen = chosen;
        chosen
    }

    /// The ballot's weights, bearings and votes, and the chosen action, for
    /// traces.
    fn note_ballot(&self, chosen: usize, notes: &mut Notes) {
        let b = &self.ballot;
        let a = &self.p.actions.actions[chosen];
        notes.behaviour(static_name(&a.name));
        let w = b.weights;
        for (k, v) in [
            ("W_ir", w.ir),
            ("W_sonar", w.sonar),
            ("W_odo", w.odo),
            ("W_plan", w.plan),
            ("W_obs", w.obs),
            ("W_goal", w.goal),
            ("mark_sum", b.mark_sum),
            ("goal_bearing_rad", b.goal_bearing_rad),
            ("temp_bearing_rad", b.temp_bearing_rad),
        ] {
            notes.value(k, v);
        }
        for (m, v) in b.fused.iter().enumerate() {
            notes.value(VOTE_NAMES.get(m).copied().unwrap_or("V(?)"), *v);
        }
    }
}

/// Escape's direction: the side with fewer IR sensors triggered, then the
/// goal's side, then left. Whether it is left.
fn escape_left(perception: &Perception, goal_bearing: f64) -> bool {
    let (mut left, mut right) = (0, 0);
    for d in &perception.ir {
        if d.triggered {
            if d.mount.theta_rad > 0.0 {
                left += 1;
            } else if d.mount.theta_rad < 0.0 {
                right += 1;
            }
        }
    }
    match left.cmp(&right) {
        std::cmp::Ordering::Less => true,
        std::cmp::Ordering::Greater => false,
        std::cmp::Ordering::Equal => goal_bearing >= 0.0,
    }
}

impl Controller for VotingController {
    fn step(&mut self, perception: &Perception, notes: &mut Notes) -> Step {
        let pose = perception.odometry;
        let t = self.p.teams;
        let Some(goal) = perception.goal else {
            return Step::Done(robot::Command::Stop);
        };
        let to_goal = goal - pose.position();
        if to_goal.norm() <= self.p.arrive_m {
            return Step::Done(robot::Command::Stop);
        }
        let goal_bearing = wrap_angle(self.steer.unwrap_or_else(|| to_goal.angle()) - pose.theta_rad);
        let memory = self
            .memory
            .get_or_insert_with(|| SpatialMemory::new(self.p.memory, pose.position()));
        memory.visit(pose.position());
        let mark_sum = f64::from(memory.mark_sum(pose.position()));
        let temp_bearing = if t.planning {
            memory.freest_bearing(&pose, goal_bearing)
        } else {
            0.0
        };
        self.cast_votes(perception, goal_bearing, temp_bearing);
        let chosen = self.fuse(perception, mark_sum, goal_bearing, temp_bearing);
        let command = self
            .p
            .actions
            .command(chosen, escape_left(perception, goal_bearing));
        if notes.is_enabled() {
            self.note_ballot(chosen, notes);
        }
        Step::Run(command)
    }
}

const VOTE_NAMES: [&str; 12] = [
    "V(0)", "V(1)", "V(2)", "V(3)", "V(4)", "V(5)", "V(6)", "V(7)", "V(8)", "V(9)", "V(10)", "V(11)",
];

/// Trace labels are `&'static str`: the default action names map to static
/// strings; other names are reported as "custom".
fn static_name(name: &str) -> &'static str {
    match name {
        "Hard Left" => "Hard Left",
        "Left" => "Left",
        "Soft Left" => "Soft Left",
        "Forward" => "Forward",
        "Soft Right" => "Soft Right",
        "Right" => "Right",
        "Hard Right" => "Hard Right",
        "Escape" => "Escape",
        _ => "custom",
    }
}

/// The goal in the robot frame (for tests and pictures).
pub fn goal_in_robot_frame(p: &Perception) -> Option<Vec2> {
    p.goal.map(|g| p.odometry.inverse_transform(g))
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::{IrReading, Pose, SonarReading};

    fn perception(ir: &[bool], sonar: [f64; 3], goal: Vec2) -> Perception {
        let n = ir.len();
        Perception {
            goal: Some(goal),
            ir: (0..n)
                .map(|i| IrReading {
                    mount: Pose::new(0.0, 0.0, (90.0 - 180.0 * i as f64 / (n - 1) as f64).to_radians()),
                    range_m: 0.8,
                    triggered: ir[i],
                })
                .collect(),
            sonar: [30.0f64, 0.0, -30.0]
                .iter()
                .zip(sonar)
                .map(|(&d, r)| SonarReading {
                    mount: Pose::new(0.0, 0.0, d.to_radians()),
                    cone_rad: 25f64.to_radians(),
                    range_m: r,
                })
                .collect(),
            ..Perception::default()
        }
    }

    #[test]
    fn weight_formulas() {
        assert_eq!(plan_weight(3.0, 6.0, 20.0), 0.0);
        assert_eq!(plan_weight(13.0, 6.0, 20.0), 0.5);
        assert_eq!(plan_weight(40.0, 6.0, 20.0), 1.0);
        assert_eq!(obstacle_weight(0, 7), 0.6);
        assert!((obstacle_weight(7, 7) - 0.9).abs() < 1e-12);
        assert!((obstacle_weight(2, 7) - (0.6 + 0.3 * 2.0 / 7.0)).abs() < 1e-12);
    }

    #[test]
    fn heads_for_the_goal_in_the_open_and_avoids_a_wall_ahead() {
        let mut c = VotingController::new(VotingParams::default()).unwrap();
        let mut notes = Notes::enabled();
        let open = perception(&[false; 7], [9.0; 3], Vec2::new(5.0, 0.0));
        let Step::Run(_) = c.step(&open, &mut notes) else {
            panic!("should run")
        };
        assert_eq!(c.ballot().chosen, 3, "Forward");
        assert_eq!(notes.behaviour, Some("Forward"));
        assert!(notes.values.iter().any(|(k, _)| *k == "W_obs"));
        // Wall ahead: the three front detectors and the centre sonar fire.
        let blocked = perception(
            &[false, false, true, true, true, false, false],
            [2.0, 0.2, 2.0],
            Vec2::new(5.0, 0.0),
        );
        c.step(&blocked, &mut Notes::disabled());
        let chosen = c.ballot().chosen;
        assert!(chosen != 3, "must not drive into the wall");
        assert!((c.ballot().weights.obs - (0.6 + 0.3 * 3.0 / 7.0)).abs() < 1e-12);
    }

    #[test]
    fn goal_behind_turns_hard_and_escape_needs_clutter() {
        let mut c = VotingController::new(VotingParams {
            teams: Teams::experiment(1).unwrap(),
            ..VotingParams::default()
        })
        .unwrap();
        // In the open, b_IR(Escape) = 0: turning on the spot cannot beat a
        // hard turn, whatever the goal says.
        let behind = perception(&[false; 7], [9.0; 3], Vec2::new(-5.0, 0.0));
        c.step(&behind, &mut Notes::disabled());
        assert_eq!(c.p.actions.actions[c.ballot().chosen].name, "Hard Left");
        // Boxed in with the goal behind: Escape.
        let boxed = perception(&[true; 7], [0.1; 3], Vec2::new(-5.0, 0.0));
        c.step(&boxed, &mut Notes::disabled());
        assert_eq!(c.p.actions.actions[c.ballot().chosen].name, "Escape");
        // All arc votes equal (no goal preference possible): Forward wins ties.
        let fused = vec![0.5; 8];
        assert_eq!(c.argmax(&fused), 3);
    }

    /// Regression: sonar alone turned into the inner corner of the bent
    /// corridor in every run — the corner, heard at +30° while ahead, is in
    /// no cone once abeam.
    #[test]
    fn sonar_alone_does_not_turn_into_a_corner_it_has_passed() {
        let run = |memory_m: f64| {
            let mut c = VotingController::new(VotingParams {
                teams: Teams::experiment(2).unwrap(),
                sonar_memory_m: memory_m,
                ..VotingParams::default()
            })
            .unwrap();
            let goal = Vec2::new(0.3, 5.0); // straight left once abeam
            // The corner 0.6 m away on the +30° axis…
            let ahead = perception(&[false; 7], [0.6, 9.0, 9.0], goal);
            c.step(&ahead, &mut Notes::disabled());
            // …then 0.3 m further on, at 54° (out of every cone) and on
            // the ground the left turns sweep.
            let mut abeam = perception(&[false; 7], [9.0; 3], goal);
            abeam.odometry = Pose::new(0.3, 0.0, 0.0);
            c.step(&abeam, &mut Notes::disabled());
            c.p.actions.actions[c.ballot().chosen].heading_rad
        };
        assert!(
            run(0.0) > 1.5,
            "without the memory it turns hard left into the corner"
        );
        assert!(
            run(1.0) < 0.6,
            "with it, it turns no harder than Soft Left: {}",
            run(1.0)
        );
        assert!(
            VotingController::new(VotingParams {
                sonar_memory_m: -1.0,
                ..VotingParams::default()
            })
            .is_err()
        );
    }

    #[test]
    fn arrival_stops_and_bad_params_are_refused() {
        let mut c = VotingController::new(VotingParams::default()).unwrap();
        // 0.1 m short of the goal by odometry is not there yet (arrive_m 0.05).
        let near = perception(&[false; 7], [9.0; 3], Vec2::new(0.1, 0.0));
        assert!(matches!(c.step(&near, &mut Notes::disabled()), Step::Run(_)));
        let there = perception(&[false; 7], [9.0; 3], Vec2::new(0.04, 0.0));
        assert!(matches!(c.step(&there, &mut Notes::disabled()), Step::Done(_)));
        assert!(
            VotingController::new(VotingParams {
                mark_max: 1.0,
                ..VotingParams::default()
            })
            .is_err()
        );
        assert!(
            VotingController::new(VotingParams {
                beta_rad: 0.0,
                ..VotingParams::default()
            })
            .is_err()
        );
    }
}
