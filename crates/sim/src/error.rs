//! The error type of the simulator.

use std::path::PathBuf;

/// What can go wrong when loading worlds or setting up and running a
/// simulation. User input never panics: it ends up here.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written.
    #[error("cannot access {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// A map or world description is malformed.
    #[error("{location}: {message}")]
    Format {
        /// Where (file, key, line when known).
        location: String,
        /// What is wrong.
        message: String,
    },
    /// A parameter is out of range (zero resolution, negative radius…).
    #[error("{what} must be {requirement}, got {}", shown(*.value))]
    InvalidValue {
        /// Which parameter.
        what: String,
        /// The rule.
        requirement: &'static str,
        /// The value given.
        value: f64,
    },
    /// A pose is not usable (start inside a wall, goal outside the map…).
    #[error("{0}")]
    Geometry(String),
}

/// Shorthand for `Result<T, sim::Error>`.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A number as a message shows it: plain, or in scientific notation when
/// very large or small (`1e300`, not 301 digits).
fn shown(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-6..1e15).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}
