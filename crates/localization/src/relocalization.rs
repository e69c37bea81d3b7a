//! Finding the robot again once the scan says it is lost.
//!
//! Under the contradiction rule ([`super::status`], decision (d)) a
//! Warning means that the scan sees past the mapped walls at the estimate:
//! the robot was pushed, turned or slipped away from where the filter
//! believes it is. A tracking filter (500 particles, motion noise of a few
//! centimetres) cannot follow a jump of a metre, so on that Warning the
//! localizer **scatters a recovery cloud** around the estimate:
//! `particles` (3 000) new particles uniform in a disc of `radius_m`
//! (2.5 m) with headings uniform within `heading_rad` (π/2) of the
//! estimate's, added to the old cloud — the kidnaps a museum visitor can
//! do (0.3–2 m, up to 90°) plus the drift of a slip. The cloud then
//! behaves as a global cloud does ([`super`]): AMCL's larger motion noise
//! while it is bigger than the tracking size, and every resampling shrinks
//! it to the KLD bound of the bins it occupies.
//!
//! The Warning lasts until the scan matches at the estimate twice *and*
//! the cloud has settled on one place (the estimate's cluster holds 80 %
//! of the weight, or KLD-sampling has shrunk the cloud to the tracking
//! size): among visitors two poses can explain the few walls in
//! view, and a recovery that ended on the first match ran off with the
//! wrong one (a 70° kidnap in building_31: Success after 0.5 s, 13.8 m off
//! at the end of the drive). While the Warning lasts, the filter runs every `period_s` (0.5 s) even
//! when the robot stands still — a robot that was pushed is usually
//! standing. If the scan still contradicts the estimate `global_after_s`
//! (20 s) after a scatter, the localizer starts **global localization**
//! (the whole free map) and, should that also fail, scatters again every
//! `global_after_s`.
//!
//! **Rejected: AMCL's random particles** ([`super::recovery`], Augmented
//! MCL), because its trigger — a drop in the mean likelihood — fires
//! whenever people hide the walls, and it scatters particles over the
//! whole building while the estimate is fine (the figures in [`super`]).
//! Here the trigger is the contradiction, which people do not raise.

use robot::{Pose, wrap_angle};

/// Parameters of the recovery (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RelocalizationParams {
    /// Whether a contradiction Warning starts a recovery. Default `true`;
    /// it never starts under the source's rule
    /// ([`super::StatusRule::Explained`]).
    pub enabled: bool,
    /// Particles of a recovery cloud, 1 to 10⁷. Default 3 000.
    pub particles: usize,
    /// Radius of the disc they are scattered in, metres, > 0. Default 2.5.
    pub radius_m: f64,
    /// Their headings lie within this of the estimate's, radians, in
    /// (0, π]. Default π/2.
    pub heading_rad: f64,
    /// While recovering, a filter iteration runs at least this often,
    /// seconds, > 0. Default 0.5.
    pub period_s: f64,
    /// Still contradicted this long after a scatter: global localization
    /// (and after as long again, a new scatter), seconds, > 0. Default 20.
    pub global_after_s: f64,
}

impl Default for RelocalizationParams {
    fn default() -> RelocalizationParams {
        RelocalizationParams {
            enabled: true,
            particles: 3000,
            radius_m: 2.5,
            heading_rad: std::f64::consts::FRAC_PI_2,
            period_s: 0.5,
            global_after_s: 20.0,
        }
    }
}

impl RelocalizationParams {
    /// A pose of the recovery cloud around `estimate` from three uniform
    /// numbers in [0, 1): radius (area-uniform), bearing, heading.
    pub fn scatter(&self, estimate: &Pose, u: [f64; 3]) -> Pose {
        let r = self.radius_m * u[0].sqrt();
        let b = std::f64::consts::TAU * u[1];
        Pose::new(
            estimate.x_m + r * b.cos(),
            estimate.y_m + r * b.sin(),
            wrap_angle(estimate.theta_rad + self.heading_rad * (2.0 * u[2] - 1.0)),
        )
    }
}

/// Where a recovery stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RecoveryStage {
    /// Not recovering.
    Idle,
    /// A recovery cloud around the estimate.
    Scattered,
    /// Global localization.
    Global,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scatter_covers_the_disc_and_the_heading_window() {
        let p = RelocalizationParams::default();
        let e = Pose::new(1.0, 2.0, 3.0);
        let corner = p.scatter(&e, [0.999_999, 0.25, 0.999_999]);
        assert!((corner.position().dist(e.position()) - 2.5).abs() < 1e-5);
        assert!((corner.x_m - 1.0).abs() < 1e-5 && corner.y_m > 4.4);
        assert!((wrap_angle(corner.theta_rad - 3.0) - std::f64::consts::FRAC_PI_2).abs() < 1e-5);
        let centre = p.scatter(&e, [0.0, 0.7, 0.5]);
        assert_eq!(centre, Pose::new(1.0, 2.0, 3.0));
    }
}
