//! What a controller sees and does, independent of where it runs.
//!
//! A robot — the simulator in `sim`, or a real one — fills a [`Perception`]
//! every control period; a [`Controller`] turns it into a [`Command`]. The
//! types are plain data, so a controller can be tested alone with hand-made
//! perceptions (the openrr `arci` idea).
//!
//! Frames and units: SI units (metres, seconds, radians); world frame x
//! right, y up; headings counter-clockwise from +x, wrapped to (−π, π].
//! Sensor mounts are given in the robot frame (x forward, y left).
//!
//! ```
//! use robot::{Command, Controller, Perception, Step};
//!
//! /// Drives straight until the front IR detector fires.
//! struct Cautious;
//!
//! impl Controller for Cautious {
//!     fn step(&mut self, p: &Perception, _notes: &mut robot::Notes) -> Step {
//!         if p.ir.iter().any(|d| d.triggered) {
//!             Step::Run(Command::Stop)
//!         } else {
//!             Step::Run(Command::Twist { v_mps: 0.3, omega_radps: 0.0 })
//!         }
//!     }
//! }
//!
//! let mut c = Cautious;
//! let mut p = Perception::default();
//! assert_eq!(c.step(&p, &mut robot::Notes::disabled()), Step::Run(Command::Twist { v_mps: 0.3, omega_radps: 0.0 }));
//! p.ir.push(robot::IrReading { mount: robot::Pose::default(), range_m: 0.8, triggered: true });
//! assert_eq!(c.step(&p, &mut robot::Notes::disabled()), Step::Run(Command::Stop));
//! ```
#![warn(missing_docs)]

use std::f64::consts::PI;

pub mod event;
pub mod map;

pub use event::{Event, EventValue};
pub use map::{Cell, CellIndex, GridMap, MapError};

/// Wraps an angle to (−π, π].
pub fn wrap_angle(a: f64) -> f64 {
    let mut r = a % (2.0 * PI);
    if r <= -PI {
        r += 2.0 * PI;
    } else if r > PI {
        r -= 2.0 * PI;
    }
    r
}

/// A point or vector in the plane, metres.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Vec2 {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
}

impl Vec2 {
    /// A new vector.
    pub const fn new(x: f64, y: f64) -> Vec2 {
        Vec2 { x, y }
    }

    /// Euclidean length.
    pub fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }

    /// Distance to `o`.
    pub fn dist(self, o: Vec2) -> f64 {
        (self - o).norm()
    }

    /// Dot product.
    pub fn dot(self, o: Vec2) -> f64 {
        self.x * o.x + self.y * o.y
    }

    /// Angle of the vector, radians from +x.
    pub fn angle(self) -> f64 {
        self.y.atan2(self.x)
    }

    /// Scaled by `k`.
    pub fn scale(self, k: f64) -> Vec2 {
        Vec2::new(self.x * k, self.y * k)
    }
}

impl std::ops::Add for Vec2 {
    type Output = Vec2;
    fn add(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x + o.x, self.y + o.y)
    }
}

impl std::ops::Sub for Vec2 {
    type Output = Vec2;
    fn sub(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x - o.x, self.y - o.y)
    }
}

/// A pose in the plane: position in metres, heading in radians.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Pose {
    /// x, metres.
    pub x_m: f64,
    /// y, metres.
    pub y_m: f64,
    /// Heading, radians counter-clockwise from +x, in (−π, π].
    pub theta_rad: f64,
}

impl Pose {
    /// A new pose (the heading is wrapped).
    pub fn new(x_m: f64, y_m: f64, theta_rad: f64) -> Pose {
        Pose {
            x_m,
            y_m,
            theta_rad: wrap_angle(theta_rad),
        }
    }

    /// The position.
    pub fn position(&self) -> Vec2 {
        Vec2::new(self.x_m, self.y_m)
    }

