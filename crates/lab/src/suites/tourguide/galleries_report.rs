//! The galleries' part of the tour-guide report: the gate — the fixed
//! strategies' tour costs and the hindsight oracle's, leg by leg — then the
//! learners against the best fixed strategy, with intervals clustered by
//! campaign ([`crate::stats::Clustered`]: the legs of a campaign share one
//! learner and one day's visitors).
//!
//! **Tour cost**: the sum of a tour's leg times, a leg that did not reach
//! its stop costing the time limit ([`galleries::leg_cost_s`]). **The
//! hindsight oracle**: per leg, the cheapest of the fixed strategies on
//! that leg (same seed: common random numbers) — a ceiling no strategy that
//! chooses before the leg can reach, since it also picks the luckier of
//! runs that differ by chance. **Headroom**: how much cheaper the oracle's
//! tours are than the best single fixed strategy's (the one of least mean
//! tour cost), and how many more legs it reaches.

use std::fmt::Write as _;

use crate::page::Block;
use crate::record::{RunRecord, Runs};
use crate::stats::Clustered;
use crate::summary::CONFIDENCE;

use super::galleries::{self, CAMPAIGN_LEGS, CONDITION, FIXED, LEGS, TOURS};

/// Headroom below which (in tour cost, and in the share of legs reached)
/// the building does not show that the answer depends on the place: the
/// issue's gate.
pub const GATE_COST: f64 = 0.10;

/// See [`GATE_COST`].
pub const GATE_SUCCESS: f64 = 0.08;

/// A strategy's legs: `legs[c][k]`, campaign `c`, leg `k` of the day.
struct Legs<'a> {
    legs: Vec<Vec<Option<&'a RunRecord>>>,
}

impl<'a> Legs<'a> {
    fn of(runs: &'a Runs, strategy: &str, campaigns: u32) -> Legs<'a> {
        let mut legs = vec![vec![None; CAMPAIGN_LEGS as usize]; campaigns as usize];
        for (run, r) in runs
            .get(&format!("{CONDITION}/{strategy}"))
            .map(Vec::as_slice)
            .unwrap_or_default()
        {
            let (c, k) = ((run / CAMPAIGN_LEGS) as usize, (run % CAMPAIGN_LEGS) as usize);
            if c < legs.len() {
                legs[c][k] = Some(r);
            }
        }
        Legs { legs }
    }

    fn get(&self, c: usize, k: usize) -> Option<&'a RunRecord> {
        self.legs.get(c).and_then(|l| l[k])
    }
}

/// The fixed strategies' legs and the campaigns complete for all of them.
struct Table<'a> {
    fixed: Vec<Legs<'a>>,
    campaigns: usize,
}

