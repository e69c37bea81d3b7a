//! Known answers for the incidence matrix and the minimal P- and T-invariants:
//! nets whose invariants are worked out by hand, built in code.

use petri::{
    ArcKind, Error, FarkasParams, Gspn, Incidence, InvariantKind, Invariants, Net, Params, p_invariants,
    structural_bounds, t_invariants,
};

fn p_inv(g: &Gspn) -> Invariants {
    p_invariants(g, &FarkasParams::default()).unwrap()
}

fn t_inv(g: &Gspn) -> Invariants {
    t_invariants(g, &FarkasParams::default()).unwrap()
}

/// A sparse vector from names, with coefficient 1 unless given as `"k*name"`.
fn vector(names: &[String], terms: &[&str]) -> Vec<(u32, u64)> {
    let mut v: Vec<(u32, u64)> = terms
        .iter()
        .map(|t| {
            let (k, name) = match t.split_once('*') {
                Some((k, n)) => (k.parse().unwrap(), n),
                None => (1, *t),
            };
            let i = names
                .iter()
                .position(|n| n == name)
                .unwrap_or_else(|| panic!("no `{name}`"));
            (i as u32, k)
        })
        .collect();
    v.sort_unstable();
    v
}

/// The expected invariants, sorted like the result.
fn expected(names: &[String], invariants: &[Vec<String>]) -> Vec<Vec<(u32, u64)>> {
    let mut all: Vec<Vec<(u32, u64)>> = invariants
        .iter()
        .map(|terms| vector(names, &terms.iter().map(String::as_str).collect::<Vec<_>>()))
        .collect();
    all.sort_unstable();
    all
}

fn strings(terms: &[&str]) -> Vec<String> {
    terms.iter().map(|s| s.to_string()).collect()
}

fn cycle(n: usize) -> Gspn {
    let mut net = Net::new("cycle");
    let places: Vec<_> = (0..n)
        .map(|i| net.add_place(format!("p{i}"), u32::from(i == 0)))
        .collect();
    for i in 0..n {
        let t = net.add_timed(format!("t{i}"), 1.0);
        net.input(places[i], t);
        net.output(t, places[(i + 1) % n]);
    }
    net.instantiate(&Params::new()).unwrap()
}

#[test]
fn cycle_has_one_p_and_one_t_invariant_of_all_ones() {
    for n in 1..=7 {
        let g = cycle(n);
        let all_ones: Vec<(u32, u64)> = (0..n as u32).map(|i| (i, 1)).collect();
        let p = p_inv(&g);
        assert_eq!(p.kind(), InvariantKind::Place);
        assert_eq!(p.vectors(), std::slice::from_ref(&all_ones), "n = {n}");
        assert_eq!(p.token_sums(), Some(&[1u128][..]));
        assert!(p.covers_all());
        assert!(p.holds_in(g.initial_marking()));
        assert_eq!(structural_bounds(&g, &p), vec![Some(1); n]);
        let t = t_inv(&g);
        assert_eq!(t.kind(), InvariantKind::Transition);
        assert_eq!(t.vectors(), std::slice::from_ref(&all_ones), "n = {n}");
        assert_eq!(t.token_sums(), None);
        assert!(t.covers_all());
        assert!(!t.holds_in(g.initial_marking()));
    }
    let g = cycle(3);
    assert_eq!(p_inv(&g).display(&g).to_string(), "p0 + p1 + p2 = 1");
    assert_eq!(t_inv(&g).display(&g).to_string(), "t0 + t1 + t2");
    // The third column is zero once two are eliminated (rank 2).
    assert_eq!(p_inv(&g).info().columns_eliminated, 2);
}

