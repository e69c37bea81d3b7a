//! GSPN behaviour selection for the tour-guide robot (`docs/gspn.md`,
//! `docs/tour-guide.md`).
//!
//! The supervisor net (`models/supervisor.toml`, embedded as [`MODEL`]) is
//! solved under two hypotheses:
//!
//! | hypothesis | λ1 | λ2 | p | left out |
//! |---|---|---|---|---|
//! | AutoMove | 0.001 | 1000 | 1 | `t1` |
//! | Contour | 1000 | 0.001 | 0 | `t0` |
//!
//! `f_auto = throughput(t9)` under the AutoMove hypothesis and
//! `f_cont = throughput(t10)` under the Contour one; AutoMove is chosen iff
//! `f_auto > f_cont` (ties go to Contour tracking, the behaviour that also
//! helps the localizer).
//!
//! Both hypotheses are compiled once ([`Supervisor::new`]); a decision binds
//! the current rates and re-solves the two 13-state chains, which takes a few
//! microseconds.
//!
//! **Decision** (reported measures): `u_auto = P{#P1 = 1}` is read under the
//! AutoMove hypothesis and `u_cont = P{#P2 = 1}` under the Contour one; the
//! localizer and planner probabilities are read under the hypothesis that was
//! chosen — the behaviour the robot is about to run.

pub mod check;
pub mod credit;
pub mod credit_learning;
pub mod learning;
pub mod log;
pub mod plan;
pub mod reference;
pub mod shrinkage;

use petri::{CompiledGspn, ExploreParams, Net, Params, PlaceId, Solution, SolveParams, TransitionId};

/// The supervisor net as shipped in `models/supervisor.toml`.
pub const MODEL: &str = include_str!("../../../../models/supervisor.toml");

/// Number of rates λ1…λ11.
pub const NUM_RATES: usize = 11;

/// The parameters the source's supervisor binds its rates to, `lambda1` …
/// `lambda11` ([`check::check_supervisor`]).
pub const RATE_BINDING: check::RateBinding = check::RateBinding::lambdas(NUM_RATES);

/// λ1 and λ2 of the hypothesis favouring a behaviour (switching towards it).
pub const FAST_SWITCH: f64 = 1000.0;
/// λ1 and λ2 of the hypothesis disfavouring a behaviour.
pub const SLOW_SWITCH: f64 = 0.001;

/// What can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum SupervisorError {
    /// The net could not be read, built or solved.
    #[error(transparent)]
    Petri(#[from] petri::Error),
    /// The net does not have the supervisor's structure.
    #[error("not a supervisor net: {0}")]
    Model(String),
    /// The net failed its check ([`check`]).
    #[error(transparent)]
    Refused(#[from] check::NetRefused),
    /// A rate outside (0, ∞) or an index outside the net's rates.
    #[error("λ{index} = {value}: rates are finite numbers > 0, indexed from 1 to the net's last")]
    BadRate {
        /// 1-based index.
        index: usize,
        /// The value given.
        value: f64,
    },
}

/// The rates λ1…λ11 of the supervisor net.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Rates {
    lambda: [f64; NUM_RATES],
}

impl Rates {
    /// The source's starting rates, before any mission was logged:
    /// `(0.001, 1000, 0.001, 1000, 0.001, 1000, 0.0082, 0.0053, 0.001, 0.001, 1000)`.
    pub fn initial() -> Rates {
        Rates {
            lambda: [
                0.001, 1000.0, 0.001, 1000.0, 0.001, 1000.0, 0.0082, 0.0053, 0.001, 0.001, 1000.0,
            ],
        }
    }

    /// λ`i` (1-based).
    pub fn get(&self, i: usize) -> f64 {
        self.lambda[i - 1]
    }

    /// Sets λ`i` (1-based). Panics on an index outside 1..=11; use
    /// [`Rates::try_set`] for input from users.
    pub fn set(&mut self, i: usize, value: f64) {
        self.lambda[i - 1] = value;
    }

