//! The optimiser against an independent method on generated MDPs and
//! Markov automata: every memoryless deterministic policy enumerated, the
//! chain it induces solved exactly (dense Gaussian elimination), the best
//! kept. Every objective, minimum and maximum, must agree within 1e-9.

// Dense matrices read best with explicit indices.
#![allow(clippy::needless_range_loop)]

use petri::mdp::{Direction, Goal, Model, ModelBuilder, ModelType, OptimizeParams, Precision, optimize};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Solves `a x = b` (dense, partial pivoting).
fn gauss(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        let d = a[c][c];
        assert!(d.abs() > 1e-300, "singular");
        for r in 0..n {
            if r != c && a[r][c] != 0.0 {
                let f = a[r][c] / d;
                for k in c..n {
                    a[r][k] -= f * a[c][k];
                }
                b[r] -= f * b[c];
            }
        }
    }
    (0..n).map(|i| b[i] / a[i][i]).collect()
}

/// The chain a policy induces: dense probabilities, sojourn times.
struct Chain {
    p: Vec<Vec<f64>>,
    tau: Vec<f64>,
}

fn chain(model: &Model, policy: &[usize]) -> Chain {
    let n = model.num_states();
    let mut p = vec![vec![0.0; n]; n];
    let mut tau = vec![0.0; n];
    for s in 0..n {
        let r = model.rows(s).start + policy[s];
        // Generated models hold probabilities in every row.
        for (t, x) in model.row_entries(r) {
            p[s][t as usize] += x;
        }
        tau[s] = match model.model_type() {
            ModelType::Mdp | ModelType::Dtmc => 1.0,
            _ if model.is_markovian(s) => 1.0 / model.exit_rate(s),
            _ => 0.0,
        };
    }
    Chain { p, tau }
}

/// States that can reach `set` in the chain (through any states).
fn reaches(c: &Chain, set: &[bool]) -> Vec<bool> {
    let n = set.len();
    let mut r = set.to_vec();
    loop {
        let mut changed = false;
        for s in 0..n {
            if !r[s] && (0..n).any(|t| c.p[s][t] > 0.0 && r[t]) {
                r[s] = true;
                changed = true;
            }
        }
        if !changed {
            return r;
        }
    }
}

fn reach_prob(c: &Chain, target: &[bool]) -> Vec<f64> {
    let n = target.len();
    let can = reaches(c, target);
    let q: Vec<usize> = (0..n).filter(|&s| can[s] && !target[s]).collect();
    let mut x = vec![0.0; n];
    for s in 0..n {
        if target[s] {
            x[s] = 1.0;
        }
    }
    let a: Vec<Vec<f64>> = q
        .iter()
        .map(|&i| {
            q.iter()
                .map(|&j| f64::from(u8::from(i == j)) - c.p[i][j])
                .collect()
        })
        .collect();
    let b: Vec<f64> = q
        .iter()
        .map(|&i| (0..n).filter(|&t| target[t]).map(|t| c.p[i][t]).sum())
        .collect();
    for (k, v) in gauss(a, b).into_iter().enumerate() {
        x[q[k]] = v;
    }
    x
}