/// A producer and a consumer around a buffer of capacity `k`, the free slots
/// held by a complementary place.
fn producer_consumer(k: u32) -> Gspn {
    let mut net = Net::new("prodcons");
    let p_idle = net.add_place("ProdIdle", 1u32);
    let p_ready = net.add_place("ProdReady", 0u32);
    let buffer = net.add_place("Buffer", 0u32);
    let free = net.add_place("Free", k);
    let c_idle = net.add_place("ConsIdle", 1u32);
    let c_busy = net.add_place("ConsBusy", 0u32);
    let produce = net.add_timed("produce", 1.0);
    let deposit = net.add_immediate("deposit", 1.0, 1);
    let remove = net.add_immediate("remove", 1.0, 1);
    let consume = net.add_timed("consume", 1.0);
    net.input(p_idle, produce);
    net.output(produce, p_ready);
    net.input(p_ready, deposit);
    net.input(free, deposit);
    net.output(deposit, p_idle);
    net.output(deposit, buffer);
    net.input(c_idle, remove);
    net.input(buffer, remove);
    net.output(remove, c_busy);
    net.output(remove, free);
    net.input(c_busy, consume);
    net.output(consume, c_idle);
    net.instantiate(&Params::new()).unwrap()
}

#[test]
fn producer_consumer_with_a_complementary_place() {
    for k in [1, 3, 10] {
        let g = producer_consumer(k);
        let names = g.place_names();
        let p = p_inv(&g);
        assert_eq!(
            p.vectors(),
            expected(
                names,
                &[
                    strings(&["ProdIdle", "ProdReady"]),
                    strings(&["Buffer", "Free"]),
                    strings(&["ConsIdle", "ConsBusy"]),
                ]
            )
        );
        assert!(p.covers_all());
        assert_eq!(
            structural_bounds(&g, &p),
            vec![
                Some(1),
                Some(1),
                Some(u64::from(k)),
                Some(u64::from(k)),
                Some(1),
                Some(1)
            ]
        );
        let t = t_inv(&g);
        assert_eq!(t.vectors(), &[vec![(0, 1), (1, 1), (2, 1), (3, 1)]]);
        assert!(t.covers_all());
    }
    let g = producer_consumer(3);
    let p = p_inv(&g);
    let lines: Vec<String> = p.display(&g).to_string().lines().map(String::from).collect();
    assert_eq!(
        lines,
        [
            "ProdIdle + ProdReady = 1",
            "Buffer + Free = 3",
            "ConsIdle + ConsBusy = 1"
        ]
    );
}

#[test]
fn mutual_exclusion_with_a_semaphore() {
    let mut net = Net::new("mutex");
    let sem = net.add_place("Sem", 1u32);
    for i in 1..=2 {
        let idle = net.add_place(format!("Idle_{i}"), 1u32);
        let wait = net.add_place(format!("Wait_{i}"), 0u32);
        let cs = net.add_place(format!("CS_{i}"), 0u32);
        let request = net.add_timed(format!("request_{i}"), 1.0);
        let enter = net.add_immediate(format!("enter_{i}"), 1.0, 1);
        let exit = net.add_timed(format!("exit_{i}"), 1.0);
        net.input(idle, request);
        net.output(request, wait);
        net.input(wait, enter);
        net.input(sem, enter);
        net.output(enter, cs);
        net.input(cs, exit);
        net.output(exit, idle);
        net.output(exit, sem);
    }
    let g = net.instantiate(&Params::new()).unwrap();
    let p = p_inv(&g);
    assert_eq!(
        p.vectors(),
        expected(
            g.place_names(),
            &[
                strings(&["Sem", "CS_1", "CS_2"]),
                strings(&["Idle_1", "Wait_1", "CS_1"]),
                strings(&["Idle_2", "Wait_2", "CS_2"]),
            ]
        )
    );
    assert_eq!(p.token_sums(), Some(&[1u128, 1, 1][..]));
    assert_eq!(structural_bounds(&g, &p), vec![Some(1); 7]);
    // Both processes in their critical section violates the semaphore's
    // invariant, so that marking is unreachable.
    let mut both = vec![0u32; 7];
    for name in ["CS_1", "CS_2"] {
        both[g.place(name).unwrap().index()] = 1;
    }
    assert!(!p.holds_in(&both));
    assert!(!p.holds_in(&[1, 1]));
    let t = t_inv(&g);
    assert_eq!(
        t.vectors(),
        expected(
            g.transition_names(),
            &[
                strings(&["request_1", "enter_1", "exit_1"]),
                strings(&["request_2", "enter_2", "exit_2"])
            ]
        )
    );
}

