//! The navigation function: cost-weighted distance to the goal from every
//! cell of a window.
//!
//! K. Konolige, *A gradient method for realtime robot control*, IROS 2000:
//! a wavefront propagated from the goal over the cost map gives, for every
//! cell, the least cost `N(cell)` of a path from it to the goal; the robot
//! then follows `−∇N` ([`super::gradient`]). ROS `navfn` and
//! `global_planner` implement the same idea.
//!
//! Here the wavefront is **Dijkstra's algorithm on the 8-connected grid**
//! of the window:
//!
//! * moving between the centres of neighbouring cells `a` and `b` costs
//!   `ℓ · (1 + (c(a) + c(b)) / 2)` with `ℓ` the distance between the
//!   centres (the resolution, or √2 times it diagonally) and `c` the
//!   intrinsic costs of [`super::cost_map`]: the trapezoid rule for
//!   `∫ (1 + c) ds`, so the cost is symmetric and, with zero intrinsic
//!   cost, `N` is the length in metres of the shortest 8-connected path;
//! * lethal cells (`c = ∞`) are never entered, nor are cells outside the
//!   window;
//! * a diagonal move is allowed only when both cells it cuts past are not
//!   lethal (no corner cutting), so the straight segment between the two
//!   centres never crosses a lethal cell;
//! * goal cells have `N = 0`; unreachable and lethal cells `N = ∞`.
//!
//! Plain Dijkstra on 8 neighbours rather than navfn's 4-neighbour update
//! with quadratic interpolation (an approximation of the Eikonal equation):
//! the values are then exactly shortest-path costs on a graph, testable
//! against an independent Dijkstra. The price is the 8-connected metric,
//! which overestimates straight-line distance by up to 8 % (at 22.5°); the
//! gradient follower cuts the staircase, so the paths are not longer for it
//! (on the real maps the routes are within −4 % to +8 % of the shortest
//! grid path).
//!
//! The queue is a ring of buckets as wide as the lightest edge (the
//! resolution), in which every entry of the lowest bucket is final
//! (`bucket_queue.rs`, Dial's algorithm for real weights): time
//! `O(n + N_max / resolution)` for `n` cells reached, memory `O(n)`; the
//! buffers are kept from one computation to the next. Measured with
//! cachegrind on the 10 m windows and global routes of `building_31`: 300
//! instructions per cell reached with this queue (and the eight
//! relaxations inlined), against 550 with a binary heap of `(value, cell)`
//! pairs with lazy deletion — 1.5× faster on the windows and 2–3× on
//! `levine`'s whole map in wall-clock time; a radix heap on the values' bit
//! patterns executed 1.7× as many instructions as the binary heap.
//!
//! # Computed towards a start
//!
//! A control cycle needs `N` only where the descent from the robot reads it
//! (a few cells around the path), not over the whole window.
//! [`NavigationFunction::compute_towards`] runs the same wavefront as `A*`
//! (P. Hart, N. Nilsson, B. Raphael, *A formal basis for the heuristic
//! determination of minimum cost paths*, IEEE SSC 4, 1968) aimed at the
//! start: the queue's keys are `N + h` with `h(c)` the octile distance from
//! `c` to the start in metres, a lower bound on the cost of any path between
//! them (every move costs at least its length) that changes by at most a
//! move's length from a cell to its neighbour (it is *consistent*). It stops
//! once the start's value is final, and
//! [`super::descend_settling`] resumes it whenever the descent reads a value
//! that is not final yet ([`NavigationFunction::complete`] runs it to the
//! end).
//!
//! **Which values are final.** With buckets `Δ` wide, when the queue is
//! emptying bucket `k`, every cell `c` whose final key `N(c) + h(c)` is below
//! `(k − 1)·Δ` has its final value: along a cheapest path from the goal to
//! `c` the final keys never decrease (consistency), so every cell of it was
//! in a bucket already emptied when it got its final value, and was then
//! processed and relaxed the next one. A cell's current key is never below
//! its final one, so a value with a current key below `(k − 1)·Δ` is final
//! (the spare bucket absorbs rounding, ~1e-13 relative); lethal cells are
//! final (`∞`) from the start. The values of a computation's cells are
//! unique — each is the least, over the paths from a goal cell, of the
//! costs summed in floating point along the path, whatever the order of
//! the relaxations — so every final value is bit for bit the one
//! [`NavigationFunction::compute`] gives, and a descent that reads only
//! final values follows the same path.
//!
//! Within a bucket the order is arbitrary, and `A*`'s moves towards the
//! start keep the key (a move's cost minus the same drop of `h`), so a cell
//! can be processed before its value is final; it is re-opened when it
//! improves (the same mechanism as for rounding slips above). Narrower
//! buckets, `resolution / 8`, make that rare: on the 53 cycles of the
//! planning benchmark, 1.8 pushes per cell reached with them against 3.1
//! with buckets one resolution wide (1.34 for the whole window's Dijkstra).
//! The descent then settles 44 800 cells over the 53 cycles where the whole
//! windows hold 1 006 000 (22× fewer), for the same paths.
//!
//! **Path blocking.** When the start is cut off from the goal (people all
//! round the robot, or across a corridor), `A*` finds out only once it has
//! settled everything the goal reaches. So the computation towards a start
//! also floods from the start over the passable cells, with the wavefront's
//! moves (8 neighbours, no corner cutting): 4 cells every time the wavefront
//! has popped 16 entries. As soon as the flood meets a cell the wavefront
//! reached, it stops: the two are connected. If it runs out of cells first,
//! the start's component does not hold the goal (the goal's cell is reached
//! from the start, the flood would have met it): each of its cells has
//! `N = ∞` in the whole computation too, final, and the descent says
//! [`PlanningError::Unreachable`] at once. With a ring of people 1 m round
//! the robot, a cycle of the planning benchmark costs 3.2× fewer
//! instructions for it; an ordinary cycle about 5 % more.

