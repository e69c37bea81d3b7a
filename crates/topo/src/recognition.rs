//! Is a newly detected reference place one the robot already knows?
//!
//! The source does not say; **Decision** (docs/topo-fpn.md): a detection matches
//! a known place when
//!
//! 1. it is of the **same type** (a, b or c),
//! 2. the robot faces the **same way** as when the place was recorded:
//!    headings within [`RecognitionParams::heading_tolerance_rad`] (45°) —
//!    a corner reached from its other leg is another situation (and another
//!    type),
//! 3. it lies within the **distance tolerance**
//!    `tol = base_m + drift_per_m · s`, capped at `max_m`, where `s` is the
//!    odometry distance travelled since the last recalibration (or the
//!    start). Odometry error grows with the distance driven; the tolerance
//!    grows with it.
//!
//! Among the places that match, the nearest wins. While navigating, the
//! place the planned transition leads to is **expected**: it matches with
//! [`RecognitionParams::expected_extra_m`] more tolerance, the heading
//! still required, and a type that is the same or *compatible*
//! ([`PlaceKind::compatible`]: one of the two is (c)) — the route says where
//! the robot should be, and a side whose free distance is near the
//! threshold of "open" flips a stop between (a) or (b) and (c): legs that
//! truly ended at the planned place were otherwise counted as failures
//! (figures: `crates/topo/EXPERIMENTS.md`, section `recognition.rs`).
//!
//! Matching a **concave** place from a concave situation **recalibrates**
//! odometry: the robot's map position is reset to the place's (its two
//! walls put the robot where it was when it recorded the place, to within
//! the strategies' stopping precision) and `s` returns to 0 — but only on
//! a **firm** match ([`RecognitionParams::firm_recalibration`]): one that
//! plain recognition would make too (same type, within the distance
//! tolerance). The expected place matched only thanks to its extra
//! tolerance or a compatible type is taken as the place, since the route
//! says it should be there, but is weaker evidence of where the robot
//! stands than its odometry: in a failing office route (issue 13) a stop
//! 0.7 m and 43° off the expected place, on the other side of a room's
//! corner, moved the map pose by 0.7 m, and no place was recognised for
//! the rest of the route (40 legs between two new places on the goal's
//! very spot).
//!
//! The **heading** is recalibrated too when both the place's heading and
//! the robot's were measured **along a wall**: wall following that tracked
//! the wall on the concave side steadily for at least
//! [`RecognitionParams::align_min_run_m`] before stopping drives parallel
//! to it, so the mean odometry heading over that run is the wall's
//! direction ([`super::Executor::aligned_heading`]). A ring of sonars 22.5°
//! apart gives no usable bearing of a wall by itself; the wall follower's
//! own motion does. A concave place first recorded without such a heading
//! takes the first aligned one measured there.

use robot::{Pose, wrap_angle};

use super::fpn::{FuzzyPetriNet, PlaceId, PlaceKind};

/// Parameters of the recognition rule (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RecognitionParams {
    /// Tolerance right after a recalibration, metres. Default 0.4.
    pub base_m: f64,
    /// Growth of the tolerance per metre driven since, metres per metre.
    /// Default 0.03 (the simulator's default odometry drifts about 1 % of
    /// the distance driven, 3 % at worst over 40–150 m in the office).
    pub drift_per_m: f64,
    /// Largest tolerance, metres. Default 1.5.
    pub max_m: f64,
    /// Largest heading difference, radians. Default 45°.
    pub heading_tolerance_rad: f64,
    /// Extra distance tolerance for the place a planned transition leads
    /// to, metres. Default 0.5.
    pub expected_extra_m: f64,
    /// Steady wall tracking needed before a stop for its heading to count
    /// as aligned with the wall, metres. Default 1.0.
    pub align_min_run_m: f64,
    /// Recalibrate only on a match that plain recognition would make too
    /// (same type, within the distance tolerance): the expected place
    /// matched only thanks to its extra tolerance or a compatible type
    /// is taken as the place, but does not move the robot's map pose
    /// (module docs). Default true.
    pub firm_recalibration: bool,
}

impl Default for RecognitionParams {
    fn default() -> RecognitionParams {
        RecognitionParams {
            base_m: 0.4,
            drift_per_m: 0.03,
            max_m: 1.5,
            heading_tolerance_rad: std::f64::consts::FRAC_PI_4,
            expected_extra_m: 0.5,
            align_min_run_m: 1.0,
            firm_recalibration: true,
        }
    }
}

