//! The intrinsic cost model of the planner's cost maps: its parameters
//! ([`CostParams`]) and the cost of a cell by its distance to the nearest
//! obstacle, tabled by squared distance in cells — shared by the window's
//! cost map ([`super::cost_map`], where the model is described) and the
//! map's precomputed static layer ([`super::static_layer`]).

use super::PlanningError;
use super::distance_transform::MAX_CAP;

/// Parameters of the cost map.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CostParams {
    /// Radius of the robot's footprint disc, metres: cells whose centre is
    /// within this distance of an obstacle cell's centre are lethal.
    /// Default 0.35 (the Jinny-like tour-guide robot).
    pub inscribed_radius_m: f64,
    /// Distance from an obstacle at which the intrinsic cost falls to 0,
    /// metres; `≥ inscribed_radius_m`. Default 1.0.
    pub inflation_radius_m: f64,
    /// Intrinsic cost just outside the inscribed radius, dimensionless
    /// (a multiplier on distance, minus one), in [0, 1000]. 0 turns the
    /// inflation off. Default 5.
    pub max_cost: f64,
    /// Exponential decay rate of the intrinsic cost with distance, 1/m.
    /// Default 10 (the cost falls by e every 0.1 m; costmap_2d's default
    /// `cost_scaling_factor`).
    pub decay_per_m: f64,
}

impl Default for CostParams {
    fn default() -> Self {
        CostParams {
            inscribed_radius_m: 0.35,
            inflation_radius_m: 1.0,
            max_cost: 5.0,
            decay_per_m: 10.0,
        }
    }
}

/// Largest `max_cost` accepted: far beyond any useful value, and it bounds
/// the navigation function's bucket ring (`√2 · (1 + max_cost)` buckets).
pub const MAX_INTRINSIC_COST: f64 = 1000.0;

impl CostParams {
    /// Checks every field: finite, `≥ 0`, `max_cost ≤` [`MAX_INTRINSIC_COST`]
    /// and `inflation_radius_m ≥ inscribed_radius_m`.
    pub fn validate(&self) -> Result<(), PlanningError> {
        let non_negative = |name: &'static str, value: f64| {
            if value.is_finite() && value >= 0.0 {
                Ok(())
            } else {
                Err(PlanningError::BadParam {
                    name,
                    value,
                    expected: "a finite number ≥ 0",
                })
            }
        };
        non_negative("inscribed_radius_m", self.inscribed_radius_m)?;
        non_negative("inflation_radius_m", self.inflation_radius_m)?;
        non_negative("max_cost", self.max_cost)?;
        if self.max_cost > MAX_INTRINSIC_COST {
            return Err(PlanningError::BadParam {
                name: "max_cost",
                value: self.max_cost,
                expected: "at most 1000",
            });
        }
        non_negative("decay_per_m", self.decay_per_m)?;
        if self.inflation_radius_m < self.inscribed_radius_m {
            return Err(PlanningError::BadParam {
                name: "inflation_radius_m",
                value: self.inflation_radius_m,
                expected: "a distance ≥ inscribed_radius_m",
            });
        }
        Ok(())
    }

    /// The intrinsic cost at distance `d_m` from the nearest obstacle
    /// ([`super::cost_map`]'s module docs): `∞` within the inscribed
    /// radius. (The cost map
    /// compares distances with the radii in cells with a tolerance of 1e-9
    /// cell, so that a radius of exactly `k` cells includes distance `k`
    /// despite rounding; and it makes its table of costs by distance
    /// non-increasing — a running minimum, which leaves the formula's values
    /// as they are as long as `exp` is monotone — so that the nearest
    /// obstacle always gives the largest cost.)
    pub fn cost_at(&self, d_m: f64) -> f64 {
        if d_m <= self.inscribed_radius_m {
            f64::INFINITY
        } else if d_m <= self.inflation_radius_m {
            self.max_cost * (-self.decay_per_m * (d_m - self.inscribed_radius_m)).exp()
        } else {
            0.0
        }
    }
}

/// The inflation margin in cells, `⌈inflation_radius_m / res⌉`: the cap of
/// the distances (errors beyond [`MAX_CAP`]).
pub(crate) fn margin_cells(params: &CostParams, res: f64) -> Result<u32, PlanningError> {
    let cap_f = (params.inflation_radius_m / res).ceil();
    if cap_f > MAX_CAP as f64 {
        return Err(PlanningError::BadParam {
            name: "inflation_radius_m",
            value: params.inflation_radius_m,
            expected: "at most 30 000 cells of the map",
        });
    }
    Ok(cap_f as u32)
}

/// Costs by squared distance in cells, `0..=cap²`, non-increasing.
pub(crate) fn cost_table(p: &CostParams, res: f64, cap: u32) -> Vec<f64> {
    let n = (cap as usize + 1).pow(2);
    // Both radii are inclusive, compared in cells with a tolerance of
    // 1e-9 cell: 0.35 m at 0.05 m (7 cells, 6.999… in floating point)
    // stays lethal.
    let inscribed_cells = p.inscribed_radius_m / res + 1e-9;
    let inflation_cells = p.inflation_radius_m / res + 1e-9;
    let mut lowest = f64::INFINITY;
    (0..n)
        .map(|d2| {
            let d = (d2 as f64).sqrt();
            let c = if d <= inscribed_cells {
                f64::INFINITY
            } else if d <= inflation_cells {
                p.max_cost * (-p.decay_per_m * (d * res - p.inscribed_radius_m)).exp()
            } else {
                0.0
            };
            // Non-increasing, so that min(d₁, d₂) costs max(c(d₁), c(d₂)).
            lowest = lowest.min(c);
            lowest
        })
        .collect()
}
