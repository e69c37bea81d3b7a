"""Type stubs of petrinav (the compiled core's classes and functions)."""

from os import PathLike
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union, final

import numpy as np
import numpy.typing as npt

from . import bt as bt
from . import errors as errors
from . import lab as lab
from . import nav as nav
from . import supervisor as supervisor
from .errors import (
    Error as Error,
    FileError as FileError,
    FormatError as FormatError,
    LabError as LabError,
    MapError as MapError,
    MeasureError as MeasureError,
    NavError as NavError,
    PanicError as PanicError,
    ParameterError as ParameterError,
    ParseError as ParseError,
    SimulationError as SimulationError,
    SolveError as SolveError,
    StateLimitError as StateLimitError,
)

__version__: str

_Path = Union[str, "PathLike[str]"]
_Value = Union[int, float, str]

@final
class Place:
    """A place: its name, initial token count and capacity."""

    @property
    def name(self) -> str: ...
    @property
    def initial(self) -> int: ...
    @property
    def capacity(self) -> Optional[int]: ...

@final
class Transition:
    """A transition: timed (rate, servers) or immediate (weight, priority)."""

    @property
    def name(self) -> str: ...
    @property
    def kind(self) -> str:
        """``"timed"`` or ``"immediate"``."""
    @property
    def rate(self) -> Optional[float]: ...
    @property
    def weight(self) -> Optional[float]: ...
    @property
    def priority(self) -> Optional[int]: ...
    @property
    def servers(self) -> Optional[int]:
        """1, k, or ``None`` for infinite servers (and for immediate transitions)."""

@final
class Arc:
    """An arc: ``"input"``, ``"output"`` or ``"inhibitor"``."""

    @property
    def kind(self) -> str: ...
    @property
    def place(self) -> str: ...
    @property
    def transition(self) -> str: ...
    @property
    def multiplicity(self) -> int: ...

@final
class StateSpace:
    """The tangible markings of a net (the states of its CTMC)."""

    def __len__(self) -> int: ...
    @property
    def markings(self) -> npt.NDArray[np.int64]:
        """``(len(space), places)`` token counts, one row per tangible marking."""
    @property
    def place_names(self) -> List[str]: ...
    @property
    def reachable_markings(self) -> int: ...
    @property
    def tangible_markings(self) -> int: ...
    @property
    def vanishing_markings(self) -> int: ...
    @property
    def ergodic(self) -> bool: ...

@final
class Solution:
    """The steady state of a net."""

    @property
    def probabilities(self) -> npt.NDArray[np.float64]:
        """One probability per tangible marking, in the order of :attr:`markings`."""
    @property
    def markings(self) -> npt.NDArray[np.int64]: ...
    @property
    def state_space(self) -> StateSpace: ...
    def probability(self, condition: str) -> float:
        """``P{condition}``, e.g. ``"#P1 = 1 and #P7 = 1"``."""
    def mean(self, expression: str) -> float:
        """The long-run mean of an expression over token counts."""
    def mean_tokens(self, place: str) -> float: ...
    def prob_nonempty(self, place: str) -> float: ...
    def throughput(self, transition: str) -> float: ...
    def marginal(self, place: str) -> npt.NDArray[np.float64]:
        """``P{#place = k}`` for k = 0, 1, … up to the place's bound."""
    @property
    def mean_tokens_by_place(self) -> Dict[str, float]: ...
    @property
    def throughputs(self) -> Dict[str, float]: ...
    @property
    def solver(self) -> str: ...
    @property
    def iterations(self) -> int: ...
    @property
    def residual(self) -> float: ...
    @property
    def seconds(self) -> float: ...
    @property
    def ergodic(self) -> bool: ...
    @property
    def bottom_probabilities(self) -> List[float]: ...
    def to_dict(self, measures: Sequence[str] = ()) -> Dict[str, Any]:
        """The dict ``petrinav gspn solve --json`` prints."""