impl RecognitionParams {
    /// Checks every field (finite; `base_m`, `max_m` > 0, `drift_per_m` ≥ 0,
    /// `base_m ≤ max_m`, heading tolerance in (0, π]).
    pub fn validate(&self) -> Result<(), String> {
        let bad = |name: &str, v: f64| format!("recognition.{name} out of range: {v}");
        if !self.base_m.is_finite() || self.base_m <= 0.0 {
            return Err(bad("base_m", self.base_m));
        }
        if !self.drift_per_m.is_finite() || self.drift_per_m < 0.0 {
            return Err(bad("drift_per_m", self.drift_per_m));
        }
        if !self.max_m.is_finite() || self.max_m < self.base_m {
            return Err(bad("max_m", self.max_m));
        }
        if !self.expected_extra_m.is_finite() || self.expected_extra_m < 0.0 {
            return Err(bad("expected_extra_m", self.expected_extra_m));
        }
        if !self.align_min_run_m.is_finite() || self.align_min_run_m <= 0.0 {
            return Err(bad("align_min_run_m", self.align_min_run_m));
        }
        let h = self.heading_tolerance_rad;
        if !h.is_finite() || h <= 0.0 || h > std::f64::consts::PI {
            return Err(bad("heading_tolerance_rad", h));
        }
        Ok(())
    }

    /// The distance tolerance after driving `since_recalibration_m`.
    pub fn tolerance_m(&self, since_recalibration_m: f64) -> f64 {
        (self.base_m + self.drift_per_m * since_recalibration_m.max(0.0)).min(self.max_m)
    }
}

/// Whether known place `id` matches a detection at `pose` of type `kind`
/// within `tolerance_m`; the distance if so.
pub fn matches(
    map: &FuzzyPetriNet,
    id: PlaceId,
    pose: Pose,
    kind: PlaceKind,
    tolerance_m: f64,
    heading_tolerance_rad: f64,
) -> Option<f64> {
    let p = map.get_place(id)?;
    if p.kind != kind || wrap_angle(p.heading_rad - pose.theta_rad).abs() > heading_tolerance_rad {
        return None;
    }
    let d = (p.x_m - pose.x_m).hypot(p.y_m - pose.y_m);
    (d <= tolerance_m).then_some(d)
}

/// The known place a detection matches, if any: same type, heading within
/// tolerance, nearest within `tolerance_m` of `pose` (module docs).
pub fn match_place(
    map: &FuzzyPetriNet,
    pose: Pose,
    kind: PlaceKind,
    tolerance_m: f64,
    heading_tolerance_rad: f64,
) -> Option<(PlaceId, f64)> {
    let mut best: Option<(PlaceId, f64)> = None;
    for id in map.place_ids() {
        if let Some(d) = matches(map, id, pose, kind, tolerance_m, heading_tolerance_rad)
            && best.is_none_or(|(_, bd)| d < bd)
        {
            best = Some((id, d));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Place;

    #[test]
    fn same_type_same_heading_nearest_within_tolerance() {
        let mut map = FuzzyPetriNet::new();
        let a = map.add_place(Place::new(0.0, 0.0, 0.0, PlaceKind::A)).unwrap();
        let a2 = map.add_place(Place::new(1.0, 0.0, 0.0, PlaceKind::A)).unwrap();
        let _b = map.add_place(Place::new(0.1, 0.0, 0.0, PlaceKind::B)).unwrap();
        let _facing_back = map.add_place(Place::new(0.05, 0.0, 3.1, PlaceKind::A)).unwrap();
        let h = std::f64::consts::FRAC_PI_4;
        assert_eq!(
            match_place(&map, Pose::new(0.2, 0.0, 0.3), PlaceKind::A, 0.5, h).map(|m| m.0),
            Some(a)
        );
        assert_eq!(
            match_place(&map, Pose::new(0.7, 0.0, 0.0), PlaceKind::A, 0.5, h).map(|m| m.0),
            Some(a2)
        );
        assert_eq!(
            match_place(&map, Pose::new(0.2, 0.0, 1.0), PlaceKind::A, 0.5, h),
            None
        );
        assert_eq!(
            match_place(&map, Pose::new(0.0, 3.0, 0.0), PlaceKind::A, 0.5, h),
            None
        );
        assert_eq!(
            match_place(&map, Pose::new(0.0, 0.0, 0.0), PlaceKind::C, 0.5, h),
            None
        );
    }

    #[test]
    fn the_tolerance_grows_with_distance_and_is_capped() {
        let p = RecognitionParams::default();
        assert_eq!(p.tolerance_m(0.0), 0.4);
        assert!((p.tolerance_m(10.0) - 0.7).abs() < 1e-12);
        assert_eq!(p.tolerance_m(1000.0), 1.5);
        assert!(p.validate().is_ok());
        assert!(RecognitionParams { max_m: 0.1, ..p }.validate().is_err());
    }
}
