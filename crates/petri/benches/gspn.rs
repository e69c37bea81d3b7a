//! Performance of the GSPN engine (docs/gspn.md, *Performance*) on the
//! scalable families of [`petri::families`] and on the robot's supervisor net.
//!
//! Groups:
//! * `generate` — state-space generation ([`ReachabilityGraph::explore`]);
//!   throughput in markings/s (tangible and vanishing).
//! * `solve` — [`CompiledGspn::solve_rates`] on chains compiled beforehand:
//!   `auto` with the default [`SolveParams`] (GTH, sparse LU or BiCGSTAB by
//!   size), and each method forced on the same mid-size chains.
//! * `end_to_end` — instantiate → generate → compile → solve, Kanban N = 3, 4
//!   (N = 5, ~10 s per run, is `#[ignore]`d: see below).
//! * `supervisor_resolve` — the robot's decision: the supervisor net compiled
//!   once per hypothesis, re-solved for new λ3..λ10 at every iteration.
//! * `optimize` — nets with decisions: the `corridors` family's Markov
//!   automaton compiled once, `Pmax` and `Tmin` solved with sound value
//!   iteration (`DecisionNet::solve`); throughput in states/s.
//!
//! Divan reports times and throughputs only; the figures that describe each
//! input (markings, bytes per marking, entries, iterations, residual) are
//! computed once per input and printed to stderr after the tables.
//!
//! ```text
//! cargo bench -p petri --bench gspn                      # everything but Kanban 5, ~1.5 min
//! cargo bench -p petri --bench gspn -- gspn::solve       # one group (a regex on gspn::group::bench)
//! cargo bench -p petri --bench gspn -- --ignored         # Kanban 5 end to end, ~70 s
//! /usr/bin/time -v target/release/examples/family kanban 5   # its peak memory
//! ```
//!
//! Results and the machine they were measured on: `crates/petri/BENCHMARKS.md`.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use divan::Bencher;
use divan::counter::ItemsCount;
use petri::{
    CompiledGspn, ExploreParams, Gspn, Method, Net, Params, ReachabilityGraph, SolveParams, families,
};

fn main() {
    divan::main();
    let figures = FIGURES.lock().unwrap();
    if !figures.is_empty() {
        eprintln!("\nFigures (one run per input):");
        for (key, line) in figures.iter() {
            eprintln!("  {key:<38} {line}");
        }
    }
}

/// One line of figures per input, in the order the inputs were first met.
static FIGURES: Mutex<Vec<(String, String)>> = Mutex::new(Vec::new());

/// Records the figures of input `key` unless already recorded.
fn figure(key: String, line: impl FnOnce() -> String) {
    let mut figures = FIGURES.lock().unwrap();
    if !figures.iter().any(|(k, _)| *k == key) {
        let line = line();
        figures.push((key, line));
    }
}

/// A family member by name: `kanban 4`, `fms 5` (the GSPN variant),
/// `philosophers 8`, `robots 100` (N robots, 3 corridors).
fn net(input: &str) -> Net {
    let (family, n) = input.split_once(' ').expect("`family n`");
    let n: u32 = n.parse().expect("a size");
    match family {
        "kanban" => families::kanban(n),
        "fms" => families::fms(n, false),
        "philosophers" => families::philosophers(n),
        "robots" => families::robots_corridors(n, CORRIDORS),
        other => panic!("unknown family {other}"),
    }
}

/// Corridors of the `robots` inputs.
const CORRIDORS: u32 = 3;

fn instantiate(net: &Net) -> Gspn {
    net.instantiate(&Params::new()).unwrap()
}

/// No state limit: the default memory guard decides.
fn explore_params() -> ExploreParams {
    ExploreParams::default()
}

/// State-space generation. Throughput counts every marking found (tangible
/// and vanishing); bytes per marking are those of the packed store and its
/// hash table, edges not included.
mod generate {
    use super::*;

    fn bench(bencher: Bencher, input: &str) {
        let gspn = instantiate(&net(input));
        let rg = ReachabilityGraph::explore(&gspn, &explore_params()).unwrap();
        let st = rg.stats().clone();
        drop(rg);
        figure(format!("generate/{input}"), || {
            format!(
                "{} markings ({} tangible, {} vanishing), {} edges, {} word(s) and {:.1} B per marking",
                st.markings, st.tangible, st.vanishing, st.edges, st.words_per_marking, st.bytes_per_marking
            )
        });
        bencher
            .counter(ItemsCount::new(st.markings))
            .bench(|| ReachabilityGraph::explore(divan::black_box(&gspn), &explore_params()).unwrap());
    }

