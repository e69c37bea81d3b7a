//! Random topological maps shaped like those of an office floor, for
//! tests, benchmarks and demonstrations.
//!
//! Places sit on a square grid 2.5 m apart (jittered by up to ±0.5 m), as
//! reference places do along corridors and in rooms; transitions join near
//! neighbours (at most two grid steps apart), so the net is planar-ish and
//! its routes take many transitions, like a real map's. Every place can
//! reach every other: a random spanning tree of grid neighbours is laid down
//! in both directions first, then the other transitions join random near
//! neighbours one way.
//!
//! The rest follows the map's rules: wall following never leaves a type (c)
//! place; the exit turn is right at type (a), left at type (b), either at
//! type (c); the duration is the distance over a strategy's speed (free
//! movement 0.4 m/s, wall following 0.25 m/s, detour 0.3 m/s, times
//! 0.9…1.3); the cost is [`cost_of`](super::cost_of). One transition in ten has failed
//! `k` times (`k` in 1…40) and carries the threshold `½^k` of the default
//! [`ThresholdParams`](super::ThresholdParams), so some are rejected.
//!
//! Deterministic: the same arguments give the same map (ChaCha8 seeded).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::TopoError;
use super::fpn::{FuzzyPetriNet, Place, PlaceId, PlaceKind, Strategy, Transition, Turn};

/// Largest number of places [`random_office_like`] makes.
pub const MAX_PLACES: usize = 1_000_000;
/// Largest number of transitions [`random_office_like`] makes.
pub const MAX_TRANSITIONS: usize = 10_000_000;

/// Distance between neighbouring places on the grid, metres.
pub const SPACING_M: f64 = 2.5;