@final
class Net:
    """A GSPN with its parameters bound."""

    @property
    def name(self) -> str: ...
    @property
    def places(self) -> List[Place]: ...
    @property
    def transitions(self) -> List[Transition]: ...
    @property
    def arcs(self) -> List[Arc]: ...
    @property
    def params(self) -> Dict[str, Optional[float]]: ...
    @property
    def initial_marking(self) -> npt.NDArray[np.int64]: ...
    def with_params(self, **params: _Value) -> "Net": ...
    def state_space(
        self, *, max_states: Optional[int] = None, max_memory: Optional[int] = None
    ) -> StateSpace: ...
    def solve(
        self,
        *,
        method: str = "auto",
        tolerance: float = 1e-12,
        default_rate: Optional[float] = None,
        max_states: Optional[int] = None,
        max_memory: Optional[int] = None,
    ) -> Solution: ...
    def properties(
        self, *, max_states: Optional[int] = None, max_memory: Optional[int] = None
    ) -> Dict[str, Any]:
        """The dict ``petrinav gspn info --json`` prints."""
    def simulate(
        self,
        *,
        time: float,
        seed: int,
        warmup: float = 0.0,
        batches: int = 20,
        confidence: float = 0.95,
        measures: Sequence[str] = (),
        default_rate: Optional[float] = None,
        max_events: int = 1_000_000_000,
        max_wall: Optional[float] = 600.0,
    ) -> Dict[str, Any]:
        """The dict ``petrinav gspn simulate --json`` prints."""
    def optimize(
        self,
        objective: str,
        *,
        precision: float = 1e-6,
        absolute: bool = False,
        default_rate: Optional[float] = None,
        max_states: Optional[int] = None,
        max_memory: Optional[int] = None,
    ) -> Dict[str, Any]:
        """The best policy for ``objective`` (``'Pmax=? [F "goal"]'``,
        ``'Tmin=? [F #Done = 1]'``, ``'R{"cost"}min=? [F "done"]'``,
        ``'LRAmax=? ["up"]'``) as ``petrinav gspn optimize --json``:
        ``value``, ``bound``, ``lower``, ``upper``, ``choices``, ``policy``
        (``{marking: transition}``), …; infinite values are ``math.inf``."""
    def save(self, path: _Path) -> None: ...
    def dumps(self, format: str = "toml") -> str: ...

@final
class Model:
    """A DTMC, CTMC, MDP or Markov automaton read from a DRN file."""

    def __len__(self) -> int: ...
    @property
    def type(self) -> str:
        """``"DTMC"``, ``"CTMC"``, ``"MDP"`` or ``"MA"``."""
    @property
    def path(self) -> str: ...
    @property
    def states(self) -> int: ...
    @property
    def actions(self) -> int: ...
    @property
    def transitions(self) -> int: ...
    @property
    def initial_states(self) -> List[int]: ...
    @property
    def labels(self) -> Dict[str, List[int]]:
        """Each label's states."""
    @property
    def reward_models(self) -> List[str]: ...
    def optimize(self, objective: str, *, precision: float = 1e-6, absolute: bool = False) -> Dict[str, Any]:
        """As :meth:`Net.optimize`; ``policy`` is ``{"state N": action}``."""

def load(
    path: _Path, params: Optional[Mapping[str, _Value]] = None, *, max_memory: Optional[int] = None
) -> Union[Net, Model]:
    """Loads a ``.pnpro``, ``.pnml`` or ``.toml`` net and binds ``params``
    (a :class:`Net`), or a ``.drn`` file (a :class:`Model`)."""

def loads(
    text: str,
    format: str = "toml",
    params: Optional[Mapping[str, _Value]] = None,
    name: str = "<string>",
) -> Net:
    """Reads a net from text."""

def family(name: str, n: int, params: Optional[Mapping[str, _Value]] = None) -> Net:
    """``"kanban"``, ``"fms"``, ``"philosophers"`` or ``"robots"`` of size ``n``."""

def formats() -> List[str]:
    """The formats :func:`load` reads."""
