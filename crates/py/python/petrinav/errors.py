"""The exceptions petrinav raises.

Every error is a :class:`Error`; ``str(e)`` is exactly the message the
``petrinav`` command line prints after ``error:`` for the same mistake (the
file, position, name or limit at fault). Where a built-in exception fits,
the class derives from it too, so ``except OSError`` or ``except
ValueError`` catch what they would expect. Ctrl-C during a long call
raises ``KeyboardInterrupt`` as usual, after the call has stopped.
"""

__all__ = [
    "Error",
    "FileError",
    "FormatError",
    "ParseError",
    "ParameterError",
    "MeasureError",
    "StateLimitError",
    "SolveError",
    "SimulationError",
    "NavError",
    "MapError",
    "LabError",
    "PanicError",
]


class Error(Exception):
    """Base class of every error petrinav raises."""


class FileError(Error, OSError):
    """A file cannot be read or written (missing, unreadable, a folder)."""


class FormatError(Error, ValueError):
    """A net file (or text) is malformed or does not describe a valid net:
    bad XML or TOML, unknown elements, duplicate names, an expression that
    does not parse, an unknown file extension."""


#: Another name for :class:`FormatError`.
ParseError = FormatError


class ParameterError(Error, ValueError):
    """A parameter or an option is missing or out of range: an unbound
    parameter, a bad assignment, a rate that is not a finite number > 0
    (NaN included), an unknown rate name for the supervisor."""


class MeasureError(Error, ValueError):
    """A measure does not parse, or names a place or transition the net
    does not have."""


class StateLimitError(Error):
    """The state space is beyond a limit: ``max_states``, the memory guard
    (``max_memory``), a token count that does not fit, a family too large."""


class SolveError(Error):
    """The numerical solution failed: no convergence, a singular system, a
    timeless trap, rates too far apart, a result that is not finite."""


class SimulationError(Error):
    """A simulation reached its cap on firings or on wall-clock time."""


class NavError(Error):
    """The guide robot cannot run as asked: a place it cannot stand on (in a
    wall, off the map), too many people, a missing places file, a policy
    without its mission log."""


class MapError(NavError):
    """A map or places file is malformed."""


class LabError(Error):
    """A suite, scenario file or results folder is wrong (unknown suite,
    another batch in the folder, results already there without
    ``resume``)."""


class PanicError(Error, RuntimeError):
    """A bug in petrinav: Rust code panicked. The interpreter is unharmed;
    please report the message."""
