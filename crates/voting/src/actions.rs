//! The discrete action set of the voting controller.
//!
//! Each arc action drives at the cruise speed and turns by its heading
//! angle `θ_m` over the look-ahead time: `ω = θ_m / T`. Escape (`θ_m = π`)
//! turns on the spot — one wheel forward, one backward.

use std::f64::consts::PI;

use robot::Command;

/// What an action does.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ActionKind {
    /// Drive along an arc at the cruise speed.
    Arc,
    /// Turn on the spot.
    Escape,
}

/// One action.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Action {
    /// Name, e.g. "Hard Left".
    pub name: String,
    /// Heading change over the look-ahead, radians (π for Escape).
    pub heading_rad: f64,
    /// Arc or escape.
    pub kind: ActionKind,
}

/// The action set and how actions become motion commands.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ActionSet {
    /// The actions, in order.
    pub actions: Vec<Action>,
    /// Forward speed of arc actions, m/s. Default 0.3 (AIBOT's average speed).
    pub cruise_mps: f64,
    /// Time over which an arc action achieves its heading change, seconds.
    /// Default 1.5.
    pub lookahead_s: f64,
    /// Turn rate of Escape, rad/s. Default 1.5.
    pub escape_radps: f64,
}

impl Default for ActionSet {
    /// Hard Left, Left, Soft Left, Forward, Soft Right, Right, Hard Right
    /// (+90°, +60°, +30°, 0°, −30°, −60°, −90°; left is counter-clockwise)
    /// and Escape.
    fn default() -> ActionSet {
        let arc = |name: &str, deg: f64| Action {
            name: name.into(),
            heading_rad: deg.to_radians(),
            kind: ActionKind::Arc,
        };
        ActionSet {
            actions: vec![
                arc("Hard Left", 90.0),
                arc("Left", 60.0),
                arc("Soft Left", 30.0),
                arc("Forward", 0.0),
                arc("Soft Right", -30.0),
                arc("Right", -60.0),
                arc("Hard Right", -90.0),
                Action {
                    name: "Escape".into(),
                    heading_rad: PI,
                    kind: ActionKind::Escape,
                },
            ],
            cruise_mps: 0.3,
            lookahead_s: 1.5,
            escape_radps: 1.5,
        }
    }
}

impl ActionSet {
    /// Number of actions.
    pub fn len(&self) -> usize {
        self.actions.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.actions.is_empty()
    }

    /// The motion command of action `m`; `turn_left` chooses Escape's
    /// direction.
    pub fn command(&self, m: usize, turn_left: bool) -> Command {
        let a = &self.actions[m];
        match a.kind {
            ActionKind::Arc => Command::Twist {
                v_mps: self.cruise_mps,
                omega_radps: a.heading_rad / self.lookahead_s,
            },
            ActionKind::Escape => Command::Twist {
                v_mps: 0.0,
                omega_radps: if turn_left {
                    self.escape_radps
                } else {
                    -self.escape_radps
                },
            },
        }
    }

    /// Checks the configuration.
    pub fn validate(&self) -> Result<(), String> {
        if self.actions.is_empty() {
            return Err("the action set is empty".into());
        }
        for (what, v) in [
            ("cruise_mps", self.cruise_mps),
            ("lookahead_s", self.lookahead_s),
            ("escape_radps", self.escape_radps),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{what} must be a finite number > 0, got {v}"));
            }
        }
        if let Some(a) = self.actions.iter().find(|a| !a.heading_rad.is_finite()) {
            return Err(format!("action `{}` has a non-finite heading", a.name));
        }
        Ok(())
    }
}
