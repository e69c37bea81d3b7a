//! People: discs that walk between exhibits (or wander), linger, sometimes
//! come to see the robot, avoid walls, each other and the robot, and get in
//! the way.
//!
//! **Model.** Each person is a disc of radius `radius_m` moved by the social
//! force model (D. Helbing, P. Molnár, *Social force model for pedestrian
//! dynamics*, Phys. Rev. E 51, 1995), per unit mass:
//!
//! - driving: `(v⁰ e − v)/τ`, `e` the unit vector to the current target,
//!   `v⁰` the person's preferred speed (zero while lingering; by the robot,
//!   see below);
//! - other people: `A exp((2r − d)/B) n`, `n` the unit vector from the other
//!   person, `d` the centre distance, weighted by Helbing's field of view
//!   `λ + (1 − λ)(1 + cos φ)/2` (`φ` between the walking direction and the
//!   other person), ignored beyond `2r + 4B`;
//! - the robot: the same, with its footprint radius and its own strength
//!   (not for people who came to see it);
//! - walls: `A_w exp((r − d_w)/B_w) n_w` from the nearest obstacle point
//!   (the world's distance field).
//!
//! The velocity is integrated explicitly (`v += F Δt`), capped at 1.3 `v⁰`
//! (Helbing's maximal speed), and the position moved by `v Δt`. Discs never
//! interpenetrate: a move that would overlap a wall, another person or the
//! robot is refused and the person stops for that step (the forces then
//! turn them away). People are updated in index order with the positions
//! already updated, so a step is deterministic.
//!
//! **Behaviour.** With waypoints (exhibits) a person picks one at random
//! (not the one just visited), aims at a random free point within
//! `gather_radius_m` of it (people gather *around* exhibits), and on arrival
//! lingers with probability `linger_probability` for an exponential time of
//! mean `linger_mean_s`; without waypoints a person wanders to random free
//! points within `wander_radius_m`. Towards an exhibit people follow the
//! world's walking-distance field of that exhibit ([`crate::routes`]:
//! around obstacles, through doors) until within `gather_radius_m + 1 m`,
//! then walk straight at their target; wanderers walk straight, so their
//! targets are drawn among points they can reach in a straight line when
//! there are any (three rays: centre line and flanks). A target not reached
//! within `target_timeout_s`, or a person who has not moved their own radius
//! in `stuck_timeout_s`, gets a new target.
//! Lingering people stand still but can still be pushed: they block
//! corridors and exhibits, and people crossing to the next target step in
//! front of the robot.
//!
//! **Visitors and the robot.** Museum visitors sometimes come to see the
//! robot and stand around it for a while. With `robot_interest_rate_per_s`
//! above 0, at each step of `Δt` each person not already with the robot,
//! asked to step aside or on their way aside, whose centre is within
//! `robot_interest_range_m` of the robot's, takes an interest in it with
//! probability `1 − exp(−rate Δt)` (a Poisson process of that rate), drawn
//! in index order; they come if they can walk straight to it (the three rays
//! of the wanderers: a robot behind a wall is not seen). Coming, they walk
//! straight at the point at the gather distance from the robot's *current*
//! centre on their own side, re-aimed at every step, until their centre is
//! within that distance: people coming from all sides stand all around the
//! robot, and the repulsion between people spreads those who come from the
//! same side. The gather distance is `robot_gather_distance_m`, or for a
//! robot too big for it 5 cm beyond `robot_clearance_m`, closer than which
//! nobody comes anyway. Then they stand by the robot for an exponential time
//! of mean `robot_linger_mean_s`, keeping to the gather distance: they walk
//! back to it either way at `distance / τ` (at most their preferred speed),
//! so they step back when the robot comes closer and follow it when it moves
//! off, while the people around them still push them along the circle.
//! People with the robot do not shy away from it (its repulsion is off for
//! them; the clearance holds). They go back to their usual behaviour — a new
//! exhibit, as after any target — when their time is up, when the robot is
//! out of range (or gone), when coming takes more than `target_timeout_s` or
//! they are stuck (`stuck_timeout_s`, as any walk), or when asked to step
//! aside: the request wins, they step aside as below (taking no interest in
//! the robot on their way) and may take an interest again once there, by the
//! same Poisson process. At the default rate 0 nothing of this happens and
//! no number is drawn: the crowd moves exactly as without it.
//!
//! **Curious groups.** [`Crowd::surround`] (the simulator's surround
//! disturbance, [`crate::disturbance`]) sends the people nearest the robot
//! to it at once, as visitors, for a set time: they come and stand all
//! around it as above, but until their time is up nothing sends them away —
//! not the robot moving off or out of range, not being stuck, not a request
//! to step aside (they are not asked at all: no number is drawn for them).
//! They are marked by [`Person::curious_until_s`]; unused, it stays `None`
//! and the crowd moves exactly as without it.
//!
//! **Asked to step aside.** When the robot asks ([`robot::Request`]), each
//! person whose centre is within the request's radius complies with
//! probability `step_aside_compliance`; after a reaction delay (uniform in
//! 0.5–1.5 × `step_aside_delay_s`, drawn per person) they walk to a free
//! point `step_aside_distance_m` outside the radius, away from where the
//! robot was when it asked (within ±60° of the direction away from it,
//! reachable in a straight line when possible), then carry on as after any
//! target: linger there or walk to the next exhibit.
//!
//! **Cost.** A uniform spatial hash with buckets of the interaction range:
//! `O(n)` per step for bounded density, no allocation.

use robot::Vec2;

use crate::crowd_params::CrowdParams;
use crate::error::{Error, Result};
use crate::fast_math::{dist, norm};
use crate::noise::{RandomStream, streams};
use crate::raycast;
use crate::spatial_hash::SpatialHash;
use crate::world::World;

/// Ratio of a person's top speed to their preferred speed (Helbing & Molnár).
pub const MAX_SPEED_RATIO: f64 = 1.3;

/// Least preferred speed, as a fraction of the mean (a draw below is
/// raised to it).
const PREFERRED_SPEED_MIN_RATIO: f64 = 0.2;

/// Greatest preferred speed, as a multiple of the mean (a draw above is
/// lowered to it).
const PREFERRED_SPEED_MAX_RATIO: f64 = 1.8;

/// The repulsions (people, robot, walls) are cut off beyond this many of
/// their ranges `B` past contact (dimensionless; `e^-4` ≈ 2 %).
const FORCE_CUTOFF_RANGES: f64 = 4.0;

/// A walker follows the route until within this far beyond the gather
/// radius of its exhibit, metres; then straight at the target.
const ROUTE_BEYOND_GATHER_M: f64 = 1.0;

