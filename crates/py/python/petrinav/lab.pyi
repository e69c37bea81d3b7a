"""Type stubs of petrinav.lab."""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Union

_Path = Union[str, "PathLike[str]"]

def run(
    what: Union[_Path, Sequence[_Path]],
    *,
    runs: Optional[int] = None,
    out: Optional[_Path] = None,
    resume: bool = False,
    jobs: Optional[int] = None,
    shard: Optional[str] = None,
    pictures: bool = True,
    report: bool = True,
) -> List[Dict[str, Any]]:
    """Runs a suite as ``petrinav lab run``; the records of ``results.jsonl``."""

def results(out: _Path) -> List[Dict[str, Any]]:
    """The records of a results folder."""

def suites() -> Dict[str, str]:
    """The registered suites."""
