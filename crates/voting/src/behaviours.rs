//! The four voting behaviours (docs/voting.md). Each maps its sensors to
//! one vote in [0, 1] per action (1 = most desired).

use std::f64::consts::PI;

use robot::{IrReading, SonarReading, wrap_angle};

use super::actions::{ActionKind, ActionSet};

/// The Π-function `1 / (1 + ((θ_m − θ)/β)²)`, the angle difference wrapped
/// to [−π, π].
pub fn pi_function(theta_m: f64, theta: f64, beta_rad: f64) -> f64 {
    let d = wrap_angle(theta_m - theta) / beta_rad;
    1.0 / (1.0 + d * d)
}

/// IR vote of an arc action from the number of its three covering
/// detectors that are triggered: 0 → 1.0, 1 → 0.7, 2 → 0.3, 3 → 0.0.
pub fn ir_table(triggered_of_three: usize) -> f64 {
    match triggered_of_three {
        0 => 1.0,
        1 => 0.7,
        2 => 0.3,
        _ => 0.0,
    }
}

/// The detectors that cover each action, for `b_IR`.
///
/// **Decision:** the three detectors that cover an arc action are the three
/// whose bearings are nearest to the action's heading (ties to the lower
/// index), so the rule works for any mounting, and at the ends of the arc
/// (±90°) the hard turns are judged by the three outermost detectors. With
/// fewer than three detectors all of them are used (and the count is scaled
/// to "of three" for the table). Computed once per sensor layout.
///
/// **Consequence** (the source's rule, kept): the beams ahead are in no
/// turn's cover, so a wall 0.5 m ahead leaves the vote of Left (covered by
/// 30°, 60°, 90°) at 1.0 although its arc (radius 0.43 m) sweeps into
/// that wall. In the voting suite this is how IR alone collides on the
/// narrow-passage fields: it meets the wall head-on, chatters between Left
/// and Right as noise flips the goal's bearing, and turns only when the
/// wall is too close for the arc (the suite's explanation, observation 3).
pub fn ir_covers(actions: &ActionSet, ir: &[IrReading]) -> Vec<Vec<usize>> {
    actions
        .actions
        .iter()
        .map(|a| {
            let mut order: Vec<usize> = (0..ir.len()).collect();
            order.sort_by(|&i, &j| {
                let di = wrap_angle(ir[i].mount.theta_rad - a.heading_rad).abs();
                let dj = wrap_angle(ir[j].mount.theta_rad - a.heading_rad).abs();
                di.total_cmp(&dj).then(i.cmp(&j))
            });
            order.truncate(3);
            order
        })
        .collect()
}

/// `b_IR`: obstacle avoidance with binary infrared detectors, with the
/// covers of [`ir_covers`]. Escape votes `triggered / total`.
pub fn ir_votes(actions: &ActionSet, ir: &[IrReading], covers: &[Vec<usize>], out: &mut [f64]) {
    let total = ir.len();
    let triggered = ir.iter().filter(|d| d.triggered).count();
    for (m, a) in actions.actions.iter().enumerate() {
        out[m] = match a.kind {
            ActionKind::Escape if total == 0 => 0.0,
            ActionKind::Escape => triggered as f64 / total as f64,
            ActionKind::Arc if covers[m].is_empty() => 1.0,
            ActionKind::Arc => {
                let k = covers[m].len();
                let hit = covers[m].iter().filter(|&&i| ir[i].triggered).count();
                ir_table((hit * 3).div_ceil(k))
            }
        };
    }
}

/// Sonar ramp: 1 beyond `d_max`, 0 within `d_min`, linear in between.
pub fn sonar_ramp(d_obs_m: f64, d_min_m: f64, d_max_m: f64) -> f64 {
    if d_obs_m > d_max_m {
        1.0
    } else if d_obs_m <= d_min_m {
        0.0
    } else {
        (d_obs_m - d_min_m) / (d_max_m - d_min_m)
    }
}

