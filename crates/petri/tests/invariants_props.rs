//! Properties of the minimal invariants on random small nets: they are
//! invariants, their supports are minimal, P-invariants hold along random
//! firing sequences, cycles of a firing sequence contain a T-invariant, and a
//! brute-force enumeration finds no minimal invariant Farkas missed.

use petri::{
    ArcKind, FarkasParams, Gspn, Incidence, Invariants, Net, Params, TransitionId, p_invariants,
    structural_bounds, t_invariants,
};
use proptest::collection::vec;
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A random net described by plain numbers, so that proptest can shrink it.
#[derive(Debug, Clone)]
struct Spec {
    places: usize,
    /// Per transition: immediate?, priority.
    transitions: Vec<(bool, u32)>,
    /// Per (transition, place), row-major: input, output, inhibitor
    /// multiplicities (0: no arc).
    arcs: Vec<(u32, u32, u32)>,
    initial: Vec<u32>,
}

fn spec(max_places: usize, max_transitions: usize) -> impl Strategy<Value = Spec> {
    (1..=max_places, 1..=max_transitions).prop_flat_map(|(np, nt)| {
        let mult = || prop_oneof![3 => Just(0u32), 2 => 1u32..=3];
        let inhibitor = prop_oneof![8 => Just(0u32), 1 => 1u32..=2];
        (
            vec((any::<bool>(), 1u32..=2), nt),
            vec((mult(), mult(), inhibitor), np * nt),
            vec(0u32..=3, np),
        )
            .prop_map(move |(transitions, arcs, initial)| Spec {
                places: np,
                transitions,
                arcs,
                initial,
            })
    })
}

fn build(s: &Spec) -> Gspn {
    let mut net = Net::new("random");
    let places: Vec<_> = (0..s.places)
        .map(|p| net.add_place(format!("p{p}"), s.initial[p]))
        .collect();
    for (t, &(immediate, priority)) in s.transitions.iter().enumerate() {
        let id = if immediate {
            net.add_immediate(format!("t{t}"), 1.0, priority)
        } else {
            net.add_timed(format!("t{t}"), 1.0)
        };
        for (p, &place) in places.iter().enumerate() {
            let (i, o, h) = s.arcs[t * s.places + p];
            for (kind, m) in [(ArcKind::Input, i), (ArcKind::Output, o), (ArcKind::Inhibitor, h)] {
                if m > 0 {
                    net.add_arc(kind, place, id, m);
                }
            }
        }
    }
    net.instantiate(&Params::new()).unwrap()
}

fn support(v: &[(u32, u64)]) -> Vec<u32> {
    v.iter().map(|&(i, _)| i).collect()
}

fn is_subset(small: &[u32], large: &[u32]) -> bool {
    small.iter().all(|i| large.contains(i))
}

