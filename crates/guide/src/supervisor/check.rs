//! Checking a supervisor net before it decides anything.
//!
//! A supervisor decides by the throughput of a completion in the long run
//! of its net. That number only means what it should if the net is a
//! proper model of missions after missions: every place bounded (a state
//! space to solve at all), no dead marking (no mission that can neither
//! succeed nor fail), every transition live (each way of completing or
//! failing stays possible), and one home state (the long run does not
//! depend on where the net started: a single bottom component, so the
//! steady state is unique). [`check_net`] computes these with our own
//! engine ([`petri::Properties`]) on the net as written *and* on every
//! hypothesis the supervisor will solve (a hypothesis leaves transitions
//! out, which can kill a transition the file keeps alive), and
//! [`NetCheck::require`] refuses the net with the first property that
//! fails.
//!
//! **Rates and weights first.** Before the structure, every rate and
//! weight is evaluated as the solver would evaluate it, in every variant
//! (the file's parameters, the variant's bound over them): a rate must be
//! a finite number > 0, a weight a finite number > 0 (the engine leaves a
//! branch of weight 0 out rather than weighting it 0), and every name an
//! expression uses a parameter of the net with a value. Each problem
//! names the transition, the expression and its value ([`ValueProblem`]).
//!
//! **What the learner writes.** A supervisor does not solve the file's
//! rates: it binds each timed transition's rate to one of its parameters
//! `lambda1…lambdaN` and writes the values it learnt into them. The
//! learners ([`super::learning`], [`super::credit_learning`]) write only
//! finite numbers > 0 (`Rates::try_set`, `CreditRates::try_set` refuse
//! anything else, and their estimates — events over exposure with one
//! pseudo-event at a prior > 0, `1 / mean time` over validated
//! durations — are never 0, infinite or NaN); the hypotheses set λ1, λ2 to
//! 0.001 or 1000 and `p` to 0 or 1. So a rate written as the bare
//! parameter is a finite number > 0 for *every* value the learner can
//! write, while any other expression (`lambda7 / 0`, `lambda7 - 0.01`,
//! `2 * lambda7`) is not what the supervisor solves at all.
//! [`check_supervisor`] therefore requires, besides [`check_net`], every
//! timed transition's rate to be one of the bound parameters
//! ([`RateBinding`]): that covers the learner's whole range, not samples
//! of it.
//!
//! Cost: one reachability graph per variant — for the shipped nets about
//! twenty markings each, well under a millisecond.

use petri::{ExploreParams, Expr, Gspn, Net, Params, ReachabilityGraph, TransitionKind};

/// Markings above which a supervisor net counts as unbounded: the nets
/// have a few dozen; a net with more is not a supervisor.
pub const MAX_SUPERVISOR_MARKINGS: usize = 100_000;

/// One variant of a net and its verdict.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct VariantCheck {
    /// Which variant: `as written`, or the hypothesis' name.
    pub variant: String,
    /// The transitions left out.
    pub without: Vec<String>,
    /// Rates and weights the solver would refuse, in transition order.
    pub values: Vec<ValueProblem>,
    /// Markings (tangible and vanishing) when bounded.
    pub markings: Option<usize>,
    /// Every place bounded (within [`MAX_SUPERVISOR_MARKINGS`] markings).
    pub bounded: bool,
    /// Markings that enable nothing.
    pub dead_markings: usize,
    /// Transitions that are not live (L4), by name.
    pub not_live: Vec<String>,
    /// A home state exists: the graph has one bottom strongly connected
    /// component.
    pub home_state: bool,
    /// `M0` itself is a home state.
    pub reversible: bool,
    /// Why the net could not be explored, if it could not.
    pub error: Option<String>,
}