/// What a person is doing.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum Activity {
    /// Walking to the target.
    Walking {
        /// When the walk started, seconds.
        since_s: f64,
        /// Where the person was at the last progress check.
        checkpoint: Vec2,
        /// When that was, seconds.
        checkpoint_s: f64,
        /// Whether the target is where they were asked to step aside to
        /// (until there, they take no interest in the robot).
        stepping_aside: bool,
    },
    /// Standing until this time, seconds.
    Lingering {
        /// When the pause ends, seconds.
        until_s: f64,
    },
    /// Coming to see the robot: walking straight at the point at the
    /// gather distance from the robot on the person's side, re-aimed at
    /// every step (module docs).
    ComingToRobot {
        /// When the walk started, seconds.
        since_s: f64,
        /// Where the person was at the last progress check.
        checkpoint: Vec2,
        /// When that was, seconds.
        checkpoint_s: f64,
    },
    /// Standing by the robot, at the gather distance from it, until this
    /// time, seconds (module docs).
    AtRobot {
        /// When the visit ends, seconds.
        until_s: f64,
    },
}

impl Activity {
    /// Starting a walk from `position` at `time_s`.
    pub fn walking(position: Vec2, time_s: f64) -> Activity {
        Activity::Walking {
            since_s: time_s,
            checkpoint: position,
            checkpoint_s: time_s,
            stepping_aside: false,
        }
    }

    /// Starting to come to the robot from `position` at `time_s`.
    pub fn coming_to_robot(position: Vec2, time_s: f64) -> Activity {
        Activity::ComingToRobot {
            since_s: time_s,
            checkpoint: position,
            checkpoint_s: time_s,
        }
    }

    /// Whether the person has come to see the robot: coming to it or
    /// standing by it.
    pub fn with_robot(&self) -> bool {
        matches!(self, Activity::ComingToRobot { .. } | Activity::AtRobot { .. })
    }
}

/// One person.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Person {
    /// Centre of the disc, world frame.
    pub position: Vec2,
    /// Velocity, m/s.
    pub velocity: Vec2,
    /// Preferred walking speed, m/s.
    pub preferred_speed_mps: f64,
    /// Where the person is heading, world frame.
    pub target: Vec2,
    /// Walking, lingering, or with the robot.
    pub activity: Activity,
    /// The exhibit the target belongs to, if any.
    pub waypoint: Option<usize>,
    /// A request to step aside the person will act on.
    pub asked: Option<Asked>,
    /// Part of a curious group closing round the robot until this time,
    /// seconds ([`Crowd::surround`]): until then the person stays with the
    /// robot and ignores requests to step aside. `None` for everybody
    /// unless [`Crowd::surround`] is used.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub curious_until_s: Option<f64>,
}

/// A request to step aside, pending until its reaction time.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Asked {
    /// Where the robot was when it asked, world frame.
    pub from: Vec2,
    /// The request's radius, metres.
    pub radius_m: f64,
    /// When the person moves, seconds.
    pub react_at_s: f64,
}

/// The people of one run (module docs).
#[derive(Debug, Clone)]
pub struct Crowd {
    people: Vec<Person>,
    radius_m: f64,
    hash: SpatialHash,
    rng: RandomStream,
}

/// Whether a disc of radius `radius_m` can walk straight from `a` to `b`:
/// three rays (its centre line and both flanks) meet no wall.
fn walkable(world: &World, a: Vec2, b: Vec2, radius_m: f64) -> bool {
    let d = b - a;
    let len = norm(d);
    if len < 1e-9 {
        return true;
    }
    let side = Vec2::new(-d.y, d.x).scale(radius_m / len);
    let angle = d.y.atan2(d.x);
    [Vec2::default(), side, side.scale(-1.0)]
        .iter()
        .all(|&o| raycast::cast(world.grid(), a + o, angle, len).is_none())
}

/// A free point for a person's target, or `None` after a few tries; with
/// `seen_from`, only points a person there can walk to straight.
fn free_point(
    world: &World,
    radius_m: f64,
    seen_from: Option<Vec2>,
    try_point: &mut dyn FnMut() -> Vec2,
) -> Option<Vec2> {
    for _ in 0..20 {
        let p = try_point();
        if world.on_map(p)
            && world.distance_field().distance_m(p) >= radius_m + 0.05
            && seen_from.is_none_or(|a| walkable(world, a, p, radius_m))
        {
            return Some(p);
        }
    }
    None
}

/// A new target for a person at `from` (module docs).
fn pick_target(
    world: &World,
    rng: &mut RandomStream,
    from: Vec2,
    last: Option<usize>,
) -> (Vec2, Option<usize>) {
    let p = world.crowd();
    let n = p.waypoints.len();
    let tau = std::f64::consts::TAU;
    if n == 0 {
        let reach = p.wander_radius_m;
        let target = free_point(world, p.radius_m, Some(from), &mut || {
            let a = rng.uniform_in(0.0, tau);
            let d = reach * rng.uniform().sqrt();
            from + Vec2::new(a.cos(), a.sin()).scale(d)
        });
        return (target.unwrap_or(from), None);
    }
    let k = match last {
        Some(l) if n > 1 => {
            let k = rng.index(n - 1);
            if k >= l { k + 1 } else { k }
        }
        _ => rng.index(n),
    };
    let centre = p.waypoints[k];
    let gather = p.gather_radius_m;
    let mut around = || {
        let a = rng.uniform_in(0.0, tau);
        let d = gather * rng.uniform().sqrt();
        centre + Vec2::new(a.cos(), a.sin()).scale(d)
    };
    let target = free_point(world, p.radius_m, Some(from), &mut around)
        .or_else(|| free_point(world, p.radius_m, None, &mut around));
    (target.unwrap_or(centre), Some(k))
}

/// People who come to see a robot too big for the gather distance stand
/// this far outside the clearance, metres (so that they can arrive: a
/// step ending inside the clearance is refused).
const GATHER_SLACK_M: f64 = 0.05;

/// How far from the centre of a robot of radius `robot_radius_m` people of
/// radius `r` who come to see it stand, metres (module docs).
fn gather_distance_m(p: &CrowdParams, r: f64, robot_radius_m: f64) -> f64 {
    p.robot_gather_distance_m
        .max(r + robot_radius_m + p.robot_clearance_m + GATHER_SLACK_M)
}

/// The point at `distance_m` from the robot's centre `robot_at` on the
/// side of `from` (`from` itself if it is the centre).
fn spot_by_robot(from: Vec2, robot_at: Vec2, distance_m: f64) -> Vec2 {
    let away = from - robot_at;
    let d = norm(away);
    if d > 1e-9 {
        robot_at + away.scale(distance_m / d)
    } else {
        from
    }
}