fn total(c: &Chain, target: &[bool], rho: &[f64]) -> Vec<f64> {
    let n = target.len();
    // Probability 1 of reaching: cannot reach a non-target state that
    // cannot reach the target.
    let can = reaches(c, target);
    let dead: Vec<bool> = (0..n).map(|s| !can[s]).collect();
    let mut avoid_reach = dead.clone();
    loop {
        let mut changed = false;
        for s in 0..n {
            if !avoid_reach[s] && !target[s] && (0..n).any(|t| c.p[s][t] > 0.0 && avoid_reach[t]) {
                avoid_reach[s] = true;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let q: Vec<usize> = (0..n).filter(|&s| !target[s] && !avoid_reach[s]).collect();
    let mut x = vec![0.0; n];
    for s in 0..n {
        if avoid_reach[s] && !target[s] {
            x[s] = f64::INFINITY;
        }
    }
    let a: Vec<Vec<f64>> = q
        .iter()
        .map(|&i| {
            q.iter()
                .map(|&j| f64::from(u8::from(i == j)) - c.p[i][j])
                .collect()
        })
        .collect();
    let b: Vec<f64> = q.iter().map(|&i| rho[i]).collect();
    for (k, v) in gauss(a, b).into_iter().enumerate() {
        x[q[k]] = v;
    }
    x
}

fn long_run(c: &Chain, rho: &[f64]) -> Vec<f64> {
    let n = rho.len();
    // Bottom strongly connected components.
    let reach_from: Vec<Vec<bool>> = (0..n)
        .map(|s| {
            // The states reachable from s.
            let mut r = vec![false; n];
            r[s] = true;
            loop {
                let mut changed = false;
                for u in 0..n {
                    if r[u] {
                        for t in 0..n {
                            if c.p[u][t] > 0.0 && !r[t] {
                                r[t] = true;
                                changed = true;
                            }
                        }
                    }
                }
                if !changed {
                    break;
                }
            }
            r
        })
        .collect();
    let bottom: Vec<bool> = (0..n)
        .map(|s| (0..n).all(|t| !reach_from[s][t] || reach_from[t][s]))
        .collect();
    let mut value = vec![0.0; n];
    let mut done = vec![false; n];
    for s in 0..n {
        if !bottom[s] || done[s] {
            continue;
        }
        let b: Vec<usize> = (0..n).filter(|&t| reach_from[s][t]).collect();
        // Stationary distribution of the embedded chain on b.
        let k = b.len();
        let mut a = vec![vec![0.0; k]; k];
        let mut rhs = vec![0.0; k];
        for (i, &u) in b.iter().enumerate() {
            for (j, &v) in b.iter().enumerate() {
                a[j][i] = c.p[u][v] - f64::from(u8::from(u == v));
            }
        }
        for j in 0..k {
            a[0][j] = 1.0;
        }
        rhs[0] = 1.0;
        let mu = gauss(a, rhs);
        let num: f64 = b.iter().zip(&mu).map(|(&u, m)| m * rho[u]).sum();
        let den: f64 = b.iter().zip(&mu).map(|(&u, m)| m * c.tau[u]).sum();
        let g = num / den;
        let mut target = vec![false; n];
        for &u in &b {
            target[u] = true;
            done[u] = true;
        }
        let p = reach_prob(c, &target);
        for t in 0..n {
            value[t] += p[t] * g;
        }
    }
    value
}

/// Every deterministic memoryless policy: the best value per state.
fn enumerate(model: &Model, dir: Direction, value_of: &dyn Fn(&[usize], &Chain) -> Vec<f64>) -> Vec<f64> {
    let n = model.num_states();
    let counts: Vec<usize> = (0..n).map(|s| model.rows(s).len()).collect();
    let mut policy = vec![0usize; n];
    let mut best: Option<Vec<f64>> = None;
    loop {
        let v = value_of(&policy, &chain(model, &policy));
        best = Some(match best {
            None => v,
            Some(b) => b
                .iter()
                .zip(&v)
                .map(|(&x, &y)| match dir {
                    Direction::Min => x.min(y),
                    Direction::Max => x.max(y),
                })
                .collect(),
        });
        let mut i = 0;
        loop {
            if i == n {
                return best.unwrap();
            }
            policy[i] += 1;
            if policy[i] < counts[i] {
                break;
            }
            policy[i] = 0;
            i += 1;
        }
    }
}

/// A random MDP (`ma` false) or Markov automaton of 3–7 states.
fn generate(rng: &mut ChaCha8Rng, ma: bool) -> Model {
    loop {
        let n = rng.random_range(3..=7usize);
        let ty = if ma {
            ModelType::MarkovAutomaton
        } else {
            ModelType::Mdp
        };
        let mut b = ModelBuilder::new(ty, false);
        for _ in 0..n {
            let markovian = ma && rng.random_bool(0.5);
            let exit = if markovian {
                rng.random_range(0.2..5.0)
            } else {
                0.0
            };
            b.state(exit);
            let rows = if markovian {
                1
            } else {
                rng.random_range(1..=3usize)
            };
            for r in 0..rows {
                b.row(&format!("a{r}"));
                let k = rng.random_range(1..=3usize);
                let mut w: Vec<(u32, f64)> = (0..k)
                    .map(|_| (rng.random_range(0..n as u32), rng.random_range(0.1..1.0)))
                    .collect();
                w.sort_by_key(|e| e.0);
                w.dedup_by_key(|e| e.0);
                let total: f64 = w.iter().map(|e| e.1).sum();
                for (t, x) in w {
                    b.entry(t, x / total);
                }
            }
        }
        b.initial(vec![0]);
        let Ok(m) = b.finish() else { continue };
        if m.zeno_states().is_none() {
            return m;
        }
    }
}

fn params() -> OptimizeParams {
    OptimizeParams {
        precision: Precision {
            epsilon: 1e-13,
            ..Precision::default()
        },
    }
}

fn agree(what: &str, got: &petri::mdp::Optimum, want: &[f64]) {
    for (s, &w) in want.iter().enumerate() {
        let (l, u) = (got.lower[s], got.upper[s]);
        if w.is_infinite() {
            assert!(
                l.is_infinite() && u.is_infinite(),
                "{what}, state {s}: got [{l}, {u}], want ∞"
            );
            continue;
        }
        let v = got.value(s);
        assert!(
            (v - w).abs() <= 1e-9 * w.abs().max(1.0),
            "{what}, state {s}: got {v} (bounds [{l}, {u}]), want {w}"
        );
        assert!(
            l <= w + 1e-9 * w.abs().max(1.0) && w <= u + 1e-9 * w.abs().max(1.0),
            "{what}, state {s}: {w} outside [{l}, {u}]"
        );
    }
}

#[test]
fn forty_generated_models_agree_with_policy_enumeration() {
    let mut rng = ChaCha8Rng::seed_from_u64(46);
    for i in 0..40 {
        let ma = i % 2 == 1;
        let model = generate(&mut rng, ma);
        let n = model.num_states();
        let rows = model.num_rows();
        let target: Vec<bool> = (0..n).map(|s| s == n - 1 || rng.random_bool(0.2)).collect();
        let state: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..2.0)).collect();
        let action: Vec<f64> = (0..rows)
            .map(|_| {
                if rng.random_bool(0.5) {
                    rng.random_range(0.0..1.0)
                } else {
                    0.0
                }
            })
            .collect();
        let tau = |s: usize| {
            if !ma {
                1.0
            } else if model.is_markovian(s) {
                1.0 / model.exit_rate(s)
            } else {
                0.0
            }
        };
        // Reward of each state's chosen row: the row's plus the state's
        // over its sojourn.
        let rho_of = |policy: &[usize], st: &[f64], ac: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|s| ac[model.rows(s).start + policy[s]] + st[s] * tau(s))
                .collect()
        };
        for dir in [Direction::Min, Direction::Max] {
            let what = |o: &str| format!("model {i} ({}), {o}{}", if ma { "MA" } else { "MDP" }, dir.name());
            let reach = Goal::Reach {
                target: target.clone(),
            };
            let opt = optimize(&model, &reach, dir, &params(), petri::Interrupt::NEVER).unwrap();
            agree(
                &what("P"),
                &opt,
                &enumerate(&model, dir, &|_, c| reach_prob(c, &target)),
            );
            for (name, st, ac) in [
                ("T", vec![1.0; n], vec![0.0; rows]),
                ("R", state.clone(), action.clone()),
            ] {
                let goal = Goal::Total {
                    target: target.clone(),
                    state: st.clone(),
                    action: ac.clone(),
                };
                let opt = optimize(&model, &goal, dir, &params(), petri::Interrupt::NEVER).unwrap();
                let want = enumerate(&model, dir, &|pol, c| total(c, &target, &rho_of(pol, &st, &ac)));
                agree(&what(name), &opt, &want);
            }
            let goal = Goal::LongRun {
                state: state.clone(),
                action: action.clone(),
            };
            let opt = optimize(&model, &goal, dir, &params(), petri::Interrupt::NEVER).unwrap();
            let want = enumerate(&model, dir, &|pol, c| long_run(c, &rho_of(pol, &state, &action)));
            agree(&what("LRA"), &opt, &want);
        }
    }
}