impl VariantCheck {
    /// The first property that fails, in the order rates and weights,
    /// the net built and explored, bounded, no dead marking, live, home
    /// state.
    pub fn failure(&self) -> Option<String> {
        if let Some(first) = self.values.first() {
            return Some(match self.values.len() {
                1 => first.to_string(),
                n => format!("{first} (and {} more)", n - 1),
            });
        }
        if let Some(e) = &self.error {
            return Some(e.clone());
        }
        if !self.bounded {
            return Some(format!(
                "not bounded: more than {MAX_SUPERVISOR_MARKINGS} reachable markings"
            ));
        }
        if self.dead_markings > 0 {
            return Some(format!("{} dead marking(s)", self.dead_markings));
        }
        if !self.not_live.is_empty() {
            return Some(format!("not live: {}", self.not_live.join(", ")));
        }
        if !self.home_state {
            return Some("no home state (more than one bottom component)".into());
        }
        None
    }
}

/// The verdict on a net: every variant checked.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NetCheck {
    /// The net's name.
    pub net: String,
    /// Timed transitions whose rate is not one of the parameters the
    /// supervisor binds ([`check_supervisor`]; empty for [`check_net`]).
    pub bound_rates: Vec<ValueProblem>,
    /// The variants, the net as written first.
    pub variants: Vec<VariantCheck>,
}

/// A rate or weight the solver, or the supervisor, would refuse.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ValueProblem {
    /// The transition.
    pub transition: String,
    /// `rate` or `weight`.
    pub what: &'static str,
    /// The expression as written (empty when there is none).
    pub expression: String,
    /// Its value, when it could be evaluated.
    pub value: Option<f64>,
    /// What is wrong.
    pub problem: String,
}

impl std::fmt::Display for ValueProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the {} of `{}`", self.what, self.transition)?;
        if !self.expression.is_empty() {
            write!(f, ", `{}`", self.expression)?;
        }
        if let Some(v) = self.value {
            write!(f, " = {v}")?;
        }
        write!(f, ": {}", self.problem)
    }
}

/// How a supervisor binds its rates: each timed transition's rate is one
/// of the parameters `{prefix}1` … `{prefix}{count}` (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RateBinding {
    /// The parameters' common prefix, `lambda`.
    pub prefix: &'static str,
    /// How many there are (11 for the source's net, 15 for the crediting one).
    pub count: usize,
}

impl RateBinding {
    /// `lambda1` … `lambda{count}`.
    pub const fn lambdas(count: usize) -> RateBinding {
        RateBinding {
            prefix: "lambda",
            count,
        }
    }

    /// Whether `e` is one of the bound parameters alone.
    fn binds(&self, e: &Expr) -> bool {
        match e {
            Expr::Param(p) => p
                .strip_prefix(self.prefix)
                .filter(|k| !k.starts_with('0'))
                .and_then(|k| k.parse::<usize>().ok())
                .is_some_and(|k| (1..=self.count).contains(&k)),
            _ => false,
        }
    }
}

/// A net refused by [`NetCheck::require`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the supervisor net `{net}` is refused: {variant}: {property}")]
pub struct NetRefused {
    /// The net.
    pub net: String,
    /// The variant that fails.
    pub variant: String,
    /// The property that fails.
    pub property: String,
}

impl NetCheck {
    /// Whether every rate is bound and every variant has every property.
    pub fn passed(&self) -> bool {
        self.require().is_ok()
    }

    /// `Ok` when every rate is bound and every variant has every property;
    /// else the first failure.
    pub fn require(&self) -> Result<(), NetRefused> {
        // Values the solver refuses first (they are what the file says),
        // then the rates the supervisor cannot bind, then the structure.
        if let Some(v) = self.variants.iter().find(|v| !v.values.is_empty()) {
            return Err(NetRefused {
                net: self.net.clone(),
                variant: v.variant.clone(),
                property: v.failure().unwrap_or_default(),
            });
        }
        if let Some(first) = self.bound_rates.first() {
            return Err(NetRefused {
                net: self.net.clone(),
                variant: "the rates the supervisor learns".into(),
                property: match self.bound_rates.len() {
                    1 => first.to_string(),
                    n => format!("{first} (and {} more)", n - 1),
                },
            });
        }
        for v in &self.variants {
            if let Some(property) = v.failure() {
                return Err(NetRefused {
                    net: self.net.clone(),
                    variant: v.variant.clone(),
                    property,
                });
            }
        }
        Ok(())
    }
}