impl<'a> Table<'a> {
    fn new(runs: &'a Runs, campaigns: u32) -> Table<'a> {
        let fixed: Vec<Legs<'a>> = FIXED.iter().map(|s| Legs::of(runs, s, campaigns)).collect();
        // Campaigns every fixed strategy finished.
        let complete = (0..campaigns as usize)
            .take_while(|&c| {
                fixed
                    .iter()
                    .all(|l| (0..CAMPAIGN_LEGS as usize).all(|k| l.get(c, k).is_some()))
            })
            .count();
        Table {
            fixed,
            campaigns: complete,
        }
    }

    /// The oracle's leg: the cheapest fixed strategy's index, its cost,
    /// whether any reached.
    fn oracle(&self, c: usize, k: usize) -> (usize, f64, bool) {
        let mut best = (0, f64::INFINITY);
        let mut any = false;
        for (s, l) in self.fixed.iter().enumerate() {
            let r = l.get(c, k).expect("complete campaign");
            let cost = galleries::leg_cost_s(r);
            if cost < best.1 {
                best = (s, cost);
            }
            any |= r.success;
        }
        (best.0, best.1, any)
    }
}

/// Per campaign, one value per tour (costs) or per leg (reached).
pub type ByCampaign = Vec<Vec<f64>>;

/// A strategy's tour costs and legs reached (1 or 0 per leg), by campaign.
pub struct Measured {
    /// Tour costs, seconds.
    pub cost: ByCampaign,
    /// Legs reached.
    pub reached: ByCampaign,
}

/// Tour costs per campaign, from leg costs.
fn tour_costs(costs: impl Fn(usize, usize) -> f64, campaigns: usize) -> ByCampaign {
    (0..campaigns)
        .map(|c| {
            (0..TOURS as usize)
                .map(|t| (0..LEGS as usize).map(|j| costs(c, t * LEGS as usize + j)).sum())
                .collect()
        })
        .collect()
}

fn mean(v: &[Vec<f64>]) -> f64 {
    let n: usize = v.iter().map(Vec::len).sum();
    v.iter().flatten().sum::<f64>() / n.max(1) as f64
}

/// What the gate measured.
pub struct Gate {
    /// Campaigns complete for every fixed strategy.
    pub campaigns: usize,
    /// Per fixed strategy.
    pub strategies: Vec<Measured>,
    /// The oracle's.
    pub oracle: Measured,
    /// The best fixed strategy (least mean tour cost), an index in [`FIXED`].
    pub best: usize,
    /// Relative headroom in tour cost, per tour: `(best − oracle) / best`,
    /// clustered by campaign.
    pub headroom_cost: Clustered,
    /// Headroom in the share of legs reached (oracle − best), clustered.
    pub headroom_success: Clustered,
    /// Per leg of the tour: each fixed strategy's mean cost, the oracle's,
    /// and how often the oracle chose each strategy.
    pub per_leg: Vec<(Vec<f64>, f64, Vec<usize>)>,
}

impl Gate {
    /// Whether the building passes: headroom at least [`GATE_COST`] in
    /// tour cost or [`GATE_SUCCESS`] in legs reached.
    pub fn passes(&self) -> bool {
        self.headroom_cost.mean >= GATE_COST || self.headroom_success.mean >= GATE_SUCCESS
    }
}

/// The gate from the fixed strategies' records; `None` until one campaign
/// is complete for all of them.
pub fn gate(runs: &Runs, campaigns: u32) -> Option<Gate> {
    let table = Table::new(runs, campaigns);
    let n = table.campaigns;
    if n == 0 {
        return None;
    }
    let reached = |legs: &dyn Fn(usize, usize) -> bool| -> ByCampaign {
        (0..n)
            .map(|c| {
                (0..CAMPAIGN_LEGS as usize)
                    .map(|k| f64::from(u8::from(legs(c, k))))
                    .collect()
            })
            .collect()
    };
    let strategies: Vec<Measured> = table
        .fixed
        .iter()
        .map(|l| Measured {
            cost: tour_costs(|c, k| galleries::leg_cost_s(l.get(c, k).expect("complete")), n),
            reached: reached(&|c, k| l.get(c, k).expect("complete").success),
        })
        .collect();
    let oracle = Measured {
        cost: tour_costs(|c, k| table.oracle(c, k).1, n),
        reached: reached(&|c, k| table.oracle(c, k).2),
    };
    let best = (0..FIXED.len())
        .min_by(|&a, &b| mean(&strategies[a].cost).total_cmp(&mean(&strategies[b].cost)))
        .unwrap_or(0);
    let rel: ByCampaign = strategies[best]
        .cost
        .iter()
        .zip(&oracle.cost)
        .map(|(b, o)| b.iter().zip(o).map(|(b, o)| (b - o) / b).collect())
        .collect();
    let more: ByCampaign = strategies[best]
        .reached
        .iter()
        .zip(&oracle.reached)
        .map(|(b, o)| b.iter().zip(o).map(|(b, o)| o - b).collect())
        .collect();
    let per_leg = (0..LEGS as usize)
        .map(|j| {
            let ks = || (0..n).flat_map(|c| (0..TOURS as usize).map(move |t| (c, t * LEGS as usize + j)));
            let count = (n * TOURS as usize) as f64;
            let means = table
                .fixed
                .iter()
                .map(|l| {
                    ks().map(|(c, k)| galleries::leg_cost_s(l.get(c, k).expect("complete")))
                        .sum::<f64>()
                        / count
                })
                .collect();
            let oracle_mean = ks().map(|(c, k)| table.oracle(c, k).1).sum::<f64>() / count;
            let mut chosen = vec![0; FIXED.len()];
            for (c, k) in ks() {
                chosen[table.oracle(c, k).0] += 1;
            }
            (means, oracle_mean, chosen)
        })
        .collect();
    Some(Gate {
        campaigns: n,
        headroom_cost: Clustered::new(&rel, CONFIDENCE),
        headroom_success: Clustered::new(&more, CONFIDENCE),
        strategies,
        oracle,
        best,
        per_leg,
    })
}

/// The report's blocks for the galleries.
pub fn blocks(runs: &Runs, campaigns: u32) -> Vec<Block> {
    let mut blocks = vec![Block::Heading(
        "The galleries: where the answer depends on the place".into(),
    )];
    let Some(g) = gate(runs, campaigns) else {
        blocks.push(Block::Text(
            "No galleries campaign is complete for every fixed strategy yet.".into(),
        ));
        return blocks;
    };
    blocks.push(Block::Text(gate_text(&g)));
    blocks.push(Block::Table(gate_table(&g)));
    blocks.push(Block::Table(leg_table(&g)));
    blocks.push(Block::Heading("The galleries: do the learners pay?".into()));
    let learners: Vec<Learner> = LEARNERS
        .iter()
        .filter_map(|s| learner(runs, campaigns, s, &g))
        .collect();
    blocks.push(Block::Text(learners_text(&g, &learners)));
    if !learners.is_empty() {
        blocks.push(Block::Table(learners_table(&g, &learners)));
        blocks.push(Block::Table(choice_table(&g, &learners)));
    }
    blocks
}

/// The learners compared with the fixed strategies.
pub const LEARNERS: [&str; 2] = ["supervisor", "calibrate_then_commit"];

/// The tour from which the learners' choices are judged (from 0: the
/// ninth).
pub const LATE_TOUR: usize = 8;

/// Relative difference in tour cost below which the primary endpoint is
/// met (with the interval below zero): −10 %.
pub const PRIMARY_TARGET: f64 = -0.10;

/// A learner's figures.
pub struct Learner {
    /// Its name.
    pub name: &'static str,
    /// Tour costs by campaign.
    pub cost: ByCampaign,
    /// Per campaign, its mean tour cost relative to the best fixed
    /// strategy's, minus 1.
    pub vs_best: Clustered,
    /// Legs reached minus the best fixed strategy's, per leg, clustered.
    pub success_vs_best: Clustered,
    /// From the ninth tour on: the share of legs it started with the
    /// behaviour the oracle's strategy starts with.
    pub agreement_late: f64,
    /// From the ninth tour on: `(best − learner) / (best − oracle)` in
    /// tour cost.
    pub recovered_late: f64,
    /// Per leg of the tour: legs started with AutoMove and with contour
    /// tracking, from the ninth tour on.
    pub starts_late: Vec<[usize; 2]>,
}

/// The behaviour a leg's record started with: the start decision's choice
/// (the supervisor), else the behaviour of the first tick's label.
fn start_behaviour(r: &RunRecord, fallback: Option<usize>) -> Option<usize> {
    let decided = r
        .events
        .iter()
        .find(|e| e.kind == "decision" && e.text("reason") == Some("start"))
        .and_then(|e| e.text("choice"))
        .map(|c| usize::from(c == "contour"));
    decided.or(fallback)
}

/// The behaviour each fixed strategy starts a leg with (0 AutoMove, 1
/// contour tracking).
fn fixed_start(s: usize) -> usize {
    usize::from(FIXED[s] == "contour")
}

fn learner(runs: &Runs, campaigns: u32, name: &'static str, g: &Gate) -> Option<Learner> {
    let legs = Legs::of(runs, name, campaigns);
    let table = Table::new(runs, campaigns);
    let n = (0..g.campaigns)
        .take_while(|&c| (0..CAMPAIGN_LEGS as usize).all(|k| legs.get(c, k).is_some()))
        .count();
    if n == 0 {
        return None;
    }
    let rec = |c: usize, k: usize| legs.get(c, k).expect("complete campaign");
    let cost = tour_costs(|c, k| galleries::leg_cost_s(rec(c, k)), n);
    let best = &g.strategies[g.best];
    let rel: ByCampaign = (0..n)
        .map(|c| {
            let mine = cost[c].iter().sum::<f64>();
            let theirs = best.cost[c].iter().sum::<f64>();
            vec![mine / theirs - 1.0]
        })
        .collect();
    let success: ByCampaign = (0..n)
        .map(|c| {
            (0..CAMPAIGN_LEGS as usize)
                .map(|k| f64::from(u8::from(rec(c, k).success)) - best.reached[c][k])
                .collect()
        })
        .collect();
    let late_legs =
        || (0..n).flat_map(|c| (LATE_TOUR * LEGS as usize..CAMPAIGN_LEGS as usize).map(move |k| (c, k)));
    let mut agree = 0usize;
    let mut starts_late = vec![[0usize; 2]; LEGS as usize];
    let (mut mine, mut theirs, mut oracle) = (0.0, 0.0, 0.0);
    for (c, k) in late_legs() {
        let r = rec(c, k);
        let committed = (name == "calibrate_then_commit").then(|| {
            let earlier: Vec<RunRecord> = (0..k).map(|i| rec(c, i).clone()).collect();
            galleries::committed(&earlier, (k % LEGS as usize) as u32)
                .map(|b| usize::from(b == guide::supervisor::Behaviour::Contour))
                .unwrap_or(0)
        });
        let start = start_behaviour(r, committed).unwrap_or(0);
        starts_late[k % LEGS as usize][start] += 1;
        let (o, oc, _) = table.oracle(c, k);
        agree += usize::from(start == fixed_start(o));
        mine += galleries::leg_cost_s(r);
        theirs += galleries::leg_cost_s(g_fixed(&table, g.best, c, k));
        oracle += oc;
    }
    let late = late_legs().count().max(1);
    Some(Learner {
        name,
        vs_best: Clustered::new(&rel, CONFIDENCE),
        success_vs_best: Clustered::new(&success, CONFIDENCE),
        agreement_late: agree as f64 / late as f64,
        recovered_late: if theirs > oracle {
            (theirs - mine) / (theirs - oracle)
        } else {
            f64::NAN
        },
        starts_late,
        cost,
    })
}

fn g_fixed<'a>(table: &Table<'a>, s: usize, c: usize, k: usize) -> &'a RunRecord {
    table.fixed[s].get(c, k).expect("complete campaign")
}