/// The ground each arc action would sweep: the robot's path over the
/// look-ahead (the arc), continued straight along the final heading out to
/// `reach_m` of travel, widened by the half-width the footprint needs.
///
/// **Decision:** the source says only "the obstacle distance the sonar sees
/// along action `m`". We place each echo on its transducer's axis at the
/// range read (the usual reading of a sonar return; the whole cone would
/// make one echo ahead block every action alike) and call it "along" an
/// action when that point lies on the ground the action sweeps: the path
/// widened by the robot's radius plus a margin. `D_obs(m)` is the nearest
/// such echo; an action no echo lies along gets 1. A close echo at the side
/// thus counts against Forward too, which a nearest-axis rule misses (a
/// robot that looks only along its heading scrapes the corners it passes).
///
/// The test is exact and O(1) per action: the distance from the point to
/// the arc (a circle of radius `L/θ_m` through the robot, `L` the arc's
/// length) and to the straight continuation.
#[derive(Debug, Clone, PartialEq)]
pub struct SweptPaths {
    /// Per action: `None` for Escape, else (heading change θ_m, arc length).
    arcs: Vec<Option<(f64, f64)>>,
    /// Travel the paths reach, metres.
    reach_m: f64,
    /// Half-width of the swept ground, metres.
    half_width_m: f64,
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
}

impl SweptPaths {
    /// Paths of `actions` out to `reach_m` of travel, for a footprint of
    /// `half_width_m` (robot radius + margin).
    pub fn new(actions: &ActionSet, reach_m: f64, half_width_m: f64) -> SweptPaths {
        let arc_len = actions.cruise_mps * actions.lookahead_s;
        let arcs = actions
            .actions
            .iter()
            .map(|a| match a.kind {
                ActionKind::Escape => None,
                ActionKind::Arc => Some((a.heading_rad, arc_len)),
            })
            .collect();
        SweptPaths {
            arcs,
            reach_m,
            half_width_m,
        }
    }

    /// Distance from the point (robot frame) to the path of action `m`
    /// (infinite for Escape).
    pub fn distance(&self, m: usize, x: f64, y: f64) -> f64 {
        let Some((theta, arc_len)) = self.arcs[m] else {
            return f64::INFINITY;
        };
        let arc = arc_len.min(self.reach_m);
        let rest = self.reach_m - arc;
        if theta.abs() < 1e-9 || arc <= 0.0 {
            return segment_distance((x, y), (0.0, 0.0), (self.reach_m, 0.0));
        }
        // Mirror right turns onto left ones.
        let (y, turn) = if theta < 0.0 { (-y, -theta) } else { (y, theta) };
        let r = arc_len / turn;
        let span = turn * arc / arc_len;
        let end = (r * span.sin(), r * (1.0 - span.cos()));
        // Around the centre (0, r), the arc's point at parameter φ lies at
        // angle φ − π/2.
        let (qx, qy) = (x, y - r);
        let phi = wrap_angle(qy.atan2(qx) + std::f64::consts::FRAC_PI_2);
        let to_arc = if (0.0..=span).contains(&phi) {
            (qx.hypot(qy) - r).abs()
        } else {
            x.hypot(y).min((x - end.0).hypot(y - end.1))
        };
        let to_line = if rest > 0.0 {
            let far = (end.0 + rest * span.cos(), end.1 + rest * span.sin());
            segment_distance((x, y), end, far)
        } else {
            f64::INFINITY
        };
        to_arc.min(to_line)
    }

    /// Whether the point (robot frame) lies on the ground action `m` sweeps.
    pub fn contains(&self, m: usize, x: f64, y: f64) -> bool {
        self.distance(m, x, y) <= self.half_width_m
    }
}

/// An echo as `b_sonar` uses it: the point in the robot frame and its
/// obstacle distance `D_obs`, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Echo {
    /// x in the robot frame, metres.
    pub x_m: f64,
    /// y in the robot frame, metres.
    pub y_m: f64,
    /// Distance from the transducer, metres.
    pub distance_m: f64,
}

/// The echoes of this reading within `d_max_m`, on their transducers' axes.
pub fn echoes(sonar: &[SonarReading], d_max_m: f64) -> impl Iterator<Item = Echo> + '_ {
    sonar.iter().filter(move |s| s.range_m <= d_max_m).map(|s| {
        let (sin, cos) = s.mount.theta_rad.sin_cos();
        Echo {
            x_m: s.mount.x_m + s.range_m * cos,
            y_m: s.mount.y_m + s.range_m * sin,
            distance_m: s.range_m,
        }
    })
}