impl Crowd {
    /// Places the world's crowd at random free positions drawn from the
    /// run's `seed` (its placement stream): no person overlaps a wall or
    /// another person, nor comes within `keep_clear_m` of the discs
    /// `keep_clear` (centre, radius: the robot's start footprint). Each
    /// person gets a preferred speed and a first target; with probability
    /// `linger_probability` they start lingering.
    ///
    /// The people at [`CrowdParams::positions`] come first, in order.
    ///
    /// Errors: [`Error::Geometry`] when a given position is not free;
    /// [`Error::InvalidValue`] when the random people do not fit (after
    /// 10 000 tries per person).
    pub fn new(world: &World, seed: u64, keep_clear: &[(Vec2, f64)]) -> Result<Crowd> {
        let p = world.crowd();
        let count = p.count(world.free_area_m2());
        let r = p.radius_m;
        // Discs of radius r pack at best one per 2√3 r² (hexagonal packing).
        let most = world.free_area_m2() / (2.0 * 3f64.sqrt() * r * r);
        if count as f64 > most {
            return Err(Error::InvalidValue {
                what: "crowd size (people)".to_string(),
                requirement: "at most the free area over 2√3 r² (densest packing)",
                value: count as f64,
            });
        }
        let mut place = RandomStream::new(seed, streams::PLACEMENT);
        let g = world.grid();
        let (wm, hm) = (
            g.width() as f64 * g.resolution_m(),
            g.height() as f64 * g.resolution_m(),
        );
        let mut people: Vec<Person> = Vec::with_capacity(count + p.positions.len());
        for (k, &q) in p.positions.iter().enumerate() {
            let overlaps_robot = keep_clear.iter().any(|&(c, rc)| dist(q, c) < r + rc);
            if !world.on_map(q)
                || g.disc_blocked(q, r)
                || overlaps_robot
                || people.iter().any(|o| dist(o.position, q) < 2.0 * r)
            {
                return Err(Error::Geometry(format!(
                    "crowd position {k} ({:.3}, {:.3}): the person (radius {r} m) overlaps a wall, \
                     another person or the robot",
                    q.x, q.y
                )));
            }
            people.push(Self::person(world, &mut place, q));
        }
        for _ in 0..count {
            let mut placed = None;
            for _ in 0..10_000 {
                let q = g.to_world(Vec2::new(place.uniform() * wm, place.uniform() * hm));
                let clear_of_robot = keep_clear
                    .iter()
                    .all(|&(c, rc)| q.dist(c) >= r + rc + p.keep_clear_m);
                if clear_of_robot
                    && world.distance_field().distance_m(q) >= r
                    && !g.disc_blocked(q, r)
                    && people.iter().all(|o| o.position.dist(q) >= 2.0 * r)
                {
                    placed = Some(q);
                    break;
                }
            }
            let Some(position) = placed else {
                return Err(Error::InvalidValue {
                    what: "crowd size (people)".to_string(),
                    requirement: "small enough for the people to fit in the free space",
                    value: count as f64,
                });
            };
            people.push(Self::person(world, &mut place, position));
        }
        let (lo, hi) = world.bounds();
        let mut hash = SpatialHash::new(lo, hi, Self::reach_m(p));
        hash.rebuild(people.iter().map(|q| q.position));
        Ok(Crowd {
            people,
            radius_m: r,
            hash,
            rng: RandomStream::new(seed, streams::PEOPLE),
        })
    }

    /// A new person at `position`: preferred speed, first target, and
    /// whether they start lingering.
    fn person(world: &World, place: &mut RandomStream, position: Vec2) -> Person {
        let p = world.crowd();
        let z = place.normal();
        let preferred_speed_mps = (p.speed_mean_mps + p.speed_sigma_mps * z).clamp(
            PREFERRED_SPEED_MIN_RATIO * p.speed_mean_mps,
            PREFERRED_SPEED_MAX_RATIO * p.speed_mean_mps,
        );
        let (target, waypoint) = pick_target(world, place, position, None);
        let activity = if place.chance(p.linger_probability) {
            Activity::Lingering {
                until_s: place.exponential(p.linger_mean_s),
            }
        } else {
            Activity::walking(position, 0.0)
        };
        Person {
            position,
            velocity: Vec2::default(),
            preferred_speed_mps,
            target,
            activity,
            waypoint,
            asked: None,
            curious_until_s: None,
        }
    }

    /// Range beyond which people do not push each other: `2r + 4B`.
    fn reach_m(p: &CrowdParams) -> f64 {
        2.0 * p.radius_m + FORCE_CUTOFF_RANGES * p.person_range_m
    }

    /// The people, in a fixed order.
    pub fn people(&self) -> &[Person] {
        &self.people
    }

    /// Radius of every person's disc, metres.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// Whether a disc (the robot's footprint) overlaps a person.
    pub fn overlaps(&self, centre: Vec2, radius_m: f64) -> bool {
        let reach = radius_m + self.radius_m;
        let mut hit = false;
        self.hash.for_each_near(centre, reach, |k| {
            hit |= dist(self.people[k].position, centre) < reach;
        });
        hit
    }

    /// Gap between a disc and the nearest person's disc, metres (negative
    /// when they overlap; infinite without people).
    pub fn gap_m(&self, centre: Vec2, radius_m: f64) -> f64 {
        let reach = radius_m + self.radius_m;
        self.people
            .iter()
            .map(|q| dist(q.position, centre) - reach)
            .fold(f64::INFINITY, f64::min)
    }

    /// The robot at `robot_at` asks the people within `radius_m` of it to
    /// step aside at `time_s` (module docs). People already asked are left
    /// as they are; a radius that is not a finite number > 0 asks nobody.
    /// Returns how many people were asked.
    pub fn ask_to_step_aside(&mut self, world: &World, robot_at: Vec2, radius_m: f64, time_s: f64) -> usize {
        if !(radius_m.is_finite() && radius_m > 0.0) {
            return 0;
        }
        let p = world.crowd();
        let mut asked = 0;
        for me in &mut self.people {
            if me.asked.is_some()
                || dist(me.position, robot_at) > radius_m
                || me.curious_until_s.is_some_and(|u| time_s < u)
            {
                continue;
            }
            if !self.rng.chance(p.step_aside_compliance) {
                continue;
            }
            let delay = p.step_aside_delay_s * self.rng.uniform_in(0.5, 1.5);
            me.asked = Some(Asked {
                from: robot_at,
                radius_m,
                react_at_s: time_s + delay,
            });
            asked += 1;
        }
        asked
    }

    /// The indices of the people whose disc comes within `gap_m` (rim to
    /// rim) of the disc `(centre, radius_m)`, ascending, into `out`
    /// (cleared first). Looked up in the crowd's buckets: `O(people
    /// nearby)`, no allocation once `out` has grown.
    pub fn within_gap(&self, centre: Vec2, radius_m: f64, gap_m: f64, out: &mut Vec<usize>) {
        out.clear();
        let reach = radius_m + self.radius_m + gap_m;
        if !(reach.is_finite() && reach >= 0.0) {
            return;
        }
        self.hash.for_each_near(centre, reach, |k| {
            if dist(self.people[k].position, centre) <= reach {
                out.push(k);
            }
        });
        out.sort_unstable();
    }

