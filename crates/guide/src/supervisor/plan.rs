//! How the crediting supervisor turns its net and one context's rates into
//! the behaviour to run: a [`Planner`].
//!
//! The controller asks its planner at every decision event (the start of a
//! mission, every Warning, every return to Success) with the rates of the
//! context it is in — the route and the crowd, re-estimated from the log
//! ([`super::credit_learning::CreditModel::rates`]) — under each
//! hypothesis: the rates differ between hypotheses where they belong to the
//! behaviour that runs (λ3, λ4: contour tracking earns credit for keeping
//! the robot localized). The planner answers with the value of each choice
//! and the choice ([`CreditDecision`]).
//!
//! Today's planner is the two-hypothesis comparison of
//! [`CreditSupervisor`]: the net solved once with each behaviour kept (at a
//! Warning, contour tracking until localized), the larger completion
//! throughput chosen — `1 / throughput` is the expected time per completed
//! mission, a failure costing the time limit. A planner that takes the
//! optimal policy of the net as a decision net (the behaviour a decision
//! transition, the objective the expected time to complete the mission)
//! re-solved with the same rates is another implementation of this trait;
//! the controller does not change.

use super::SupervisorError;
use super::credit::{CreditDecision, CreditRates, CreditSupervisor};

/// Chooses the behaviour to run from a context's rates (module docs).
pub trait Planner: std::fmt::Debug + Send + Sync {
    /// A short name for logs and reports (`two_hypotheses`).
    fn name(&self) -> &'static str;

    /// The identity of the net it plans on (name and a hash of its text),
    /// for mission logs.
    fn net_id(&self) -> &str;

    /// The decision with `automove`'s rates under the AutoMove hypothesis
    /// and `contour`'s under the contour one, the localizer `localized`
    /// (Success) or not (Warning).
    fn decide(
        &self,
        automove: &CreditRates,
        contour: &CreditRates,
        localized: bool,
    ) -> Result<CreditDecision, SupervisorError>;
}

impl Planner for CreditSupervisor {
    fn name(&self) -> &'static str {
        "two_hypotheses"
    }

    fn net_id(&self) -> &str {
        CreditSupervisor::net_id(self)
    }

    fn decide(
        &self,
        automove: &CreditRates,
        contour: &CreditRates,
        localized: bool,
    ) -> Result<CreditDecision, SupervisorError> {
        self.decide_with(automove, contour, localized)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::supervisor::Behaviour;

    #[test]
    fn a_planner_sees_each_hypothesis_with_its_own_localizer_rates() {
        let s = CreditSupervisor::new().unwrap();
        let p: &dyn Planner = &s;
        assert_eq!(p.name(), "two_hypotheses");
        let mut auto = CreditRates::initial();
        auto.try_set(7, 1.0 / 60.0).unwrap();
        auto.try_set(8, 1.0 / 70.0).unwrap();
        // AutoMove slightly faster, but lost often (λ3) and failing while
        // lost; contour tracking keeps the robot localized.
        auto.try_set(3, 1.0 / 10.0).unwrap();
        auto.try_set(12, 1.0 / 5.0).unwrap();
        let mut cont = auto;
        cont.try_set(3, 1.0 / 1000.0).unwrap();
        let d = p.decide(&auto, &cont, true).unwrap();
        assert_eq!(d.choice, Behaviour::Contour, "{d:?}");
        // Both lost as often, and AutoMove not failing while lost: the
        // faster one.
        let mut same = auto;
        same.try_set(12, 0.001).unwrap();
        let d = p.decide(&same, &same, true).unwrap();
        assert_eq!(d.choice, Behaviour::AutoMove, "{d:?}");
    }
}
