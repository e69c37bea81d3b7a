//! A controller that plays a fixed list of commands, for users who want to
//! drive a robot through a world by hand and for tests.

use robot::{Command, Controller, Notes, Perception, Step};

use crate::error::Result;
use crate::validate;

/// Plays `(command, duration)` segments in order, by the perception's
/// clock: segment `k` runs for `t` in `[T_k, T_k + duration_k)` with `T_k`
/// the sum of the earlier durations. After the last segment it answers
/// `Step::Done(Command::Stop)` (the run then ends by goal, collision or time
/// limit). Reusable: a clock that goes back (a new run) restarts the script.
///
/// ```
/// use robot::Command;
/// let script = sim::ScriptedController::new(vec![
///     (Command::Twist { v_mps: 0.3, omega_radps: 0.0 }, 2.0),
///     (Command::Wheels { left_mps: -0.1, right_mps: 0.1 }, 1.5),
/// ])?;
/// assert_eq!(script.duration_s(), 3.5);
/// # Ok::<(), sim::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ScriptedController {
    segments: Vec<(Command, f64)>,
    /// End time of each segment, seconds.
    ends_s: Vec<f64>,
    current: usize,
    last_time_s: f64,
}

impl ScriptedController {
    /// A script; durations must be finite and ≥ 0, seconds.
    pub fn new(segments: Vec<(Command, f64)>) -> Result<ScriptedController> {
        let mut ends_s = Vec::with_capacity(segments.len());
        let mut t = 0.0;
        for (k, (_, d)) in segments.iter().enumerate() {
            validate::non_negative(&format!("script segment {k} duration_s"), *d)?;
            t += d;
            ends_s.push(t);
        }
        Ok(ScriptedController {
            segments,
            ends_s,
            current: 0,
            last_time_s: 0.0,
        })
    }

    /// Total duration of the script, seconds.
    pub fn duration_s(&self) -> f64 {
        self.ends_s.last().copied().unwrap_or(0.0)
    }

    /// The command for time `time_s`, if the script has not ended.
    pub fn command_at(&mut self, time_s: f64) -> Option<Command> {
        if time_s < self.last_time_s {
            self.current = 0;
        }
        self.last_time_s = time_s;
        // Tolerance for clocks computed as tick · period.
        while self.current < self.ends_s.len() && time_s + 1e-9 >= self.ends_s[self.current] {
            self.current += 1;
        }
        self.segments.get(self.current).map(|s| s.0)
    }
}

impl Controller for ScriptedController {
    fn step(&mut self, perception: &Perception, notes: &mut Notes) -> Step {
        match self.command_at(perception.time_s) {
            Some(c) => {
                notes.behaviour("script");
                notes.value("segment", self.current as f64);
                Step::Run(c)
            }
            None => Step::Done(Command::Stop),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plays_segments_by_time_and_restarts() {
        let a = Command::Twist {
            v_mps: 0.3,
            omega_radps: 0.0,
        };
        let b = Command::Stop;
        let mut s = ScriptedController::new(vec![(a, 0.3), (b, 0.0), (b, 0.2)]).unwrap();
        let got: Vec<Option<Command>> = (0..7).map(|k| s.command_at(k as f64 * 0.1)).collect();
        assert_eq!(got, vec![Some(a), Some(a), Some(a), Some(b), Some(b), None, None]);
        assert_eq!(s.command_at(0.0), Some(a));
        assert!(matches!(
            ScriptedController::new(vec![(a, -1.0)]),
            Err(crate::Error::InvalidValue { .. })
        ));
    }
}