    /// A curious group closes round the robot (footprint `robot`: centre,
    /// radius) at `time_s`: the `count` people nearest its centre, within
    /// `range_m` of it, come to see it as visitors do (module docs: they
    /// walk straight to the gather distance on their side and stand there,
    /// all around it) and stay until `until_s`. Until then they ignore
    /// requests to step aside (a pending request is dropped), keep coming
    /// however long it takes or wherever the robot goes (no range, stuck
    /// or time-out rule), and take no interest of their own; at `until_s`
    /// they go back to their usual behaviour, as after any visit.
    ///
    /// People are taken nearest first (ties by index), skipping those
    /// already in a curious group and those who cannot walk straight to
    /// their spot by the robot (a wall between: the three rays of the
    /// module docs); people stepping aside or already with the robot join.
    /// Fewer than `count` come if fewer are there. No random number is
    /// drawn. Returns the people who came, nearest first.
    ///
    /// Cost: `O(n log n)` for the `n` people in range, and three rays per
    /// person tried.
    pub fn surround(
        &mut self,
        world: &World,
        robot: (Vec2, f64),
        count: usize,
        range_m: f64,
        time_s: f64,
        until_s: f64,
    ) -> Vec<usize> {
        let (c, rr) = robot;
        let r = self.radius_m;
        let by = gather_distance_m(world.crowd(), r, rr);
        let mut near: Vec<(f64, usize)> = self
            .people
            .iter()
            .enumerate()
            .filter(|(_, q)| q.curious_until_s.is_none())
            .map(|(k, q)| (dist(q.position, c), k))
            .filter(|&(d, _)| d <= range_m)
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut came = Vec::with_capacity(count.min(near.len()));
        for (_, k) in near {
            if came.len() >= count {
                break;
            }
            let me = &mut self.people[k];
            let spot = spot_by_robot(me.position, c, by);
            if !walkable(world, me.position, spot, r) {
                continue;
            }
            me.target = spot;
            me.waypoint = None;
            me.asked = None;
            me.activity = Activity::coming_to_robot(me.position, time_s);
            me.curious_until_s = Some(until_s);
            came.push(k);
        }
        came
    }

    /// Where a person asked to step aside goes (module docs).
    fn aside_target(world: &World, rng: &mut RandomStream, me: &Person, asked: &Asked) -> Vec2 {
        let p = world.crowd();
        let away = me.position - asked.from;
        let base = if norm(away) > 1e-9 {
            away.y.atan2(away.x)
        } else {
            rng.uniform_in(0.0, std::f64::consts::TAU)
        };
        let reach = asked.radius_m + p.step_aside_distance_m;
        let third = std::f64::consts::FRAC_PI_3;
        let mut around = || {
            let a = base + rng.uniform_in(-third, third);
            asked.from + Vec2::new(a.cos(), a.sin()).scale(reach)
        };
        free_point(world, p.radius_m, Some(me.position), &mut around)
            .or_else(|| free_point(world, p.radius_m, None, &mut around))
            .unwrap_or(me.position)
    }

    /// Moves everybody by one step of `dt_s` seconds ending at `time_s`
    /// (module docs), with the robot's footprint `(centre, radius)` as an
    /// obstacle if given.
    pub fn step(&mut self, world: &World, robot: Option<(Vec2, f64)>, time_s: f64, dt_s: f64) {
        if self.people.is_empty() {
            return;
        }
        let p = world.crowd();
        let r = self.radius_m;
        // People move at most this far in a step: query with that slack so
        // the buckets (built at the start) stay a superset.
        let slack = 2.0 * MAX_SPEED_RATIO * PREFERRED_SPEED_MAX_RATIO * p.speed_mean_mps * dt_s;
        // Probability that a person takes an interest in the robot in this
        // step: 1 − exp(−rate Δt).
        let interest = if p.robot_interest_rate_per_s > 0.0 {
            -(-p.robot_interest_rate_per_s * dt_s).exp_m1()
        } else {
            0.0
        };
        let ctx = StepContext {
            world,
            p,
            robot,
            time_s,
            dt_s,
            r,
            reach: Self::reach_m(p),
            slack,
            wall_reach: r + FORCE_CUTOFF_RANGES * p.wall_range_m,
            interest,
        };
        for i in 0..self.people.len() {
            let mut me = self.people[i];
            self.decide(&ctx, &mut me);
            let desired = desired_velocity(world, p, &me);
            let force = self.force_on(&ctx, i, &me, desired);
            self.integrate(&ctx, i, &mut me, force);
            self.people[i] = me;
        }
        self.hash.rebuild(self.people.iter().map(|q| q.position));
    }

    /// What a person does this step: steps aside when asked, takes an
    /// interest in the robot, and goes on with (or ends) their activity,
    /// picking a new target when it is over.
    fn decide(&mut self, ctx: &StepContext<'_>, me: &mut Person) {
        let (world, p, time_s) = (ctx.world, ctx.p, ctx.time_s);
        // Part of a curious group ([`Crowd::surround`]) until when?
        let group_over = me.curious_until_s.is_some_and(|u| time_s >= u);
        if group_over {
            me.curious_until_s = None;
        }
        let curious = me.curious_until_s.is_some();
        // Asked to step aside, and time to move?
        if let Some(asked) = me.asked
            && time_s >= asked.react_at_s
        {
            me.target = Self::aside_target(world, &mut self.rng, me, &asked);
            me.waypoint = None;
            me.activity = Activity::Walking {
                since_s: time_s,
                checkpoint: me.position,
                checkpoint_s: time_s,
                stepping_aside: true,
            };
            me.asked = None;
        }
        // Taking an interest in the robot (in sight, within range)?
        if ctx.interest > 0.0
            && let Some((c, rr)) = ctx.robot
            && !me.activity.with_robot()
            && me.asked.is_none()
            && !matches!(
                me.activity,
                Activity::Walking {
                    stepping_aside: true,
                    ..
                }
            )
            && dist(me.position, c) <= p.robot_interest_range_m
            && self.rng.chance(ctx.interest)
        {
            let spot = spot_by_robot(me.position, c, gather_distance_m(p, ctx.r, rr));
            if walkable(world, me.position, spot, ctx.r) {
                me.target = spot;
                me.waypoint = None;
                me.activity = Activity::coming_to_robot(me.position, time_s);
            }
        }
        if self.activity_over(ctx, me, group_over, curious) {
            (me.target, me.waypoint) = pick_target(world, &mut self.rng, me.position, me.waypoint);
            me.activity = Activity::walking(me.position, time_s);
            me.curious_until_s = None;
        }
    }