    /// Composes `self ∘ local`: `local` given in the frame of `self`
    /// (e.g. a sensor mount on the robot) expressed in `self`'s parent frame.
    pub fn compose(&self, local: &Pose) -> Pose {
        let (s, c) = self.theta_rad.sin_cos();
        Pose::new(
            self.x_m + c * local.x_m - s * local.y_m,
            self.y_m + s * local.x_m + c * local.y_m,
            self.theta_rad + local.theta_rad,
        )
    }

    /// A point given in the frame of `self`, in the parent frame.
    pub fn transform(&self, p: Vec2) -> Vec2 {
        self.transformer()(p)
    }

    /// [`Pose::transform`] for many points: the heading's sine and cosine
    /// taken once (the same result, bit for bit).
    pub fn transformer(&self) -> impl Fn(Vec2) -> Vec2 + Copy + use<> {
        let (s, c) = self.theta_rad.sin_cos();
        let (x, y) = (self.x_m, self.y_m);
        move |p: Vec2| Vec2::new(x + c * p.x - s * p.y, y + s * p.x + c * p.y)
    }

    /// A point of the parent frame, in the frame of `self`.
    pub fn inverse_transform(&self, p: Vec2) -> Vec2 {
        let (s, c) = self.theta_rad.sin_cos();
        let (dx, dy) = (p.x - self.x_m, p.y - self.y_m);
        Vec2::new(c * dx + s * dy, -s * dx + c * dy)
    }
}

/// A motion command.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Command {
    /// Wheel rim speeds, m/s.
    Wheels {
        /// Left wheel, m/s.
        left_mps: f64,
        /// Right wheel, m/s.
        right_mps: f64,
    },
    /// Forward speed (m/s) and turn rate (rad/s, counter-clockwise).
    Twist {
        /// Forward speed, m/s.
        v_mps: f64,
        /// Turn rate, rad/s.
        omega_radps: f64,
    },
    /// Both wheels to zero (subject to acceleration limits).
    Stop,
}

impl Command {
    /// The wheel speeds `(left, right)` of this command for wheel base `d`
    /// (metres): `v_L = v − ω d / 2`, `v_R = v + ω d / 2`.
    pub fn wheels(&self, wheel_base_m: f64) -> (f64, f64) {
        match *self {
            Command::Wheels { left_mps, right_mps } => (left_mps, right_mps),
            Command::Twist { v_mps, omega_radps } => {
                let h = omega_radps * wheel_base_m / 2.0;
                (v_mps - h, v_mps + h)
            }
            Command::Stop => (0.0, 0.0),
        }
    }
}

/// One laser scan: `ranges_m[i]` along angle `angle_min_rad + i·angle_increment_rad`
/// in the sensor frame; `f64::INFINITY` when nothing was hit within
/// `range_max_m`, `NAN` for a drop-out.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct LaserScan {
    /// The sensor's pose on the robot.
    pub mount: Pose,
    /// Angle of the first beam, radians.
    pub angle_min_rad: f64,
    /// Angle between beams, radians.
    pub angle_increment_rad: f64,
    /// Maximum range, metres.
    pub range_max_m: f64,
    /// Ranges, metres.
    pub ranges_m: Vec<f64>,
}

impl LaserScan {
    /// The `(cos a, sin a)` of every beam's angle `a = angle_min_rad + k ·
    /// angle_increment_rad` (sensor frame), bit for bit `a.cos()` and
    /// `a.sin()`: computed once per thread and scan geometry and kept (a
    /// cache, not an approximation; the consumers of a scan each turned
    /// every beam into a point, two trigonometric calls a beam, several
    /// times a control cycle).
    pub fn beam_directions(&self) -> std::rc::Rc<[(f64, f64)]> {
        type Key = (u64, u64, usize);
        type Directions = std::rc::Rc<[(f64, f64)]>;
        thread_local! {
            static CACHE: std::cell::RefCell<Option<(Key, Directions)>> = const { std::cell::RefCell::new(None) };
        }
        let key = (
            self.angle_min_rad.to_bits(),
            self.angle_increment_rad.to_bits(),
            self.ranges_m.len(),
        );
        CACHE.with(|c| {
            let mut c = c.borrow_mut();
            match &*c {
                Some((k, dirs)) if *k == key => dirs.clone(),
                _ => {
                    let dirs: Directions = (0..self.ranges_m.len())
                        .map(|k| {
                            let a = self.angle_min_rad + k as f64 * self.angle_increment_rad;
                            (a.cos(), a.sin())
                        })
                        .collect();
                    *c = Some((key, dirs.clone()));
                    dirs
                }
            }
        })
    }
}