    /// 160 / 4,600 / 58,400 / 454,475 markings, no vanishing ones.
    #[divan::bench(args = ["kanban 1", "kanban 2", "kanban 3", "kanban 4"], max_time = 2)]
    fn kanban(bencher: Bencher, input: &str) {
        bench(bencher, input);
    }

    /// About 3/4 of the markings are vanishing.
    #[divan::bench(args = ["fms 1", "fms 2", "fms 3", "fms 4", "fms 5"], max_time = 2)]
    fn fms(bencher: Bencher, input: &str) {
        bench(bencher, input);
    }

    /// 3^N markings, all tangible.
    #[divan::bench(
        args = ["philosophers 5", "philosophers 6", "philosophers 7", "philosophers 8", "philosophers 9",
                "philosophers 10"],
        max_time = 2
    )]
    fn philosophers(bencher: Bencher, input: &str) {
        bench(bencher, input);
    }

    /// N robots, 3 corridors; the immediate choice of a corridor makes
    /// about 2/3 of the markings vanishing.
    #[divan::bench(args = ["robots 50", "robots 100", "robots 200", "robots 400"], max_time = 2)]
    fn robots_corridors(bencher: Bencher, input: &str) {
        bench(bencher, input);
    }
}

/// Compiled chains shared by the `solve` benchmarks (compiling Kanban 4 or
/// FMS 6 takes a second or two: once per input, not once per method).
static CHAINS: Mutex<Vec<(String, Arc<CompiledGspn>)>> = Mutex::new(Vec::new());

fn compiled(input: &str) -> Arc<CompiledGspn> {
    let mut chains = CHAINS.lock().unwrap();
    if let Some((_, c)) = chains.iter().find(|(k, _)| k == input) {
        return c.clone();
    }
    let gspn = instantiate(&net(input));
    let c = Arc::new(CompiledGspn::build(&gspn, &explore_params()).unwrap());
    chains.push((input.to_string(), c.clone()));
    c
}

/// Solving compiled chains for their rates. The solution (π, throughputs,
/// mean tokens) is computed in full, as a caller would get it.
mod solve {
    use super::*;

    fn bench(bencher: Bencher, input: &str, method: Method) {
        let chain = compiled(input);
        let rates = chain.gspn().rates(&Params::new(), None).unwrap();
        let params = SolveParams {
            method,
            ..SolveParams::default()
        };
        let sol = chain.solve_rates(&rates, &params).unwrap();
        let st = chain.stats();
        figure(format!("solve/{method:?}/{input}"), || {
            format!(
                "{} states, {} entries: {} {} iterations, residual {:.1e}",
                chain.num_tangible(),
                st.entries,
                sol.info.method,
                sol.info.iterations,
                sol.info.residual
            )
        });
        assert!(
            sol.info.residual <= 1e-10,
            "{input}: residual {}",
            sol.info.residual
        );
        bencher
            .counter(ItemsCount::new(chain.num_tangible()))
            .bench(|| chain.solve_rates(divan::black_box(&rates), &params).unwrap());
    }

    /// The default settings, as the CLI and the supervisor use them.
    #[divan::bench(
        args = ["kanban 1", "kanban 2", "kanban 3", "kanban 4", "fms 3", "fms 4", "fms 5", "fms 6"],
        max_time = 4
    )]
    fn auto(bencher: Bencher, input: &str) {
        bench(bencher, input, Method::Auto);
    }

    /// Mid-size chains, each method forced.
    const MID: [&str; 3] = ["kanban 3", "fms 4", "fms 5"];

    #[divan::bench(args = MID, max_time = 3)]
    fn bicgstab(bencher: Bencher, input: &str) {
        bench(bencher, input, Method::Bicgstab);
    }

    #[divan::bench(args = MID, max_time = 3)]
    fn gauss_seidel(bencher: Bencher, input: &str) {
        bench(bencher, input, Method::GaussSeidel);
    }

    /// Sparse LU, on chains small enough for it (on FMS 4, 35,910 states,
    /// it takes minutes). `auto` picks it up to 2,000 states.
    #[divan::bench(args = ["fms 2", "kanban 2", "fms 3"], max_time = 3)]
    fn direct(bencher: Bencher, input: &str) {
        bench(bencher, input, Method::Direct);
    }
}

