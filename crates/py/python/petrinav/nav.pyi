"""Type stubs of petrinav.nav."""

from os import PathLike
from typing import Any, Dict, List, Optional, Tuple, Union

_Path = Union[str, "PathLike[str]"]

BEHAVIOURS: Tuple[str, ...]

def tour(
    map: _Path,
    goals: Optional[_Path] = None,
    behaviour: str = "automove",
    people: int = 0,
    seed: int = 1,
    *,
    time_limit: float = 300.0,
    log: Optional[_Path] = None,
    calibration: bool = False,
    output: Optional[_Path] = None,
) -> List[Dict[str, Any]]:
    """A guided tour, as ``petrinav nav tour --json``: one dict per leg."""
