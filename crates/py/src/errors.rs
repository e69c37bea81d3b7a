//! Rust errors as Python exceptions.
//!
//! The classes are defined in Python (`petrinav/errors.py`, so that they
//! can also derive from the built-in exception a Python user expects, e.g.
//! `FileError` from `OSError`); this module picks the class for an error
//! and raises it with the command line's message: the `anyhow` chain
//! printed as `petrinav` prints it after `error: ` (`{:#}`).

use std::any::Any;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyType;

/// The `petrinav.errors` classes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// `Error`: none of the others.
    Error,
    /// `FileError`: a file that cannot be read or written.
    File,
    /// `FormatError`: a malformed or invalid net file.
    Format,
    /// `ParameterError`: parameters, rates, options out of range.
    Parameter,
    /// `MeasureError`: a measure that does not parse or names what the net lacks.
    Measure,
    /// `StateLimitError`: the state space is beyond a limit.
    StateLimit,
    /// `SolveError`: the numerical solution failed.
    Solve,
    /// `SimulationError`: a simulation hit its event or wall-time cap.
    Simulation,
    /// `NavError`: the guide robot's runs (places, crowd, policy…).
    Nav,
    /// `MapError`: a map or places file.
    Map,
    /// `LabError`: suites, scenarios, results folders.
    Lab,
    /// `PanicError`: a bug in petrinav (a Rust panic).
    Panic,
}

impl Kind {
    fn class_name(self) -> &'static str {
        match self {
            Kind::Error => "Error",
            Kind::File => "FileError",
            Kind::Format => "FormatError",
            Kind::Parameter => "ParameterError",
            Kind::Measure => "MeasureError",
            Kind::StateLimit => "StateLimitError",
            Kind::Solve => "SolveError",
            Kind::Simulation => "SimulationError",
            Kind::Nav => "NavError",
            Kind::Map => "MapError",
            Kind::Lab => "LabError",
            Kind::Panic => "PanicError",
        }
    }
}

/// The class of a GSPN engine error, `None` when the caller's default
/// fits best.
fn of_petri(e: &petri::Error) -> Option<Kind> {
    use petri::Error as E;
    Some(match e {
        E::Io { .. } => Kind::File,
        E::Xml { .. } | E::Format { .. } | E::UnknownFormat { .. } | E::DuplicateName { .. } => Kind::Format,
        E::UnknownNode { .. } | E::Expr { .. } => Kind::Format,
        E::Eval { .. }
        | E::UnboundParameter { .. }
        | E::UnknownParameter { .. }
        | E::BadAssignment { .. }
        | E::InvalidValue { .. }
        | E::MissingRate { .. }
        | E::StructuralParameter { .. } => Kind::Parameter,
        E::UnknownName { .. } | E::Property { .. } => Kind::Measure,
        E::Policy { .. } => Kind::Format,
        E::StateLimit { .. }
        | E::MemoryLimit { .. }
        | E::TokenOverflow { .. }
        | E::SizeLimit { .. }
        | E::FileTooLarge { .. } => Kind::StateLimit,
        E::TimelessTrap { .. }
        | E::NoConvergence { .. }
        | E::Singular { .. }
        | E::RateSpread { .. }
        | E::NotFinite { .. }
        | E::InvariantRowLimit { .. }
        | E::InvariantOverflow { .. }
        | E::Zeno { .. }
        | E::Undecided { .. } => Kind::Solve,
        E::WallTimeLimit { .. } | E::EventLimit { .. } | E::Interrupted { .. } => Kind::Simulation,
        _ => return None,
    })
}

/// The class of an error: the outermost cause of a known type decides,
/// else `default` (the kind of the call that failed).
pub(crate) fn classify(e: &anyhow::Error, default: Kind) -> Kind {
    for (k, cause) in e.chain().enumerate() {
        if cause.is::<lab::map_file::MapFileError>() {
            // A missing or unreadable map is a file error, anything else in
            // it a map error.
            let unreadable = e.chain().skip(k + 1).any(|c| {
                c.is::<std::io::Error>()
                    || matches!(c.downcast_ref::<sim::Error>(), Some(sim::Error::Io { .. }))
            });
            return if unreadable { Kind::File } else { Kind::Map };
        }
        if cause.is::<lab::gspn::MeasureError>() {
            return Kind::Measure;
        }
        if let Some(s) = cause.downcast_ref::<lab::gspn::SimulationError>() {
            return of_petri(&s.error).unwrap_or(Kind::Simulation);
        }
        if let Some(p) = cause.downcast_ref::<petri::Error>()
            && let Some(k) = of_petri(p)
        {
            return k;
        }
        if let Some(b) = cause.downcast_ref::<bt::Error>() {
            return match b {
                bt::Error::Io { .. } => Kind::File,
                bt::Error::Param { .. } => Kind::Parameter,
                bt::Error::Petri(p) => of_petri(p).unwrap_or(Kind::Solve),
                bt::Error::Analysis(_) => Kind::Solve,
                _ => Kind::Format,
            };
        }
        if let Some(s) = cause.downcast_ref::<sim::Error>() {
            return match s {
                sim::Error::Io { .. } => Kind::File,
                _ => Kind::Map,
            };
        }
        if cause.is::<std::io::Error>() {
            return Kind::File;
        }
    }
    default
}

/// A `petrinav.errors` exception of `kind` with `message`.
pub(crate) fn raise(py: Python<'_>, kind: Kind, message: String) -> PyErr {
    let class = py
        .import("petrinav.errors")
        .and_then(|m| m.getattr(kind.class_name()))
        .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
    match class {
        Ok(class) => PyErr::from_type(class, message),
        // Only when the package is broken: still an exception, never a crash.
        Err(_) => PyRuntimeError::new_err(message),
    }
}

/// `e` as the exception of its class, with the command line's message.
pub(crate) fn to_py(py: Python<'_>, e: &anyhow::Error, default: Kind) -> PyErr {
    raise(py, classify(e, default), format!("{e:#}"))
}

/// A panic's payload as `PanicError`.
pub(crate) fn panic_to_py(py: Python<'_>, payload: Box<dyn Any + Send>) -> PyErr {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".into());
    raise(
        py,
        Kind::Panic,
        format!("internal error in petrinav (a bug; please report it): {what}"),
    )
}
