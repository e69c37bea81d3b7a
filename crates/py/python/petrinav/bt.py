"""Behaviour trees: BehaviorTree.CPP (v3, v4) and Nav2 trees read, checked
and quantified through their GSPN::

    import petrinav as pn

    tree = pn.bt.load("models/bt/nav2/navigate_w_replanning_time.xml")
    tree.check()                                   # [] : no finding
    r = tree.analyze("models/bt/nav2/nominal.toml")
    r["p_success"], r["mean_time"], r["quantiles"]

The same functions as ``petrinav bt check --json`` and ``petrinav bt
analyze --json``: the lists and dicts are their JSON, and errors are
:class:`petrinav.Error` exceptions with their messages (malformed XML or an
unknown node: :class:`petrinav.FormatError`; a parameter out of range:
:class:`petrinav.ParameterError`). The parameters are a TOML sidecar (see
``docs/behaviour-trees.md``); without one, the stated defaults.
"""

from os import PathLike, fspath
from typing import Any, Dict, List, Optional, Sequence, Union

from . import _petrinav

__all__ = ["Tree", "load"]

Path = Union[str, "PathLike[str]"]


def _path(p: Optional[Path]) -> Optional[str]:
    return None if p is None else fspath(p)


class Tree:
    """A tree read from a file (subtrees and includes expanded); made by
    :func:`load`. ``name`` is the main tree's ID, ``nodes`` the number of
    nodes after expansion, ``files`` the files read."""

    def __init__(self, path: Path, main: Optional[str], info: Dict[str, Any]):
        self.path = fspath(path)
        self.main = main
        self.name: str = info["tree"]
        self.nodes: int = info["nodes"]
        self.files: List[str] = list(info["files"])
        self.format: int = info["format"]

    def __repr__(self) -> str:
        return f"Tree({self.name!r}, nodes={self.nodes}, path={self.path!r})"

    def check(
        self, params: Optional[Path] = None, *, blackboard: Sequence[str] = ()
    ) -> List[Dict[str, Any]]:
        """The structural findings, as ``petrinav bt check --json``'s
        ``findings``: one dict per finding (``kind``, ``path``, ``file``,
        ``line``, ``message``); empty when nothing is found. ``blackboard``
        names entries the application writes (besides Nav2's)."""
        return _petrinav.bt_check(self.path, self.main, _path(params), list(blackboard))

    def analyze(
        self,
        params: Optional[Path] = None,
        *,
        sensitivities: bool = False,
        quantiles: Optional[Sequence[float]] = None,
    ) -> Dict[str, Any]:
        """The analysis, as ``petrinav bt analyze --json``: ``p_success``,
        ``p_failure``, ``p_never``, ``mean_time``, ``quantiles`` (pairs
        ``[q, t]``; default 0.5, 0.9, 0.99), each node's figures, and with
        ``sensitivities`` the derivatives by parameter. Long analyses
        release the GIL."""
        qs = None if quantiles is None else [float(q) for q in quantiles]
        return _petrinav.bt_analyze(self.path, self.main, _path(params), sensitivities, qs)


def load(path: Path, *, main: Optional[str] = None) -> Tree:
    """Reads a tree file; ``main`` picks the tree to run (default: the
    file's ``main_tree_to_execute``, or its only tree)."""
    return Tree(path, main, _petrinav.bt_load(fspath(path), main))