/// One sonar transducer: the nearest echo inside its cone.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct SonarReading {
    /// The transducer's pose on the robot (its axis is the x axis).
    pub mount: Pose,
    /// Full cone width, radians.
    pub cone_rad: f64,
    /// Distance to the nearest echo, metres (`f64::INFINITY`: none within range).
    pub range_m: f64,
}

/// One binary infrared proximity detector.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct IrReading {
    /// The detector's pose on the robot (its beam is the x axis).
    pub mount: Pose,
    /// Detection range, metres.
    pub range_m: f64,
    /// Whether something is within range along the beam.
    pub triggered: bool,
}

/// Everything the robot knows at one control tick.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct Perception {
    /// Time since the start of the run, seconds.
    pub time_s: f64,
    /// Pose estimated by dead reckoning from wheel odometry (drifts).
    pub odometry: Pose,
    /// Wheel speeds measured by the encoders over the last period, m/s.
    pub wheel_speeds_mps: (f64, f64),
    /// The goal of the current task, in the world frame, if any.
    pub goal: Option<Vec2>,
    /// Laser scans (usually zero or one).
    pub lasers: Vec<LaserScan>,
    /// Sonar transducers.
    pub sonar: Vec<SonarReading>,
    /// Infrared detectors.
    pub ir: Vec<IrReading>,
    /// The bumper is pressed (contact this tick).
    pub bumper: bool,
}

/// A controller's answer for one tick.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum Step {
    /// Keep running with this command.
    Run(Command),
    /// The controller believes the task is done. The simulator judges by
    /// the true position: within the goal tolerance the run succeeds,
    /// otherwise it ends as lost (the controller's estimate was wrong).
    Done(Command),
    /// The controller gives up (the run ends as a failure).
    GiveUp,
}

/// Annotations a controller may attach to a tick (selected behaviour,
/// votes, typed events) for traces, records and pictures. Costs nothing
/// when disabled: check [`Notes::is_enabled`] before building expensive
/// values.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Notes {
    enabled: bool,
    /// The behaviour or action in control this tick.
    pub behaviour: Option<&'static str>,
    /// Named numbers (votes, weights, activations…).
    pub values: Vec<(&'static str, f64)>,
    /// Events this tick (e.g. a dead-lock, a localizer warning).
    pub events: Vec<Event>,
    /// Named sets of poses this tick (a localizer's particle cloud), in
    /// the controller's frame.
    pub clouds: Vec<(&'static str, Vec<Pose>)>,
}

impl Notes {
    /// Notes that record.
    pub fn enabled() -> Notes {
        Notes {
            enabled: true,
            ..Notes::default()
        }
    }

    /// Notes that ignore everything.
    pub fn disabled() -> Notes {
        Notes::default()
    }

    /// Whether anything is recorded.
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// Clears the notes of the previous tick.
    pub fn clear(&mut self) {
        self.behaviour = None;
        self.values.clear();
        self.events.clear();
        self.clouds.clear();
    }

    /// Records the behaviour in control.
    pub fn behaviour(&mut self, name: &'static str) {
        if self.enabled {
            self.behaviour = Some(name);
        }
    }

    /// Records a named value.
    pub fn value(&mut self, name: &'static str, v: f64) {
        if self.enabled {
            self.values.push((name, v));
        }
    }

    /// Copies these notes into `to` (when `to` records): for a controller
    /// that wraps another and passes its notes on.
    pub fn forward_to(&self, to: &mut Notes) {
        if !to.enabled {
            return;
        }
        if let Some(b) = self.behaviour {
            to.behaviour = Some(b);
        }
        to.values.extend_from_slice(&self.values);
        to.events.extend(self.events.iter().cloned());
        to.clouds.extend(self.clouds.iter().cloned());
    }

    /// Records an event.
    pub fn event(&mut self, event: Event) {
        if self.enabled {
            self.events.push(event);
        }
    }

    /// Records a named set of poses (e.g. `particles`); the iterator is
    /// not consumed when the notes are disabled.
    pub fn cloud(&mut self, name: &'static str, poses: impl IntoIterator<Item = Pose>) {
        if self.enabled {
            self.clouds.push((name, poses.into_iter().collect()));
        }
    }
}

/// What a robot may ask of the people around it (on its speaker or
/// screen), besides moving.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Request {
    /// "Excuse me, please step aside": the people within `radius_m` of the
    /// robot's centre are asked to move away from it.
    StepAside {
        /// Radius of the request around the robot, metres.
        radius_m: f64,
    },
}

