//! The local spatial memory of `b_plan`: a grid of visit counts over the
//! odometry frame (after Balch & Arkin, *Avoiding the Past*, 1993).
//!
//! Each time the robot enters a cell, that cell's count is incremented
//! (leaving a trail). Around the robot, the sum of the counts (`mark_sum`)
//! measures the belief of being trapped; the least-visited direction gives a
//! temporary goal that leads away from where the robot has been.

use std::f64::consts::PI;

use robot::{Pose, Vec2};

/// Parameters of the spatial memory.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MemoryParams {
    /// Side of a memory cell, metres (≈ the robot's size). Default 0.3.
    pub cell_m: f64,
    /// Cells of the square grid on each side; the grid is centred on the
    /// start. Default 256 (77 m at 0.3 m).
    pub size: usize,
    /// Radius (cells) of the neighbourhood summed into `mark_sum`. Default 2.
    pub neighbourhood: i64,
    /// Directions examined for the temporary goal. Default 16.
    pub directions: usize,
    /// How far (cells) each direction is examined. Default 4.
    pub reach: i64,
}

impl Default for MemoryParams {
    fn default() -> Self {
        MemoryParams {
            cell_m: 0.3,
            size: 256,
            neighbourhood: 2,
            directions: 16,
            reach: 4,
        }
    }
}

/// The grid of visit counts.
#[derive(Debug, Clone)]
pub struct SpatialMemory {
    p: MemoryParams,
    counts: Vec<u32>,
    origin: Vec2,
    last: Option<(i64, i64)>,
}

impl SpatialMemory {
    /// An empty memory centred on `start`.
    pub fn new(p: MemoryParams, start: Vec2) -> SpatialMemory {
        SpatialMemory {
            p,
            counts: vec![0; p.size * p.size],
            origin: start,
            last: None,
        }
    }

    fn cell(&self, at: Vec2) -> (i64, i64) {
        let half = (self.p.size / 2) as f64;
        (
            ((at.x - self.origin.x) / self.p.cell_m + half).floor() as i64,
            ((at.y - self.origin.y) / self.p.cell_m + half).floor() as i64,
        )
    }

    fn count(&self, (i, j): (i64, i64)) -> u32 {
        let n = self.p.size as i64;
        if (0..n).contains(&i) && (0..n).contains(&j) {
            self.counts[(j * n + i) as usize]
        } else {
            0
        }
    }

    /// Records the robot at `at`: increments the count of the cell it has
    /// just entered (nothing if it is still in the same cell).
    pub fn visit(&mut self, at: Vec2) {
        let c = self.cell(at);
        if self.last == Some(c) {
            return;
        }
        self.last = Some(c);
        let n = self.p.size as i64;
        if (0..n).contains(&c.0) && (0..n).contains(&c.1) {
            self.counts[(c.1 * n + c.0) as usize] += 1;
        }
    }

    /// Sum of the visit counts in the neighbourhood of `at`.
    pub fn mark_sum(&self, at: Vec2) -> u32 {
        let (ci, cj) = self.cell(at);
        let r = self.p.neighbourhood;
        let mut sum = 0;
        for j in cj - r..=cj + r {
            for i in ci - r..=ci + r {
                sum += self.count((i, j));
            }
        }
        sum
    }

    /// Bearing (relative to the robot's heading) of the least-visited
    /// direction around `pose`; ties go to the direction nearest
    /// `preferred_rad` (the goal's bearing), then to the first examined.
    pub fn freest_bearing(&self, pose: &Pose, preferred_rad: f64) -> f64 {
        let k = self.p.directions.max(1);
        let mut best: Option<(u32, f64, f64)> = None;
        for d in 0..k {
            let rel = robot::wrap_angle(-PI + 2.0 * PI * d as f64 / k as f64);
            let a = pose.theta_rad + rel;
            let (s, c) = a.sin_cos();
            let mut visits = 0;
            for step in 1..=self.p.reach {
                let at = Vec2::new(
                    pose.x_m + c * step as f64 * self.p.cell_m,
                    pose.y_m + s * step as f64 * self.p.cell_m,
                );
                visits += self.count(self.cell(at));
            }
            let off = robot::wrap_angle(rel - preferred_rad).abs();
            let better = match best {
                None => true,
                Some((v, o, _)) => visits < v || (visits == v && off < o),
            };
            if better {
                best = Some((visits, off, rel));
            }
        }
        best.map_or(0.0, |b| b.2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trail_and_mark_sum() {
        let mut m = SpatialMemory::new(MemoryParams::default(), Vec2::new(0.0, 0.0));
        for k in 0..10 {
            m.visit(Vec2::new(0.01 * k as f64, 0.0)); // same cell: counted once
        }
        assert_eq!(m.mark_sum(Vec2::new(0.0, 0.0)), 1);
        // Go back and forth between two cells: every entry counts.
        for _ in 0..5 {
            m.visit(Vec2::new(0.35, 0.0));
            m.visit(Vec2::new(0.05, 0.0));
        }
        assert_eq!(m.mark_sum(Vec2::new(0.0, 0.0)), 11);
    }

    #[test]
    fn the_freest_direction_leads_away_from_the_trail() {
        let mut m = SpatialMemory::new(MemoryParams::default(), Vec2::new(0.0, 0.0));
        // A trail east of the robot, walked many times.
        for _ in 0..5 {
            for k in 0..8 {
                m.visit(Vec2::new(0.3 * k as f64 + 0.15, 0.15));
            }
            m.visit(Vec2::new(-5.0, -5.0));
        }
        let pose = Pose::new(0.15, 0.15, 0.0);
        // The goal is east too: the nearest unvisited direction is 45° off.
        let b = m.freest_bearing(&pose, 0.0);
        assert!(
            (b.abs() - std::f64::consts::FRAC_PI_4).abs() < 1e-9,
            "should leave the trail: {b}"
        );
        // Without a trail the goal's direction wins.
        let fresh = SpatialMemory::new(MemoryParams::default(), Vec2::new(0.0, 0.0));
        assert_eq!(fresh.freest_bearing(&pose, 0.0), 0.0);
    }
}