/// `b_sonar`: obstacle avoidance with sonar, `D_obs(m)` per [`SweptPaths`]
/// over this reading's echoes and `remembered` ones (earlier echoes carried
/// into the robot frame; see [`super::VotingParams::sonar_memory_m`]).
/// Escape (undefined in the source) votes the fraction of transducers
/// reading `≤ d_min`.
pub fn sonar_votes(
    actions: &ActionSet,
    sonar: &[SonarReading],
    remembered: &[Echo],
    swept: &SweptPaths,
    d_min_m: f64,
    d_max_m: f64,
    out: &mut [f64],
) {
    let close = sonar.iter().filter(|s| s.range_m <= d_min_m).count();
    for (m, a) in actions.actions.iter().enumerate() {
        out[m] = match a.kind {
            ActionKind::Escape => {
                if sonar.is_empty() {
                    0.0
                } else {
                    close as f64 / sonar.len() as f64
                }
            }
            ActionKind::Arc => {
                let mut d_obs = f64::INFINITY;
                for e in echoes(sonar, d_max_m).chain(remembered.iter().copied()) {
                    if e.distance_m < d_obs && swept.contains(m, e.x_m, e.y_m) {
                        d_obs = e.distance_m;
                    }
                }
                sonar_ramp(d_obs, d_min_m, d_max_m)
            }
        };
    }
}

/// Goal seeking (odometry or planning): the Π-function of each action's
/// heading against the bearing `theta_rad` (relative to the robot's heading).
pub fn goal_votes(actions: &ActionSet, theta_rad: f64, beta_rad: f64, out: &mut [f64]) {
    for (m, a) in actions.actions.iter().enumerate() {
        out[m] = pi_function(a.heading_rad, theta_rad, beta_rad);
    }
}

/// Half a turn, for the docs of Escape's vote.
pub const ESCAPE_HEADING: f64 = PI;

#[cfg(test)]
mod tests {
    use super::*;
    use robot::Pose;

    fn ir_ring(triggered: &[bool]) -> Vec<IrReading> {
        let n = triggered.len();
        (0..n)
            .map(|i| IrReading {
                mount: Pose::new(0.0, 0.0, (90.0 - 180.0 * i as f64 / (n - 1) as f64).to_radians()),
                range_m: 0.8,
                triggered: triggered[i],
            })
            .collect()
    }

    #[test]
    fn ir_votes_follow_the_table() {
        let a = ActionSet::default();
        let mut v = vec![0.0; a.len()];
        // Detectors at +90 … −90 in 30° steps; the front three triggered.
        let ring = ir_ring(&[false, false, true, true, true, false, false]);
        let covers = ir_covers(&a, &ring);
        ir_votes(&a, &ring, &covers, &mut v);
        assert_eq!(v[3], 0.0, "Forward: 3 of its 3 triggered");
        assert_eq!(v[2], 0.3, "Soft Left: detectors at 60, 30, 0 → 2 triggered");
        assert_eq!(v[1], 0.7, "Left: 90, 60, 30 → 1");
        assert_eq!(v[0], 0.7, "Hard Left: nearest three are 90, 60, 30 → 1");
        assert_eq!(v[7], 3.0 / 7.0, "Escape = triggered / total");
        ir_votes(&a, &ir_ring(&[false; 7]), &covers, &mut v);
        assert!(v[..7].iter().all(|&x| x == 1.0) && v[7] == 0.0);
        assert_eq!(
            (ir_table(0), ir_table(1), ir_table(2), ir_table(3)),
            (1.0, 0.7, 0.3, 0.0)
        );
    }