/// A random office-like map of `n_places` places and `n_transitions`
/// transitions (see the module documentation). Needs `1 ≤ n_places ≤`
/// [`MAX_PLACES`] and `2 (n_places − 1) ≤ n_transitions ≤`
/// [`MAX_TRANSITIONS`] (the spanning tree both ways). A single place gets
/// self-loops. `O(n_places + n_transitions)`.
pub fn random_office_like(
    n_places: usize,
    n_transitions: usize,
    seed: u64,
) -> Result<FuzzyPetriNet, TopoError> {
    if !(1..=MAX_PLACES).contains(&n_places) {
        return Err(TopoError::BadParam {
            name: "number of places",
            value: n_places as f64,
            expected: "between 1 and 1000000",
        });
    }
    let tree = 2 * (n_places - 1);
    if n_transitions < tree || n_transitions > MAX_TRANSITIONS {
        return Err(TopoError::BadParam {
            name: "number of transitions",
            value: n_transitions as f64,
            expected: "at least 2 (places − 1), to join every place both ways, and at most 10000000",
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let width = (n_places as f64).sqrt().ceil() as usize;
    let mut net = FuzzyPetriNet::new();
    for k in 0..n_places {
        let (col, row) = ((k % width) as f64, (k / width) as f64);
        let mut place = Place::new(
            col * SPACING_M + rng.random_range(-0.5..0.5),
            row * SPACING_M + rng.random_range(-0.5..0.5),
            rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
            match rng.random_range(0..3) {
                0 => PlaceKind::A,
                1 => PlaceKind::B,
                _ => PlaceKind::C,
            },
        );
        place.concave = rng.random_bool(0.25);
        place.visits = rng.random_range(1..=5);
        net.add_place(place)?;
    }
    let mut edges: Vec<(usize, usize)> = Vec::with_capacity(n_transitions);
    for k in 1..n_places {
        let left = (k % width != 0).then(|| k - 1);
        let up = (k >= width).then(|| k - width);
        let parent = match (left, up) {
            (Some(l), Some(u)) => {
                if rng.random_bool(0.5) {
                    l
                } else {
                    u
                }
            }
            (Some(l), None) => l,
            (None, Some(u)) => u,
            (None, None) => unreachable!("every place but the first has a left or upper neighbour"),
        };
        edges.push((k, parent));
        edges.push((parent, k));
    }
    while edges.len() < n_transitions {
        let a = rng.random_range(0..n_places);
        if n_places == 1 {
            edges.push((a, a));
            continue;
        }
        let (dx, dy) = (rng.random_range(-2i64..=2), rng.random_range(-2i64..=2));
        let (col, row) = ((a % width) as i64 + dx, (a / width) as i64 + dy);
        if (dx, dy) == (0, 0) || col < 0 || row < 0 || col >= width as i64 {
            continue;
        }
        let b = row as usize * width + col as usize;
        if b < n_places {
            edges.push((a, b));
        }
    }
    for (a, b) in edges {
        let origin = net.place(PlaceId(a as u32));
        let kind = origin.kind;
        let (ax, ay) = (origin.x_m, origin.y_m);
        let dest = net.place(PlaceId(b as u32));
        let distance = (dest.x_m - ax).hypot(dest.y_m - ay);
        let strategy = if kind == PlaceKind::C {
            [
                Strategy::FreeMovement,
                Strategy::DetourLeft,
                Strategy::DetourRight,
            ][rng.random_range(0..3)]
        } else {
            Strategy::ALL[rng.random_range(0..Strategy::ALL.len())]
        };
        let exit_turn = match kind {
            PlaceKind::A => Turn::Right,
            PlaceKind::B => Turn::Left,
            PlaceKind::C => {
                if rng.random_bool(0.5) {
                    Turn::Left
                } else {
                    Turn::Right
                }
            }
        };
        let speed = match strategy {
            Strategy::FreeMovement => 0.4,
            Strategy::WallFollowLeft | Strategy::WallFollowRight => 0.25,
            Strategy::DetourLeft | Strategy::DetourRight => 0.3,
        };
        let duration_s = distance / speed * rng.random_range(0.9..1.3);
        // The default cost, `cost_of(duration_s, strategy)`.
        let mut t = Transition::new(
            PlaceId(a as u32),
            PlaceId(b as u32),
            strategy,
            exit_turn,
            duration_s,
        );
        t.attempts = rng.random_range(0..5);
        if rng.random_bool(0.1) {
            let k = rng.random_range(1..=40);
            t.failures = k;
            t.attempts += k;
            t.lambda = 0.5f64.powi(k as i32);
        }
        net.add_transition(t)?;
    }
    Ok(net)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{PlanMode, Planner};

    #[test]
    fn sizes_seeds_and_connectivity() {
        let net = random_office_like(50, 200, 7).unwrap();
        assert_eq!((net.num_places(), net.num_transitions()), (50, 200));
        assert_eq!(net, random_office_like(50, 200, 7).unwrap());
        assert_ne!(net, random_office_like(50, 200, 8).unwrap());
        // With every threshold at 1, every place reaches every other.
        let mut open = net.clone();
        for t in net.transition_ids() {
            open.set_lambda(t, 1.0).unwrap();
        }
        let planner = Planner::new(&open);
        for goal in [PlaceId(0), PlaceId(23), PlaceId(49)] {
            let p = planner.plan(PlaceId(17), &[goal], PlanMode::Optimal).unwrap();
            assert!(p.reached.iter().all(|&r| r));
        }
        for t in net.transitions() {
            assert!(net.place(t.from).kind.allows(t.strategy));
            let (a, b) = (net.place(t.from), net.place(t.to));
            assert!((a.x_m - b.x_m).abs() <= 3.0 * SPACING_M && (a.y_m - b.y_m).abs() <= 3.0 * SPACING_M);
        }
    }

    #[test]
    fn bad_sizes_are_errors() {
        assert!(random_office_like(0, 0, 1).is_err());
        assert!(random_office_like(10, 17, 1).is_err());
        assert!(random_office_like(10, 18, 1).is_ok());
        let single = random_office_like(1, 3, 1).unwrap();
        assert!(single.transitions().iter().all(|t| t.from == t.to));
        let two = random_office_like(2, 9, 1).unwrap();
        assert_eq!(two.num_transitions(), 9);
    }
}
