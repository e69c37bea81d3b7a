//! Whether a scan contradicts the map at a pose: the evidence that tells a
//! robot that is lost from one that is only surrounded by people.
//!
//! Every valid beam of the scan, projected from the laser's pose, falls in
//! one of three classes ([`ScanConsistency`]):
//!
//! | class | the beam | what it says about the pose |
//! |---|---|---|
//! | **hit** | ends within `hit_within_m + r · through_tolerance_rad` (0.1 m + 2° × range) of a mapped wall | agrees |
//! | **through** | passes through a mapped (occupied) cell before `r − (through_tolerance_m + r · through_tolerance_rad)` and does not end on a wall | contradicts: the laser saw past a wall the map says is there |
//! | **short** | ends in the open, before any mapped wall | nothing: a person, a bag, anything not on the map stands in front |
//!
//! A reading at or beyond the maximum range (nothing returned) is a
//! *through* beam when the map has a wall on its line closer than the
//! maximum range less the tolerance, and is ignored otherwise; drop-outs
//! (`NaN`) and negative ranges are ignored.
//!
//! Both tolerances grow with the range `r` because a tracking filter's
//! heading is off by a degree or two: at 15 m that moves an endpoint by
//! 0.25–0.5 m across the wall it hit, and a beam that grazes a wall meets
//! it metres further along — with fixed tolerances the far walls of a
//! hall contradict a good estimate whenever the robot turns.
//!
//! People only ever *shorten* beams. So at the true pose the through
//! beams are those the pose error and the laser noise push past a wall
//! (a few grazing ones), however crowded the place; at a pose that is off
//! by half a metre or twenty degrees, every wall the laser sees on the
//! far side of the error is seen *behind* its mapped place. The
//! **contradiction** `through / (hit + through)` is therefore small at a
//! good pose whatever hides the walls, and large at a wrong one as long
//! as some walls are in view; with fewer than `min_evidence_beams` hit or
//! through beams the scan says nothing either way.
//!
//! Short beams are also counted as **unmapped objects**: runs of
//! consecutive short beams whose endpoints lie within
//! [`OBJECT_GAP_M`] of each other — roughly the people in view, a measure
//! of the crowd the robot can take from its own scan.
//!
//! **Lost, or only off?** A filter that lags behind a slip can be a few
//! degrees or decimetres off and contradict the far walls without being
//! lost. Before a contradicted scan counts against the pose, it is tried
//! at the poses of a [`Neighbourhood`] around it (a 3 × 3 grid 0.3 m apart
//! and headings ±15° in 5° steps: 62 poses, a couple of milliseconds, only
//! for contradicted scans); if one of them explains the scan, the robot is
//! off by less than the loss threshold (0.5 m, 20°) and the pose found is
//! a correction ([`LikelihoodField::nearest_consistent`]).
//!
//! **The ray march.** Whether a beam crosses an occupied cell is decided
//! cell by cell (Amanatides–Woo traversal), jumping through empty space by
//! the likelihood field's distance to the nearest occupied cell (less one
//! and a half cells, so no occupied cell is ever jumped over). In a museum
//! hall a 15 m beam takes a dozen jumps; `O(beams × jumps)` per scan, no
//! allocation.

use robot::{LaserScan, Pose, Vec2};

use super::likelihood_field::LikelihoodField;

/// Two short beams whose endpoints are farther apart than this belong to
/// different unmapped objects, metres (a person's shoulders are ~0.5 m
/// apart; two people side by side leave a gap).
pub const OBJECT_GAP_M: f64 = 0.3;

/// How a scan agrees with the map at one pose (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct ScanConsistency {
    /// Beams with a usable reading (endpoint, or nothing returned).
    pub beams: usize,
    /// Beams ending on a mapped wall.
    pub hit: usize,
    /// Beams seeing past a mapped wall.
    pub through: usize,
    /// Beams ending in front of the mapped walls (occluded).
    pub short: usize,
    /// Runs of short beams: unmapped objects in view (people).
    pub unmapped_objects: usize,
}

impl ScanConsistency {
    /// Beams that say something about the pose: hit or through.
    pub fn evidence(&self) -> usize {
        self.hit + self.through
    }

    /// `through / (hit + through)`; 0 without evidence.
    pub fn contradiction(&self) -> f64 {
        let e = self.evidence();
        if e == 0 {
            0.0
        } else {
            self.through as f64 / e as f64
        }
    }

    /// The share of usable beams that end short (occluded); 0 without
    /// beams.
    pub fn occluded_fraction(&self) -> f64 {
        if self.beams == 0 {
            0.0
        } else {
            self.short as f64 / self.beams as f64
        }
    }
}