/// `n` dining philosophers: philosopher `i` thinks, takes fork `i` (left),
/// waits, takes fork `i+1` (right), eats, then puts both back.
fn philosophers(n: usize) -> Gspn {
    let mut net = Net::new("philosophers");
    let mut think = Vec::new();
    let mut wait = Vec::new();
    let mut eat = Vec::new();
    let mut fork = Vec::new();
    for i in 0..n {
        think.push(net.add_place(format!("Think_{i}"), 1u32));
        wait.push(net.add_place(format!("Wait_{i}"), 0u32));
        eat.push(net.add_place(format!("Eat_{i}"), 0u32));
        fork.push(net.add_place(format!("Fork_{i}"), 1u32));
    }
    for i in 0..n {
        let (left, right) = (fork[i], fork[(i + 1) % n]);
        let take_left = net.add_timed(format!("TakeLeft_{i}"), 1.0);
        let take_right = net.add_timed(format!("TakeRight_{i}"), 1.0);
        let release = net.add_timed(format!("Release_{i}"), 1.0);
        net.input(think[i], take_left);
        net.input(left, take_left);
        net.output(take_left, wait[i]);
        net.input(wait[i], take_right);
        net.input(right, take_right);
        net.output(take_right, eat[i]);
        net.input(eat[i], release);
        net.output(release, think[i]);
        net.output(release, left);
        net.output(release, right);
    }
    net.instantiate(&Params::new()).unwrap()
}

#[test]
fn dining_philosophers_one_invariant_per_philosopher_and_per_fork() {
    for n in 2..=6 {
        let g = philosophers(n);
        let mut want = Vec::new();
        for i in 0..n {
            want.push(vec![
                format!("Think_{i}"),
                format!("Wait_{i}"),
                format!("Eat_{i}"),
            ]);
            // Fork i is held by philosopher i while waiting or eating, and by
            // philosopher i−1 while eating.
            want.push(vec![
                format!("Fork_{i}"),
                format!("Wait_{i}"),
                format!("Eat_{i}"),
                format!("Eat_{}", (i + n - 1) % n),
            ]);
        }
        let p = p_inv(&g);
        assert_eq!(p.len(), 2 * n);
        assert_eq!(p.vectors(), expected(g.place_names(), &want), "n = {n}");
        assert!(p.token_sums().unwrap().iter().all(|&s| s == 1));
        assert_eq!(structural_bounds(&g, &p), vec![Some(1); 4 * n]);
        let t = t_inv(&g);
        let want: Vec<Vec<String>> = (0..n)
            .map(|i| {
                vec![
                    format!("TakeLeft_{i}"),
                    format!("TakeRight_{i}"),
                    format!("Release_{i}"),
                ]
            })
            .collect();
        assert_eq!(t.vectors(), expected(g.transition_names(), &want), "n = {n}");
        assert!(t.covers_all());
    }
    let g = philosophers(3);
    let p = p_inv(&g);
    let text = p.display(&g).to_string();
    assert!(
        text.lines().any(|l| l == "Think_1 + Wait_1 + Eat_1 = 1"),
        "{text}"
    );
    assert!(
        text.lines().any(|l| l == "Eat_0 + Wait_1 + Eat_1 + Fork_1 = 1"),
        "{text}"
    );
}

