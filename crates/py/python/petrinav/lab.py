"""Experiment suites: batches of seeded runs into a results folder.

::

    import petrinav as pn

    records = pn.lab.run("voting", runs=2, out="out/v")   # 140 runs, a few seconds
    records[0]["key"], records[0]["outcome"], records[0]["time_s"]

The folder is the one ``petrinav lab run`` writes (``suite.json``,
``results.jsonl``, the report ``index.html``), so the command line's
``lab report``, ``lab replay`` and ``lab merge`` work on it.
"""

from os import PathLike, fspath
from typing import Any, Dict, List, Optional, Sequence, Union

from . import _petrinav

__all__ = ["run", "results", "suites"]

Path = Union[str, "PathLike[str]"]


def run(
    what: Union[str, Path, Sequence[Union[str, Path]]],
    *,
    runs: Optional[int] = None,
    out: Optional[Path] = None,
    resume: bool = False,
    jobs: Optional[int] = None,
    shard: Optional[str] = None,
    pictures: bool = True,
    report: bool = True,
) -> List[Dict[str, Any]]:
    """Runs a suite (``"voting"``, ``"deadlock"``, ``"maps"``,
    ``"tourguide"``, ``"topo"``; see :func:`suites`) or scenario files
    (``.toml``), as ``petrinav lab run``, and returns the records: one dict
    per run, the lines of ``results.jsonl`` in job order.

    ``runs`` per scenario (default: the suite's); ``out`` is the folder
    (default ``out/<suite>``); ``jobs`` worker threads (results do not
    depend on it); ``shard`` ``"i/n"`` runs one slice; ``report`` writes the
    report (tables, ``index.html``; ``pictures`` with its pictures).

    Resumable: every finished run is a complete line of ``results.jsonl``.
    Ctrl-C stops the batch (``KeyboardInterrupt``) once the runs in flight
    have been written; ``run(..., resume=True)`` with the same arguments
    continues it, and the finished batch is the same file as an
    uninterrupted one. Without ``resume`` a folder that already holds
    results raises :class:`petrinav.LabError`.
    """
    if isinstance(what, (str, PathLike)):
        what = [what]
    _dir, records = _petrinav.lab_run(
        [fspath(w) for w in what],
        runs,
        jobs,
        None if out is None else fspath(out),
        resume,
        shard,
        pictures,
        report,
    )
    return records


def results(out: Path) -> List[Dict[str, Any]]:
    """The records of a results folder (the complete lines of its
    ``results.jsonl``)."""
    return _petrinav.lab_results(fspath(out))


def suites() -> Dict[str, str]:
    """The registered suites: ``{name: description}``."""
    return dict(_petrinav.lab_suites())