    /// Sets λ`i`, checking the index and the value.
    pub fn try_set(&mut self, i: usize, value: f64) -> Result<(), SupervisorError> {
        if !((1..=NUM_RATES).contains(&i) && value.is_finite() && value > 0.0) {
            return Err(SupervisorError::BadRate { index: i, value });
        }
        self.lambda[i - 1] = value;
        Ok(())
    }

    /// All eleven, λ1 first.
    pub fn as_array(&self) -> [f64; NUM_RATES] {
        self.lambda
    }
}

/// The two navigation behaviours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Behaviour {
    /// Map-based planner (navigation function).
    #[serde(rename = "automove")]
    AutoMove,
    /// Wall following.
    Contour,
}

/// A decision and the measures behind it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Decision {
    /// Throughput of `t9` (AutoMove completes) under the AutoMove hypothesis.
    pub f_auto: f64,
    /// Throughput of `t10` (Contour completes) under the Contour hypothesis.
    pub f_cont: f64,
    /// AutoMove iff `f_auto > f_cont`.
    pub choice: Behaviour,
    /// `P{#P1 = 1}` under the AutoMove hypothesis.
    pub u_auto: f64,
    /// `P{#P2 = 1}` under the Contour hypothesis.
    pub u_cont: f64,
    /// `P{#P5 = 1}` (localizer Success) under the chosen hypothesis.
    pub p_loc_succ: f64,
    /// `P{#P6 = 1}` (localizer Warning) under the chosen hypothesis.
    pub p_loc_warn: f64,
    /// `P{#P7 = 1}` (planner Normal) under the chosen hypothesis.
    pub p_pp_norm: f64,
    /// `P{#P8 = 1}` (planner Abnormal) under the chosen hypothesis.
    pub p_pp_abno: f64,
    /// Tangible markings of the net (13 for the shipped model).
    pub tangible_markings: usize,
}

/// One hypothesis, compiled.
#[derive(Debug, Clone)]
struct Hypothesis {
    compiled: CompiledGspn,
    /// For each transition, the index (0-based) of the λ giving its rate.
    rate_of: Vec<Option<usize>>,
    switch_auto_to_cont: f64,
    switch_cont_to_auto: f64,
}

impl Hypothesis {
    fn new(net: &Net, drop: &str, p: f64, lambda1: f64, lambda2: f64) -> Result<Hypothesis, SupervisorError> {
        let net = net.without_transition(drop)?;
        let gspn = net.instantiate(&Params::new().with("p", p))?;
        let mut rate_of = Vec::with_capacity(gspn.num_transitions());
        for t in 0..gspn.num_transitions() {
            let tid = TransitionId(t as u32);
            if gspn.is_immediate(tid) {
                rate_of.push(None);
                continue;
            }
            let name = &gspn.transition_names()[t];
            let index = match gspn.rate_expr(tid) {
                Some(petri::Expr::Param(p)) => p
                    .strip_prefix("lambda")
                    .and_then(|k| k.parse::<usize>().ok())
                    .filter(|k| (1..=NUM_RATES).contains(k)),
                _ => None,
            };
            let Some(k) = index else {
                return Err(SupervisorError::Model(format!(
                    "the rate of `{name}` must be one of lambda1 … lambda11"
                )));
            };
            rate_of.push(Some(k - 1));
        }
        let compiled = CompiledGspn::build(&gspn, &ExploreParams::default())?;
        Ok(Hypothesis {
            compiled,
            rate_of,
            switch_auto_to_cont: lambda1,
            switch_cont_to_auto: lambda2,
        })
    }

    fn solve(&self, rates: &Rates) -> Result<Solution, SupervisorError> {
        let mut lambda = rates.lambda;
        lambda[0] = self.switch_auto_to_cont;
        lambda[1] = self.switch_cont_to_auto;
        let v: Vec<f64> = self
            .rate_of
            .iter()
            .map(|k| k.map_or(0.0, |k| lambda[k]))
            .collect();
        Ok(self.compiled.solve_rates(&v, &SolveParams::default())?)
    }
}