/// Everything a user of a new model waits for: instantiate, generate,
/// compile and solve with the default settings.
mod end_to_end {
    use super::*;

    fn run(n: u32) -> petri::Solution {
        let gspn = families::kanban(n).instantiate(&Params::new()).unwrap();
        let chain = CompiledGspn::build(&gspn, &explore_params()).unwrap();
        chain
            .solve(&Params::new(), None, &SolveParams::default())
            .unwrap()
    }

    fn bench(bencher: Bencher, n: u32) {
        let gspn = families::kanban(n).instantiate(&Params::new()).unwrap();
        let chain = CompiledGspn::build(&gspn, &explore_params()).unwrap();
        let sol = chain
            .solve(&Params::new(), None, &SolveParams::default())
            .unwrap();
        let st = chain.stats();
        figure(format!("end_to_end/kanban {n}"), || {
            format!(
                "{} states: explore {:.3} s, compile {:.3} s, solve {:.3} s ({} {} it., residual {:.1e}), chain {:.0} MB",
                chain.num_tangible(),
                st.explore.seconds,
                st.compile_seconds,
                sol.info.seconds,
                sol.info.method,
                sol.info.iterations,
                sol.info.residual,
                chain.heap_bytes() as f64 / 1e6
            )
        });
        drop(chain);
        bencher
            .counter(ItemsCount::new(sol.pi.len()))
            .bench(|| run(divan::black_box(n)));
    }

    #[divan::bench(sample_count = 10, sample_size = 1)]
    fn kanban_3(bencher: Bencher) {
        bench(bencher, 3);
    }

    /// Target: under 2 s.
    #[divan::bench(sample_count = 5, sample_size = 1)]
    fn kanban_4(bencher: Bencher) {
        bench(bencher, 4);
    }

    /// Target: under 15 s (and 4 GiB: measure with `/usr/bin/time -v` on
    /// the `family` example). About a minute with its setup run; run with
    /// `cargo bench -p petri --bench gspn -- --ignored`.
    #[ignore]
    #[divan::bench(sample_count = 3, sample_size = 1)]
    fn kanban_5(bencher: Bencher) {
        bench(bencher, 5);
    }
}

/// The robot's decision (docs/gspn.md, tour-guide supervisor): the net is
/// compiled once per hypothesis, and re-solved whenever the learnt rates
/// λ3..λ10 change. Each iteration takes the next of 16 precomputed rate
/// vectors, so no two consecutive solves see the same rates.
mod supervisor_resolve {
    use super::*;

    const MODEL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/supervisor.toml");

    /// The net under one hypothesis: the branch of weight 0 removed, λ1/λ2
    /// fixed, `p` at the value of the remaining branch.
    fn hypothesis(automove: bool) -> (CompiledGspn, Params) {
        let net = petri::io::read_file(MODEL).unwrap();
        let (removed, lambda1, lambda2, p) = if automove {
            ("t1", 0.001, 1000.0, 1.0)
        } else {
            ("t0", 1000.0, 0.001, 0.0)
        };
        let net = net.without_transition(removed).unwrap();
        let fixed = Params::new().with("lambda1", lambda1).with("lambda2", lambda2);
        let gspn = net.instantiate(&fixed.clone().with("p", p)).unwrap();
        let chain = CompiledGspn::build(&gspn, &ExploreParams::default()).unwrap();
        (chain, fixed)
    }

    /// Parameters as the robot learns them from its log: mean travel times
    /// of 120–250 s (λ7, λ8), failure ratios of 1–30 % (λ9, λ10), localizer
    /// and planner event rates spanning 1e-4..1e-2 and recoveries 1e2..1e4.
    fn learnt_params(fixed: &Params) -> Vec<Params> {
        (0..16)
            .map(|i| {
                let f = f64::from(i) / 15.0;
                let lambda7 = 1.0 / (122.33 + 80.0 * f);
                let lambda8 = 1.0 / (186.98 + 60.0 * (1.0 - f));
                fixed
                    .clone()
                    .with("lambda3", 1e-4 * 100f64.powf(f))
                    .with("lambda4", 1e2 * 100f64.powf(1.0 - f))
                    .with("lambda5", 1e-2 * 0.01f64.powf(f))
                    .with("lambda6", 1e4 * 0.01f64.powf(f))
                    .with("lambda7", lambda7)
                    .with("lambda8", lambda8)
                    .with("lambda9", lambda7 * (0.01 + 0.3 * f))
                    .with("lambda10", lambda8 * (0.3 - 0.29 * f))
            })
            .collect()
    }