/// The Kanban system of Ciardo & Tilgner with `n` kanbans per cell.
fn kanban(n: u32) -> Gspn {
    let mut net = Net::new("kanban");
    let mut pm = Vec::new();
    let mut pback = Vec::new();
    let mut pkan = Vec::new();
    let mut pout = Vec::new();
    for i in 1..=4 {
        pm.push(net.add_place(format!("Pm{i}"), 0u32));
        pback.push(net.add_place(format!("Pback{i}"), 0u32));
        pkan.push(net.add_place(format!("Pkan{i}"), n));
        pout.push(net.add_place(format!("Pout{i}"), 0u32));
    }
    let tin1 = net.add_timed("tin1", 1.0);
    net.input(pkan[0], tin1);
    net.output(tin1, pm[0]);
    for i in 0..4 {
        let redo = net.add_timed(format!("tredo{}", i + 1), 1.0);
        net.input(pm[i], redo);
        net.output(redo, pback[i]);
        let back = net.add_timed(format!("tback{}", i + 1), 1.0);
        net.input(pback[i], back);
        net.output(back, pm[i]);
        let ok = net.add_timed(format!("tok{}", i + 1), 1.0);
        net.input(pm[i], ok);
        net.output(ok, pout[i]);
    }
    let s1 = net.add_immediate("tsynch1_23", 1.0, 1);
    for p in [pout[0], pkan[1], pkan[2]] {
        net.input(p, s1);
    }
    for p in [pkan[0], pm[1], pm[2]] {
        net.output(s1, p);
    }
    let s4 = net.add_timed("tsynch4_23", 1.0);
    for p in [pout[1], pout[2], pkan[3]] {
        net.input(p, s4);
    }
    for p in [pkan[1], pkan[2], pm[3]] {
        net.output(s4, p);
    }
    let tout4 = net.add_timed("tout4", 1.0);
    net.input(pout[3], tout4);
    net.output(tout4, pkan[3]);
    net.instantiate(&Params::new()).unwrap()
}

#[test]
fn kanban_cells_are_p_invariants_bounding_every_place_by_n() {
    for n in [1, 3, 5] {
        let g = kanban(n);
        let cell = |i: usize| {
            strings(&[
                &format!("Pm{i}"),
                &format!("Pback{i}"),
                &format!("Pkan{i}"),
                &format!("Pout{i}"),
            ])
        };
        // Cells 2 and 3 work in parallel between the two synchronisations:
        // `u2 + u3 = k2 + k3` (work in progress vs free kanbans) also gives
        // the two crossed invariants.
        let crossed = |i: usize, j: usize| {
            strings(&[
                &format!("Pm{i}"),
                &format!("Pback{i}"),
                &format!("Pout{i}"),
                &format!("Pkan{j}"),
            ])
        };
        let p = p_inv(&g);
        assert_eq!(
            p.vectors(),
            expected(
                g.place_names(),
                &[cell(1), cell(2), cell(3), cell(4), crossed(2, 3), crossed(3, 2)]
            ),
        );
        assert!(p.token_sums().unwrap().iter().all(|&s| s == u128::from(n)));
        assert!(p.covers_all());
        assert_eq!(structural_bounds(&g, &p), vec![Some(u64::from(n)); 16]);
        let t = t_inv(&g);
        let mut want: Vec<Vec<String>> = (1..=4)
            .map(|i| vec![format!("tredo{i}"), format!("tback{i}")])
            .collect();
        want.push(strings(&[
            "tin1",
            "tok1",
            "tsynch1_23",
            "tok2",
            "tok3",
            "tsynch4_23",
            "tok4",
            "tout4",
        ]));
        assert_eq!(t.vectors(), expected(g.transition_names(), &want));
        assert!(t.covers_all());
    }
}

/// Places `a1..an` all feed one transition that fills `b1..bm`: the minimal
/// P-invariants are the `n·m` sums `ai + bj`.
fn fan(n: usize, m: usize) -> Gspn {
    let mut net = Net::new("fan");
    let t = net.add_timed("t", 1.0);
    for i in 0..n {
        let p = net.add_place(format!("a{i}"), 1u32);
        net.input(p, t);
    }
    for j in 0..m {
        let p = net.add_place(format!("b{j}"), 0u32);
        net.output(t, p);
    }
    net.instantiate(&Params::new()).unwrap()
}

