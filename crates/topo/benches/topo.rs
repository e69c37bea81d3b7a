//! Route planning on a large topological map: a random office-like FPN of
//! 10 000 places and 40 000 transitions ([`random_office_like`], seed 1; a
//! 100 × 100 grid of places 2.5 m apart, about 4 000 transitions with a
//! threshold lowered by failures).
//!
//! Each iteration plans one of 16 fixed routes, taken in turn: 8 between
//! random places, 4 across the floor (corner to opposite corner, both ways,
//! and edge to edge), 4 towards three goals at once. All have a route.
//!
//! * `planner_new`: laying the net out for planning ([`Planner::new`]: `C`,
//!   `λ` and the transitions entering each place in compressed rows), once
//!   per map version;
//! * `optimal`: [`Planner::plan`] in optimal mode (the label-setting search
//!   over the whole map, its `f` for every transition, the route);
//!   **target ≤ 5 ms**;
//! * `optimal_values`: the search alone ([`Planner::label_setting`]);
//! * `optimal_from_scratch`: [`plan`], which lays the net out first;
//! * `paper`: [`Planner::plan`] in paper mode (synchronous rounds over all
//!   transitions until the start has a value: as many rounds as the route's
//!   fewest transitions, up to about 100 across this floor);
//! * `literal_fixed_point`: the literal rounds to the fixed point
//!   ([`Planner::propagate_literal`], [`Stop::FixedPoint`]), what optimal
//!   mode would cost without the search.
//!
//! Run with `cargo bench -p topo --bench topo`. Figures in
//! `crates/topo/BENCHMARKS.md`.

use std::sync::LazyLock;

use divan::Bencher;
use topo::{FuzzyPetriNet, PlaceId, PlanMode, Planner, Stop, plan, random_office_like};

#[global_allocator]
static ALLOC: divan::AllocProfiler = divan::AllocProfiler::system();

fn main() {
    divan::main();
}

const PLACES: usize = 10_000;
const TRANSITIONS: usize = 40_000;

static MAP: LazyLock<FuzzyPetriNet> =
    LazyLock::new(|| random_office_like(PLACES, TRANSITIONS, 1).expect("valid sizes"));

/// The 16 routes: `(start, goals)`.
static ROUTES: LazyLock<Vec<(PlaceId, Vec<PlaceId>)>> = LazyLock::new(|| {
    let side = (PLACES as f64).sqrt() as u32;
    let corner = |col: u32, row: u32| PlaceId(row * side + col);
    let last = side - 1;
    let mut routes = vec![
        (corner(0, 0), vec![corner(last, last)]),
        (corner(last, last), vec![corner(0, 0)]),
        (corner(last, 0), vec![corner(0, last)]),
        (corner(0, side / 2), vec![corner(last, side / 2)]),
    ];
    // A fixed xorshift: the same places every run.
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        PlaceId((s % PLACES as u64) as u32)
    };
    let planner = Planner::new(&MAP);
    while routes.len() < 16 {
        let start = next();
        let goals: Vec<PlaceId> = if routes.len() < 12 {
            vec![next()]
        } else {
            vec![next(), next(), next()]
        };
        if planner.plan(start, &goals, PlanMode::Optimal).is_ok() {
            routes.push((start, goals));
        }
    }
    for (s, g) in &routes {
        planner
            .plan(*s, g, PlanMode::Optimal)
            .expect("every benchmark route exists");
    }
    routes
});

/// Calls `f` with the routes in turn.
fn each_route<T>(b: Bencher, mut f: impl FnMut(PlaceId, &[PlaceId]) -> T) {
    let routes = &*ROUTES;
    let mut k = 0;
    b.bench_local(|| {
        let (s, g) = &routes[k % routes.len()];
        k += 1;
        f(*s, g)
    });
}

#[divan::bench]
fn planner_new(b: Bencher) {
    let map = &*MAP;
    b.bench_local(|| Planner::new(divan::black_box(map)));
}

#[divan::bench]
fn optimal(b: Bencher) {
    let planner = Planner::new(&MAP);
    each_route(b, |s, g| planner.plan(s, g, PlanMode::Optimal).unwrap());
}

#[divan::bench]
fn optimal_values(b: Bencher) {
    let planner = Planner::new(&MAP);
    each_route(b, |_, g| planner.label_setting(g).unwrap());
}

#[divan::bench]
fn optimal_from_scratch(b: Bencher) {
    let map = &*MAP;
    each_route(b, |s, g| plan(map, s, g, PlanMode::Optimal).unwrap());
}

#[divan::bench]
fn paper(b: Bencher) {
    let planner = Planner::new(&MAP);
    each_route(b, |s, g| planner.plan(s, g, PlanMode::Paper).unwrap());
}

#[divan::bench(sample_count = 20)]
fn literal_fixed_point(b: Bencher) {
    let planner = Planner::new(&MAP);
    each_route(b, |_, g| planner.propagate_literal(g, Stop::FixedPoint).unwrap());
}