/// A hypothesis to check: a name, the transitions it leaves out, and the
/// parameters it binds.
#[derive(Debug, Clone)]
pub struct Variant<'a> {
    /// Its name.
    pub name: &'a str,
    /// Transitions left out.
    pub without: &'a [&'a str],
    /// Parameters bound (the rest keep the file's values).
    pub params: Params,
}

fn check_variant(net: &Net, v: &Variant<'_>) -> VariantCheck {
    let mut out = VariantCheck {
        variant: v.name.to_string(),
        without: v.without.iter().map(|s| s.to_string()).collect(),
        values: Vec::new(),
        markings: None,
        bounded: false,
        dead_markings: 0,
        not_live: Vec::new(),
        home_state: false,
        reversible: false,
        error: None,
    };
    let mut n = net.clone();
    for t in v.without {
        match n.without_transition(t) {
            Ok(m) => n = m,
            Err(e) => {
                out.error = Some(e.to_string());
                return out;
            }
        }
    }
    out.values = value_problems(&n, &v.params);
    let gspn: Gspn = match n.instantiate(&v.params) {
        Ok(g) => g,
        Err(e) => {
            out.error = Some(e.to_string());
            return out;
        }
    };
    let explore = ExploreParams {
        max_states: MAX_SUPERVISOR_MARKINGS,
        ..ExploreParams::default()
    };
    let rg = match ReachabilityGraph::explore(&gspn, &explore) {
        Ok(rg) => rg,
        Err(petri::Error::StateLimit { .. }) => return out,
        Err(e) => {
            out.error = Some(e.to_string());
            return out;
        }
    };
    let p = petri::Properties::of(&gspn, &rg);
    out.markings = Some(rg.num_markings());
    out.bounded = true;
    out.dead_markings = p.dead_markings.len();
    let live: std::collections::BTreeSet<u32> = p.live_transitions.iter().map(|t| t.0).collect();
    out.not_live = (0..gspn.num_transitions() as u32)
        .filter(|t| !live.contains(t))
        .map(|t| gspn.transition_names()[t as usize].clone())
        .collect();
    out.home_state = p.terminal_components == 1;
    out.reversible = p.reversible;
    out
}

/// Every rate and weight of `net` evaluated with the file's parameters
/// under `overrides`, and what the solver would refuse (module docs).
pub fn value_problems(net: &Net, overrides: &Params) -> Vec<ValueProblem> {
    let value = |name: &str| -> Result<f64, String> {
        if let Some(v) = overrides.get(name) {
            return Ok(v);
        }
        match net.param(name) {
            Some(p) => p
                .value
                .ok_or_else(|| format!("parameter `{name}` has no value in the file")),
            None => Err(format!(
                "`{name}` is not a parameter of the net{}",
                closest_param(net, name)
            )),
        }
    };
    let mut out = Vec::new();
    for t in &net.transitions {
        let (what, expr, rule) = match &t.kind {
            TransitionKind::Timed { rate: Some(e), .. } => ("rate", e, "a rate must be a finite number > 0"),
            TransitionKind::Timed { rate: None, .. } => {
                out.push(ValueProblem {
                    transition: t.name.clone(),
                    what: "rate",
                    expression: String::new(),
                    value: None,
                    problem: "the transition has no rate".into(),
                });
                continue;
            }
            TransitionKind::Immediate { weight, .. } => (
                "weight",
                weight,
                "a weight must be a finite number > 0 (a branch of weight 0 is left out of the net)",
            ),
        };
        let evaluated = expr.eval_with(&mut |n| value(n), &mut |p| {
            Err(format!("it reads the marking (#{p}): rates and weights may not"))
        });
        let problem = match evaluated {
            Ok(v) if v.is_finite() && v > 0.0 => continue,
            Ok(v) => (Some(v), rule.to_string()),
            Err(message) => (None, message),
        };
        out.push(ValueProblem {
            transition: t.name.clone(),
            what,
            expression: expr.to_string(),
            value: problem.0,
            problem: problem.1,
        });
    }
    out
}