use robot::{CellIndex, Vec2};

use super::bucket_queue::BucketQueue;
use super::{CostMap, PlanningError, Window};

/// What a computation did.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct NavigationInfo {
    /// Cells with a finite value (goal cells included); computed towards a
    /// start, the cells reached so far.
    pub reached_cells: usize,
    /// Entries pushed on the queue.
    pub pushes: usize,
    /// Largest finite value a cell was processed with: the largest finite
    /// `N` of the whole window. (Computed towards a start, a cell may be
    /// processed before its value is final, with a value less than one
    /// resolution above it: this is then an upper bound, that close, of the
    /// largest `N` reached.)
    pub max_value: f64,
}

/// Buckets per resolution towards a start.
const BUCKETS_PER_CELL: f64 = 8.0;

/// The flood from the start (module docs, *Path blocking*) visits
/// `FLOOD_CELLS` cells every time the wavefront has popped `FLOOD_POPS`
/// entries.
const FLOOD_POPS: usize = 16;
const FLOOD_CELLS: usize = 4;

/// The value of a cell that is not lethal and not reached (yet): larger
/// than any path's cost, and unlike `∞` telling it from a lethal cell.
const UNREACHED: f64 = f64::MAX;

/// The navigation function of a window (module docs); a reusable buffer.
#[derive(Debug, Clone, Default)]
pub struct NavigationFunction {
    window: Option<Window>,
    /// Values of the window plus a ring of `∞`, laid out as
    /// [`CostMap::padded_costs`]; lethal cells `∞`, cells not reached
    /// [`UNREACHED`]. Meaningless without goal cells.
    values: Vec<f64>,
    goal: Option<Vec2>,
    goal_cells: Vec<CellIndex>,
    info: NavigationInfo,
    queue: BucketQueue,
    /// Per padded cell: processed with its current value.
    done: Vec<bool>,
    /// Computed towards a start: its padded coordinates, the target of the
    /// heuristic.
    towards: Option<(usize, usize)>,
    /// Cells may be left to settle (the queue is not empty).
    partial: bool,
    /// Width of the queue's buckets, cost-weighted metres.
    bucket_m: f64,
    /// The flood from the start (padded cells, in the order visited), and
    /// per padded cell whether it has been visited (all false between
    /// computations).
    flood: Vec<u32>,
    flooded: Vec<bool>,
    /// Tests only: a ring of buckets too small, so that entries land too
    /// early and the re-opening of cells has to correct them.
    #[cfg(test)]
    tiny_ring: bool,
}

impl NavigationFunction {
    /// An empty navigation function (no goal: every value is `∞`).
    pub fn new() -> NavigationFunction {
        NavigationFunction::default()
    }

    /// Computes `N` over the cost map's window towards the goal point
    /// `goal` (world frame; its cell gets `N = 0`).
    ///
    /// Errors: [`PlanningError::NoFreeCell`] if the window has no free cell,
    /// [`PlanningError::BadPoint`] for a non-finite goal,
    /// [`PlanningError::GoalOutsideWindow`], [`PlanningError::GoalBlocked`]
    /// (the goal's cell is lethal — an obstacle of the map, unknown, seen by
    /// the sensors, or too close to one). On error the function is left
    /// empty (every value `∞`).
    pub fn compute(&mut self, cost: &CostMap, goal: Vec2) -> Result<NavigationInfo, PlanningError> {
        let cell = self.check(cost, goal)?;
        self.goal = Some(goal);
        self.begin(cost, &[cell], None)?;
        self.run::<false>(cost.padded_costs(), None, usize::MAX);
        Ok(self.info)
    }