/// The tolerances of the classification (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConsistencyTolerances {
    /// A beam ending within this distance of a wall, plus
    /// `through_tolerance_rad` per metre of range, is a hit, metres.
    pub hit_within_m: f64,
    /// A beam is through only if it crosses a wall this far before its
    /// endpoint, metres, plus `through_tolerance_rad` per metre of range.
    pub through_tolerance_m: f64,
    /// The part of the through tolerance that grows with the range: a
    /// heading error of this many radians moves an endpoint at range `r`
    /// by `r` times as much.
    pub through_tolerance_rad: f64,
}

impl ConsistencyTolerances {
    /// The hit distance of a beam of range `r`, metres.
    pub fn hit_m(&self, r: f64) -> f64 {
        self.hit_within_m + self.through_tolerance_rad * r
    }

    /// The through tolerance of a beam of range `r`, metres.
    pub fn through_m(&self, r: f64) -> f64 {
        self.through_tolerance_m + self.through_tolerance_rad * r
    }
}

impl LikelihoodField {
    /// Distance in cells along the ray from `(u, v)` (map-cell coordinates)
    /// in the unit direction `(du, dv)` to the first occupied cell, if one
    /// lies within `max_cells`; `None` when the ray leaves the map or
    /// reaches `max_cells` first. A start inside an occupied cell gives 0.
    pub fn first_occupied_cells(&self, u: f64, v: f64, du: f64, dv: f64, max_cells: f64) -> Option<f64> {
        if !(u.is_finite() && v.is_finite() && du.is_finite() && dv.is_finite()) {
            return None;
        }
        let (w, h) = (self.width() as f64, self.height() as f64);
        let mut t = 0.0f64;
        while t <= max_cells {
            let (x, y) = (u + t * du, v + t * dv);
            if !(x >= 0.0 && y >= 0.0 && x < w && y < h) {
                return None;
            }
            let (i, j) = (x.floor(), y.floor());
            let k = j as usize * self.width() + i as usize;
            if self.occupied_index(k) {
                return Some(t);
            }
            // Every point of this cell is within √2/2 of its centre, every
            // point of an occupied cell within √2/2 of that one's: a jump
            // of the centre distance less 1.5 cells passes no occupied cell.
            let safe = self.centre_distance_cells(k) - 1.5;
            if safe > 1.0 {
                t += safe;
                continue;
            }
            // Otherwise to the next cell boundary.
            let tx = if du > 0.0 {
                (i + 1.0 - x) / du
            } else if du < 0.0 {
                (x - i) / -du
            } else {
                f64::INFINITY
            };
            let ty = if dv > 0.0 {
                (j + 1.0 - y) / dv
            } else if dv < 0.0 {
                (y - j) / -dv
            } else {
                f64::INFINITY
            };
            t += tx.min(ty) + 1e-6;
        }
        None
    }

    /// How `scan` agrees with the map for a robot at `pose` (module docs).
    /// `O(beams × cells marched)`.
    pub fn consistency(&self, pose: &Pose, scan: &LaserScan, tol: ConsistencyTolerances) -> ScanConsistency {
        let mut out = ScanConsistency::default();
        let laser = pose.compose(&scan.mount);
        let (lu, lv) = self.to_cells(laser.position());
        let res = self.resolution_m();
        let map_theta = self.origin_theta_rad();
        let range_max = scan.range_max_m;
        // The previous beam's endpoint, if it was short.
        let mut last_short: Option<Vec2> = None;
        for (k, &r) in scan.ranges_m.iter().enumerate() {
            if r.is_nan() || r < 0.0 {
                last_short = None;
                continue;
            }
            let a = laser.theta_rad + scan.angle_min_rad + k as f64 * scan.angle_increment_rad;
            let (s, c) = (a - map_theta).sin_cos();
            let returned = r.is_finite() && r < range_max;
            out.beams += 1;
            if returned {
                let (sw, cw) = a.sin_cos();
                let end = Vec2::new(laser.x_m + r * cw, laser.y_m + r * sw);
                if self.distance_at(end) <= tol.hit_m(r) {
                    out.hit += 1;
                    last_short = None;
                    continue;
                }
                let reach = (r - tol.through_m(r)) / res;
                if reach > 0.0 && self.first_occupied_cells(lu, lv, c, s, reach).is_some() {
                    out.through += 1;
                    last_short = None;
                    continue;
                }
                out.short += 1;
                if last_short.is_none_or(|p| p.dist(end) > OBJECT_GAP_M) {
                    out.unmapped_objects += 1;
                }
                last_short = Some(end);
            } else {
                last_short = None;
                let reach = (range_max - tol.through_m(range_max)) / res;
                if range_max.is_finite()
                    && reach > 0.0
                    && self.first_occupied_cells(lu, lv, c, s, reach).is_some()
                {
                    out.through += 1;
                } else {
                    out.beams -= 1;
                }
            }
        }
        out
    }
}