#[test]
fn row_limit_is_an_error_naming_the_limit() {
    let g = fan(10, 10);
    let p = p_inv(&g);
    assert_eq!(p.len(), 100);
    assert_eq!(p.info().rows_peak, 100);
    assert!(t_inv(&g).is_empty());

    let err = p_invariants(&g, &FarkasParams { max_rows: 50 }).unwrap_err();
    match &err {
        Error::InvariantRowLimit {
            what,
            limit,
            eliminated,
            columns,
        } => {
            assert_eq!((*what, *limit, *eliminated, *columns), ("P-invariants", 50, 0, 1));
        }
        other => panic!("unexpected {other:?}"),
    }
    let text = err.to_string();
    assert!(text.contains("50") && text.contains("max_rows"), "{text}");
    // Even the initial rows must fit.
    assert!(matches!(
        t_invariants(&g, &FarkasParams { max_rows: 0 }),
        Err(Error::InvariantRowLimit { limit: 0, .. })
    ));
}

#[test]
fn source_transition_makes_places_uncovered_and_unbounded() {
    let mut net = Net::new("open");
    let a = net.add_place("a", 0u32);
    let b = net.add_place("b", 2u32);
    let c = net.add_place("c", 1u32);
    let d = net.add_place("d", 0u32);
    let source = net.add_timed("source", 1.0);
    net.output(source, a);
    let mv = net.add_timed("move", 1.0);
    net.input(a, mv);
    net.output(mv, b);
    let go = net.add_timed("go", 1.0);
    net.input(c, go);
    net.output(go, d);
    let back = net.add_timed("back", 1.0);
    net.input(d, back);
    net.output(back, c);
    let g = net.instantiate(&Params::new()).unwrap();
    let p = p_inv(&g);
    assert_eq!(p.vectors(), &[vec![(2, 1), (3, 1)]]);
    assert!(!p.covers_all());
    assert_eq!(p.uncovered(), vec![0, 1]);
    assert_eq!(structural_bounds(&g, &p), vec![None, None, Some(1), Some(1)]);
    let t = t_inv(&g);
    assert_eq!(t.vectors(), &[vec![(2, 1), (3, 1)]]);
    assert_eq!(t.uncovered(), vec![0, 1]);
    // T-invariants give no bounds.
    assert_eq!(structural_bounds(&g, &t), vec![None; 4]);
}

#[test]
fn inhibitor_arcs_do_not_change_the_invariants() {
    let plain = cycle(3);
    let mut net = Net::new("cycle");
    let places: Vec<_> = (0..3)
        .map(|i| net.add_place(format!("p{i}"), u32::from(i == 0)))
        .collect();
    for i in 0..3 {
        let t = net.add_timed(format!("t{i}"), 1.0);
        net.input(places[i], t);
        net.output(t, places[(i + 1) % 3]);
        net.inhibitor(places[(i + 2) % 3], t);
    }
    let g = net.instantiate(&Params::new()).unwrap();
    assert_eq!(Incidence::new(&g), Incidence::new(&plain));
    assert_eq!(p_inv(&g).vectors(), p_inv(&plain).vectors());
    assert_eq!(t_inv(&g).vectors(), t_inv(&plain).vectors());
}

/// `p0 → t0 → k·p1 → t1 → k·p2 …`: the P-invariant is `(k^(n−1), …, k, 1)`.
fn multiplying_chain(places: usize, k: u32) -> Gspn {
    let mut net = Net::new("chain");
    let ps: Vec<_> = (0..places)
        .map(|i| net.add_place(format!("p{i}"), u32::from(i == 0)))
        .collect();
    for i in 0..places - 1 {
        let t = net.add_timed(format!("t{i}"), 1.0);
        net.input(ps[i], t);
        net.add_arc(ArcKind::Output, ps[i + 1], t, k);
    }
    net.instantiate(&Params::new()).unwrap()
}

#[test]
fn multiplicities_give_weighted_invariants() {
    let g = multiplying_chain(3, 2);
    let p = p_inv(&g);
    assert_eq!(p.vectors(), &[vec![(0, 4), (1, 2), (2, 1)]]);
    assert_eq!(p.display(&g).to_string(), "4·p0 + 2·p1 + p2 = 4");
    assert_eq!(structural_bounds(&g, &p), vec![Some(1), Some(2), Some(4)]);
    assert!(p.holds_in(&[0, 1, 2]));
    assert!(p.holds_in(&[0, 0, 4]));
    assert!(!p.holds_in(&[0, 0, 3]));
}