    #[test]
    fn sonar_ramp_and_escape() {
        assert_eq!(sonar_ramp(2.0, 0.2, 1.0), 1.0);
        assert_eq!(sonar_ramp(0.2, 0.2, 1.0), 0.0);
        assert!((sonar_ramp(0.6, 0.2, 1.0) - 0.5).abs() < 1e-12);
        let a = ActionSet::default();
        let s: Vec<SonarReading> = [30.0f64, 0.0, -30.0]
            .iter()
            .zip([0.1, 0.6, 5.0])
            .map(|(&deg, r)| SonarReading {
                mount: Pose::new(0.0, 0.0, deg.to_radians()),
                cone_rad: 25f64.to_radians(),
                range_m: r,
            })
            .collect();
        let mut v = vec![0.0; a.len()];
        let swept = SweptPaths::new(&a, 1.0, 0.2);
        sonar_votes(&a, &s, &[], &swept, 0.2, 1.0, &mut v);
        assert!(
            v[..7].iter().all(|&x| x == 0.0),
            "0.1 m at +30° is beside every path: {v:?}"
        );
        assert!((v[7] - 1.0 / 3.0).abs() < 1e-12, "Escape: one of three ≤ d_min");
        // Echoes at 0.3 m (+30°), 0.6 m (0°), none (−30°).
        let mid: Vec<SonarReading> = s
            .iter()
            .zip([0.3, 0.6, f64::INFINITY])
            .map(|(r, range_m)| SonarReading { range_m, ..*r })
            .collect();
        sonar_votes(&a, &mid, &[], &swept, 0.2, 1.0, &mut v);
        let ramp = |d: f64| (d - 0.2) / 0.8;
        assert!(
            (v[0] - ramp(0.3)).abs() < 1e-12,
            "Hard Left runs into the +30° echo"
        );
        assert!(
            (v[3] - ramp(0.3)).abs() < 1e-12,
            "Forward passes the +30° echo within the footprint"
        );
        assert_eq!(v[6], 1.0, "Hard Right sweeps away from both echoes");
        assert_eq!(v[7], 0.0);
    }

    /// The path of [`SweptPaths`] sampled every millimetre, as a reference.
    fn sampled_distance(actions: &ActionSet, m: usize, reach: f64, x: f64, y: f64) -> f64 {
        let a = &actions.actions[m];
        let arc_len = actions.cruise_mps * actions.lookahead_s;
        let kappa = a.heading_rad / arc_len;
        let n = (reach / 0.001).ceil() as usize;
        (0..=n)
            .map(|k| {
                let s = k as f64 * 0.001;
                let sa = s.min(arc_len);
                let (px, py, th) = if kappa.abs() < 1e-9 {
                    (sa, 0.0, 0.0)
                } else {
                    let th = kappa * sa;
                    (th.sin() / kappa, (1.0 - th.cos()) / kappa, th)
                };
                let rest = s - sa;
                (x - px - rest * th.cos()).hypot(y - py - rest * th.sin())
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn swept_path_distance_is_exact() {
        let a = ActionSet::default();
        let swept = SweptPaths::new(&a, 1.0, 0.2);
        // A grid of points around the robot, every action but Escape.
        for m in 0..7 {
            for i in -12..=12 {
                for j in -12..=12 {
                    let (x, y) = (0.1 * i as f64, 0.1 * j as f64);
                    let exact = swept.distance(m, x, y);
                    let sampled = sampled_distance(&a, m, 1.0, x, y);
                    assert!(
                        (exact - sampled).abs() < 1e-3,
                        "action {m} at ({x}, {y}): {exact} vs {sampled}"
                    );
                }
            }
        }
        assert_eq!(
            swept.distance(7, 0.3, 0.0),
            f64::INFINITY,
            "Escape sweeps nothing"
        );
    }

    #[test]
    fn remembered_echoes_vote_like_heard_ones() {
        let a = ActionSet::default();
        let swept = SweptPaths::new(&a, 1.0, 0.2);
        let mut v = vec![0.0; a.len()];
        // Nothing heard now; a corner remembered 0.3 m to the left, just
        // past the +42.5° edge of the left cone.
        let corner = Echo {
            x_m: 0.2,
            y_m: 0.3,
            distance_m: 0.36 - 0.15,
        };
        sonar_votes(&a, &[], &[corner], &swept, 0.25, 1.0, &mut v);
        assert_eq!(v[0], 0.0, "Hard Left runs into the corner (≤ D_min)");
        assert_eq!(v[3], 1.0, "Forward passes it");
        assert_eq!(v[6], 1.0, "Hard Right turns away");
    }

    #[test]
    fn pi_function_wraps() {
        let beta = 0.5;
        assert_eq!(pi_function(0.3, 0.3, beta), 1.0);
        assert!((pi_function(0.0, 0.5, beta) - 0.5).abs() < 1e-12);
        // 179° vs −179° are 2° apart, not 358°.
        let near = pi_function(179f64.to_radians(), (-179f64).to_radians(), beta);
        assert!(near > 0.99, "{near}");
    }
}