    /// Starts computing `N` towards `goal` as [`NavigationFunction::compute`]
    /// does, but settles only what the descent from `start` needs first
    /// (module docs, *Computed towards a start*): the start's cell, then
    /// more as [`super::descend_settling`] reads them, or everything with
    /// [`NavigationFunction::complete`]. Every settled value is the one
    /// [`NavigationFunction::compute`] gives, bit for bit.
    ///
    /// Errors: those of [`NavigationFunction::compute`], checked first, then
    /// [`PlanningError::BadPoint`] for a non-finite start and
    /// [`PlanningError::StartOutsideWindow`]. On error the function is left
    /// empty.
    pub fn compute_towards(
        &mut self,
        cost: &CostMap,
        goal: Vec2,
        start: Vec2,
    ) -> Result<NavigationInfo, PlanningError> {
        let cell = self.check(cost, goal)?;
        let window = cost.window();
        let s = window.cell_of("start", start)?;
        let Some(k) = window.index_of(s) else {
            return Err(PlanningError::StartOutsideWindow { start, cell: s });
        };
        self.goal = Some(goal);
        let (u, v) = (k % window.width() + 1, k / window.width() + 1);
        self.begin(cost, &[cell], Some((u, v)))?;
        self.settle_start(cost.padded_costs(), u, v);
        Ok(self.info)
    }

    /// Computes `N` towards a set of goal cells (each gets `N = 0`). Errors
    /// as [`NavigationFunction::compute`], with the goal cells' centres as
    /// goal points, and [`PlanningError::NoGoal`] for an empty set.
    pub fn compute_from_cells(
        &mut self,
        cost: &CostMap,
        goals: &[CellIndex],
    ) -> Result<NavigationInfo, PlanningError> {
        let window = cost.window();
        self.clear(window);
        if cost.info().free_cells == 0 {
            return Err(PlanningError::NoFreeCell { window });
        }
        if goals.is_empty() {
            return Err(PlanningError::NoGoal);
        }
        for &c in goals {
            check_goal(cost, window.cell_center(c), c)?;
        }
        self.begin(cost, goals, None)?;
        self.run::<false>(cost.padded_costs(), None, usize::MAX);
        Ok(self.info)
    }

    /// Settles every cell a computation towards a start left (nothing to do
    /// for a complete function): `N` is then that of
    /// [`NavigationFunction::compute`]. `cost` must be the cost map the
    /// function was computed on, unchanged.
    ///
    /// Errors: [`PlanningError::OtherCostMap`] for a cost map of another
    /// window.
    pub fn complete(&mut self, cost: &CostMap) -> Result<NavigationInfo, PlanningError> {
        if self.partial {
            if self.window != Some(cost.window()) {
                return Err(PlanningError::OtherCostMap);
            }
            self.run::<true>(cost.padded_costs(), None, usize::MAX);
        }
        Ok(self.info)
    }

    /// Whether every value is final (always, but for a computation towards
    /// a start not completed).
    pub fn is_complete(&self) -> bool {
        !self.partial
    }

    /// Whether `N` of a map cell is final (for a complete function: always).
    pub fn is_settled(&self, c: CellIndex) -> bool {
        let Some(window) = self.window else {
            return true;
        };
        match window.index_of(c) {
            Some(k) => {
                let (u, v) = (k % window.width() + 1, k / window.width() + 1);
                self.settled(u, v)
            }
            None => true,
        }
    }

    /// Forgets everything (no window, no goal: every value `∞`), keeping
    /// the memory.
    pub(crate) fn forget(&mut self) {
        self.window = None;
        self.goal = None;
        self.goal_cells.clear();
        self.info = NavigationInfo::default();
        self.towards = None;
        self.partial = false;
    }

    /// Forgets the goal, checks the cost map and the goal; the goal's cell.
    fn check(&mut self, cost: &CostMap, goal: Vec2) -> Result<CellIndex, PlanningError> {
        self.clear(cost.window());
        let window = cost.window();
        if cost.info().free_cells == 0 {
            return Err(PlanningError::NoFreeCell { window });
        }
        let cell = window.cell_of("goal", goal)?;
        check_goal(cost, goal, cell)?;
        Ok(cell)
    }

    /// Forgets the goal (every value is then `∞`), adopts `window`.
    fn clear(&mut self, window: Window) {
        self.window = Some(window);
        self.goal = None;
        self.goal_cells.clear();
        self.info = NavigationInfo::default();
        self.towards = None;
        self.partial = false;
    }

