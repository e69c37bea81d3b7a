//! The topological map's files: the JSON map file round-trips exactly, and
//! the PNML export opens in petri's own PNML reader as the same
//! place/transition net.
//!
//! * `tests/data/small_office.fpn.json` (hand-made: five places, one of them
//!   unreachable, a name with quotes, learnt thresholds, one transition
//!   rejected on some routes and one on every route) reads and writes back
//!   byte for byte;
//! * generated maps, and maps changed the way a robot changes them
//!   (failures lowering thresholds, costs of every magnitude, headings
//!   measured along walls), read → write → read equal and
//!   write → read → write byte-identical;
//! * the PNML of a map, read by `petri::io::read_pnml` and `read_file`, has
//!   the map's places (names, in order, the start marked), one transition
//!   per FPN transition (named as `pnml_transition_names` says) and exactly
//!   one input arc from the origin and one output arc to the destination,
//!   each of weight 1, per transition.

use petri::ArcKind;
use topo::export::pnml_transition_names;
use topo::{
    FuzzyPetriNet, Place, PlaceId, PlaceKind, PlanMode, Strategy, ThresholdParams, Transition, TransitionId,
    Turn, plan, random_office_like, to_pnml,
};

const SMALL_OFFICE: &str = include_str!("data/small_office.fpn.json");

