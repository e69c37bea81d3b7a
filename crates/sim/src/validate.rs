//! Parameter checks shared by the parameter structs: each returns
//! [`Error::InvalidValue`] naming the parameter, the rule and the value.

use crate::error::{Error, Result};

fn fail(what: &str, requirement: &'static str, value: f64) -> Error {
    Error::InvalidValue {
        what: what.to_string(),
        requirement,
        value,
    }
}

/// `value` is finite.
pub(crate) fn finite(what: &str, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(fail(what, "finite", value))
    }
}

/// `value` is finite and > 0.
pub(crate) fn positive(what: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(fail(what, "finite and > 0", value))
    }
}

/// `value` is finite and ≥ 0.
pub(crate) fn non_negative(what: &str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(fail(what, "finite and >= 0", value))
    }
}

/// `value` is a probability, in [0, 1].
pub(crate) fn probability(what: &str, value: f64) -> Result<()> {
    if (0.0..=1.0).contains(&value) {
        Ok(())
    } else {
        Err(fail(what, "a probability in [0, 1]", value))
    }
}

/// `value` lies in `[lo, hi]` (both finite).
pub(crate) fn within(what: &str, value: f64, lo: f64, hi: f64, requirement: &'static str) -> Result<()> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(fail(what, requirement, value))
    }
}

/// A count is at least `min`.
pub(crate) fn count_at_least(what: &str, value: usize, min: usize, requirement: &'static str) -> Result<()> {
    count_within(what, value, min, usize::MAX, requirement)
}

/// A count lies in `[min, max]`.
pub(crate) fn count_within(
    what: &str,
    value: usize,
    min: usize,
    max: usize,
    requirement: &'static str,
) -> Result<()> {
    if value >= min && value <= max {
        Ok(())
    } else {
        Err(fail(what, requirement, value as f64))
    }
}

/// Every component of a pose is finite.
pub(crate) fn pose(what: &str, p: &robot::Pose) -> Result<()> {
    finite(&format!("{what}.x_m"), p.x_m)?;
    finite(&format!("{what}.y_m"), p.y_m)?;
    finite(&format!("{what}.theta_rad"), p.theta_rad)
}

/// Both coordinates of a point are finite.
pub(crate) fn point(what: &str, p: robot::Vec2) -> Result<()> {
    finite(&format!("{what}.x"), p.x)?;
    finite(&format!("{what}.y"), p.y)
}