/// Each vector is sparse, sorted, positive, coprime; the list is sorted; no
/// support contains another's.
fn check_shape(inv: &Invariants) -> Result<(), TestCaseError> {
    let vs = inv.vectors();
    prop_assert!(vs.windows(2).all(|w| w[0] < w[1]), "not sorted: {vs:?}");
    for v in vs {
        prop_assert!(!v.is_empty());
        prop_assert!(v.windows(2).all(|w| w[0].0 < w[1].0));
        prop_assert!(v.iter().all(|&(i, c)| c > 0 && (i as usize) < inv.dimension()));
        let g = v.iter().fold(0u64, |g, &(_, c)| gcd(g, c));
        prop_assert_eq!(g, 1, "not coprime: {:?}", v);
    }
    for a in vs {
        for b in vs {
            if a != b {
                prop_assert!(
                    !is_subset(&support(a), &support(b)),
                    "support of {:?} within that of {:?}",
                    a,
                    b
                );
            }
        }
    }
    Ok(())
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// All `y ∈ {0..=k}^n`, `y ≠ 0`, with `yᵀ·A = 0` (`A` dense, `n` rows).
fn brute_force(a: &[Vec<i64>], k: u64) -> Vec<Vec<(u32, u64)>> {
    let n = a.len();
    let cols = a.first().map_or(0, Vec::len);
    let mut found = Vec::new();
    let mut y = vec![0u64; n];
    loop {
        // Next vector in base k+1; stop after wrapping around to zero.
        let mut i = 0;
        while i < n && y[i] == k {
            y[i] = 0;
            i += 1;
        }
        if i == n {
            break;
        }
        y[i] += 1;
        let zero = (0..cols).all(|c| (0..n).map(|r| y[r] as i64 * a[r][c]).sum::<i64>() == 0);
        if zero {
            found.push(
                y.iter()
                    .enumerate()
                    .filter(|&(_, &c)| c > 0)
                    .map(|(i, &c)| (i as u32, c))
                    .collect(),
            );
        }
    }
    found
}

/// Farkas against brute force with coefficients up to `k`.
fn check_against_brute_force(inv: &Invariants, a: &[Vec<i64>], k: u64) -> Result<(), TestCaseError> {
    let all = brute_force(a, k);
    let farkas = inv.vectors();
    let max = |v: &[(u32, u64)]| v.iter().map(|&(_, c)| c).max().unwrap_or(0);
    // Every invariant found by brute force contains a minimal one.
    for s in &all {
        prop_assert!(
            farkas.iter().any(|f| is_subset(&support(f), &support(s))),
            "{:?} contains no minimal invariant of {:?}",
            s,
            farkas
        );
    }
    // A Farkas invariant within the enumerated range is enumerated, and none
    // enumerated has a strictly smaller support.
    for f in farkas.iter().filter(|f| max(f) <= k) {
        prop_assert!(all.contains(f), "{:?} not found by brute force", f);
        for s in &all {
            prop_assert!(
                !(is_subset(&support(s), &support(f)) && support(s) != support(f)),
                "{:?} has a smaller support than {:?}",
                s,
                f
            );
        }
    }
    // Every enumerated invariant of minimal support (among those enumerated)
    // is a Farkas invariant, unless a Farkas invariant with coefficients
    // beyond the range has a strictly smaller support.
    for s in &all {
        let minimal = !all
            .iter()
            .any(|o| is_subset(&support(o), &support(s)) && support(o) != support(s));
        let g = s.iter().fold(0, |g, &(_, c)| gcd(g, c));
        let normalised: Vec<(u32, u64)> = s.iter().map(|&(i, c)| (i, c / g)).collect();
        if minimal && !farkas.contains(&normalised) {
            prop_assert!(
                farkas
                    .iter()
                    .any(|f| max(f) > k && is_subset(&support(f), &support(s)) && support(f) != support(s)),
                "minimal invariant {:?} missed; Farkas found {:?}",
                s,
                farkas
            );
        }
    }
    Ok(())
}

fn transpose(a: &[Vec<i64>], cols: usize) -> Vec<Vec<i64>> {
    (0..cols).map(|c| a.iter().map(|row| row[c]).collect()).collect()
}

fn dot(y: &[(u32, u64)], m: &[u32]) -> u128 {
    y.iter()
        .map(|&(i, c)| u128::from(c) * u128::from(m[i as usize]))
        .sum()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn p_invariants_are_minimal_and_hold_along_firing_sequences(s in spec(6, 6), seed in any::<u64>()) {
        let g = build(&s);
        let c = Incidence::new(&g);
        let p = p_invariants(&g, &FarkasParams::default()).unwrap();
        check_shape(&p)?;
        for y in p.vectors() {
            prop_assert!(c.is_p_invariant(y), "{:?} is not a P-invariant", y);
        }
        let sums = p.token_sums().unwrap().to_vec();
        let bounds = structural_bounds(&g, &p);
        let mut m = g.initial_marking().to_vec();
        prop_assert!(p.holds_in(&m));
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut firable = Vec::new();
        for _ in 0..60 {
            g.firable(&m, &mut firable);
            if firable.is_empty() {
                break;
            }
            let t = firable[rng.random_range(0..firable.len())];
            g.fire(t, &mut m).unwrap();
            for (y, &s0) in p.vectors().iter().zip(&sums) {
                prop_assert_eq!(dot(y, &m), s0);
            }
            prop_assert!(p.holds_in(&m));
            for (k, b) in m.iter().zip(&bounds) {
                if let Some(b) = b {
                    prop_assert!(u64::from(*k) <= *b);
                }
            }
        }
        prop_assert_eq!(p.covers_all(), p.uncovered().is_empty());
    }

    #[test]
    fn t_invariants_are_minimal_and_in_every_cycle(s in spec(6, 6), seed in any::<u64>()) {
        let g = build(&s);
        let c = Incidence::new(&g);
        let t = t_invariants(&g, &FarkasParams::default()).unwrap();
        check_shape(&t)?;
        for x in t.vectors() {
            prop_assert!(c.is_t_invariant(x), "{:?} is not a T-invariant", x);
        }
        // A firing sequence that comes back to a marking fires a T-invariant
        // (not necessarily minimal): its support contains a minimal one.
        let mut m = g.initial_marking().to_vec();
        let mut seen = vec![m.clone()];
        let mut fired: Vec<TransitionId> = Vec::new();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut firable = Vec::new();
        for _ in 0..60 {
            g.firable(&m, &mut firable);
            if firable.is_empty() {
                break;
            }
            let tr = firable[rng.random_range(0..firable.len())];
            g.fire(tr, &mut m).unwrap();
            fired.push(tr);
            if let Some(start) = seen.iter().position(|old| *old == m) {
                let mut x: Vec<(u32, u64)> = Vec::new();
                for &tr in &fired[start..] {
                    match x.iter_mut().find(|(i, _)| *i == tr.0) {
                        Some((_, k)) => *k += 1,
                        None => x.push((tr.0, 1)),
                    }
                }
                x.sort_unstable();
                prop_assert!(c.is_t_invariant(&x));
                prop_assert!(
                    t.vectors().iter().any(|f| is_subset(&support(f), &support(&x))),
                    "cycle {:?} contains no minimal T-invariant of {:?}", x, t.vectors()
                );
                for covered in support(&x) {
                    prop_assert!(!t.uncovered().contains(&covered));
                }
            }
            seen.push(m.clone());
        }
    }

    #[test]
    fn farkas_finds_every_minimal_invariant_of_tiny_nets(s in spec(5, 5)) {
        let g = build(&s);
        let c = Incidence::new(&g);
        let dense = c.to_dense();
        let p = p_invariants(&g, &FarkasParams::default()).unwrap();
        check_against_brute_force(&p, &dense, 3)?;
        let t = t_invariants(&g, &FarkasParams::default()).unwrap();
        check_against_brute_force(&t, &transpose(&dense, c.num_transitions()), 3)?;
    }
}
