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
//! Cost: one reachability graph per variant — for the shipped nets about
//! twenty markings each, well under a millisecond.

use petri::{ExploreParams, Gspn, Net, Params, ReachabilityGraph};

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
    /// The first property that fails, in the order bounded, no dead
    /// marking, live, home state.
    pub fn failure(&self) -> Option<String> {
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
    /// The variants, the net as written first.
    pub variants: Vec<VariantCheck>,
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
    /// Whether every variant has every property.
    pub fn passed(&self) -> bool {
        self.variants.iter().all(|v| v.failure().is_none())
    }

    /// `Ok` when every variant has every property; else the first failure.
    pub fn require(&self) -> Result<(), NetRefused> {
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
