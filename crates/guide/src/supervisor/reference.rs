//! Reference runs of a behaviour: how long it takes, how fast it goes, and
//! the trajectory it drove — what λ7 and λ8 come from (docs/gspn.md, "Parameters").
//!
//! At the start of a mission the completion rate of a behaviour is
//! `1 / mean travel time` of its reference runs; mid-mission it is
//! `1 / (remaining length / mean speed)`, the remaining length measured
//! along the saved reference trajectory from the point of it nearest the
//! robot's estimate.

use robot::Vec2;

/// A behaviour's reference: mean travel time and speed of its successful
/// calibration runs, and one trajectory (the run whose time is the median).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Reference {
    /// Mean travel time of the successful reference runs, seconds.
    pub mean_time_s: f64,
    /// Mean speed along the trajectory (length over time, averaged over
    /// the runs), m/s.
    pub mean_speed_mps: f64,
    /// The trajectory, world frame, from start to goal.
    pub trajectory: Vec<Vec2>,
}

/// Shortest time the remaining travel is taken to last, seconds: near the
/// goal the remaining length goes to zero and its rate to infinity; the
/// supervisor's chain needs finite rates (1 s is ten control periods).
pub const MIN_REMAINING_S: f64 = 1.0;

impl Reference {
    /// Length of the trajectory, metres.
    pub fn length_m(&self) -> f64 {
        self.trajectory.windows(2).map(|w| w[0].dist(w[1])).sum()
    }

    /// The remaining length along the trajectory from the point of it
    /// nearest `at`, metres (the whole length for an empty trajectory's
    /// start, 0 past its end).
    pub fn remaining_m(&self, at: Vec2) -> f64 {
        let t = &self.trajectory;
        if t.len() < 2 {
            return 0.0;
        }
        // The segment whose nearest point is nearest `at`, and how far along.
        let mut best = (f64::INFINITY, 0usize, 0.0f64);
        for (k, w) in t.windows(2).enumerate() {
            let d = w[1] - w[0];
            let len2 = d.dot(d);
            let u = if len2 > 0.0 {
                ((at - w[0]).dot(d) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let q = w[0] + d.scale(u);
            let dist = q.dist(at);
            if dist < best.0 {
                best = (dist, k, u);
            }
        }
        let (_, k, u) = best;
        let seg = t[k].dist(t[k + 1]);
        let rest: f64 = t[k + 1..].windows(2).map(|w| w[0].dist(w[1])).sum();
        (1.0 - u) * seg + rest
    }

    /// The expected remaining travel time from `at`, seconds (at least
    /// [`MIN_REMAINING_S`]); the mean time when there is no trajectory.
    pub fn remaining_time_s(&self, at: Vec2) -> f64 {
        if self.trajectory.len() < 2 {
            return self.mean_time_s.max(MIN_REMAINING_S);
        }
        (self.remaining_m(at) / self.mean_speed_mps).max(MIN_REMAINING_S)
    }

    /// A reference without runs: the mean time only (no trajectory, so the
    /// completion rate stays `1 / mean_time_s` all along).
    pub fn prior(mean_time_s: f64) -> Reference {
        Reference {
            mean_time_s,
            mean_speed_mps: 0.0,
            trajectory: Vec::new(),
        }
    }

    /// The completion rate from `at`, 1/s: `1 / remaining time`.
    pub fn rate_from(&self, at: Vec2) -> f64 {
        1.0 / self.remaining_time_s(at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l_shape() -> Reference {
        Reference {
            mean_time_s: 20.0,
            mean_speed_mps: 0.5,
            trajectory: vec![Vec2::new(0.0, 0.0), Vec2::new(6.0, 0.0), Vec2::new(6.0, 4.0)],
        }
    }

    #[test]
    fn the_remaining_length_follows_the_trajectory() {
        let r = l_shape();
        assert_eq!(r.length_m(), 10.0);
        assert!((r.remaining_m(Vec2::new(0.0, 0.0)) - 10.0).abs() < 1e-12);
        // Beside the first leg, 2 m along it: 4 + 4 left.
        assert!((r.remaining_m(Vec2::new(2.0, 0.3)) - 8.0).abs() < 1e-12);
        // Half-way up the second leg.
        assert!((r.remaining_m(Vec2::new(6.2, 2.0)) - 2.0).abs() < 1e-12);
        // At the goal: floored to one second.
        assert_eq!(r.remaining_m(Vec2::new(6.0, 4.0)), 0.0);
        assert_eq!(r.remaining_time_s(Vec2::new(6.0, 4.0)), MIN_REMAINING_S);
        assert!((r.rate_from(Vec2::new(2.0, 0.0)) - 0.5 / 8.0).abs() < 1e-12);
    }
}
