//! A simulated robot: its drive and its sensors.

use robot::Pose;

use crate::error::Result;
use crate::kinematics::DriveParams;
use crate::sensors::{BumperParams, IrParams, LaserParams, OdometryParams, SonarParams, rim_mounts};

/// Transducers on the ring of [`RobotParams::sonar_ring`].
pub const SONAR_RING_COUNT: usize = 16;

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
    /// The AIBOT-like robot of the voting experiments (docs/voting.md): radius
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

    /// An AIBOT-sized base (radius 0.15 m) with a ring of 16 sonar
    /// transducers 22.5° apart all round (first straight ahead, cones 25°:
    /// the ring leaves no blind bearing), odometry and a bumper; no IR, no
    /// laser. This is the robot of the dead-lock experiments
    /// (docs/activity-trace.md): the priority controller's behaviours react to
    /// obstacles ahead, on either side and *behind* (speed up), which needs
    /// ranges all round, as on the sonar rings of Pioneer- or Khepera-class
    /// robots such experiments use. AIBOT's binary IR says only "something
    /// within 0.8 m" and it has nothing facing back.
    pub fn sonar_ring() -> RobotParams {
        let angles: Vec<f64> = (0..SONAR_RING_COUNT)
            .map(|k| robot::wrap_angle(std::f64::consts::TAU * k as f64 / SONAR_RING_COUNT as f64))
            .collect();
        RobotParams {
            drive: DriveParams::aibot(),
            lasers: Vec::new(),
            sonar: SonarParams {
                mounts: rim_mounts(&angles, 0.15),
                ..SonarParams::default()
            },
            ir: IrParams::none(),
            odometry: OdometryParams::default(),
            bumper: BumperParams::default(),
        }
    }

    /// The Jinny-like tour-guide robot (docs/tour-guide.md): radius 0.35 m, one
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
