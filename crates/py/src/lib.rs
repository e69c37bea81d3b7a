//! `petrinav` from Python: the extension module `petrinav._petrinav`
//! behind the Python package in `python/petrinav/` (built by maturin, see
//! `pyproject.toml`).
//!
//! It is a thin layer over the library crates: every call goes through the
//! same functions as the command line (`lab::gspn`, `lab::tours`,
//! `lab::batch`, `bt`), so numbers, records and error messages are the command
//! line's. What this crate adds is the Python side of things:
//!
//! - numpy arrays for markings and probabilities (`net.rs`);
//! - decisions: optimal policies as dicts, DRN models (`optimize.rs`);
//! - errors as `petrinav.errors` exceptions chosen by the error's type,
//!   with the command line's message (`errors.rs`);
//! - long calls off the GIL, stopped by Ctrl-C, panics caught (`run.rs`);
//! - JSON values as dicts, parameter values as assignments (`convert.rs`).

mod bt;
mod commands;
mod convert;
mod errors;
mod net;
mod optimize;
mod run;

use pyo3::prelude::*;

/// The compiled core of :mod:`petrinav`; import :mod:`petrinav` instead.
#[pymodule]
#[pyo3(name = "_petrinav")]
fn petrinav_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<net::Net>()?;
    m.add_class::<net::Place>()?;
    m.add_class::<net::Transition>()?;
    m.add_class::<net::Arc_>()?;
    m.add_class::<net::StateSpace>()?;
    m.add_class::<net::Solution>()?;
    m.add_class::<optimize::Model>()?;
    m.add_function(wrap_pyfunction!(net::load, m)?)?;
    m.add_function(wrap_pyfunction!(net::loads, m)?)?;
    m.add_function(wrap_pyfunction!(net::family, m)?)?;
    m.add_function(wrap_pyfunction!(net::formats, m)?)?;
    m.add_function(wrap_pyfunction!(commands::select, m)?)?;
    m.add_function(wrap_pyfunction!(commands::tour, m)?)?;
    m.add_function(wrap_pyfunction!(commands::lab_run, m)?)?;
    m.add_function(wrap_pyfunction!(commands::lab_results, m)?)?;
    m.add_function(wrap_pyfunction!(commands::lab_suites, m)?)?;
    m.add_function(wrap_pyfunction!(bt::bt_load, m)?)?;
    m.add_function(wrap_pyfunction!(bt::bt_check, m)?)?;
    m.add_function(wrap_pyfunction!(bt::bt_analyze, m)?)?;
    m.add_function(wrap_pyfunction!(commands::_panic_for_tests, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
