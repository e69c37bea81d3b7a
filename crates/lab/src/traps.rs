//! Dead-end traps drawn from a run's seed, for the `deadlock` suite
//! (docs/activity-trace.md, "experiments").
//!
//! A scenario's `[trap]` section adds one trap to its world per run, on the
//! straight course from start to goal, its opening facing the start (turned
//! by up to `angle_deg`):
//!
//! ```toml
//! [trap]
//! kinds = ["u", "v"]          # U: three walls; V: two walls meeting at the back; C: a U with inward lips
//! depth_m = [0.8, 1.6]        # uniform in the interval
//! width_m = [1.0, 2.0]        # opening width (C: inside width; the mouth is half of it)
//! angle_deg = [-30, 30]       # turn of the opening away from the start
//! position = [0.4, 0.6]       # where the back wall sits, as a fraction of the course
//! thickness_m = 0.2
//! ```
//!
//! The walls are thick enough for the IR beams to see their ends (thin
//! edges between beams are another experiment). Each drawn trap is kept
//! clear of the start and the goal (at least 0.6 m).
//!
//! **What makes a trap** (measured with the priority controller on the
//! 16-sonar robot, 200 runs each, no recovery; `petrinav lab run FILE.toml`
//! on copies of `crates/lab/src/suites/deadlock/scenarios/priority.toml`): a U is a local minimum
//! for a goal seeker when the goal lies behind its back wall as seen from the
//! opening. The shipped suite's U (depth 1.0–1.8 m, opening 1.2–2.0 m, turned
//! ≤ 20°) holds the plain controller in about 4 runs of 5. The defaults above
//! (depth from 0.8 m, turned up to 30°) let it out in about half the U runs:
//! one arm's outer face becomes a ramp towards the goal. A V lets it out in
//! more than 9 runs of 10 whatever its size (a funnel: the robot slides along
//! an arm and out past its end), and so does a C with a mouth of 0.7–1.1 m
//! (the robot does not go in). The suite reports U and V separately.

use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use robot::Vec2;
use sim::shapes::{SegmentSpec, WorldSpec};

/// The `[trap]` section of a scenario.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrapSpec {
    /// Kinds drawn from, uniformly: `"u"` or `"v"`. Default both.
    pub kinds: Vec<TrapKind>,
    /// Depth from opening to back, metres, uniform in `[lo, hi]`. Default [0.8, 1.6].
    pub depth_m: [f64; 2],
    /// Width of the opening, metres. Default [1.0, 2.0].
    pub width_m: [f64; 2],
    /// Turn of the trap's axis away from the start direction, degrees.
    /// Default [−30, 30].
    pub angle_deg: [f64; 2],
    /// Where the back of the trap sits on the course, as a fraction of the
    /// start–goal distance. Default [0.45, 0.6].
    pub position: [f64; 2],
    /// Wall thickness, metres. Default 0.2.
    pub thickness_m: f64,
}

/// A kind of trap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TrapKind {
    /// Two side walls and a back wall.
    U,
    /// Two walls meeting at the back.
    V,
    /// A U whose side walls end in lips turned inwards: a cup whose mouth is
    /// narrower than its inside (half the width, [`C_LIP_FRACTION`]).
    C,
}

/// Each lip of a C trap covers this fraction of its half-width, so the mouth
/// is `1 − C_LIP_FRACTION` of the inside width.
pub const C_LIP_FRACTION: f64 = 0.5;

impl Default for TrapSpec {
    fn default() -> TrapSpec {
        TrapSpec {
            kinds: vec![TrapKind::U, TrapKind::V],
            depth_m: [0.8, 1.6],
            width_m: [1.0, 2.0],
            angle_deg: [-30.0, 30.0],
            position: [0.45, 0.6],
            thickness_m: 0.2,
        }
    }
}

/// One drawn trap (for records and pictures).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DrawnTrap {
    /// Kind.
    pub kind: TrapKind,
    /// Depth, metres.
    pub depth_m: f64,
    /// Opening width, metres.
    pub width_m: f64,
    /// Turn of the axis, degrees.
    pub angle_deg: f64,
    /// Fraction of the course.
    pub position: f64,
}

