"""Type stubs of petrinav.bt."""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Union

_Path = Union[str, "PathLike[str]"]

class Tree:
    path: str
    main: Optional[str]
    name: str
    nodes: int
    files: List[str]
    format: int
    def check(
        self, params: Optional[_Path] = None, *, blackboard: Sequence[str] = ()
    ) -> List[Dict[str, Any]]:
        """The structural findings, as ``petrinav bt check --json``."""
    def analyze(
        self,
        params: Optional[_Path] = None,
        *,
        sensitivities: bool = False,
        quantiles: Optional[Sequence[float]] = None,
    ) -> Dict[str, Any]:
        """The analysis, as ``petrinav bt analyze --json``."""

def load(path: _Path, *, main: Optional[str] = None) -> Tree:
    """Reads a tree file."""
