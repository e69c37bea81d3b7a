//! Potential-field recovery: recorded dead-locks repel, the goal attracts
//! (docs/activity-trace.md).
//!
//! * repulsion of dead-lock `k` at distance `L_k`:
//!   `|F_r,k| = k_r (1/L_k − 1/L_0)²` if `L_k < L_0`, else 0, pointing away;
//! * attraction `|F_a| = k_a / L_T²` towards the target at distance `L_T`;
//! * the goal-tracking behaviour steers to `Θ_d = arg(F_a + Σ F_r,k)`.

use robot::Vec2;

/// Parameters of the field.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FieldParams {
    /// Repulsion gain `k_r` (m⁻²·m² = dimensionless scale). Default 1.
    pub k_r: f64,
    /// Attraction gain `k_a`, m². Default 1.
    pub k_a: f64,
    /// Range of a dead-lock's repulsion `L_0`, metres. Default 2.
    pub l0_m: f64,
}

impl Default for FieldParams {
    fn default() -> Self {
        FieldParams {
            k_r: 1.0,
            k_a: 1.0,
            l0_m: 2.0,
        }
    }
}

/// Repulsive force of a dead-lock at `deadlock` on a robot at `at`.
pub fn repulsion(p: &FieldParams, at: Vec2, deadlock: Vec2) -> Vec2 {
    let d = at - deadlock;
    let l = d.norm();
    if l >= p.l0_m || l == 0.0 {
        return Vec2::default();
    }
    let mag = p.k_r * (1.0 / l - 1.0 / p.l0_m).powi(2);
    d.scale(mag / l)
}

/// Attractive force of the goal.
pub fn attraction(p: &FieldParams, at: Vec2, goal: Vec2) -> Vec2 {
    let d = goal - at;
    let l = d.norm();
    if l == 0.0 {
        return Vec2::default();
    }
    d.scale(p.k_a / (l * l) / l)
}

/// Total force `F = F_a + Σ_k F_r,k`.
pub fn total_force(p: &FieldParams, at: Vec2, goal: Vec2, deadlocks: &[Vec2]) -> Vec2 {
    deadlocks
        .iter()
        .fold(attraction(p, at, goal), |f, &d| f + repulsion(p, at, d))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repulsion_vanishes_beyond_l0_and_points_away() {
        let p = FieldParams::default();
        let dl = Vec2::new(0.0, 0.0);
        assert_eq!(repulsion(&p, Vec2::new(2.0, 0.0), dl), Vec2::default());
        assert_eq!(repulsion(&p, Vec2::new(3.0, 1.0), dl), Vec2::default());
        let f = repulsion(&p, Vec2::new(0.5, 0.0), dl);
        assert!(f.x > 0.0 && f.y.abs() < 1e-15);
        assert!((f.x - (1.0 / 0.5 - 1.0 / 2.0f64).powi(2)).abs() < 1e-12);
    }

    #[test]
    fn attraction_follows_the_inverse_square() {
        let p = FieldParams::default();
        let f = attraction(&p, Vec2::new(0.0, 0.0), Vec2::new(0.0, 2.0));
        assert!(f.x.abs() < 1e-15 && (f.y - 0.25).abs() < 1e-12);
    }

    #[test]
    fn a_deadlock_between_robot_and_goal_deflects_the_heading() {
        let p = FieldParams::default();
        let at = Vec2::new(0.0, 0.0);
        let goal = Vec2::new(10.0, 0.0);
        let straight = total_force(&p, at, goal, &[]).angle();
        let bent = total_force(&p, at, goal, &[Vec2::new(0.5, 0.1)]).angle();
        assert_eq!(straight, 0.0);
        assert!(bent.abs() > 1.0, "pushed away from the dead-lock: {bent}");
    }
}