fn learners_text(g: &Gate, learners: &[Learner]) -> String {
    let mut text = format!(
        "**Primary endpoint** (named before the numbers): the tour cost over the museum day — every tour of the campaign, the learner's calibration and exploration included — of the crediting supervisor relative to the best single fixed strategy (`{}`), mission by mission on the same draws; the 95 % interval is Student's t over the campaigns' relative differences (a campaign's legs share one learner and one day). Met if at most {} with the interval below zero, and legs reached not lower by more than 0.03 (paired, clustered).\n\n",
        FIXED[g.best],
        percent(PRIMARY_TARGET)
    );
    if learners.is_empty() {
        text.push_str("No learner's campaign is complete yet.\n");
    }
    for l in learners {
        let met =
            l.vs_best.mean <= PRIMARY_TARGET && l.vs_best.high() < 0.0 && l.success_vs_best.mean >= -0.03;
        let _ = writeln!(
            text,
            "- `{}`: tour cost **{}** ({} to {}) against `{}`, legs reached {}; from the ninth tour on it starts {} of legs as the oracle's strategy does and recovers {} of the oracle's headroom{}.",
            l.name,
            percent(l.vs_best.mean),
            percent(l.vs_best.low()),
            percent(l.vs_best.high()),
            FIXED[g.best],
            l.success_vs_best.signed(3),
            percent(l.agreement_late),
            percent(l.recovered_late),
            if l.name == "supervisor" {
                if met {
                    " — **the primary endpoint is met**"
                } else {
                    " — **the primary endpoint is not met**"
                }
            } else {
                ""
            }
        );
    }
    if let (Some(sup), Some(ctc)) = (
        learners.iter().find(|l| l.name == "supervisor"),
        learners.iter().find(|l| l.name == "calibrate_then_commit"),
    ) {
        let rel: ByCampaign = sup
            .cost
            .iter()
            .zip(&ctc.cost)
            .map(|(a, b)| vec![a.iter().sum::<f64>() / b.iter().sum::<f64>() - 1.0])
            .collect();
        let d = Clustered::new(&rel, CONFIDENCE);
        let _ = writeln!(
            text,
            "\nThe supervisor against calibrate-then-commit (per-route calibration, then the rule): tour cost {} ({} to {}). {}",
            percent(d.mean),
            percent(d.low()),
            percent(d.high()),
            if d.high() < 0.0 {
                "The supervisor is cheaper: learning per route and crowd, and the net's decisions within a leg, add something beyond per-route calibration here."
            } else if d.low() > 0.0 {
                "Calibrate-then-commit is cheaper: the supervisor's learning costs more than it returns here."
            } else {
                "No difference shown: here the net adds nothing measurable beyond per-route calibration."
            }
        );
    }
    text.push('\n');
    text
}