    /// Goes on with a person's activity (arrivals, lingering, progress
    /// checks, time-outs, the robot's spot); whether it is over and a new
    /// target is wanted.
    fn activity_over(
        &mut self,
        ctx: &StepContext<'_>,
        me: &mut Person,
        group_over: bool,
        curious: bool,
    ) -> bool {
        let (p, r, time_s) = (ctx.p, ctx.r, ctx.time_s);
        let mut new_target = false;
        match me.activity {
            // A curious group's time is up (some may not have arrived
            // yet): they go, as after any visit.
            Activity::ComingToRobot { .. } | Activity::AtRobot { .. } if group_over => new_target = true,
            Activity::Lingering { until_s } => new_target = time_s >= until_s,
            Activity::Walking {
                since_s,
                checkpoint,
                checkpoint_s,
                stepping_aside,
            } => {
                if dist(me.position, me.target) <= p.arrival_tolerance_m {
                    if self.rng.chance(p.linger_probability) {
                        me.activity = Activity::Lingering {
                            until_s: time_s + self.rng.exponential(p.linger_mean_s),
                        };
                    } else {
                        new_target = true;
                    }
                } else if time_s - checkpoint_s >= p.stuck_timeout_s {
                    // Progress check: stuck behind something?
                    new_target = dist(me.position, checkpoint) < r;
                    me.activity = Activity::Walking {
                        since_s,
                        checkpoint: me.position,
                        checkpoint_s: time_s,
                        stepping_aside,
                    };
                }
                new_target |= time_s - since_s > p.target_timeout_s;
            }
            Activity::ComingToRobot {
                since_s,
                checkpoint,
                checkpoint_s,
            } => match ctx.robot {
                Some((c, rr)) if curious || dist(me.position, c) <= p.robot_interest_range_m => {
                    let by = gather_distance_m(p, r, rr);
                    me.target = spot_by_robot(me.position, c, by);
                    if dist(me.position, c) <= by {
                        let until_s = match me.curious_until_s {
                            Some(u) => u,
                            None => time_s + self.rng.exponential(p.robot_linger_mean_s),
                        };
                        me.activity = Activity::AtRobot { until_s };
                    } else if !curious {
                        // Progress check and time out, as for any walk.
                        if time_s - checkpoint_s >= p.stuck_timeout_s {
                            new_target = dist(me.position, checkpoint) < r;
                            me.activity = Activity::ComingToRobot {
                                since_s,
                                checkpoint: me.position,
                                checkpoint_s: time_s,
                            };
                        }
                        new_target |= time_s - since_s > p.target_timeout_s;
                    }
                }
                // The robot has gone out of range.
                _ => new_target = true,
            },
            Activity::AtRobot { until_s } => match ctx.robot {
                Some((c, rr))
                    if time_s < until_s && (curious || dist(me.position, c) <= p.robot_interest_range_m) =>
                {
                    me.target = spot_by_robot(me.position, c, gather_distance_m(p, r, rr));
                }
                // Time to go, or the robot has gone out of range.
                _ => new_target = true,
            },
        }
        new_target
    }

    /// The social force on person `i` (`me`, wanting to go at `desired`):
    /// relaxation to `desired`, and repulsion by the other people (within
    /// the field of view's weighting), the robot and the walls.
    fn force_on(&self, ctx: &StepContext<'_>, i: usize, me: &Person, desired: Vec2) -> Vec2 {
        let (p, r, reach) = (ctx.p, ctx.r, ctx.reach);
        let mut force = (desired - me.velocity).scale(1.0 / p.relaxation_time_s);
        let heading = {
            let h = if norm(desired) > 0.0 { desired } else { me.velocity };
            let n = norm(h);
            if n > 1e-9 { Some(h.scale(1.0 / n)) } else { None }
        };
        let fov = |n: Vec2| match heading {
            Some(e) => p.anisotropy + (1.0 - p.anisotropy) * 0.5 * (1.0 - e.dot(n)),
            None => 1.0,
        };
        let people = &self.people;
        self.hash.for_each_near(me.position, reach + ctx.slack, |j| {
            if j == i {
                return;
            }
            let n = me.position - people[j].position;
            let d2 = n.dot(n);
            if d2 >= reach * reach || d2 <= 1e-24 {
                return;
            }
            let d = d2.sqrt();
            let u = n.scale(1.0 / d);
            let mag = p.person_repulsion_mps2 * ((2.0 * r - d) / p.person_range_m).exp();
            force = force + u.scale(mag * fov(u));
        });
        // People who came to see the robot do not shy away from it.
        if let Some((c, rr)) = ctx.robot
            && !me.activity.with_robot()
        {
            let n = me.position - c;
            let d = norm(n);
            if d > 1e-12 && d < r + rr + FORCE_CUTOFF_RANGES * p.person_range_m {
                let u = n.scale(1.0 / d);
                let mag = p.robot_repulsion_mps2 * ((r + rr - d) / p.person_range_m).exp();
                force = force + u.scale(mag * fov(u));
            }
        }
        // Walls (the free radius, one look-up, rules most people out).
        let field = ctx.world.distance_field();
        if field.free_radius_m(me.position) < ctx.wall_reach {
            let wall = field.nearest(me.position);
            if wall.distance_m > 1e-12 && wall.distance_m < ctx.wall_reach {
                let u = (me.position - wall.point).scale(1.0 / wall.distance_m);
                let mag = p.wall_repulsion_mps2 * ((r - wall.distance_m) / p.wall_range_m).exp();
                force = force + u.scale(mag);
            }
        }
        force
    }

    /// Integrates person `i` (`me`) under `force` for one step, the speed
    /// capped, without interpenetration (a blocked move stops them).
    fn integrate(&self, ctx: &StepContext<'_>, i: usize, me: &mut Person, force: Vec2) {
        let (p, r, dt_s) = (ctx.p, ctx.r, ctx.dt_s);
        let field = ctx.world.distance_field();
        let mut v = me.velocity + force.scale(dt_s);
        let vmax = MAX_SPEED_RATIO * me.preferred_speed_mps;
        let speed = norm(v);
        if speed > vmax {
            v = v.scale(vmax / speed);
        }
        let next = me.position + v.scale(dt_s);
        let mut free = field.free_radius_m(next) >= r || field.distance_m(next) >= r;
        if let Some((c, rr)) = ctx.robot {
            // Not closer than the clearance, unless already closer and
            // moving away.
            let keep = r + rr + p.robot_clearance_m;
            let d = dist(next, c);
            free &= d >= keep || d > dist(me.position, c);
        }
        if free {
            let people = &self.people;
            let contact2 = 4.0 * r * r;
            self.hash.for_each_near(next, 2.0 * r + ctx.slack, |j| {
                let n = people[j].position - next;
                if j != i && n.dot(n) < contact2 {
                    free = false;
                }
            });
        }
        if free {
            me.position = next;
            me.velocity = v;
        } else {
            me.velocity = Vec2::default();
        }
    }
}

/// What every person's part of one [`Crowd::step`] shares: the world, the
/// robot, the time and the step's derived distances.
struct StepContext<'a> {
    world: &'a World,
    p: &'a CrowdParams,
    /// The robot's footprint `(centre, radius)`, if any.
    robot: Option<(Vec2, f64)>,
    /// The time at the end of the step, seconds.
    time_s: f64,
    /// The step, seconds.
    dt_s: f64,
    /// A person's radius, metres.
    r: f64,
    /// Range beyond which people do not push each other, metres.
    reach: f64,
    /// How far people move at most in a step, twice, metres.
    slack: f64,
    /// Range beyond which walls do not push, metres.
    wall_reach: f64,
    /// Probability that a person takes an interest in the robot in this step.
    interest: f64,
}