/// Reads, writes, reads: equal maps and identical text.
fn assert_round_trip(net: &FuzzyPetriNet) {
    let text = net.to_json();
    let back = FuzzyPetriNet::from_json(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_eq!(&back, net, "read → write → read");
    assert_eq!(back.to_json(), text, "write → read → write");
    assert_eq!(back.total_cost().to_bits(), net.total_cost().to_bits());
    for t in net.transition_ids() {
        assert_eq!(back.weighted_cost(t).to_bits(), net.weighted_cost(t).to_bits());
        assert_eq!(
            back.transition(t).lambda.to_bits(),
            net.transition(t).lambda.to_bits()
        );
    }
}

#[test]
fn the_hand_made_map_reads_and_writes_back_byte_for_byte() {
    let net = FuzzyPetriNet::from_json(SMALL_OFFICE).unwrap();
    assert_eq!((net.num_places(), net.num_transitions()), (5, 8));
    assert_eq!(net.to_json(), SMALL_OFFICE);
    assert_round_trip(&net);
    // What the file says, as the library sees it.
    let closet = net.place_id("closet \"B\"").unwrap();
    assert!(net.place(closet).concave);
    assert!(net.place(PlaceId(1)).heading_aligned);
    let t4 = net.transition(TransitionId(4));
    assert_eq!((t4.lambda, t4.attempts, t4.failures), (0.125, 4, 3));
    assert_eq!(net.total_cost(), 98.0);
    // The learnt thresholds in action: t4 (door → window, λ = 1/8) is
    // accepted towards the window (f = 9/98) and rejected on the way to the
    // desk through it (f = 13/98); t6 (λ = 2^-40) on every route.
    let (door, desk, window) = (PlaceId(0), PlaceId(2), PlaceId(3));
    let to_desk = plan(&net, door, &[desk], PlanMode::Optimal).unwrap();
    assert_eq!(to_desk.route, [TransitionId(1), TransitionId(2)]);
    assert!(!to_desk.accepted[4] && !to_desk.accepted[6]);
    let to_window = plan(&net, door, &[window], PlanMode::Optimal).unwrap();
    assert_eq!(to_window.route, [TransitionId(4)]);
    assert!(plan(&net, closet, &[desk], PlanMode::Optimal).is_err());
}

/// A map with everything a file must keep: learnt thresholds (one down to
/// 0), costs of every magnitude, odd names and coordinates.
fn tricky() -> FuzzyPetriNet {
    let mut net = random_office_like(30, 110, 11).unwrap();
    let names = ["Büro 3.14", "t0", "p-1 (\"north\")", "日本", "a\\b", "x y"];
    for (k, name) in names.iter().enumerate() {
        let mut p = Place::new(-1e-300 * k as f64, 1e15 + k as f64, 0.1 + 0.2, PlaceKind::C);
        p.name = (*name).to_string();
        p.concave = k % 2 == 0;
        p.visits = u32::MAX - k as u32;
        net.add_place(p).unwrap();
    }
    let first = PlaceId(30);
    for k in 0..names.len() as u32 {
        let t = net
            .add_transition(Transition::new(
                PlaceId(30 + k),
                PlaceId((k * 7) % 36),
                [
                    Strategy::FreeMovement,
                    Strategy::DetourLeft,
                    Strategy::DetourRight,
                ][k as usize % 3],
                Turn::Straight,
                f64::from(k) / 3.0,
            ))
            .unwrap();
        net.set_cost(t, [5e-324, 1e-9, 0.1 + 0.2, 7.0, 1e200, 2.0 / 3.0][k as usize])
            .unwrap();
    }
    net.set_heading(first, 2.0, true).unwrap();
    let params = ThresholdParams::default();
    for k in 0..1200 {
        net.record_attempt(TransitionId(3), k % 100 == 0, &params)
            .unwrap();
    }
    assert_eq!(net.transition(TransitionId(3)).lambda, 0.0, "2^-1074 halved is 0");
    net.record_attempt(TransitionId(5), false, &ThresholdParams { factor: 0.3 })
        .unwrap();
    net
}

#[test]
fn generated_and_changed_maps_round_trip_exactly() {
    for (places, transitions, seed) in [(1, 3, 1), (2, 2, 5), (10, 40, 2), (200, 800, 3), (1000, 4500, 4)] {
        let net = random_office_like(places, transitions, seed).unwrap();
        assert!(
            places < 200 || net.transitions().iter().any(|t| t.lambda < 1.0),
            "some thresholds learnt"
        );
        assert_round_trip(&net);
    }
    assert_round_trip(&tricky());
    assert_round_trip(&FuzzyPetriNet::new());
}

#[test]
fn the_pnml_export_opens_in_petris_reader_as_the_same_net() {
    let office = FuzzyPetriNet::from_json(SMALL_OFFICE).unwrap();
    let generated = random_office_like(120, 500, 9).unwrap();
    let tricky = tricky();
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("topo_files");
    std::fs::create_dir_all(&dir).unwrap();
    for (name, net) in [
        ("office", &office),
        ("generated", &generated),
        ("tricky", &tricky),
    ] {
        let start = PlaceId(1);
        let goals = [PlaceId(net.num_places() as u32 - 3)];
        let route = plan(net, start, &goals, PlanMode::Optimal).ok();
        for with_plan in [None, route.as_ref()] {
            let text = to_pnml(net, name, Some(start), with_plan).unwrap();
            let read = petri::io::read_pnml(&text, name).unwrap_or_else(|e| panic!("{name}: {e}"));
            let path = dir.join(format!("{name}.pnml"));
            std::fs::write(&path, &text).unwrap();
            assert_eq!(petri::io::read_file(&path).unwrap(), read, "{name}: read_file");
            assert_eq!(read.name, name);
            let place_names: Vec<&str> = read.places.iter().map(|p| p.name.as_str()).collect();
            let expected: Vec<&str> = net.places().iter().map(|p| p.name.as_str()).collect();
            assert_eq!(place_names, expected, "{name}: places");
            for (i, p) in read.places.iter().enumerate() {
                let tokens = if i == start.index() { 1.0 } else { 0.0 };
                assert_eq!(
                    p.initial.as_number(),
                    Some(tokens),
                    "{name}: marking of {}",
                    p.name
                );
            }
            let transition_names: Vec<&str> = read.transitions.iter().map(|t| t.name.as_str()).collect();
            assert_eq!(
                transition_names,
                pnml_transition_names(net),
                "{name}: transitions"
            );
            assert_eq!(read.arcs.len(), 2 * net.num_transitions(), "{name}: arcs");
            for (i, t) in net.transitions().iter().enumerate() {
                let arcs: Vec<_> = read.arcs.iter().filter(|a| a.transition.index() == i).collect();
                let ends: Vec<(ArcKind, usize, Option<f64>)> = arcs
                    .iter()
                    .map(|a| (a.kind, a.place.index(), a.multiplicity.as_number()))
                    .collect();
                assert_eq!(
                    ends,
                    [
                        (ArcKind::Input, t.from.index(), Some(1.0)),
                        (ArcKind::Output, t.to.index(), Some(1.0))
                    ],
                    "{name}: arcs of t{i}"
                );
            }
        }
    }
}