    /// Seeds the wavefront with `goals` (checked: in the window, not
    /// lethal), towards a target cell (padded coordinates) or none.
    fn begin(
        &mut self,
        cost: &CostMap,
        goals: &[CellIndex],
        towards: Option<(usize, usize)>,
    ) -> Result<(), PlanningError> {
        let window = cost.window();
        let pw = window.width() + 2;
        // Lethal cells (and the padding ring) are never entered: their `∞`
        // is final; the others start unreached. (`fill` and the loop are
        // vectorised, `resize` alone writes one value at a time.)
        let n = cost.padded_costs().len();
        self.values.resize(n, UNREACHED);
        for (v, &c) in self.values.iter_mut().zip(cost.padded_costs()) {
            *v = if c > UNREACHED { c } else { UNREACHED };
        }
        self.done.resize(n, false);
        self.done.fill(false);
        // The lightest edge weighs `res` (intrinsic costs are ≥ 0), the
        // heaviest `diag · (1 + max_cost)`; towards a target, a key (value
        // plus heuristic) grows by at most that and one diagonal more.
        let max_cost = cost.params().max_cost;
        #[allow(unused_mut)]
        let mut span = std::f64::consts::SQRT_2 * (1.0 + max_cost + f64::from(u8::from(towards.is_some())));
        #[cfg(test)]
        if self.tiny_ring {
            span = 0.0;
        }
        let per_cell = if towards.is_some() { BUCKETS_PER_CELL } else { 1.0 };
        self.bucket_m = window.resolution_m() / per_cell;
        self.queue.reset(self.bucket_m, span * per_cell);
        self.towards = towards;
        for &c in goals {
            let k = window.index_of(c).map(|k| padded(pw, window.width(), k)).ok_or(
                PlanningError::GoalOutsideWindow {
                    goal: window.cell_center(c),
                    cell: c,
                },
            )?;
            if self.values[k] != 0.0 {
                self.values[k] = 0.0;
                let key = self.heuristic(k % pw, k / pw);
                self.queue.push(key, k as u32);
                self.info.pushes += 1;
                self.info.reached_cells += 1;
            }
        }
        self.goal_cells.extend_from_slice(goals);
        self.partial = true;
        Ok(())
    }

    /// The heuristic at padded cell `(u, v)`: the octile distance to the
    /// target in metres (no path between the two can cost less), or 0.
    #[inline]
    fn heuristic(&self, u: usize, v: usize) -> f64 {
        match (self.towards, self.window) {
            (Some((tu, tv)), Some(w)) => octile(u.abs_diff(tu), v.abs_diff(tv), w.resolution_m()),
            _ => 0.0,
        }
    }

    /// Padded index of padded cell `(u, v)`.
    #[inline]
    fn index(&self, u: usize, v: usize) -> usize {
        v * self.window.map_or(0, |w| w.width() + 2) + u
    }

    /// Whether the value at padded cell `(u, v)` is final (module docs):
    /// the wavefront is done, the cell is lethal or outside (`∞`, never
    /// entered), or its value plus heuristic is a whole bucket below the one
    /// being emptied.
    #[inline]
    fn settled(&self, u: usize, v: usize) -> bool {
        if !self.partial {
            return true;
        }
        let n = self.values[self.index(u, v)];
        n == f64::INFINITY || n + self.heuristic(u, v) < (self.queue.current() as f64 - 1.0) * self.bucket_m
    }

    /// Runs the wavefront until the value at padded cell `(u, v)` is final.
    fn settle(&mut self, costs: &[f64], u: usize, v: usize) {
        if !self.settled(u, v) {
            let until = (self.index(u, v), self.heuristic(u, v));
            self.run::<true>(costs, Some(until), usize::MAX);
        }
    }

