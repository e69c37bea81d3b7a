//! Analytic range queries against discs (people): a ray, and a cone.
//!
//! Positions are relative to the sensor (the disc's centre minus the ray's
//! origin), so callers rotate once per disc, not once per ray. `O(1)` each.

use robot::Vec2;

/// Distance along the ray of unit direction `dir` to the first point of the
/// disc of radius `radius_m` centred at `rel` (relative to the ray's
/// origin), or `None` if the ray misses it. A ray starting inside the disc
/// hits at 0.
#[inline]
pub fn ray_disc(rel: Vec2, dir: Vec2, radius_m: f64) -> Option<f64> {
    let r2 = radius_m * radius_m;
    let d2 = rel.dot(rel);
    if d2 <= r2 {
        return Some(0.0);
    }
    let along = rel.dot(dir);
    if along <= 0.0 {
        return None;
    }
    let perp2 = d2 - along * along;
    if perp2 > r2 {
        return None;
    }
    Some(along - (r2 - perp2).max(0.0).sqrt())
}

/// Distance from the apex to the nearest point of a disc inside a cone: the
/// cone's axis is +x, its half-width `half_angle_rad` (< π), the disc of
/// radius `radius_m` centred at `rel` (in the cone's frame). `None` if the
/// disc lies wholly outside the cone.
///
/// If the centre's bearing is inside the cone, the nearest point is on the
/// line to the centre (`|rel| − r`); otherwise it is on one of the two edge
/// rays, the distance along the circle to the apex being unimodal.
#[inline]
pub fn cone_disc(rel: Vec2, half_angle_rad: f64, radius_m: f64) -> Option<f64> {
    let d = rel.norm();
    if d <= radius_m {
        return Some(0.0);
    }
    if rel.y.atan2(rel.x).abs() <= half_angle_rad {
        return Some(d - radius_m);
    }
    let (s, c) = half_angle_rad.sin_cos();
    let a = ray_disc(rel, Vec2::new(c, s), radius_m);
    let b = ray_disc(rel, Vec2::new(c, -s), radius_m);
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_hit_discs_at_the_near_side() {
        let x = Vec2::new(1.0, 0.0);
        assert_eq!(ray_disc(Vec2::new(2.0, 0.0), x, 0.5), Some(1.5));
        assert_eq!(ray_disc(Vec2::new(-2.0, 0.0), x, 0.5), None);
        assert_eq!(ray_disc(Vec2::new(2.0, 0.6), x, 0.5), None);
        let t = ray_disc(Vec2::new(2.0, 0.3), x, 0.5).unwrap();
        assert!((t - 1.6).abs() < 1e-12);
        assert_eq!(ray_disc(Vec2::new(0.1, 0.0), x, 0.5), Some(0.0));
    }

    #[test]
    fn cones_see_the_nearest_point_inside() {
        let h = 0.2;
        // On the axis.
        assert!((cone_disc(Vec2::new(3.0, 0.0), h, 0.25).unwrap() - 2.75).abs() < 1e-12);
        // Centre outside the cone, disc across its edge: hit on the edge ray.
        let rel = Vec2::new(2.0, 2.0 * (h + 0.1).tan());
        let got = cone_disc(rel, h, 0.25).unwrap();
        let dir = Vec2::new(h.cos(), h.sin());
        assert!((got - ray_disc(rel, dir, 0.25).unwrap()).abs() < 1e-12);
        // Wholly outside.
        assert_eq!(cone_disc(Vec2::new(2.0, 2.0), h, 0.25), None);
        // Brute force: sample the disc's area, keep the nearest point in the cone.
        for &(x, y) in &[(1.0, 0.3), (1.5, -0.45), (0.8, 0.25), (2.0, 0.0)] {
            let rel = Vec2::new(x, y);
            let mut best = f64::INFINITY;
            for a in 0..400 {
                for k in 0..=100 {
                    let t = a as f64 / 400.0 * std::f64::consts::TAU;
                    let p = rel + Vec2::new(t.cos(), t.sin()).scale(0.25 * k as f64 / 100.0);
                    if p.y.atan2(p.x).abs() <= h {
                        best = best.min(p.norm());
                    }
                }
            }
            let got = cone_disc(rel, h, 0.25);
            match got {
                Some(g) => assert!((g - best).abs() < 2e-3, "{x},{y}: {g} vs {best}"),
                None => assert!(best.is_infinite()),
            }
        }
    }
}