/// The velocity a person wants: along the route or at the target while
/// walking, at the robot's spot when coming to it, back to the gather
/// distance at the robot, none while lingering.
fn desired_velocity(world: &World, p: &CrowdParams, me: &Person) -> Vec2 {
    match me.activity {
        Activity::Walking { .. } => {
            // Far from the exhibit: follow the route; near it (or
            // wandering): straight at the target.
            let routed = me.waypoint.and_then(|k| {
                (world.routes().distance_m(k, me.position) > p.gather_radius_m + ROUTE_BEYOND_GATHER_M)
                    .then(|| world.routes().direction(k, me.position))
                    .flatten()
            });
            let to = me.target - me.position;
            let d = norm(to);
            match routed {
                Some(u) => u.scale(me.preferred_speed_mps),
                None if d > 1e-9 => to.scale(me.preferred_speed_mps / d),
                None => Vec2::default(),
            }
        }
        Activity::Lingering { .. } => Vec2::default(),
        Activity::ComingToRobot { .. } => {
            let to = me.target - me.position;
            let d = norm(to);
            if d > 1e-9 {
                to.scale(me.preferred_speed_mps / d)
            } else {
                Vec2::default()
            }
        }
        Activity::AtRobot { .. } => {
            // Back to the gather distance (either way), the faster
            // the farther, at most at the preferred speed.
            let to = me.target - me.position;
            let d = norm(to);
            if d > 1e-9 {
                let speed = (d / p.relaxation_time_s).min(me.preferred_speed_mps);
                to.scale(speed / d)
            } else {
                Vec2::default()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd_params::CrowdSize;
    use crate::grid::{Cell, CellIndex, OccupancyGrid};
    use robot::Pose;

    fn room() -> World {
        // 10 m × 6 m, walls around, a pillar in the middle.
        let mut g = OccupancyGrid::new(200, 120, 0.05, Pose::default());
        for i in 0..200 {
            g.set(CellIndex { i, j: 0 }, Cell::Occupied);
            g.set(CellIndex { i, j: 119 }, Cell::Occupied);
        }
        for j in 0..120 {
            g.set(CellIndex { i: 0, j }, Cell::Occupied);
            g.set(CellIndex { i: 199, j }, Cell::Occupied);
        }
        for j in 50..70 {
            for i in 90..110 {
                g.set(CellIndex { i, j }, Cell::Occupied);
            }
        }
        World::new(g)
    }

    #[test]
    fn density_gives_the_count_and_placement_is_free() {
        let w = room()
            .with_crowd(CrowdParams {
                size: CrowdSize::PerArea {
                    people_per_100m2: 30.0,
                },
                ..CrowdParams::default()
            })
            .unwrap();
        let c = Crowd::new(&w, 1, &[(Vec2::new(2.0, 3.0), 0.3)]).unwrap();
        let expected = (30.0 * w.free_area_m2() / 100.0).round() as usize;
        assert_eq!(c.people().len(), expected);
        for (k, a) in c.people().iter().enumerate() {
            assert!(!w.grid().disc_blocked(a.position, 0.25));
            assert!(a.position.dist(Vec2::new(2.0, 3.0)) >= 0.25 + 0.3 + 1.0);
            for b in &c.people()[k + 1..] {
                assert!(a.position.dist(b.position) >= 0.5);
            }
        }
    }

    #[test]
    fn walking_never_overlaps_and_people_move() {
        let w = room()
            .with_crowd(CrowdParams {
                size: CrowdSize::Count { people: 40 },
                waypoints: vec![Vec2::new(2.0, 2.0), Vec2::new(8.0, 4.0), Vec2::new(5.0, 5.0)],
                linger_mean_s: 3.0,
                ..CrowdParams::default()
            })
            .unwrap();
        let robot = (Vec2::new(1.0, 1.0), 0.2);
        let mut c = Crowd::new(&w, 2, &[robot]).unwrap();
        let start: Vec<Vec2> = c.people().iter().map(|q| q.position).collect();
        for t in 1..=600 {
            c.step(&w, Some(robot), t as f64 * 0.1, 0.1);
            for (k, a) in c.people().iter().enumerate() {
                assert!(
                    w.distance_field().distance_m(a.position) >= 0.25 - 1e-9,
                    "person {k} in a wall"
                );
                assert!(a.position.dist(robot.0) >= 0.45 - 1e-9);
                for b in &c.people()[k + 1..] {
                    assert!(a.position.dist(b.position) >= 0.5 - 1e-9);
                }
            }
        }
        let moved = c
            .people()
            .iter()
            .zip(&start)
            .filter(|(a, s)| a.position.dist(**s) > 1.0)
            .count();
        assert!(moved > 20, "only {moved} people moved");
    }

    #[test]
    fn people_find_the_door_to_an_exhibit() {
        // A wall across the room at x = 3 m with a 1 m door near the top.
        let mut g = OccupancyGrid::new(200, 120, 0.05, Pose::default());
        for j in 0..100 {
            for i in 58..62 {
                g.set(CellIndex { i, j }, Cell::Occupied);
            }
        }
        let w = World::new(g)
            .with_crowd(CrowdParams {
                positions: vec![Vec2::new(1.0, 1.0), Vec2::new(1.0, 2.0)],
                waypoints: vec![Vec2::new(8.0, 1.0)],
                gather_radius_m: 0.5,
                linger_probability: 0.0,
                ..CrowdParams::default()
            })
            .unwrap();
        let mut c = Crowd::new(&w, 4, &[]).unwrap();
        let mut nearest = [f64::INFINITY; 2];
        for t in 1..=400 {
            c.step(&w, None, t as f64 * 0.1, 0.1);
            for (k, q) in c.people().iter().enumerate() {
                nearest[k] = nearest[k].min(dist(q.position, Vec2::new(8.0, 1.0)));
            }
        }
        // Straight at it they would press against the wall for ever.
        assert!(nearest.iter().all(|&d| d < 1.0), "{nearest:?}");
    }

    #[test]
    fn people_asked_to_step_aside_leave_the_radius_after_their_delay() {
        // Eight people lingering for ever around a robot in the open,
        // pushed by nothing.
        let around: Vec<Vec2> = (0..8)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 8.0;
                Vec2::new(3.0, 3.0) + Vec2::new(a.cos(), a.sin()).scale(0.9)
            })
            .collect();
        let w = room()
            .with_crowd(CrowdParams {
                positions: around.clone(),
                linger_probability: 1.0,
                linger_mean_s: 1e9,
                person_repulsion_mps2: 0.0,
                robot_repulsion_mps2: 0.0,
                ..CrowdParams::default()
            })
            .unwrap();
        let robot = (Vec2::new(3.0, 3.0), 0.3);
        let mut c = Crowd::new(&w, 7, &[robot]).unwrap();
        // Nobody moves on their own.
        for t in 1..=20 {
            c.step(&w, Some(robot), t as f64 * 0.1, 0.1);
        }
        let near = |c: &Crowd| {
            c.people()
                .iter()
                .filter(|q| q.position.dist(robot.0) < 1.5)
                .count()
        };
        assert_eq!(near(&c), 8);
        assert_eq!(c.ask_to_step_aside(&w, robot.0, 1.2, 2.0), 8);
        assert_eq!(c.ask_to_step_aside(&w, robot.0, 1.2, 2.0), 0, "asked once");
        // Within half the mean delay nobody has reacted yet.
        for t in 21..=24 {
            c.step(&w, Some(robot), t as f64 * 0.1, 0.1);
        }
        assert_eq!(near(&c), 8);
        for t in 25..=120 {
            c.step(&w, Some(robot), t as f64 * 0.1, 0.1);
        }
        assert!(near(&c) <= 1, "{} people still near the robot", near(&c));
        // Bad radii ask nobody; compliance 0 ignores the robot.
        assert_eq!(c.ask_to_step_aside(&w, robot.0, f64::NAN, 13.0), 0);
        let w0 = room()
            .with_crowd(CrowdParams {
                positions: around,
                step_aside_compliance: 0.0,
                ..CrowdParams::default()
            })
            .unwrap();
        let mut c0 = Crowd::new(&w0, 7, &[robot]).unwrap();
        assert_eq!(c0.ask_to_step_aside(&w0, robot.0, 1.2, 0.0), 0);
    }

    /// FNV-1a over the bits of every person's position, velocity and
    /// target after each of 600 steps: scenario `exhibits` (40 people
    /// between three exhibits, a robot standing by) or `wanderers` (30
    /// people wandering around a robot driving a circle, who ask the people
    /// near it to step aside at 20 s).
    fn trajectory_hash(scenario: &str) -> u64 {
        let exhibits = scenario == "exhibits";
        let w = room()
            .with_crowd(CrowdParams {
                size: CrowdSize::Count {
                    people: if exhibits { 40 } else { 30 },
                },
                waypoints: if exhibits {
                    vec![Vec2::new(2.0, 2.0), Vec2::new(8.0, 4.0), Vec2::new(5.0, 5.0)]
                } else {
                    Vec::new()
                },
                linger_mean_s: 3.0,
                ..CrowdParams::default()
            })
            .unwrap();
        let robot_at = |t: f64| {
            if exhibits {
                Vec2::new(1.0, 1.0)
            } else {
                Vec2::new(2.5 + (0.2 * t).cos(), 3.0 + (0.2 * t).sin())
            }
        };
        let mut c = Crowd::new(&w, 2, &[(robot_at(0.0), 0.2)]).unwrap();
        let mut hash = 0xcbf2_9ce4_8422_2325_u64;
        let mut eat = |x: f64| {
            for b in x.to_bits().to_le_bytes() {
                hash = (hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
            }
        };
        for t in 1..=600 {
            let time_s = t as f64 * 0.1;
            if !exhibits && t == 200 {
                let asked = c.ask_to_step_aside(&w, robot_at(time_s), 1.5, time_s);
                assert!(asked > 0, "nobody near the robot to ask");
            }
            c.step(&w, Some((robot_at(time_s), 0.2)), time_s, 0.1);
            for q in c.people() {
                for x in [q.position, q.velocity, q.target] {
                    eat(x.x);
                    eat(x.y);
                }
            }
        }
        hash
    }

    /// Golden values recorded on the code before the robot could draw
    /// visitors (x86_64 Linux, glibc 2.36: `exp`, `sin`, `cos`, `atan2`
    /// and `ln` come from the platform's maths library, so other platforms
    /// may round differently). With the interest rate at its default 0
    /// the crowd must move exactly as it did.
    #[test]
    #[cfg(all(target_arch = "x86_64", target_os = "linux"))]
    fn crowd_trajectories_are_those_recorded_before_visitors() {
        assert_eq!(trajectory_hash("exhibits"), 7_435_467_198_821_824_746, "exhibits");
        assert_eq!(
            trajectory_hash("wanderers"),
            8_967_712_204_152_860_570,
            "wanderers"
        );
    }

    /// The room with `people` people (and the people at `positions`)
    /// walking between two exhibits, who take an interest in a robot
    /// within `range_m` at `rate_per_s` and stand by it for
    /// `linger_mean_s` on average.
    fn visitors(
        people: usize,
        positions: Vec<Vec2>,
        rate_per_s: f64,
        range_m: f64,
        linger_mean_s: f64,
    ) -> World {
        room()
            .with_crowd(CrowdParams {
                size: CrowdSize::Count { people },
                positions,
                waypoints: vec![Vec2::new(8.5, 1.0), Vec2::new(8.5, 5.0)],
                robot_interest_rate_per_s: rate_per_s,
                robot_interest_range_m: range_m,
                robot_linger_mean_s: linger_mean_s,
                ..CrowdParams::default()
            })
            .unwrap()
    }

    #[test]
    fn visitors_come_from_within_range_and_lose_interest_out_of_it() {
        let w = visitors(20, Vec::new(), 1.0, 3.0, 1e9);
        let a = (Vec2::new(2.5, 3.0), 0.3);
        let mut c = Crowd::new(&w, 5, &[a]).unwrap();
        let mut came = 0;
        for t in 1..=300 {
            let before: Vec<Person> = c.people().to_vec();
            c.step(&w, Some(a), t as f64 * 0.1, 0.1);
            for (q, was) in c.people().iter().zip(&before) {
                if q.activity.with_robot() && !was.activity.with_robot() {
                    came += 1;
                    assert!(dist(was.position, a.0) <= 3.0, "came from {:?}", was.position);
                }
            }
        }
        let with = |c: &Crowd| c.people().iter().filter(|q| q.activity.with_robot()).count();
        assert!(
            came >= 5 && with(&c) >= 5,
            "{came} came, {} with the robot",
            with(&c)
        );
        // The robot moves 6 m away: out of everybody's range, they go about
        // their business (a new exhibit).
        let b = (Vec2::new(8.5, 3.0), 0.3);
        let mut away = c.clone();
        away.step(&w, Some(b), 30.1, 0.1);
        for (q, was) in away.people().iter().zip(c.people()) {
            if was.activity.with_robot() && dist(q.position, b.0) > 3.0 {
                assert!(matches!(q.activity, Activity::Walking { .. }) && q.waypoint.is_some());
            }
        }
        // Without a robot, nobody is with it.
        c.step(&w, None, 30.1, 0.1);
        assert_eq!(with(&c), 0);
    }

    #[test]
    fn visitors_of_a_big_robot_stand_just_outside_its_clearance() {
        // 0.9 m from the centre of a robot of radius 0.8 m would be inside
        // it: they stand at 0.25 + 0.8 + 0.1 + 0.05 = 1.2 m.
        let w = visitors(10, Vec::new(), 1.0, 8.0, 1e9);
        let robot = (Vec2::new(2.5, 3.0), 0.8);
        let mut c = Crowd::new(&w, 6, &[robot]).unwrap();
        for t in 1..=300 {
            c.step(&w, Some(robot), t as f64 * 0.1, 0.1);
        }
        let standing: Vec<f64> = c
            .people()
            .iter()
            .filter(|q| matches!(q.activity, Activity::AtRobot { .. }))
            .map(|q| dist(q.position, robot.0))
            .collect();
        assert!(standing.len() >= 4, "{standing:?}");
        assert!(
            standing.iter().all(|&d| (1.15 - 1e-9..1.5).contains(&d)),
            "{standing:?}"
        );
    }

    #[test]
    fn a_visitor_leaves_for_an_exhibit_when_their_time_is_up() {
        let w = visitors(0, vec![Vec2::new(1.0, 1.0)], 5.0, 8.0, 2.0);
        let robot = (Vec2::new(2.5, 3.0), 0.3);
        let mut c = Crowd::new(&w, 8, &[robot]).unwrap();
        let mut t = 0;
        let until_s = loop {
            t += 1;
            assert!(t < 100, "never came");
            c.step(&w, Some(robot), t as f64 * 0.1, 0.1);
            if let Activity::AtRobot { until_s } = c.people()[0].activity {
                break until_s;
            }
        };
        assert!(dist(c.people()[0].position, robot.0) <= 1.0);
        // From now on nobody takes an interest: they leave when due, for
        // an exhibit, and walk away.
        let off = w
            .clone()
            .with_crowd(CrowdParams {
                robot_interest_rate_per_s: 0.0,
                ..w.crowd().clone()
            })
            .unwrap();
        while c.people()[0].activity.with_robot() {
            t += 1;
            c.step(&off, Some(robot), t as f64 * 0.1, 0.1);
        }
        let left_s = t as f64 * 0.1;
        assert!(
            left_s >= until_s && left_s < until_s + 0.1,
            "left at {left_s} s, due at {until_s} s"
        );
        assert!(c.people()[0].waypoint.is_some());
        for k in 1..=100 {
            c.step(&off, Some(robot), (t + k) as f64 * 0.1, 0.1);
        }
        assert!(dist(c.people()[0].position, robot.0) > 3.0);
    }

    #[test]
    fn bad_visitor_parameters_are_errors_naming_them() {
        let set = |field: &str, v: f64| {
            let mut p = CrowdParams::default();
            match field {
                "robot_interest_rate_per_s" => p.robot_interest_rate_per_s = v,
                "robot_interest_range_m" => p.robot_interest_range_m = v,
                "robot_gather_distance_m" => p.robot_gather_distance_m = v,
                _ => p.robot_linger_mean_s = v,
            }
            p
        };
        for field in [
            "robot_interest_rate_per_s",
            "robot_interest_range_m",
            "robot_gather_distance_m",
            "robot_linger_mean_s",
        ] {
            for v in [-1.0, f64::NAN, f64::INFINITY] {
                match set(field, v).validate() {
                    Err(Error::InvalidValue { what, .. }) => assert_eq!(what, format!("crowd.{field}")),
                    other => panic!("{field} = {v}: {other:?}"),
                }
            }
            assert!(set(field, 0.0).validate().is_ok());
        }
        assert_eq!(
            CrowdParams::default().robot_interest_rate_per_s,
            0.0,
            "off by default"
        );
    }

    #[test]
    fn a_surrounding_group_is_the_nearest_who_can_come_and_ignores_requests_until_its_time() {
        // Nearest first: B 1.5 m, A 1.6, D 1.7, C 1.8, F 4.9; E (5.5 m)
        // has the pillar between it and the robot.
        let positions = vec![
            Vec2::new(2.5, 4.6),
            Vec2::new(1.0, 3.0),
            Vec2::new(2.5, 1.2),
            Vec2::new(4.2, 3.0),
            Vec2::new(8.0, 3.0),
            Vec2::new(7.0, 5.0),
        ];
        let w = room()
            .with_crowd(CrowdParams {
                positions,
                ..CrowdParams::default()
            })
            .unwrap();
        let robot = (Vec2::new(2.5, 3.0), 0.3);
        let mut c = Crowd::new(&w, 4, &[robot]).unwrap();
        assert!(c.people().iter().all(|q| q.curious_until_s.is_none()));
        assert_eq!(c.surround(&w, robot, 3, 6.0, 0.0, 25.0), vec![1, 0, 3]);
        let mut d = Crowd::new(&w, 4, &[robot]).unwrap();
        assert_eq!(d.surround(&w, robot, 10, 6.0, 0.0, 25.0), vec![1, 0, 3, 2, 5]);
        assert_eq!(
            d.surround(&w, robot, 10, 1.55, 0.0, 25.0),
            Vec::<usize>::new(),
            "already curious"
        );
        let mut near = Vec::new();
        // Rim to rim: B 0.95 m, A 1.05, D 1.15, C 1.25, F 4.4, E 4.95.
        d.within_gap(robot.0, robot.1, 1.0, &mut near);
        assert_eq!(near, vec![1]);
        d.within_gap(robot.0, robot.1, 1.3, &mut near);
        assert_eq!(near, vec![0, 1, 2, 3], "ascending");
        let came = [0, 1, 2, 3, 5];
        for t in 1..=200 {
            d.step(&w, Some(robot), t as f64 * 0.1, 0.1);
        }
        // At 20 s they all stand round the robot, and a request to step
        // aside asks nobody.
        for &k in &came {
            let q = d.people()[k];
            assert_eq!(q.activity, Activity::AtRobot { until_s: 25.0 }, "person {k}");
            assert!(dist(q.position, robot.0) <= 1.0, "person {k} at {:?}", q.position);
            assert_eq!(q.curious_until_s, Some(25.0));
        }
        assert_eq!(d.people()[4].curious_until_s, None);
        assert_eq!(d.ask_to_step_aside(&w, robot.0, 2.0, 20.0), 0);
        for t in 201..=249 {
            d.step(&w, Some(robot), t as f64 * 0.1, 0.1);
        }
        assert!(came.iter().all(|&k| d.people()[k].activity.with_robot()));
        // Their time is up: they go about their business, and can be
        // asked again.
        d.step(&w, Some(robot), 25.0, 0.1);
        for &k in &came {
            let q = d.people()[k];
            assert!(
                !q.activity.with_robot() && q.curious_until_s.is_none(),
                "person {k}: {q:?}"
            );
        }
        assert!(d.ask_to_step_aside(&w, robot.0, 2.0, 25.0) >= 4);
        // A group whose time is up before they arrive goes all the same.
        let mut e = Crowd::new(&w, 4, &[robot]).unwrap();
        assert_eq!(e.surround(&w, robot, 5, 6.0, 0.0, 1.0), vec![1, 0, 3, 2, 5]);
        for t in 1..=10 {
            e.step(&w, Some(robot), t as f64 * 0.1, 0.1);
        }
        let far = e.people()[5];
        assert!(dist(far.position, robot.0) > 2.0, "{far:?}");
        assert!(
            !far.activity.with_robot() && far.curious_until_s.is_none(),
            "{far:?}"
        );
    }

    #[test]
    fn too_many_people_is_an_error() {
        let w = room()
            .with_crowd(CrowdParams {
                size: CrowdSize::Count { people: 1000 },
                ..CrowdParams::default()
            })
            .unwrap();
        assert!(matches!(Crowd::new(&w, 1, &[]), Err(Error::InvalidValue { .. })));
        for size in [
            CrowdSize::Count { people: usize::MAX },
            CrowdSize::PerArea {
                people_per_100m2: 1e300,
            },
        ] {
            let w = room()
                .with_crowd(CrowdParams {
                    size,
                    ..CrowdParams::default()
                })
                .unwrap();
            assert!(matches!(Crowd::new(&w, 1, &[]), Err(Error::InvalidValue { .. })));
        }
        let bad = CrowdParams {
            radius_m: -1.0,
            ..CrowdParams::default()
        };
        assert!(matches!(room().with_crowd(bad), Err(Error::InvalidValue { .. })));
    }
}