fn learners_table(g: &Gate, learners: &[Learner]) -> String {
    let mut md = String::from(
        "| strategy | mean tour cost (s) | vs the best fixed (95 % CI over campaigns) | legs reached vs the best fixed | oracle's start, tours 9–12 | headroom recovered, tours 9–12 |\n|---|---:|---|---|---:|---:|\n",
    );
    let _ = writeln!(
        md,
        "| {} (best fixed) | {:.1} | – | – | – | – |",
        FIXED[g.best],
        mean(&g.strategies[g.best].cost)
    );
    for l in learners {
        let _ = writeln!(
            md,
            "| {} | {:.1} | {} ({} to {}) | {} | {} | {} |",
            l.name,
            mean(&l.cost),
            percent(l.vs_best.mean),
            percent(l.vs_best.low()),
            percent(l.vs_best.high()),
            l.success_vs_best.signed(3),
            percent(l.agreement_late),
            percent(l.recovered_late)
        );
    }
    let _ = writeln!(
        md,
        "| hindsight oracle | {:.1} | – | – | – | 100 % |",
        mean(&g.oracle.cost)
    );
    md
}

fn choice_table(g: &Gate, learners: &[Learner]) -> String {
    let stops = galleries::galleries().map(|g| g.stops).unwrap_or_default();
    let mut md = String::from("| leg | oracle's start (AutoMove / contour), all tours |");
    for l in learners {
        let _ = write!(md, " {} starts, tours 9–12 |", l.name);
    }
    md.push_str("\n|---|---|");
    md.push_str(&"---|".repeat(learners.len()));
    md.push('\n');
    for (j, (_, _, chosen)) in g.per_leg.iter().enumerate() {
        let name = stops
            .get(j)
            .zip(stops.get(j + 1))
            .map_or(format!("leg {}", j + 1), |(a, b)| {
                galleries::route_name(&a.name, &b.name)
            });
        let mut o = [0usize; 2];
        for (s, n) in chosen.iter().enumerate() {
            o[fixed_start(s)] += n;
        }
        let _ = write!(md, "| {name} | {} / {} |", o[0], o[1]);
        for l in learners {
            let _ = write!(md, " {} / {} |", l.starts_late[j][0], l.starts_late[j][1]);
        }
        md.push('\n');
    }
    md
}