/// The poses around an estimate that a contradicted scan is tried at
/// before the estimate is judged lost ([`LikelihoodField::nearest_consistent`]):
/// offsets of `-steps..=steps` times `step_m` in x and in y, and of
/// `-heading_steps..=heading_steps` times `heading_step_rad` in heading.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Neighbourhood {
    /// Spacing of the positions, metres. Default 0.3.
    pub step_m: f64,
    /// Positions on each side in x and in y. Default 1 (a 3 × 3 grid).
    pub steps: usize,
    /// Spacing of the headings, radians. Default 5°.
    pub heading_step_rad: f64,
    /// Headings on each side. Default 3 (±15°).
    pub heading_steps: usize,
}

impl Default for Neighbourhood {
    fn default() -> Neighbourhood {
        Neighbourhood {
            step_m: 0.3,
            steps: 1,
            heading_step_rad: 5f64.to_radians(),
            heading_steps: 3,
        }
    }
}

impl LikelihoodField {
    /// Among the poses of `hood` around `pose` (itself excluded), the one
    /// whose scan consistency has at most `max_contradiction` with at least
    /// `min_evidence` hit-or-through beams and the least contradiction
    /// (ties: the nearest, positions before headings); `None` when no pose
    /// there explains the scan. `O(poses × beams × cells marched)`.
    pub fn nearest_consistent(
        &self,
        pose: &Pose,
        scan: &LaserScan,
        tol: ConsistencyTolerances,
        max_contradiction: f64,
        min_evidence: usize,
        hood: &Neighbourhood,
    ) -> Option<(Pose, ScanConsistency)> {
        let n = hood.steps as i64;
        let m = hood.heading_steps as i64;
        let mut offsets: Vec<(i64, i64, i64)> = Vec::new();
        for i in -n..=n {
            for j in -n..=n {
                for k in -m..=m {
                    if (i, j, k) != (0, 0, 0) {
                        offsets.push((i, j, k));
                    }
                }
            }
        }
        // Nearest first: position steps, then heading steps.
        offsets.sort_by_key(|&(i, j, k)| (i * i + j * j, k.abs(), i, j, k));
        let mut best: Option<(Pose, ScanConsistency)> = None;
        for (i, j, k) in offsets {
            let q = Pose::new(
                pose.x_m + i as f64 * hood.step_m,
                pose.y_m + j as f64 * hood.step_m,
                robot::wrap_angle(pose.theta_rad + k as f64 * hood.heading_step_rad),
            );
            let c = self.consistency(&q, scan, tol);
            if c.evidence() < min_evidence.max(1) || c.contradiction() > max_contradiction {
                continue;
            }
            if best.is_none_or(|(_, b)| c.contradiction() < b.contradiction()) {
                best = Some((q, c));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::{Cell, GridMap};

    const TOL: ConsistencyTolerances = ConsistencyTolerances {
        hit_within_m: 0.1,
        through_tolerance_m: 0.25,
        through_tolerance_rad: 0.035,
    };

    /// A 10 m × 6 m room (0.05 m cells) with 0.1 m walls, and a 0.1 m
    /// wall across it at x = 5 m with a 1 m door at y ∈ [2.5, 3.5].
    fn room() -> GridMap {
        let (w, h) = (200, 120);
        let cells = (0..w * h)
            .map(|k| {
                let (i, j) = (k % w, k / w);
                let border = i < 2 || j < 2 || i >= w - 2 || j >= h - 2;
                let inner = (100..102).contains(&i) && !(50..70).contains(&j);
                if border || inner {
                    Cell::Occupied
                } else {
                    Cell::Free
                }
            })
            .collect();
        GridMap::new(w, h, 0.05, Pose::default(), cells).unwrap()
    }

    fn scan(ranges: Vec<f64>) -> LaserScan {
        let n = ranges.len();
        LaserScan {
            mount: Pose::default(),
            angle_min_rad: -std::f64::consts::FRAC_PI_2,
            angle_increment_rad: std::f64::consts::PI / (n - 1) as f64,
            range_max_m: 30.0,
            ranges_m: ranges,
        }
    }

    /// The exact scan of the map from `pose`, beams every degree, an
    /// optional disc (a person) in front.
    fn true_scan(map: &GridMap, pose: Pose, person: Option<(Vec2, f64)>) -> LaserScan {
        let field = LikelihoodField::new(map, 2.0);
        let mut ranges = Vec::new();
        for k in 0..181 {
            let a = pose.theta_rad - std::f64::consts::FRAC_PI_2 + (k as f64).to_radians();
            let (u, v) = field.to_cells(pose.position());
            let wall = field
                .first_occupied_cells(u, v, a.cos(), a.sin(), 1e4)
                .map_or(f64::INFINITY, |t| t * 0.05);
            let mut r = wall;
            if let Some((c, rad)) = person {
                // Ray–disc intersection.
                let d = Vec2::new(a.cos(), a.sin());
                let o = pose.position();
                let oc = Vec2::new(o.x - c.x, o.y - c.y);
                let b = oc.x * d.x + oc.y * d.y;
                let cc = oc.x * oc.x + oc.y * oc.y - rad * rad;
                let disc = b * b - cc;
                if disc >= 0.0 {
                    let t = -b - disc.sqrt();
                    if t > 0.0 {
                        r = r.min(t);
                    }
                }
            }
            ranges.push(r);
        }
        scan(ranges)
    }

    #[test]
    fn the_ray_march_finds_the_first_wall_like_a_cell_walk() {
        let map = room();
        let f = LikelihoodField::new(&map, 2.0);
        // From (2, 3) m, facing +x: the inner wall's face at x = 5.0 m.
        let (u, v) = f.to_cells(Vec2::new(2.0, 3.5 + 0.3));
        let t = f.first_occupied_cells(u, v, 1.0, 0.0, 1e4).unwrap();
        assert!((t * 0.05 - 3.0).abs() < 1e-6, "{t}");
        // Through the door: the far wall at x = 9.9 m.
        let (u, v) = f.to_cells(Vec2::new(2.0, 3.0));
        let t = f.first_occupied_cells(u, v, 1.0, 0.0, 1e4).unwrap();
        assert!((t * 0.05 - 7.9).abs() < 1e-6, "{t}");
        // Not within reach.
        assert_eq!(f.first_occupied_cells(u, v, 1.0, 0.0, 100.0), None);
        // Diagonal rays agree with a fine-stepped walk.
        for k in 0..64 {
            let a = k as f64 * std::f64::consts::TAU / 64.0;
            let (du, dv) = (a.cos(), a.sin());
            let (u, v) = f.to_cells(Vec2::new(3.3, 2.1));
            let fast = f.first_occupied_cells(u, v, du, dv, 1e4).unwrap();
            let mut slow = 0.0;
            loop {
                let (x, y) = (u + slow * du, v + slow * dv);
                if map.blocked(robot::CellIndex {
                    i: x.floor() as i64,
                    j: y.floor() as i64,
                }) {
                    break;
                }
                slow += 1e-3;
            }
            assert!((fast - slow).abs() < 2e-3, "angle {a}: {fast} vs {slow}");
        }
    }

    #[test]
    fn a_good_pose_agrees_and_a_person_only_shortens_beams() {
        let map = room();
        let f = LikelihoodField::new(&map, 2.0);
        let pose = Pose::new(2.5, 2.0, 0.3);
        let c = f.consistency(&pose, &true_scan(&map, pose, None), TOL);
        assert_eq!(c.through, 0, "{c:?}");
        assert!(c.hit > 170, "{c:?}");
        // A person 1 m ahead hides part of the scan: short beams, one object.
        let person = pose.transform(Vec2::new(1.0, 0.0));
        let c = f.consistency(&pose, &true_scan(&map, pose, Some((person, 0.25))), TOL);
        assert_eq!(c.through, 0, "{c:?}");
        assert!(c.short > 20, "{c:?}");
        assert_eq!(c.unmapped_objects, 1, "{c:?}");
        assert_eq!(c.contradiction(), 0.0);
    }

    #[test]
    fn a_wrong_pose_sees_walls_behind_their_mapped_place() {
        let map = room();
        let f = LikelihoodField::new(&map, 2.0);
        let truth = Pose::new(2.5, 2.0, 0.3);
        let s = true_scan(&map, truth, None);
        for wrong in [
            Pose::new(3.0, 2.0, 0.3),
            Pose::new(2.5, 2.5, 0.3),
            Pose::new(2.5, 2.0, 0.3 + 20f64.to_radians()),
            Pose::new(2.5, 2.0, 0.3 - 20f64.to_radians()),
        ] {
            let c = f.consistency(&wrong, &s, TOL);
            assert!(c.contradiction() > 0.2, "{wrong:?}: {c:?}");
        }
    }

    #[test]
    fn no_return_where_the_map_has_a_wall_contradicts() {
        let map = room();
        let f = LikelihoodField::new(&map, 2.0);
        let pose = Pose::new(2.5, 2.0, 0.0);
        let c = f.consistency(&pose, &scan(vec![f64::INFINITY; 5]), TOL);
        assert_eq!((c.beams, c.through), (5, 5));
        let c = f.consistency(&pose, &scan(vec![f64::NAN, -1.0]), TOL);
        assert_eq!(c, ScanConsistency::default());
    }
}
