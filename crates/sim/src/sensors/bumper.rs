//! Bumper: a contact switch around the footprint.
//!
//! **Model.** The bumper is pressed at a tick when the robot's footprint
//! touched an obstacle or a person during the previous control period (a
//! collision, fatal or not), or — with a positive `margin_m` — when the
//! footprint grown by the margin overlaps one now (a bumper skirt that sticks
//! out). Noiseless.

use crate::error::Result;
use crate::validate;

/// Parameters of the bumper.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BumperParams {
    /// Whether the robot has a bumper (if not, `Perception::bumper` stays
    /// `false`). Default `true`.
    pub enabled: bool,
    /// How far the bumper sticks out beyond the footprint, metres.
    /// Default 0.
    pub margin_m: f64,
}

impl Default for BumperParams {
    fn default() -> BumperParams {
        BumperParams {
            enabled: true,
            margin_m: 0.0,
        }
    }
}

impl BumperParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        validate::non_negative("bumper.margin_m", self.margin_m)
    }
}