    /// [`NavigationFunction::settle`] for the start, padded cell `(u, v)`,
    /// with a flood from it interleaved (module docs, *Path blocking*):
    /// [`FLOOD_CELLS`] cells of the flood every [`FLOOD_POPS`] entries the
    /// wavefront pops. If the flood runs out of cells without meeting one the
    /// wavefront reached, the start is cut off from the goal, and so is
    /// everything the flood visited: `∞`, final.
    fn settle_start(&mut self, costs: &[f64], u: usize, v: usize) {
        let start = self.index(u, v);
        let until = (start, self.heuristic(u, v));
        // `flooded` is all false between calls: the marks of the cells
        // visited are taken back at the end.
        self.flood.clear();
        self.flooded.resize(costs.len(), false);
        if costs[start].is_finite() {
            self.flood.push(start as u32);
            self.flooded[start] = true;
        }
        let pw = self.window.map_or(0, |w| w.width() + 2);
        let mut next = 0;
        'flood: while !self.settled(u, v) {
            self.run::<true>(costs, Some(until), FLOOD_POPS);
            for _ in 0..FLOOD_CELLS {
                // One cell of the flood: its passable neighbours not flooded
                // yet (the wavefront's moves), unless it has been reached.
                let Some(&a) = self.flood.get(next) else {
                    // Out of cells without meeting the goal's (reached from
                    // the start): cut off.
                    for &c in &self.flood {
                        self.values[c as usize] = f64::INFINITY;
                        self.flooded[c as usize] = false;
                    }
                    return;
                };
                next += 1;
                let a = a as usize;
                if self.values[a] != UNREACHED {
                    break 'flood; // met the wavefront
                }
                let ok = |b: usize| costs[b].is_finite();
                let (r, l, up, d) = (ok(a + 1), ok(a - 1), ok(a + pw), ok(a - pw));
                let neighbours = [
                    (a + 1, r),
                    (a - 1, l),
                    (a + pw, up),
                    (a - pw, d),
                    (a + pw + 1, r && up && ok(a + pw + 1)),
                    (a + pw - 1, l && up && ok(a + pw - 1)),
                    (a - pw + 1, r && d && ok(a - pw + 1)),
                    (a - pw - 1, l && d && ok(a - pw - 1)),
                ];
                for (b, passable) in neighbours {
                    if passable && !self.flooded[b] {
                        self.flooded[b] = true;
                        self.flood.push(b as u32);
                    }
                }
            }
        }
        for &c in &self.flood {
            self.flooded[c as usize] = false;
        }
        self.settle(costs, u, v);
    }

    /// Dijkstra (`A*` with `HEURISTIC`, keys `N + h`) from the seeded
    /// goals, until the queue is empty or, with `HEURISTIC` and `until =
    /// Some((k, h))`, the value of padded cell `k` (heuristic `h`) is final;
    /// with `HEURISTIC`, at most `budget` entries are popped.
    fn run<const HEURISTIC: bool>(&mut self, costs: &[f64], until: Option<(usize, f64)>, mut budget: usize) {
        let Some(window) = self.window else { return };
        let pw = window.width() + 2;
        let res = window.resolution_m();
        let diag = res * std::f64::consts::SQRT_2;
        let (tu, tv) = self.towards.unwrap_or((0, 0));
        let heuristic = self.towards.is_some();
        let bucket_m = self.bucket_m;
        let values = &mut self.values;
        let done = &mut self.done;
        let queue = &mut self.queue;
        let NavigationInfo {
            mut reached_cells,
            mut pushes,
            mut max_value,
        } = self.info;
        loop {
            if HEURISTIC
                && let Some((k, h)) = until
                && values[k] + h < (queue.current() as f64 - 1.0) * bucket_m
            {
                break;
            }
            if HEURISTIC {
                if budget == 0 {
                    break;
                }
                budget -= 1;
            }
            let Some(a) = queue.pop() else {
                self.partial = false;
                break;
            };
            let a = a as usize;
            if done[a] {
                continue; // a stale entry: processed with a lower value
            }
            done[a] = true;
            let na = values[a];
            max_value = max_value.max(na);
            let ca = costs[a];
            let (au, av) = if HEURISTIC && heuristic {
                (a % pw, a / pw)
            } else {
                (0, 0)
            };
            // A macro rather than a closure: the eight relaxations inline.
            macro_rules! relax {
                ($b:expr, $l:expr, $du:expr, $dv:expr) => {{
                    let b: usize = $b;
                    let nb = na + $l * (1.0 + 0.5 * (ca + costs[b]));
                    if nb < values[b] {
                        reached_cells += usize::from(values[b] == UNREACHED);
                        values[b] = nb;
                        // Re-open a cell settled too early (after a rounding
                        // slip of the buckets, or towards a target when a
                        // bucket held a better path; see the module docs).
                        done[b] = false;
                        let key = if HEURISTIC && heuristic {
                            nb + octile(
                                (au as isize + $du).abs_diff(tu as isize),
                                (av as isize + $dv).abs_diff(tv as isize),
                                res,
                            )
                        } else {
                            nb
                        };
                        queue.push(key, b as u32);
                        pushes += 1;
                    }
                }};
            }
            // Orthogonal neighbours; the padding ring (∞) stops at the edge.
            let (right, left, up, down) = (a + 1, a - 1, a + pw, a - pw);
            let (r_ok, l_ok, u_ok, d_ok) = (
                costs[right].is_finite(),
                costs[left].is_finite(),
                costs[up].is_finite(),
                costs[down].is_finite(),
            );
            if r_ok {
                relax!(right, res, 1, 0);
            }
            if l_ok {
                relax!(left, res, -1, 0);
            }
            if u_ok {
                relax!(up, res, 0, 1);
            }
            if d_ok {
                relax!(down, res, 0, -1);
            }
            // Diagonals: both cells cut past must be passable; an infinite
            // target cost gives an infinite candidate, never stored.
            if r_ok && u_ok {
                relax!(up + 1, diag, 1, 1);
            }
            if l_ok && u_ok {
                relax!(up - 1, diag, -1, 1);
            }
            if r_ok && d_ok {
                relax!(down + 1, diag, 1, -1);
            }
            if l_ok && d_ok {
                relax!(down - 1, diag, -1, -1);
            }
        }
        self.info = NavigationInfo {
            reached_cells,
            pushes,
            max_value,
        };
    }

    /// The window, once computed.
    pub fn window(&self) -> Option<Window> {
        self.window
    }

    /// The goal point of [`NavigationFunction::compute`] (`None` for goal
    /// cells, or without a goal).
    pub fn goal(&self) -> Option<Vec2> {
        self.goal
    }

    /// The goal cells (empty without a goal).
    pub fn goal_cells(&self) -> &[CellIndex] {
        &self.goal_cells
    }

    /// What the last computation did.
    pub fn info(&self) -> NavigationInfo {
        self.info
    }

    /// `N` of a map cell, cost-weighted metres: `∞` if unreachable, lethal
    /// or outside the window — and, computed towards a start and not
    /// completed, for a cell not settled yet
    /// ([`NavigationFunction::is_settled`]).
    #[inline]
    pub fn value(&self, c: CellIndex) -> f64 {
        let Some(w) = self.window.filter(|_| !self.goal_cells.is_empty()) else {
            return f64::INFINITY;
        };
        match w.index_of(c) {
            Some(k) => {
                let (u, v) = (k % w.width() + 1, k / w.width() + 1);
                self.settled_value(u, v).unwrap_or(f64::INFINITY)
            }
            None => f64::INFINITY,
        }
    }

    /// The value at padded cell `(u, v)` if final (for the descent, once
    /// the function has goal cells).
    #[inline]
    pub(crate) fn settled_value(&self, u: usize, v: usize) -> Option<f64> {
        self.settled(u, v)
            .then(|| finite_or_infinite(self.values[self.index(u, v)]))
    }

    /// The value at padded cell `(u, v)`, settling it first if need be;
    /// `costs` are those of the cost map it was computed on.
    #[inline]
    pub(crate) fn settled_value_with(&mut self, costs: &[f64], u: usize, v: usize) -> f64 {
        self.settle(costs, u, v);
        finite_or_infinite(self.values[self.index(u, v)])
    }
}

