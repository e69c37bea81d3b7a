"""Type stubs of petrinav.supervisor."""

from os import PathLike
from typing import Any, Dict, Optional, Union

def select(
    *, model: Optional[Union[str, "PathLike[str]"]] = None, **rates: Union[float, int, str]
) -> Dict[str, Any]:
    """The supervisor's decision, as ``petrinav gspn select --json``."""
