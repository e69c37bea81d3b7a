//! The supervisor's decision, the guide robot's tours and the lab's
//! batches (the Python modules `petrinav.supervisor`, `petrinav.nav` and
//! `petrinav.lab` wrap these).

use std::path::PathBuf;

use lab::batch::RunOptions;
use lab::tours::{BehaviourChoice, GuideOptions};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::json_to_py;
use crate::errors::Kind;
use crate::run::{detached, guarded};

/// The supervisor's decision for rates ``{"lambdaN": value}`` (the others
/// at the source's initial values): the dict ``petrinav gspn select
/// --json`` prints.
#[pyfunction]
#[pyo3(signature = (rates=None, model=None))]
pub(crate) fn select<'py>(
    py: Python<'py>,
    rates: Option<&Bound<'py, PyDict>>,
    model: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let assignments = crate::convert::assignments(rates)?;
    let json = detached(py, Kind::Parameter, |_| {
        lab::gspn::select(&assignments, model.as_deref(), true)?.to_json()
    })?;
    json_to_py(py, &json)
}

/// A guided tour, as ``petrinav nav tour --json``: the legs' results.
#[pyfunction]
#[pyo3(signature = (map, goals, behaviour, people, seed, time_limit, log, calibration, output))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn tour<'py>(
    py: Python<'py>,
    map: PathBuf,
    goals: Option<PathBuf>,
    behaviour: &str,
    people: usize,
    seed: u64,
    time_limit: f64,
    log: Option<PathBuf>,
    calibration: bool,
    output: Option<PathBuf>,
) -> PyResult<(Bound<'py, PyList>, Bound<'py, PyAny>)> {
    let behaviour = guarded(py, Kind::Parameter, || BehaviourChoice::from_name(behaviour))?;
    let options = GuideOptions {
        goals,
        behaviour,
        people,
        seed,
        time_limit_s: time_limit,
        log,
        calibration,
        ..GuideOptions::new(map)
    };
    let (legs, summary) = detached(py, Kind::Nav, |stop| {
        let tour = lab::tours::tour(&GuideOptions {
            stop: Some(stop.clone()),
            ..options
        })?;
        if let Some(path) = &output {
            lab::runs::mission::picture(tour.setup.world.grid(), &tour.legs, &tour.stops, path)?;
        }
        Ok((tour.legs_json()?, tour.summary_json()))
    })?;
    let list = PyList::empty(py);
    for leg in &legs {
        list.append(json_to_py(py, leg)?)?;
    }
    Ok((list, json_to_py(py, &summary)?))
}

/// A suite (or scenario files) run into a results folder, as ``petrinav
/// lab run``; returns the folder and the records of ``results.jsonl``.
#[pyfunction]
#[pyo3(signature = (what, runs, jobs, out, resume, shard, pictures, report))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn lab_run<'py>(
    py: Python<'py>,
    what: Vec<String>,
    runs: Option<u32>,
    jobs: Option<usize>,
    out: Option<PathBuf>,
    resume: bool,
    shard: Option<String>,
    pictures: bool,
    report: bool,
) -> PyResult<(PathBuf, Bound<'py, PyList>)> {
    let shard = guarded(py, Kind::Parameter, || {
        shard
            .as_deref()
            .map(|s| s.parse::<lab::runner::Shard>().map_err(anyhow::Error::msg))
            .transpose()
    })?;
    let (dir, records) = detached(py, Kind::Lab, |stop| {
        let suite = lab::suites::load(&what, runs)?;
        let ran = lab::batch::run(
            suite,
            &RunOptions {
                jobs,
                out,
                resume,
                shard,
                progress: false,
                stop: Some(stop.clone()),
            },
        )?;
        if report && shard.is_none() {
            lab::report::write(&ran.out, ran.suite.as_ref(), pictures)?;
        }
        let (records, _) = lab::runner::read_results(&ran.results)?;
        Ok((ran.out, records))
    })?;
    let list = PyList::empty(py);
    for r in &records {
        list.append(json_to_py(py, r)?)?;
    }
    Ok((dir, list))
}

/// The records of a results folder's ``results.jsonl`` (complete lines).
#[pyfunction]
pub(crate) fn lab_results(py: Python<'_>, dir: PathBuf) -> PyResult<Bound<'_, PyList>> {
    let records = guarded(py, Kind::Lab, || {
        Ok(lab::runner::read_results(&dir.join("results.jsonl"))?.0)
    })?;
    let list = PyList::empty(py);
    for r in &records {
        list.append(json_to_py(py, r)?)?;
    }
    Ok(list)
}

/// The registered suites: ``{name: one-line description}``.
#[pyfunction]
pub(crate) fn lab_suites(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for r in lab::suites::REGISTRY {
        d.set_item(r.name, r.about)?;
    }
    Ok(d)
}

/// Raises a Rust panic, to test that it arrives as ``PanicError`` (never a
/// crash).
#[pyfunction]
pub(crate) fn _panic_for_tests(py: Python<'_>, detach: bool) -> PyResult<()> {
    if detach {
        detached(py, Kind::Error, |_| -> anyhow::Result<()> {
            panic!("a test panic on the worker thread")
        })
    } else {
        guarded(py, Kind::Error, || -> anyhow::Result<()> {
            panic!("a test panic")
        })
    }
}