/// A stored value as `N`: [`UNREACHED`] is `∞`.
#[inline]
fn finite_or_infinite(n: f64) -> f64 {
    if n == UNREACHED { f64::INFINITY } else { n }
}

/// `res · (max + (√2 − 1) · min)` of the two offsets: the length of the
/// shortest 8-connected path over that many columns and rows.
#[inline]
fn octile(du: usize, dv: usize, res: f64) -> f64 {
    let (lo, hi) = if du < dv { (du, dv) } else { (dv, du) };
    res * (hi as f64 + (std::f64::consts::SQRT_2 - 1.0) * lo as f64)
}

/// Padded index of window index `k` (`pw = width + 2`).
#[inline]
fn padded(pw: usize, width: usize, k: usize) -> usize {
    (k / width + 1) * pw + k % width + 1
}

/// A goal must lie in the window, in a cell that is not lethal.
fn check_goal(cost: &CostMap, goal: Vec2, cell: CellIndex) -> Result<(), PlanningError> {
    if !cost.window().contains(cell) {
        return Err(PlanningError::GoalOutsideWindow { goal, cell });
    }
    if let Some(why) = cost.why_lethal(cell) {
        return Err(PlanningError::GoalBlocked { goal, cell, why });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Blocked, CostParams};
    use robot::{Cell, GridMap, Pose};

    fn free_params() -> CostParams {
        CostParams {
            inscribed_radius_m: 0.0,
            inflation_radius_m: 0.0,
            max_cost: 0.0,
            decay_per_m: 0.0,
        }
    }

    fn ci(i: i64, j: i64) -> CellIndex {
        CellIndex { i, j }
    }

    #[test]
    fn open_floor_gives_octile_distances() {
        let m = GridMap::new(12, 9, 0.5, Pose::default(), vec![Cell::Free; 12 * 9]).unwrap();
        let cm = CostMap::build(free_params(), &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let mut nf = NavigationFunction::new();
        let info = nf.compute(&cm, m.cell_center(ci(2, 3))).unwrap();
        assert_eq!(info.reached_cells, 12 * 9);
        for i in 0..12i64 {
            for j in 0..9i64 {
                let (dx, dy) = ((i - 2).abs() as f64, (j - 3).abs() as f64);
                let octile = 0.5 * (dx.max(dy) - dx.min(dy) + std::f64::consts::SQRT_2 * dx.min(dy));
                assert!((nf.value(ci(i, j)) - octile).abs() < 1e-12);
            }
        }
        assert_eq!(nf.value(ci(-1, 0)), f64::INFINITY);
    }

    #[test]
    fn entries_in_too_early_buckets_are_corrected() {
        // Random walls and intrinsic costs up to 1000: with a ring of two
        // buckets most entries are clamped early and cells are re-opened;
        // the values must still be the exact ones.
        let (w, h) = (40, 30);
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let cells: Vec<Cell> = (0..w * h)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                if s % 7 == 0 { Cell::Occupied } else { Cell::Free }
            })
            .collect();
        let m = GridMap::new(w, h, 0.1, Pose::default(), cells).unwrap();
        let p = CostParams {
            inscribed_radius_m: 0.0,
            inflation_radius_m: 0.3,
            max_cost: 1000.0,
            decay_per_m: 20.0,
        };
        let cm = CostMap::build(p, &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let goal = (0..w * h)
            .map(|k| ci((k % w) as i64, (k / w) as i64))
            .find(|&c| !cm.is_lethal(c))
            .unwrap();
        let mut exact = NavigationFunction::new();
        let a = exact.compute_from_cells(&cm, &[goal]).unwrap();
        let mut corrected = NavigationFunction {
            tiny_ring: true,
            ..NavigationFunction::new()
        };
        let b = corrected.compute_from_cells(&cm, &[goal]).unwrap();
        assert!(b.pushes > a.pushes, "the small ring must cause corrections");
        assert_eq!(a.reached_cells, b.reached_cells);
        for k in 0..w * h {
            let c = ci((k % w) as i64, (k / w) as i64);
            assert_eq!(exact.value(c).to_bits(), corrected.value(c).to_bits(), "{c:?}");
        }
    }

    #[test]
    fn towards_a_start_values_are_exact_despite_early_buckets() {
        // As above, towards a start: the tiny ring clamps most keys early,
        // and the settled values must still be the exact ones.
        let (w, h) = (40, 30);
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let cells: Vec<Cell> = (0..w * h)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                if s % 6 == 0 { Cell::Occupied } else { Cell::Free }
            })
            .collect();
        let m = GridMap::new(w, h, 0.1, Pose::default(), cells).unwrap();
        let p = CostParams {
            inscribed_radius_m: 0.0,
            inflation_radius_m: 0.3,
            max_cost: 1000.0,
            decay_per_m: 20.0,
        };
        let cm = CostMap::build(p, &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let free: Vec<CellIndex> = (0..w * h)
            .map(|k| ci((k % w) as i64, (k / w) as i64))
            .filter(|&c| !cm.is_lethal(c))
            .collect();
        // A goal in the middle, a start reachable from it a few cells away.
        let middle = free.iter().position(|c| c.j == 15 && c.i >= 20).unwrap();
        let goal = m.cell_center(free[middle]);
        let mut exact = NavigationFunction::new();
        exact.compute(&cm, goal).unwrap();
        let start = free[middle + 3..]
            .iter()
            .find(|&&c| exact.value(c).is_finite())
            .map(|&c| m.cell_center(c))
            .unwrap();
        for tiny_ring in [false, true] {
            let mut towards = NavigationFunction {
                tiny_ring,
                ..NavigationFunction::new()
            };
            towards.compute_towards(&cm, goal, start).unwrap();
            if !tiny_ring {
                // (With the tiny ring, the buckets move on too slowly to
                // stop before the end.)
                assert!(!towards.is_complete());
                let settled = free.iter().filter(|&&c| towards.is_settled(c)).count();
                assert!(settled < free.len() / 2, "{settled} settled of {}", free.len());
            }
            for &c in &free {
                if towards.is_settled(c) {
                    assert_eq!(exact.value(c).to_bits(), towards.value(c).to_bits(), "{c:?}");
                }
            }
            towards.complete(&cm).unwrap();
            assert!(towards.is_complete());
            for k in 0..w * h {
                let c = ci((k % w) as i64, (k / w) as i64);
                assert_eq!(exact.value(c).to_bits(), towards.value(c).to_bits(), "{c:?}");
            }
        }
    }

    #[test]
    fn a_start_walled_in_is_found_cut_off_early() {
        // A 200 × 200 room, the start in a 5 × 5 pocket walled in.
        let (w, h) = (200, 200);
        let mut cells = vec![Cell::Free; w * h];
        for k in 0..7 {
            for (i, j) in [(150 + k, 150), (150 + k, 156), (150, 150 + k), (156, 150 + k)] {
                cells[j * w + i] = Cell::Occupied;
            }
        }
        let m = GridMap::new(w, h, 0.05, Pose::default(), cells).unwrap();
        let cm = CostMap::build(free_params(), &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let (goal, start) = (m.cell_center(ci(20, 20)), m.cell_center(ci(153, 153)));
        let mut nf = NavigationFunction::new();
        let info = nf.compute_towards(&cm, goal, start).unwrap();
        assert!(info.reached_cells < 1000, "{info:?}");
        assert!(nf.is_settled(ci(153, 153)));
        assert_eq!(nf.value(ci(153, 153)), f64::INFINITY);
        let mut path = Vec::new();
        assert!(matches!(
            crate::descend_settling(&mut nf, &cm, start, &Default::default(), &mut path),
            Err(PlanningError::Unreachable { .. })
        ));
        assert!(nf.info().reached_cells < 1000);
        // Completed, the pocket stays at ∞ and the rest is the whole
        // computation.
        let mut whole = NavigationFunction::new();
        whole.compute(&cm, goal).unwrap();
        nf.complete(&cm).unwrap();
        for k in 0..w * h {
            let c = ci((k % w) as i64, (k / w) as i64);
            assert_eq!(whole.value(c).to_bits(), nf.value(c).to_bits(), "{c:?}");
        }
        // From outside the pocket, towards it: the flood from a start that
        // reaches the goal stops when it meets the wavefront.
        nf.compute_towards(&cm, goal, m.cell_center(ci(100, 100)))
            .unwrap();
        assert_eq!(
            nf.value(ci(100, 100)).to_bits(),
            whole.value(ci(100, 100)).to_bits()
        );
    }

    #[test]
    fn errors_towards_a_start() {
        let m = GridMap::new(30, 30, 0.1, Pose::default(), vec![Cell::Free; 900]).unwrap();
        let cm = CostMap::build(free_params(), &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let mut nf = NavigationFunction::new();
        let goal = m.cell_center(ci(2, 2));
        assert!(matches!(
            nf.compute_towards(&cm, goal, Vec2::new(5.0, 1.0)),
            Err(PlanningError::StartOutsideWindow { .. })
        ));
        assert!(matches!(
            nf.compute_towards(&cm, goal, Vec2::new(f64::NAN, 1.0)),
            Err(PlanningError::BadPoint { .. })
        ));
        assert_eq!(nf.value(ci(2, 2)), f64::INFINITY, "left empty after an error");
        // A start near the goal: the far corner is not settled, and a
        // descent that does not settle cannot start there.
        nf.compute_towards(&cm, goal, m.cell_center(ci(4, 3))).unwrap();
        assert!((nf.value(ci(4, 3)) - 0.1 * (1.0 + std::f64::consts::SQRT_2)).abs() < 1e-12);
        assert!(!nf.is_settled(ci(29, 29)));
        assert_eq!(nf.value(ci(29, 29)), f64::INFINITY);
        let mut path = Vec::new();
        let far = m.cell_center(ci(29, 29));
        assert_eq!(
            crate::descend(&nf, far, &Default::default(), &mut path),
            Err(PlanningError::Unsettled { cell: ci(29, 29) })
        );
        // Completing needs the same cost map.
        let other =
            CostMap::build(free_params(), &m, Window::new(&m, ci(0, 0), 10, 10).unwrap(), &[]).unwrap();
        assert_eq!(nf.complete(&other), Err(PlanningError::OtherCostMap));
        assert_eq!(
            crate::descend_settling(&mut nf, &other, far, &Default::default(), &mut path),
            Err(PlanningError::OtherCostMap)
        );
        crate::descend_settling(&mut nf, &cm, far, &Default::default(), &mut path).unwrap();
        assert_eq!(*path.last().unwrap(), goal);
        nf.complete(&cm).unwrap();
        assert!(nf.is_settled(ci(29, 0)));
    }

    #[test]
    fn no_corner_cutting_and_walls_are_infinite() {
        // . . .
        // # . .      goal at (0, 0); (1, 0) and (0, 1) blocked
        // G # .
        let mut cells = vec![Cell::Free; 9];
        cells[1] = Cell::Occupied;
        cells[3] = Cell::Occupied;
        let m = GridMap::new(3, 3, 1.0, Pose::default(), cells).unwrap();
        let cm = CostMap::build(free_params(), &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let mut nf = NavigationFunction::new();
        let info = nf.compute(&cm, Vec2::new(0.5, 0.5)).unwrap();
        assert_eq!(info.reached_cells, 1, "the diagonal to (1, 1) cuts two walls");
        assert_eq!(nf.value(ci(1, 1)), f64::INFINITY);
        assert_eq!(nf.value(ci(1, 0)), f64::INFINITY);
    }

    #[test]
    fn goal_errors() {
        let mut cells = vec![Cell::Free; 25];
        cells[12] = Cell::Occupied;
        cells[13] = Cell::Unknown;
        let m = GridMap::new(5, 5, 1.0, Pose::default(), cells).unwrap();
        let cm = CostMap::build(free_params(), &m, Window::whole(&m).unwrap(), &[]).unwrap();
        let mut nf = NavigationFunction::new();
        assert!(matches!(
            nf.compute(&cm, Vec2::new(2.5, 2.5)),
            Err(PlanningError::GoalBlocked {
                why: Blocked::Occupied,
                ..
            })
        ));
        assert!(matches!(
            nf.compute(&cm, Vec2::new(3.5, 2.5)),
            Err(PlanningError::GoalBlocked {
                why: Blocked::Unknown,
                ..
            })
        ));
        assert!(matches!(
            nf.compute(&cm, Vec2::new(7.5, 2.5)),
            Err(PlanningError::GoalOutsideWindow { .. })
        ));
        assert!(matches!(
            nf.compute(&cm, Vec2::new(f64::NAN, 2.5)),
            Err(PlanningError::BadPoint { .. })
        ));
        assert_eq!(nf.value(ci(0, 0)), f64::INFINITY, "left empty after an error");
        assert_eq!(nf.compute_from_cells(&cm, &[]), Err(PlanningError::NoGoal));
        let info = nf.compute_from_cells(&cm, &[ci(0, 0), ci(4, 4)]).unwrap();
        assert_eq!(info.reached_cells, 23);
        assert_eq!(nf.value(ci(4, 0)), 4.0);
        let blocked = GridMap::new(3, 3, 1.0, Pose::default(), vec![Cell::Occupied; 9]).unwrap();
        let cm = CostMap::build(free_params(), &blocked, Window::whole(&blocked).unwrap(), &[]).unwrap();
        assert!(matches!(
            nf.compute(&cm, Vec2::new(1.5, 1.5)),
            Err(PlanningError::NoFreeCell { .. })
        ));
    }
}
