"""Exceptions and warning categories of rotorid.

Every error rotorid raises on purpose derives from :class:`RotoridError`, so a caller can
catch them all at once; the subclasses also derive from the matching built-in exception
(``ValueError``, ``FileNotFoundError`` …) so generic handlers keep working.
"""

from __future__ import annotations

from enum import IntEnum


class ExitStatus(IntEnum):
    """Exit statuses of the ``rotorid`` command (docs/conventions.md)."""

    OK = 0
    CHECK_FAILED = 1      #: a verified check failed and ``--strict`` was given
    USAGE = 2             #: the command line is wrong (argparse's status)
    ERROR = 3             #: data, model, case or file error: the run could not be done
    NOT_CONVERGED = 4     #: the fit did not converge and ``--strict`` was given
    INTERRUPTED = 130     #: stopped with Ctrl-C


class RotoridError(Exception):
    """Base class of all rotorid errors."""


class UsageError(RotoridError, ValueError):
    """A command-line argument is missing, contradictory or out of range; the ``rotorid``
    command exits with :attr:`ExitStatus.USAGE`, like argparse."""


class DerivativeError(RotoridError, ValueError):
    """A derivative or delay declaration is invalid (unknown name, contradictory settings)."""


class StructureError(RotoridError, ValueError):
    """A model structure or flight condition is invalid or misused."""


class SignalError(RotoridError, ValueError):
    """A named signal, signal set, unit or channel map is invalid (unknown or duplicate name,
    unknown unit, a unit that does not fit the signal's kind)."""


class DataError(RotoridError, ValueError):
    """Maneuver data are malformed (shapes, channels, time base, NaN/inf)."""


class DataFileError(DataError):
    """A maneuver or model file cannot be read or written; the message names file, channel and row."""


class MissingFileError(RotoridError, FileNotFoundError):
    """A file the user named does not exist."""


class OverwriteError(RotoridError, FileExistsError):
    """A file to be written exists already and overwriting it was not asked for."""


class PluginError(RotoridError, LookupError):
    """A plugin is unknown, broken or registered twice."""


class SimulationDivergedError(RotoridError, ArithmeticError):
    """A simulated response grew without bound (an unstable candidate model)."""


class EstimationError(RotoridError, RuntimeError):
    """An estimation cannot proceed (for example a singular information matrix)."""


class VerificationError(RotoridError, ValueError):
    """A verification cannot proceed: unknown response pair, malformed envelope table,
    no coherent frequency points, or spectra that cannot be formed from the records."""


class OrphanedRunError(RotoridError, RuntimeError):
    """A task's run has ended (its process died): the task refuses to write into the run's
    results directory and stops (:mod:`rotorid.lease`)."""


class RotoridWarning(UserWarning):
    """Base class of rotorid warnings."""


class IdentifiabilityWarning(RotoridWarning):
    """Parameters are nearly unidentifiable (ill-conditioned information matrix)."""


class ConvergenceWarning(RotoridWarning):
    """An iterative procedure stopped without meeting its convergence criteria."""


class DataWarning(RotoridWarning):
    """Maneuver data look wrong before a fit (an input that never moves, outputs that are not
    perturbations, an implausible unit, a clipped or dropped-out sensor, rates that do not
    integrate to the attitudes); the message gives the numbers and the fix
    (:mod:`rotorid.estimation.sanity`), or a fit reproduces them exactly (noise-free data)."""


class TrimError(RotoridError, ValueError):
    """A simulation model cannot be trimmed at the requested flight condition (outside the
    flight envelope, beyond control travel or power, or the trim iteration failed)."""


class StudyError(RotoridError, RuntimeError):
    """Independent tasks of a study or a Monte Carlo failed.

    ``failures`` maps each failed task (case name, run seed) to what went wrong and where;
    ``results`` holds the tasks that finished, so their work is not lost.
    """

    def __init__(self, message: str, results=None, failures=None):
        super().__init__(message)
        self.results = dict(results or {})
        self.failures = dict(failures or {})
