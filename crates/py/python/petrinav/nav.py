"""The tour-guide robot on real building maps: guided tours.

A Jinny-like robot with a laser, Monte Carlo localization, and AutoMove
(a global route and a navigation function in a 10 m window) or contour
tracking, among walking people::

    import petrinav as pn

    legs = pn.nav.tour("maps/levine/levine.yaml", goals="maps/levine/places.yaml",
                       behaviour="automove", people=20, seed=1)
    [leg["outcome"] for leg in legs]
"""

from os import PathLike
from typing import Any, Dict, List, Optional, Union

from . import _petrinav

__all__ = ["tour", "BEHAVIOURS"]

Path = Union[str, "PathLike[str]"]

#: The behaviours a tour can use.
BEHAVIOURS = ("automove", "contour", "automove-then-contour", "rule", "supervisor")


def _path(p: Optional[Path]) -> Optional[str]:
    return None if p is None else str(p)


def tour(
    map: Path,
    goals: Optional[Path] = None,
    behaviour: str = "automove",
    people: int = 0,
    seed: int = 1,
    *,
    time_limit: float = 300.0,
    log: Optional[Path] = None,
    calibration: bool = False,
    output: Optional[Path] = None,
) -> List[Dict[str, Any]]:
    """A guided tour, as ``petrinav nav tour --json``: one dict per leg.

    The robot starts at the first place of ``goals`` (YAML, one
    ``name: [x, y, theta]`` per line) and visits the others in the file's
    order on ``map`` (a ROS map_server ``.yaml``, or a ``.toml`` world).
    ``behaviour`` is one of :data:`BEHAVIOURS` (``"supervisor"`` learns its
    rates from the mission ``log``); ``people`` walk among the places;
    ``seed`` fixes every random draw (the same seed, the same legs);
    ``time_limit`` is per leg, in seconds; ``log`` appends every leg to a
    mission log (as calibration runs with ``calibration``); ``output``
    draws the tour (``.png`` or ``.svg``).

    Each leg: ``from``, ``to``, ``outcome`` (``"reached"``,
    ``"collision"``, ``"timeout"``, ``"lost"``, ``"unreachable"``,
    ``"gave_up"``), ``time_s``, ``path_m``, ``final_error_m``,
    ``localization`` (``mean_error_m``, ``median_error_m``,
    ``max_error_m``, ``warnings``, ``time_in_warning_s``) and ``planner``
    (``abnormal_episodes``, ``time_abnormal_s``).

    Raises :class:`petrinav.NavError` (a place in a wall, too many people…)
    or :class:`petrinav.MapError` (a malformed map or places file). Releases
    the GIL while the robot drives.
    """
    legs, _summary = _petrinav.tour(
        str(map),
        _path(goals),
        behaviour,
        people,
        seed,
        time_limit,
        _path(log),
        calibration,
        _path(output),
    )
    return legs
