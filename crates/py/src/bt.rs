//! Behaviour trees (the Python module `petrinav.bt` wraps these): a
//! BehaviorTree.CPP / Nav2 tree read, checked and analysed through the same
//! functions as `petrinav bt check --json` and `bt analyze --json`.

use std::path::{Path, PathBuf};

use bt::check::CheckOptions;
use bt::{AnalyzeOptions, ReadOptions, Tree, TreeParams};
use pyo3::prelude::*;

use crate::convert::json_to_py;
use crate::errors::Kind;
use crate::run::{detached, guarded};

fn read(path: &Path, main: Option<String>, keep_missing: bool) -> anyhow::Result<Tree> {
    let options = ReadOptions {
        main,
        keep_missing,
        ..ReadOptions::default()
    };
    Ok(bt::read_file(path, &options)?)
}

/// The sidecar, checked against the tree's leaves.
fn params(path: Option<&Path>, tree: &Tree) -> anyhow::Result<TreeParams> {
    let p = match path {
        Some(p) => TreeParams::read_file(p)?,
        None => TreeParams::default(),
    };
    p.check_kinds(tree)?;
    Ok(p)
}

/// A tree read (subtrees and includes expanded): ``{"tree", "nodes",
/// "files", "format"}``.
#[pyfunction]
#[pyo3(signature = (path, main=None))]
pub(crate) fn bt_load(py: Python<'_>, path: PathBuf, main: Option<String>) -> PyResult<Bound<'_, PyAny>> {
    let json = guarded(py, Kind::Format, || {
        let t = read(&path, main, false)?;
        Ok(serde_json::json!({
            "tree": t.main,
            "nodes": t.len(),
            "files": t.files,
            "format": t.format,
        }))
    })?;
    json_to_py(py, &json)
}

/// The findings of ``petrinav bt check --json`` (Nav2's blackboard entries
/// written by the application, plus ``blackboard``).
#[pyfunction]
#[pyo3(signature = (path, main, params, blackboard))]
pub(crate) fn bt_check(
    py: Python<'_>,
    path: PathBuf,
    main: Option<String>,
    params: Option<PathBuf>,
    blackboard: Vec<String>,
) -> PyResult<Bound<'_, PyAny>> {
    let json = guarded(py, Kind::Format, || {
        let tree = read(&path, main, true)?;
        let p = match &params {
            Some(_) => Some(self::params(params.as_deref(), &tree)?),
            None => None,
        };
        let mut options = CheckOptions::nav2();
        options.external.extend(blackboard);
        Ok(serde_json::to_value(bt::check(&tree, p.as_ref(), &options))?)
    })?;
    json_to_py(py, &json)
}

/// The report of ``petrinav bt analyze --json``.
#[pyfunction]
#[pyo3(signature = (path, main, params, sensitivities, quantiles))]
pub(crate) fn bt_analyze(
    py: Python<'_>,
    path: PathBuf,
    main: Option<String>,
    params: Option<PathBuf>,
    sensitivities: bool,
    quantiles: Option<Vec<f64>>,
) -> PyResult<Bound<'_, PyAny>> {
    let json = detached(py, Kind::Solve, |_| {
        let tree = read(&path, main, false)?;
        let p = self::params(params.as_deref(), &tree)?;
        let mut options = AnalyzeOptions {
            sensitivities,
            ..AnalyzeOptions::default()
        };
        if let Some(q) = quantiles {
            if let Some(bad) = q.iter().find(|q| !(**q > 0.0 && **q < 1.0)) {
                anyhow::bail!("quantile {bad}: a probability strictly between 0 and 1");
            }
            options.quantiles = q;
        }
        Ok(serde_json::to_value(bt::analyze(&tree, &p, &options)?)?)
    })?;
    json_to_py(py, &json)
}