/// The hypotheses the source's supervisor solves, for [`check::check_net`].
pub fn source_variants() -> Vec<check::Variant<'static>> {
    vec![
        check::Variant {
            name: "AutoMove hypothesis",
            without: &["t1"],
            params: Params::new().with("p", 1.0),
        },
        check::Variant {
            name: "contour hypothesis",
            without: &["t0"],
            params: Params::new().with("p", 0.0),
        },
    ]
}

/// A net's identity: its name and an FNV-1a hash of its text as written in
/// TOML. Mission logs name it, so that rates learnt for one net are never
/// read for another.
pub fn net_id(net: &Net) -> Result<String, SupervisorError> {
    let text = petri::io::write_string(net, petri::io::Format::Toml)?;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    Ok(format!("{}-{h:016x}", net.name))
}

/// Names of the places and transitions the supervisor reads.
#[derive(Debug, Clone, Copy)]
struct Ids {
    auto_done: TransitionId,
    cont_done: TransitionId,
    p1: PlaceId,
    p2: PlaceId,
    p5: PlaceId,
    p6: PlaceId,
    p7: PlaceId,
    p8: PlaceId,
}

/// The supervisor: both hypotheses compiled, ready to decide.
#[derive(Debug, Clone)]
pub struct Supervisor {
    net_id: String,
    auto: Hypothesis,
    cont: Hypothesis,
    auto_ids: Ids,
    cont_ids: Ids,
}

fn ids(c: &CompiledGspn) -> Result<Ids, SupervisorError> {
    let g = c.gspn();
    let model = |e: petri::Error| SupervisorError::Model(e.to_string());
    Ok(Ids {
        auto_done: g.transition("t9").map_err(model)?,
        cont_done: g.transition("t10").map_err(model)?,
        p1: g.place("P1").map_err(model)?,
        p2: g.place("P2").map_err(model)?,
        p5: g.place("P5").map_err(model)?,
        p6: g.place("P6").map_err(model)?,
        p7: g.place("P7").map_err(model)?,
        p8: g.place("P8").map_err(model)?,
    })
}

impl Supervisor {
    /// Compiles the shipped supervisor net.
    pub fn new() -> Result<Supervisor, SupervisorError> {
        let net = petri::io::read_str(MODEL, petri::io::Format::Toml, "models/supervisor.toml")?;
        Supervisor::from_net(&net)
    }

    /// Checks ([`check`]: bounded, live, no dead marking, a home state, as
    /// written and under both hypotheses) and compiles a supervisor net of
    /// the same structure (places `P0`…`P8`, transitions `t0`…`t14`, rates
    /// `lambda1`…`lambda11`, weight `p`); a net failing its check is
    /// refused with the property ([`SupervisorError::Refused`]).
    pub fn from_net(net: &Net) -> Result<Supervisor, SupervisorError> {
        check::check_supervisor(net, &source_variants(), &RATE_BINDING).require()?;
        let net_id = net_id(net)?;
        let auto = Hypothesis::new(net, "t1", 1.0, SLOW_SWITCH, FAST_SWITCH)?;
        let cont = Hypothesis::new(net, "t0", 0.0, FAST_SWITCH, SLOW_SWITCH)?;
        let auto_ids = ids(&auto.compiled)?;
        let cont_ids = ids(&cont.compiled)?;
        Ok(Supervisor {
            net_id,
            auto,
            cont,
            auto_ids,
            cont_ids,
        })
    }

    /// The net's identity: its name and a hash of its text (as written in
    /// TOML). Mission logs name it, so that rates learnt for one net are
    /// never read for another.
    pub fn net_id(&self) -> &str {
        &self.net_id
    }

    /// Tangible markings of the supervisor net.
    pub fn tangible_markings(&self) -> usize {
        self.auto.compiled.num_tangible()
    }

    /// The long-run solution of one hypothesis for these rates.
    pub fn solve(&self, hypothesis: Behaviour, rates: &Rates) -> Result<Solution, SupervisorError> {
        match hypothesis {
            Behaviour::AutoMove => self.auto.solve(rates),
            Behaviour::Contour => self.cont.solve(rates),
        }
    }