    fn setup(automove: bool) -> (CompiledGspn, Vec<Params>, Vec<Vec<f64>>) {
        let (chain, fixed) = hypothesis(automove);
        let params = learnt_params(&fixed);
        let rates = params
            .iter()
            .map(|p| chain.gspn().rates(p, None).unwrap())
            .collect();
        (chain, params, rates)
    }

    fn bench(bencher: Bencher, automove: bool) {
        let (chain, _, rates) = setup(automove);
        let params = SolveParams::default();
        let (t, name) = if automove {
            ("t9", "f_auto")
        } else {
            ("t10", "f_cont")
        };
        let t = chain.gspn().transition(t).unwrap();
        let first = chain.solve_rates(&rates[0], &params).unwrap();
        let last = chain.solve_rates(&rates[15], &params).unwrap();
        figure(
            format!(
                "supervisor_resolve/{}",
                if automove { "automove" } else { "contour" }
            ),
            || {
                format!(
                    "{} tangible markings, {}: {name} {:.3e} .. {:.3e}, residual ≤ {:.1e}",
                    chain.num_tangible(),
                    first.info.method,
                    first.throughput(t),
                    last.throughput(t),
                    first.info.residual.max(last.info.residual)
                )
            },
        );
        let next = AtomicUsize::new(0);
        bencher
            .with_inputs(|| &rates[next.fetch_add(1, Ordering::Relaxed) % rates.len()])
            .bench_local_values(|r| chain.solve_rates(r, &params).unwrap());
    }

    /// Target: under 20 µs.
    #[divan::bench(sample_count = 1000)]
    fn automove(bencher: Bencher) {
        bench(bencher, true);
    }

    /// Target: under 20 µs.
    #[divan::bench(sample_count = 1000)]
    fn contour(bencher: Bencher) {
        bench(bencher, false);
    }

    /// As `automove`, from named parameters: the rate expressions are
    /// evaluated ([`Gspn::rates`]) before solving.
    #[divan::bench(sample_count = 1000)]
    fn automove_from_params(bencher: Bencher) {
        let (chain, params, _) = setup(true);
        let next = AtomicUsize::new(0);
        bencher
            .with_inputs(|| &params[next.fetch_add(1, Ordering::Relaxed) % params.len()])
            .bench_local_values(|p| chain.solve(p, None, &SolveParams::default()).unwrap());
    }
}

/// Nets with decisions (docs/gspn.md, *Decisions*): the `corridors` family
/// (N robots choosing among three corridors) compiled once into its Markov
/// automaton, then each property prepared and solved with sound value
/// iteration for its rates — the hot loop of `gspn optimize`.
mod optimize {
    use super::*;
    use petri::DecisionNet;
    use petri::mdp::{OptimizeParams, Property};

    fn bench(bencher: Bencher, n: u32, property: &str) {
        let gspn = families::corridors_decide(n).instantiate(&Params::new()).unwrap();
        let d = DecisionNet::build(&gspn, &explore_params()).unwrap();
        let rates = d.rates(&Params::new(), None).unwrap();
        let objective = d.objective(&Property::parse(property).unwrap()).unwrap();
        let params = OptimizeParams::default();
        let (model, first) = d.solve(&objective, &rates, &params).unwrap();
        let s0 = model.initial_states()[0] as usize;
        figure(format!("optimize/corridors {n} {property}"), || {
            format!(
                "{} states, {}: {:.6} ± {:.1e}, {} sweeps",
                d.num_states(),
                first.method,
                first.value(s0),
                first.error_bound(s0),
                first.iterations
            )
        });
        bencher
            .counter(ItemsCount::new(d.num_states()))
            .bench_local(|| d.solve(&objective, &rates, &params).unwrap());
    }

    #[divan::bench(args = [10, 20, 40], max_time = 3)]
    fn pmax(bencher: Bencher, n: u32) {
        bench(bencher, n, r#"Pmax=? [F "all_working"]"#);
    }

    #[divan::bench(args = [10, 20, 40], max_time = 3)]
    fn tmin(bencher: Bencher, n: u32) {
        bench(bencher, n, r#"Tmin=? [F "all_working" | "lost"]"#);
    }
}
