"""petrinav from Python: the GSPN engine, the tour-guide robot and the lab.

Load a net, solve its steady state, read measures as numbers and numpy
arrays::

    import petrinav as pn

    net = pn.load("kanban.pnpro", params={"N": 3})  # .pnpro / .pnml / .toml
    sol = net.solve()                                # as `petrinav gspn solve`
    sol.probabilities                                # numpy float64, one per tangible marking
    sol.probability("#Pm1 >= 1"), sol.mean_tokens("Pm1"), sol.throughput("tout4")
    net.save("kanban.pnml")                          # opens in pm4py

Nets with decisions and DRN models (Storm's explicit format) are
optimised: ``net.optimize('Tmin=? [F #Done = 1]')`` and
``pn.load("model.drn").optimize('Pmax=? [F "goal"]')`` return the value,
its guaranteed bounds and the policy as a dict.

The same engine as the ``petrinav`` command line, called in-process: the
numbers are the command line's to the last bit, and errors are
:class:`petrinav.Error` exceptions carrying its messages. Long calls
release the GIL and stop on Ctrl-C (``KeyboardInterrupt``).

Modules: :mod:`petrinav.supervisor` (the tour-guide supervisor's
decision), :mod:`petrinav.nav` (guided tours on building maps),
:mod:`petrinav.lab` (experiment suites), :mod:`petrinav.bt` (behaviour
trees checked and quantified), :mod:`petrinav.errors`.
"""

from . import errors
from ._petrinav import (
    Arc,
    Model,
    Net,
    Place,
    Solution,
    StateSpace,
    Transition,
    __version__,
    family,
    formats,
    load,
    loads,
)
from .errors import (
    Error,
    FileError,
    FormatError,
    LabError,
    MapError,
    MeasureError,
    NavError,
    PanicError,
    ParameterError,
    ParseError,
    SimulationError,
    SolveError,
    StateLimitError,
)
from . import bt, lab, nav, supervisor

__all__ = [
    "Arc",
    "Error",
    "FileError",
    "FormatError",
    "LabError",
    "MapError",
    "MeasureError",
    "Model",
    "NavError",
    "Net",
    "PanicError",
    "ParameterError",
    "ParseError",
    "Place",
    "SimulationError",
    "Solution",
    "SolveError",
    "StateLimitError",
    "StateSpace",
    "Transition",
    "__version__",
    "bt",
    "errors",
    "family",
    "formats",
    "lab",
    "load",
    "loads",
    "nav",
    "supervisor",
]