    /// Decides between AutoMove and Contour tracking for these rates.
    pub fn decide(&self, rates: &Rates) -> Result<Decision, SupervisorError> {
        for (i, &v) in rates.lambda.iter().enumerate() {
            if !(v.is_finite() && v > 0.0) {
                return Err(SupervisorError::BadRate {
                    index: i + 1,
                    value: v,
                });
            }
        }
        let a = self.auto.solve(rates)?;
        let c = self.cont.solve(rates)?;
        let f_auto = a.throughput(self.auto_ids.auto_done);
        let f_cont = c.throughput(self.cont_ids.cont_done);
        let choice = if f_auto > f_cont {
            Behaviour::AutoMove
        } else {
            Behaviour::Contour
        };
        let (chosen, ids) = match choice {
            Behaviour::AutoMove => (&a, &self.auto_ids),
            Behaviour::Contour => (&c, &self.cont_ids),
        };
        Ok(Decision {
            f_auto,
            f_cont,
            choice,
            u_auto: a.prob_nonempty(self.auto_ids.p1),
            u_cont: c.prob_nonempty(self.cont_ids.p2),
            p_loc_succ: chosen.prob_nonempty(ids.p5),
            p_loc_warn: chosen.prob_nonempty(ids.p6),
            p_pp_norm: chosen.prob_nonempty(ids.p7),
            p_pp_abno: chosen.prob_nonempty(ids.p8),
            tangible_markings: self.tangible_markings(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn museum_rates() -> Rates {
        let mut r = Rates::initial();
        r.set(7, 1.0 / 122.33);
        r.set(8, 1.0 / 186.98);
        r
    }

    #[test]
    fn published_decision() {
        let s = Supervisor::new().unwrap();
        let d = s.decide(&museum_rates()).unwrap();
        assert_eq!(d.tangible_markings, 13);
        assert_eq!(format!("{:.3e}", d.f_cont), "5.348e-3");
        assert!(
            (d.f_auto - 1.0 / 122.33).abs() / (1.0 / 122.33) < 0.01,
            "{}",
            d.f_auto
        );
        assert_eq!(d.choice, Behaviour::AutoMove);
        for p in [
            d.u_auto,
            d.u_cont,
            d.p_loc_succ,
            d.p_loc_warn,
            d.p_pp_norm,
            d.p_pp_abno,
        ] {
            assert!((0.0..=1.0).contains(&p));
        }
        assert!((d.p_loc_succ + d.p_loc_warn - 1.0).abs() < 1e-12);
        assert!((d.p_pp_norm + d.p_pp_abno - 1.0).abs() < 1e-12);
    }

    #[test]
    fn frequent_warnings_favour_contour_tracking() {
        // A crowded museum: the localizer is in Warning a third of the time,
        // the planner often Abnormal, AutoMove fails often.
        let mut r = museum_rates();
        r.set(3, 1.0 / 20.0);
        r.set(4, 1.0 / 10.0);
        r.set(5, 1.0 / 15.0);
        r.set(6, 1.0 / 30.0);
        r.set(9, r.get(7) * 3.0);
        let d = Supervisor::new().unwrap().decide(&r).unwrap();
        assert_eq!(d.choice, Behaviour::Contour, "{d:?}");
        assert!(d.p_loc_warn > 0.2);
    }

    #[test]
    fn the_identities_of_the_spec_hold() {
        // f_cont = λ8·P{#P2 = 1}: t10 is enabled exactly when P2 is marked.
        let s = Supervisor::new().unwrap();
        let r = museum_rates();
        let c = s.solve(Behaviour::Contour, &r).unwrap();
        let p2 = s.cont_ids.p2;
        assert!((c.throughput(s.cont_ids.cont_done) - r.get(8) * c.prob_nonempty(p2)).abs() < 1e-15);
    }

    #[test]
    fn bad_rates_are_errors() {
        let s = Supervisor::new().unwrap();
        let mut r = Rates::initial();
        assert!(r.try_set(12, 1.0).is_err());
        assert!(r.try_set(3, -1.0).is_err());
        assert!(r.try_set(3, f64::NAN).is_err());
        r.set(4, 0.0);
        assert!(matches!(
            s.decide(&r),
            Err(SupervisorError::BadRate { index: 4, .. })
        ));
    }
}
