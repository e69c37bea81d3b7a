//! A simulated robot: its drive and its sensors.

use robot::Pose;

use crate::error::Result;
use crate::kinematics::DriveParams;
use crate::sensors::{BumperParams, IrParams, LaserParams, OdometryParams, SonarParams};

/// Everything that describes the simulated robot. The default is the
/// AIBOT-like robot ([`RobotParams::aibot`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotParams {
    /// Base, footprint and limits.
    pub drive: DriveParams,
    /// Laser range finders (usually none or one); `Perception::lasers[k]`
    /// comes from `lasers[k]`.
    pub lasers: Vec<LaserParams>,
    /// Sonar array (no mounts: none).
    pub sonar: SonarParams,
    /// Infrared detectors (no mounts: none).
    pub ir: IrParams,
    /// Wheel odometry error model.
    pub odometry: OdometryParams,
    /// Bumper.
    pub bumper: BumperParams,
}

impl Default for RobotParams {
    fn default() -> RobotParams {
        RobotParams::aibot()
    }
}

impl RobotParams {
    /// The AIBOT-like robot of the voting experiments (voting.md): radius
    /// 0.15 m, 7 binary IR detectors across the front (range 0.8 m), 3 sonar
    /// transducers at −30°, 0°, +30°, odometry, a bumper; no laser.
    pub fn aibot() -> RobotParams {
        RobotParams {
            drive: DriveParams::aibot(),
            lasers: Vec::new(),
            sonar: SonarParams::default(),
            ir: IrParams::default(),
            odometry: OdometryParams::default(),
            bumper: BumperParams::default(),
        }
    }

    /// The Jinny-like tour-guide robot (tour-guide.md): radius 0.35 m, one
    /// 181-beam laser over 180° (30 m) mounted 0.2 m ahead of the centre,
    /// odometry, a bumper; no sonar or IR.
    pub fn jinny() -> RobotParams {
        RobotParams {
            drive: DriveParams::jinny(),
            lasers: vec![LaserParams {
                mount: Pose::new(0.2, 0.0, 0.0),
                ..LaserParams::default()
            }],
            sonar: SonarParams::none(),
            ir: IrParams::none(),
            odometry: OdometryParams::default(),
            bumper: BumperParams::default(),
        }
    }

    /// Checks every part.
    pub fn validate(&self) -> Result<()> {
        self.drive.validate()?;
        for l in &self.lasers {
            l.validate()?;
        }
        self.sonar.validate()?;
        self.ir.validate()?;
        self.odometry.validate()?;
        self.bumper.validate()
    }
}