#[test]
fn coefficients_too_large_are_an_error() {
    // (2³²−1)³ does not fit u64; (2³²−1)⁴ does not fit i128.
    for places in [4, 5, 8] {
        let g = multiplying_chain(places, u32::MAX);
        let err = p_invariants(&g, &FarkasParams::default()).unwrap_err();
        assert!(
            matches!(
                err,
                Error::InvariantOverflow {
                    what: "P-invariants",
                    ..
                }
            ),
            "{err}"
        );
    }
    // (2³²−1)² still fits.
    let g = multiplying_chain(3, u32::MAX);
    let m = u64::from(u32::MAX);
    assert_eq!(p_inv(&g).vectors(), &[vec![(0, m * m), (1, m), (2, 1)]]);
}

#[test]
fn nets_without_places_or_transitions() {
    let g = Net::new("empty").instantiate(&Params::new()).unwrap();
    assert!(p_inv(&g).is_empty() && p_inv(&g).covers_all());
    assert!(t_inv(&g).is_empty());
    assert_eq!(p_inv(&g).display(&g).to_string(), "");

    // Without transitions every place is its own invariant.
    let mut net = Net::new("still");
    net.add_place("x", 3u32);
    net.add_place("y", 0u32);
    let g = net.instantiate(&Params::new()).unwrap();
    let p = p_inv(&g);
    assert_eq!(p.vectors(), &[vec![(0, 1)], vec![(1, 1)]]);
    assert_eq!(structural_bounds(&g, &p), vec![Some(3), Some(0)]);

    // A transition without arcs is a T-invariant on its own.
    let mut net = Net::new("idle");
    net.add_timed("tick", 1.0);
    let g = net.instantiate(&Params::new()).unwrap();
    assert_eq!(t_inv(&g).vectors(), &[vec![(0, 1)]]);
}

#[test]
fn bounds_follow_another_initial_marking_of_the_same_net() {
    let small = producer_consumer(2);
    let large = producer_consumer(7);
    let p = p_inv(&small);
    assert_eq!(structural_bounds(&large, &p)[2], Some(7));
    // Invariants of another size give nothing rather than nonsense.
    assert_eq!(structural_bounds(&cycle(2), &p), vec![None, None]);
}

#[test]
fn json_and_named_output() {
    let g = multiplying_chain(3, 2);
    let p = p_inv(&g);
    let json = serde_json::to_value(&p).unwrap();
    assert_eq!(json["kind"], "place");
    assert_eq!(json["dimension"], 3);
    assert_eq!(json["vectors"], serde_json::json!([[[0, 4], [1, 2], [2, 1]]]));
    assert_eq!(json["token_sums"], serde_json::json!([4]));
    assert_eq!(json["info"]["columns_eliminated"], 2);
    let named = serde_json::to_value(p.named(&g)).unwrap();
    assert_eq!(
        named,
        serde_json::json!([{
            "terms": [
                {"name": "p0", "coefficient": 4},
                {"name": "p1", "coefficient": 2},
                {"name": "p2", "coefficient": 1}
            ],
            "token_sum": 4
        }])
    );
    let t = t_inv(&cycle(2));
    let json = serde_json::to_value(&t).unwrap();
    assert_eq!(json["kind"], "transition");
    assert!(json.get("token_sums").is_none());
    assert!(p.display_vector(1, &g).is_none());
    assert_eq!(
        p.display_vector(0, &g).unwrap().to_string(),
        "4·p0 + 2·p1 + p2 = 4"
    );
    let c = serde_json::to_value(Incidence::new(&g)).unwrap();
    assert_eq!(
        c["columns"],
        serde_json::json!([[[0, -1], [1, 2]], [[1, -1], [2, 2]]])
    );
}

#[test]
fn results_are_deterministic() {
    let g = kanban(2);
    assert_eq!(p_inv(&g), p_inv(&g));
    assert_eq!(t_inv(&g), t_inv(&g));
}
