//! What kind of reference place the robot has stopped at: which turns the
//! obstacle ahead leaves open, and whether a concave corner is there to
//! recalibrate odometry against (docs/topo-fpn.md, "Reference places").
//!
//! Read from the ring when the robot has stopped with an obstacle ahead:
//!
//! - a turn toward a side is **possible** when the transducer at 90° on
//!   that side sees more than [`SituationParams::turn_free_m`] (room for the
//!   robot to turn and drive off that way). Only the 90° transducer: those
//!   at ±67.5° have cones that reach forward onto the wall ahead;
//! - type **(a)**: only the right turn is possible; **(b)**: only the left;
//!   **(c)**: both — and also neither (a dead end: the robot turns about,
//!   either way; **Decision**, the source has three types and a dead end
//!   fits (c) best: either turn leads on, here back out);
//! - **concave**: a side is closed — the wall ahead meets something within
//!   [`SituationParams::turn_free_m`] on that side: an inner corner, whose
//!   two walls fix the robot's position against them. Types (a) and (b)
//!   are always concave, a dead end too; a T junction (walls only ahead) and
//!   a free-standing obstacle are not.

use std::f64::consts::FRAC_PI_2;

use super::fpn::PlaceKind;
use super::ring::Ring;

/// Thresholds of the classification (from the robot's centre).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SituationParams {
    /// A side is open for a turn beyond this, metres. Default 1.0.
    pub turn_free_m: f64,
}

impl Default for SituationParams {
    fn default() -> SituationParams {
        SituationParams { turn_free_m: 1.0 }
    }
}

impl SituationParams {
    /// Checks the field (finite, positive).
    pub fn validate(&self) -> Result<(), String> {
        let v = self.turn_free_m;
        if !v.is_finite() || v <= 0.0 {
            return Err(format!("situation.turn_free_m must be finite and > 0, got {v}"));
        }
        Ok(())
    }
}

/// The classification of a stop in front of an obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Situation {
    /// The place's type.
    pub kind: PlaceKind,
    /// An inner corner is there.
    pub concave: bool,
    /// A left turn is possible.
    pub left_open: bool,
    /// A right turn is possible.
    pub right_open: bool,
}

impl Situation {
    /// Classifies the ring's view (module docs).
    pub fn classify(ring: &Ring, params: &SituationParams) -> Situation {
        let left = ring.range_toward(FRAC_PI_2);
        let right = ring.range_toward(-FRAC_PI_2);
        let left_open = left > params.turn_free_m;
        let right_open = right > params.turn_free_m;
        let kind = match (left_open, right_open) {
            (false, true) => PlaceKind::A,
            (true, false) => PlaceKind::B,
            _ => PlaceKind::C,
        };
        let concave = !left_open || !right_open;
        Situation {
            kind,
            concave,
            left_open,
            right_open,
        }
    }

    /// Whether this is a dead end (no turn possible).
    pub fn dead_end(&self) -> bool {
        !self.left_open && !self.right_open
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(left: f64, right: f64) -> Ring {
        Ring::from_degrees(&[(0.0, 0.5), (90.0, left), (-90.0, right), (180.0, 3.0)])
    }

    #[test]
    fn the_three_types_and_the_concave_flag() {
        let p = SituationParams::default();
        let s = Situation::classify(&ring(0.45, 4.0), &p);
        assert_eq!((s.kind, s.concave), (PlaceKind::A, true));
        let s = Situation::classify(&ring(4.0, 0.45), &p);
        assert_eq!((s.kind, s.concave), (PlaceKind::B, true));
        let s = Situation::classify(&ring(4.0, 4.0), &p);
        assert_eq!((s.kind, s.concave), (PlaceKind::C, false));
        let s = Situation::classify(&ring(0.5, 0.5), &p);
        assert_eq!((s.kind, s.concave, s.dead_end()), (PlaceKind::C, true, true));
        // Just beyond the threshold: open.
        let s = Situation::classify(&ring(1.01, 4.0), &p);
        assert_eq!((s.kind, s.concave), (PlaceKind::C, false));
    }
}
