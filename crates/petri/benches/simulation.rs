//! Simulation speed, in firings per second, on closed cyclic queueing
//! networks of growing size.
//!
//! `ring/N`: N single-server stations in a ring (rates 1, 1.1, 1.2, …), N
//! customers, timed transitions only. `ring_routing/N`: after each service
//! the customer goes to the next station or skips one, an immediate choice
//! of weights 1:2, so half the firings are immediate. Each firing costs one
//! scan of the transitions (`Gspn::firable`), so the rate falls with N.
//!
//! Run with `cargo bench -p petri --bench simulation`.

use divan::Bencher;
use divan::counter::ItemsCount;
use petri::simulation::{SimParams, simulate};
use petri::{Gspn, Net, Params};

fn main() {
    divan::main();
}

/// The ring: place `q{i}` is the queue of station `i`, `s{i}` its service.
fn ring(stations: usize, routing: bool) -> Net {
    let mut n = Net::new(format!("ring{stations}"));
    let queues: Vec<_> = (0..stations)
        .map(|i| n.add_place(format!("q{i}"), 1u32))
        .collect();
    for i in 0..stations {
        let s = n.add_timed(format!("s{i}"), 1.0 + 0.1 * i as f64);
        n.input(queues[i], s);
        if routing {
            let out = n.add_place(format!("r{i}"), 0u32);
            n.output(s, out);
            let next = n.add_immediate(format!("next{i}"), 1.0, 1);
            let skip = n.add_immediate(format!("skip{i}"), 2.0, 1);
            n.input(out, next);
            n.output(next, queues[(i + 1) % stations]);
            n.input(out, skip);
            n.output(skip, queues[(i + 2) % stations]);
        } else {
            n.output(s, queues[(i + 1) % stations]);
        }
    }
    n
}

/// The net, its rates, and run parameters giving about `target` firings
/// (exactly `events` with this seed).
fn setup(stations: usize, routing: bool, target: f64) -> (Gspn, Vec<f64>, SimParams, u64) {
    let g = ring(stations, routing).instantiate(&Params::new()).unwrap();
    let r = g.rates(&Params::new(), None).unwrap();
    let probe = simulate(&g, &r, &[], &SimParams::new(1_000.0)).unwrap();
    let per_time = probe.events as f64 / probe.simulated_time;
    let params = SimParams {
        seed: 1,
        ..SimParams::new(target / per_time)
    };
    let events = simulate(&g, &r, &[], &params).unwrap().events;
    (g, r, params, events)
}

fn bench(bencher: Bencher, stations: usize, routing: bool) {
    let (g, r, params, events) = setup(stations, routing, 200_000.0);
    bencher
        .counter(ItemsCount::new(events))
        .bench(|| simulate(divan::black_box(&g), &r, &[], &params).unwrap());
}

#[divan::bench(args = [4, 16, 64], sample_count = 20)]
fn ring_timed(bencher: Bencher, stations: usize) {
    bench(bencher, stations, false);
}

#[divan::bench(args = [4, 16, 64], sample_count = 20)]
fn ring_routing(bencher: Bencher, stations: usize) {
    bench(bencher, stations, true);
}
