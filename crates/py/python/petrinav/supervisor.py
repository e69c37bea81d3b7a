"""The tour-guide robot's GSPN supervisor: which behaviour to run.

The supervisor net (``models/supervisor.toml`` of the repository, built
into petrinav) is solved under the AutoMove and the Contour hypotheses;
the behaviour with the higher completion throughput wins::

    import petrinav as pn

    d = pn.supervisor.select(lambda7=1 / 122.33, lambda8=1 / 186.98)
    d["choice"], d["f_auto"], d["f_cont"]
"""

from os import PathLike
from typing import Any, Dict, Optional, Union

from . import _petrinav

__all__ = ["select"]


def select(
    *, model: Optional[Union[str, "PathLike[str]"]] = None, **rates: Union[float, int, str]
) -> Dict[str, Any]:
    """The supervisor's decision, as ``petrinav gspn select --json``.

    ``rates`` are ``lambda3`` … ``lambda11`` (``lambda1`` and ``lambda2``
    are set by the hypotheses and ignored), as numbers or expression
    strings such as ``"1/122.33"``; the others keep the source's initial
    values. ``model`` is another supervisor net of the same structure.

    Returns a dict: ``choice`` (``"automove"`` or ``"contour"``),
    ``f_auto``, ``f_cont`` (throughputs of t9 and t10), ``u_auto``,
    ``u_cont``, ``p_loc_succ``, ``p_loc_warn``, ``p_pp_norm``,
    ``p_pp_abno``, ``tangible_markings``.

    Raises :class:`petrinav.ParameterError` for an unknown rate name or a
    value out of range.
    """
    return _petrinav.select(rates, None if model is None else str(model))