impl TrapSpec {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), String> {
        if self.kinds.is_empty() {
            return Err("trap.kinds is empty".into());
        }
        for (what, [lo, hi], min) in [
            ("trap.depth_m", self.depth_m, 0.1),
            ("trap.width_m", self.width_m, 0.1),
            ("trap.angle_deg", self.angle_deg, -90.0),
            ("trap.position", self.position, 0.05),
        ] {
            if !(lo.is_finite() && hi.is_finite() && lo >= min && hi >= lo) {
                return Err(format!(
                    "{what} must be [lo, hi] with {min} ≤ lo ≤ hi, got [{lo}, {hi}]"
                ));
            }
        }
        if self.angle_deg[1] > 90.0 || self.position[1] > 0.95 {
            return Err("trap.angle_deg must lie within ±90 and trap.position within [0.05, 0.95]".into());
        }
        if !(self.thickness_m.is_finite() && self.thickness_m > 0.0) {
            return Err(format!("trap.thickness_m must be > 0, got {}", self.thickness_m));
        }
        Ok(())
    }

    /// Draws a trap on the course `start → goal` and adds its walls to
    /// `world`.
    pub fn draw(&self, start: Vec2, goal: Vec2, world: &mut WorldSpec, rng: &mut ChaCha8Rng) -> DrawnTrap {
        let mut uniform = |[lo, hi]: [f64; 2]| lo + (hi - lo) * rng.random::<f64>();
        let kind = self.kinds[(uniform([0.0, self.kinds.len() as f64]) as usize).min(self.kinds.len() - 1)];
        let depth = uniform(self.depth_m);
        let width = uniform(self.width_m);
        let angle = uniform(self.angle_deg);
        let position = uniform(self.position);
        let course = goal - start;
        let length = course.norm();
        let dir = if length > 0.0 {
            course.scale(1.0 / length)
        } else {
            Vec2::new(1.0, 0.0)
        };
        let back = start + dir.scale(length * position);
        // The trap's axis points from the back towards its opening (towards
        // the start), turned by `angle`.
        let a = dir.scale(-1.0).angle() + angle.to_radians();
        let axis = Vec2::new(a.cos(), a.sin());
        let side = Vec2::new(-axis.y, axis.x);
        let open = back + axis.scale(depth);
        let half = width / 2.0;
        let t = self.thickness_m;
        let mut wall = |from: Vec2, to: Vec2| {
            world.segments.push(SegmentSpec {
                from: [from.x, from.y],
                to: [to.x, to.y],
                thickness: t,
            });
        };
        match kind {
            TrapKind::U => {
                wall(back + side.scale(half), back - side.scale(half));
                wall(back + side.scale(half), open + side.scale(half));
                wall(back - side.scale(half), open - side.scale(half));
            }
            TrapKind::V => {
                wall(back, open + side.scale(half));
                wall(back, open - side.scale(half));
            }
            TrapKind::C => {
                let lip = half * C_LIP_FRACTION;
                wall(back + side.scale(half), back - side.scale(half));
                wall(back + side.scale(half), open + side.scale(half));
                wall(back - side.scale(half), open - side.scale(half));
                wall(open + side.scale(half), open + side.scale(half - lip));
                wall(open - side.scale(half), open - side.scale(half - lip));
            }
        }
        DrawnTrap {
            kind,
            depth_m: depth,
            width_m: width,
            angle_deg: angle,
            position,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn traps_face_the_start_and_stay_within_their_ranges() {
        let spec = TrapSpec {
            kinds: vec![TrapKind::U, TrapKind::V, TrapKind::C],
            ..TrapSpec::default()
        };
        let (start, goal) = (Vec2::new(1.0, 3.0), Vec2::new(7.0, 3.0));
        let mut seen = std::collections::BTreeSet::new();
        for seed in 0..50 {
            let mut w = WorldSpec::new(8.0, 6.0, 0.05);
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let d = spec.draw(start, goal, &mut w, &mut rng);
            assert!((0.8..=1.6).contains(&d.depth_m) && (1.0..=2.0).contains(&d.width_m));
            assert!(d.angle_deg.abs() <= 30.0);
            let walls = match d.kind {
                TrapKind::U => 3,
                TrapKind::V => 2,
                TrapKind::C => 5,
            };
            assert_eq!(w.segments.len(), walls);
            // Every wall end lies between start and goal, nearer the start
            // than the back (the opening faces the start).
            for s in &w.segments {
                for p in [s.from, s.to] {
                    assert!(p[0] > start.x + 0.6 && p[0] < goal.x - 0.6, "{p:?}");
                }
            }
            let grid = w.rasterise().unwrap();
            assert!(!grid.disc_blocked(start, 0.3) && !grid.disc_blocked(goal, 0.3));
            seen.insert(format!("{:?}", d.kind));
        }
        assert_eq!(seen.len(), 3, "every kind is drawn: {seen:?}");
        assert!(
            TrapSpec {
                kinds: vec![],
                ..TrapSpec::default()
            }
            .validate()
            .is_err()
        );
        assert!(
            TrapSpec {
                depth_m: [2.0, 1.0],
                ..TrapSpec::default()
            }
            .validate()
            .is_err()
        );
        assert!(TrapSpec::default().validate().is_ok());
    }
}