/// `; did you mean `NAME`?` for the net's parameter closest to `name`, if
/// one is close.
fn closest_param(net: &Net, name: &str) -> String {
    let names: Vec<&str> = net.params.iter().map(|p| p.name.as_str()).collect();
    petri::closest(name, &names).map_or(String::new(), |c| format!("; did you mean `{c}`?"))
}

/// The timed transitions of `net` whose rate is not one of the parameters
/// `binding` names (module docs: then every value the learner writes
/// gives a rate the solver takes).
pub fn unbound_rates(net: &Net, binding: &RateBinding) -> Vec<ValueProblem> {
    net.transitions
        .iter()
        .filter_map(|t| match &t.kind {
            TransitionKind::Timed { rate, .. } if !rate.as_ref().is_some_and(|e| binding.binds(e)) => {
                Some(ValueProblem {
                    transition: t.name.clone(),
                    what: "rate",
                    expression: rate.as_ref().map(ToString::to_string).unwrap_or_default(),
                    value: None,
                    problem: format!(
                        "the supervisor binds each rate to one of {p}1 … {p}{n} and writes what it learnt there; write the rate as that parameter alone",
                        p = binding.prefix,
                        n = binding.count
                    ),
                })
            }
            _ => None,
        })
        .collect()
}

/// [`check_net`], and every timed transition's rate one of the parameters
/// the supervisor binds ([`unbound_rates`]).
pub fn check_supervisor(net: &Net, variants: &[Variant<'_>], binding: &RateBinding) -> NetCheck {
    NetCheck {
        bound_rates: unbound_rates(net, binding),
        ..check_net(net, variants)
    }
}

/// Checks `net` as written and under each of `variants` (module docs).
pub fn check_net(net: &Net, variants: &[Variant<'_>]) -> NetCheck {
    let mut all = vec![check_variant(
        net,
        &Variant {
            name: "as written",
            without: &[],
            params: Params::new(),
        },
    )];
    all.extend(variants.iter().map(|v| check_variant(net, v)));
    NetCheck {
        net: net.name.clone(),
        bound_rates: Vec::new(),
        variants: all,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn net(text: &str) -> Net {
        petri::io::read_str(text, petri::io::Format::Toml, "test.toml").unwrap()
    }

    const CYCLE: &str = r#"
name = "cycle"
[params]
a = 1.0
[[place]]
name = "A"
initial = 1
[[place]]
name = "B"
[[transition]]
name = "go"
rate = "a"
inputs = ["A"]
outputs = ["B"]
[[transition]]
name = "back"
rate = "a"
inputs = ["B"]
outputs = ["A"]
"#;

    #[test]
    fn a_cycle_passes_and_leaving_out_its_return_kills_it() {
        let n = net(CYCLE);
        let c = check_net(&n, &[]);
        assert!(c.passed(), "{c:?}");
        assert_eq!(c.variants[0].markings, Some(2));
        let c = check_net(
            &n,
            &[Variant {
                name: "one way",
                without: &["back"],
                params: Params::new(),
            }],
        );
        let e = c.require().unwrap_err();
        assert_eq!(e.variant, "one way");
        assert_eq!(e.property, "1 dead marking(s)");
    }

    /// Regression (issue 51): the check accepted the crediting net with a
    /// rate the solver refuses.
    #[test]
    fn rates_the_solver_refuses_are_named_with_their_expression_and_value() {
        let net = |from: &str, to: &str| {
            let text = super::super::credit::CREDIT_MODEL.replacen(from, to, 1);
            assert_ne!(text, super::super::credit::CREDIT_MODEL, "{from}");
            petri::io::read_str(&text, petri::io::Format::Toml, "m.toml").unwrap()
        };
        let variants = super::super::credit::credit_variants();
        let binding = super::super::credit::CREDIT_RATE_BINDING;
        for (from, to, says) in [
            (
                "value = 0.0082",
                "value = -0.0082",
                "`lambda7` = -0.0082: a rate must be a finite number > 0",
            ),
            ("value = 0.0082", "value = nan", "`lambda7` = NaN"),
            ("value = 0.0082", "value = inf", "`lambda7` = inf"),
            ("value = 0.0082", "value = 0", "`lambda7` = 0: a rate"),
            (
                "rate = \"lambda7\"",
                "rate = \"lambda7 / 0\"",
                "`lambda7 / 0` = inf",
            ),
            (
                "rate = \"lambda7\"",
                "rate = \"lambda77\"",
                "`lambda77` is not a parameter of the net; did you mean `lambda7`?",
            ),
        ] {
            let c = check_supervisor(&net(from, to), &variants, &binding);
            let e = c.require().unwrap_err();
            assert!(e.to_string().contains(says), "{to}: {e}");
            assert!(e.property.starts_with("the rate of `t9`"), "{e}");
            // Every variant has the problem; the structure is still shown.
            assert!(
                c.variants
                    .iter()
                    .all(|v| v.values.len() == 1 && v.markings.is_some())
            );
        }
        // A rate the supervisor cannot bind, though the file's value is fine.
        let c = check_supervisor(
            &net("rate = \"lambda7\"", "rate = \"2 * lambda7\""),
            &variants,
            &binding,
        );
        assert!(c.variants.iter().all(|v| v.values.is_empty()));
        let e = c.require().unwrap_err();
        assert!(e.property.contains("one of lambda1 … lambda15"), "{e}");
        // The shipped net passes.
        let shipped = petri::io::read_str(
            super::super::credit::CREDIT_MODEL,
            petri::io::Format::Toml,
            "m.toml",
        )
        .unwrap();
        assert!(check_supervisor(&shipped, &variants, &binding).passed());
    }

    #[test]
    fn bindings_are_the_bare_parameters_only() {
        let b = RateBinding::lambdas(11);
        for (e, ok) in [
            ("lambda1", true),
            ("lambda11", true),
            ("lambda12", false),
            ("lambda0", false),
            ("lambda07", false),
            ("mu", false),
            ("lambda1 * 2", false),
        ] {
            assert_eq!(b.binds(&Expr::parse(e).unwrap()), ok, "{e}");
        }
    }

    #[test]
    fn an_unbounded_net_is_refused_not_exhausted() {
        let n = net(&CYCLE.replace("outputs = [\"A\"]", "outputs = [\"A\", \"A\"]"));
        let e = check_net(&n, &[]).require().unwrap_err();
        assert!(e.property.starts_with("not bounded"), "{e}");
    }

    #[test]
    fn two_bottom_components_have_no_home_state() {
        // From A the token goes to B or C for good, each cycling on itself.
        let text = r#"
name = "split"
[params]
a = 1.0
[[place]]
name = "A"
initial = 1
[[place]]
name = "B"
[[place]]
name = "C"
[[transition]]
name = "toB"
rate = "a"
inputs = ["A"]
outputs = ["B"]
[[transition]]
name = "toC"
rate = "a"
inputs = ["A"]
outputs = ["C"]
[[transition]]
name = "loopB"
rate = "a"
inputs = ["B"]
outputs = ["B"]
[[transition]]
name = "loopC"
rate = "a"
inputs = ["C"]
outputs = ["C"]
"#;
        let e = check_net(&net(text), &[]).require().unwrap_err();
        // Neither toB nor toC can fire again: not live comes first.
        assert!(e.property.starts_with("not live"), "{e}");
        let v = &check_net(&net(text), &[]).variants[0];
        assert!(!v.home_state);
    }
}