fn percent(x: f64) -> String {
    format!("{:.1} %", 100.0 * x)
}

fn gate_text(g: &Gate) -> String {
    let h = &g.headroom_cost;
    let s = &g.headroom_success;
    format!(
        "**The gate** (fixed strategies alone, {} campaigns of {TOURS} tours of {LEGS} legs, visitors {:?} by quarter of the day): the hindsight oracle — per leg, the cheapest fixed strategy on that leg's random numbers — against the best single fixed strategy, `{}`: tour cost **{} cheaper** ({} to {}, 95 % interval over campaigns), legs reached **{:+.3}** ({:+.3} to {:+.3}). The building {} the gate (at least {} in tour cost or {:+.2} in legs reached). Part of any oracle's headroom is luck — on legs where two strategies differ by chance it picks the luckier run — so the leg table below shows where the difference is systematic.\n\n",
        g.campaigns,
        galleries::VISITORS,
        FIXED[g.best],
        percent(h.mean),
        percent(h.low()),
        percent(h.high()),
        s.mean,
        s.low(),
        s.high(),
        if g.passes() {
            "**passes**"
        } else {
            "**does not pass**"
        },
        percent(GATE_COST),
        GATE_SUCCESS,
    )
}

fn gate_table(g: &Gate) -> String {
    let mut md = String::from("| strategy | mean tour cost (s) | legs reached |\n|---|---:|---:|\n");
    for (s, m) in g.strategies.iter().enumerate() {
        let _ = writeln!(
            md,
            "| {}{} | {:.1} | {:.3} |",
            FIXED[s],
            if s == g.best { " (best)" } else { "" },
            mean(&m.cost),
            mean(&m.reached)
        );
    }
    let _ = writeln!(
        md,
        "| hindsight oracle | {:.1} | {:.3} |",
        mean(&g.oracle.cost),
        mean(&g.oracle.reached)
    );
    md
}

fn leg_table(g: &Gate) -> String {
    let stops = galleries::galleries().map(|g| g.stops).unwrap_or_default();
    let name = |j: usize| {
        stops
            .get(j)
            .zip(stops.get(j + 1))
            .map_or(format!("leg {}", j + 1), |(a, b)| {
                galleries::route_name(&a.name, &b.name)
            })
    };
    let mut md = String::from("| leg | ");
    for s in FIXED {
        let _ = write!(md, "{s} (s) | ");
    }
    md.push_str("oracle (s) | oracle's choice |\n|---|");
    md.push_str(&"---:|".repeat(FIXED.len() + 1));
    md.push_str("---|\n");
    for (j, (means, oracle, chosen)) in g.per_leg.iter().enumerate() {
        let _ = write!(md, "| {} | ", name(j));
        for m in means {
            let _ = write!(md, "{m:.1} | ");
        }
        let choice: Vec<String> = chosen
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(s, n)| format!("{} {n}", FIXED[s]))
            .collect();
        let _ = writeln!(md, "{oracle:.1} | {} |", choice.join(", "));
    }
    md
}