/// A controller: perception in, command out, once per control period.
pub trait Controller {
    /// Decides the command for this tick. `notes` is cleared by the caller
    /// before each tick.
    fn step(&mut self, perception: &Perception, notes: &mut Notes) -> Step;

    /// What the controller asks of the people around the robot this tick;
    /// the robot reads it after each [`Controller::step`] and plays it.
    /// Controllers that wrap another pass its request on. Default: nothing.
    fn request(&self) -> Option<Request> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beam_directions_are_the_angles_cosines_and_follow_the_geometry() {
        let scan = |min: f64, inc: f64, n: usize| LaserScan {
            mount: Pose::default(),
            angle_min_rad: min,
            angle_increment_rad: inc,
            range_max_m: 10.0,
            ranges_m: vec![1.0; n],
        };
        for s in [
            scan(-1.5, 0.01745, 181),
            scan(-2.0, 0.1, 41),
            scan(-1.5, 0.01745, 181),
            scan(0.3, 0.02, 3),
        ] {
            let dirs = s.beam_directions();
            assert_eq!(dirs.len(), s.ranges_m.len());
            for (k, &(c, sn)) in dirs.iter().enumerate() {
                let a = s.angle_min_rad + k as f64 * s.angle_increment_rad;
                assert_eq!(
                    (c.to_bits(), sn.to_bits()),
                    (a.cos().to_bits(), a.sin().to_bits())
                );
            }
        }
    }

    #[test]
    fn angles_wrap_to_minus_pi_exclusive_pi_inclusive() {
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-15);
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(2.0 * PI + 0.5) - 0.5).abs() < 1e-12);
        assert!((wrap_angle(-0.5) + 0.5).abs() < 1e-15);
    }

    #[test]
    fn frames_round_trip() {
        let p = Pose::new(1.0, 2.0, 0.7);
        let q = Vec2::new(-3.0, 0.25);
        let back = p.inverse_transform(p.transform(q));
        assert!((back.x - q.x).abs() < 1e-12 && (back.y - q.y).abs() < 1e-12);
        let mount = Pose::new(0.1, 0.0, PI / 2.0);
        let s = p.compose(&mount);
        assert!((s.theta_rad - (0.7 + PI / 2.0)).abs() < 1e-12);
    }

    #[test]
    fn twist_to_wheels() {
        let (l, r) = Command::Twist {
            v_mps: 0.3,
            omega_radps: 1.0,
        }
        .wheels(0.2);
        assert!((l - 0.2).abs() < 1e-12 && (r - 0.4).abs() < 1e-12);
    }
}
