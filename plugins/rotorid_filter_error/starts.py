"""Start values of a filter-error fit: process noise, gusts and measurement noise from the
data, R and the output biases matched to the start's innovations, and the user's overrides."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from rotorid.errors import EstimationError
from rotorid.model.structure import ModelStructure

from .kalman import Records

#: Default start of F relative to the measurement-noise size of the state's output: small,
#: because large process noise lets the filter follow the data, a poor local minimum.
PROCESS_START = 0.1
#: Passes of the measurement-noise start matched to the start innovations (B depends on R
#: through the filter's P, so R and B are matched alternately; three passes settle it).
_MATCH_PASSES = 3
#: Start of a disturbance's correlation time, s.
CORRELATION_START = 1.0
#: Lowest matched R, relative to the output's mean square innovation.
_MATCH_FLOOR = 0.05


def _measuring_output(structure: ModelStructure, state: str, parameter: str,
                      option: str) -> tuple[int, bool]:
    """:func:`measuring_output`, refusing a state no output measures: ``parameter`` (such as
    ``F_w``) then has no default start, and ``option`` names the setting to leave it out of."""
    output, reads_rate = measuring_output(structure, state)
    if output is None:
        raise EstimationError(f"no output measures state {state} or its rate, so {parameter} "
                              f"has no default start; give its start value or leave {state} "
                              f"out of {option}")
    return output, reads_rate


def process_noise_start(structure: ModelStructure, states: tuple[str, ...],
                        variance: np.ndarray, dt: float, parameter: str = "F",
                        option: str = "process_noise") -> dict[str, float]:
    """Default start of ``F_<state>`` (structure units per sample): a tenth of the noise size
    of an output that measures the state, either the state itself (σ) or an output that reads
    its equation's derivative terms, such as a velocity's specific force (σ·dt, the change
    over one sample).

    ``variance`` (p,) is the start of R over the structure's outputs; ``parameter`` and
    ``option`` name the parameter and the setting in errors (the disturbances' starts are
    built from these).
    """
    starts = {}
    for state in states:
        output, reads_rate = _measuring_output(structure, state, f"{parameter}_{state}", option)
        size = np.sqrt(variance[output]) * (dt if reads_rate else 1.0)
        starts[state] = PROCESS_START * float(size)
    return starts


def gust_start(structure: ModelStructure, states: tuple[str, ...],
               records: Records) -> dict[str, float]:
    """Default start of ``G_<state>`` (state units): the standard deviation of the recorded
    output measuring the state (:func:`measuring_output`), or of the accelerometer reading its
    equation times the correlation time's start (the speed that acceleration builds in that
    time). Measured, not a fraction of the noise: from a gust far smaller than the data's
    the fit ends with the gust switched off through its derivative (on the linear tests'
    data, from a tenth of the noise size, L_v and L_p near zero, 50–560 CR off)."""
    starts = {}
    for state in states:
        output, reads_rate = _measuring_output(structure, state, f"G_{state}", "gusts")
        signal = records.outputs[..., output][records.mask]
        starts[state] = float(np.std(signal)) * (CORRELATION_START if reads_rate else 1.0)
    return starts


def measuring_output(structure: ModelStructure, state: str) -> tuple[int | None, bool]:
    """(index of the output that measures ``state``, whether it reads the state's equation
    rather than the state): the state itself if an output does, else an output reading its
    equation's derivative terms (a velocity's specific force); (None, False) if none."""
    known = structure.known_terms()
    column = structure.states.index(state)
    direct = np.flatnonzero(known.c[:, column])
    rate = np.flatnonzero(known.measured[:, column])
    if direct.size:
        return int(direct[0]), False
    return (int(rate[0]), True) if rate.size else (None, False)


def _innovation_scatter(problem, values: np.ndarray):
    """(mean square innovation (p,), B (p, p)) at ``values``; None when the filter does not
    exist or the innovations overflow there."""
    try:
        innovations, b = problem.innovations(values)
    except (EstimationError, np.linalg.LinAlgError):
        return None
    mean_square = np.einsum("nmi,nmi->i", innovations, innovations) / problem.n_samples
    return (mean_square, b) if np.all(np.isfinite(mean_square)) else None


def matched_measurement_noise(problem, values: np.ndarray,
                              keep: tuple[str, ...] = ()) -> np.ndarray:
    """``values`` with the measurement noise R (except the ``R_<output>`` in ``keep``) set so
    that each output's innovation variance B_ii = (HPHᵀ)_ii + R_ii equals its mean square
    innovation at these values.

    The noise start from first differences fits a model that already follows the data; from
    equation-error derivatives in turbulence the innovations are tens of times larger, the
    quadratic term of the likelihood then dwarfs ln det B, and Levenberg-Marquardt stalls
    after one step (on the hover case in moderate turbulence at a cost of 3e32). Matched,
    the quadratic term starts at its optimum value, the number of outputs. Left unchanged
    when the filter does not exist or the innovations overflow at ``values``.
    """
    values = np.array(values, dtype=float)
    rows = [i for i, n in enumerate(problem.parameter_names)
            if n.startswith("R_") and n not in keep]
    outputs = [problem.output_names.index(problem.parameter_names[i][2:]) for i in rows]
    for _ in range(_MATCH_PASSES if rows else 0):
        found = _innovation_scatter(problem, values)
        if found is None:
            return values
        mean_square = found[0][outputs]
        predicted = np.diag(found[1])[outputs] - values[rows]            # (HPHᵀ)_ii
        values[rows] = np.maximum(mean_square - predicted, _MATCH_FLOOR * mean_square)
    return values


def matched_biases(problem, values: np.ndarray,
                   keep: tuple[str, ...] = ()) -> np.ndarray:
    """``values`` with each output bias (except those in ``keep``) moved by its record's mean
    innovation at these values, so that the fit starts near each sensor's offset. Unchanged
    when the filter does not exist at ``values``."""
    values = np.array(values, dtype=float)
    names = problem.parameter_names
    rows = [i for i, n in enumerate(names) if n.startswith("bias_") and n not in keep]
    if not rows:
        return values
    try:
        innovations, _ = problem.innovations(values)
    except (EstimationError, np.linalg.LinAlgError):
        return values
    mask = problem.records.mask[..., None]
    means = np.sum(innovations * mask, axis=0) / np.sum(mask, axis=0)          # (M, p)
    parts = problem.maneuver_parameters
    for i in rows:
        record, output = divmod(i - problem.n_global, parts.per_maneuver)
        column = output - len(parts.states)
        values[i] += means[record, column]
    return values


def measurement_noise_start(records) -> np.ndarray:
    """Start of R (p,): half the mean square first difference of each output of ``records``
    (time-major ``outputs`` (N, M, p) and ``mask`` (N, M)): the white measurement noise's
    variance plus the (small) signal change over one sample."""
    both = records.mask[1:] & records.mask[:-1]
    change = np.diff(records.outputs, axis=0) * both[..., None]
    pairs = max(int(np.sum(both)), 1)
    return np.maximum(0.5 * np.sum(change**2, axis=(0, 1)) / pairs, 1e-12)


def given_process_noise_start(starts, states) -> dict[str, float]:
    """``process_noise_start`` checked: every name an ``F_<state>`` of ``states``."""
    given = dict(starts or {})
    unknown = set(given) - {f"F_{s}" for s in states}
    if unknown:
        raise EstimationError(f"process_noise_start for unknown parameters {sorted(unknown)}; "
                              f"the process noise is {', '.join(f'F_{s}' for s in states)}")
    return given


def with_start(values: np.ndarray, start, names) -> tuple[np.ndarray, tuple[str, ...]]:
    """(``values`` with ``start`` applied, the names it gives): ``start`` is None, a mapping
    of some of ``names`` or a whole vector."""
    if start is None:
        return values, ()
    if isinstance(start, Mapping):
        unknown = set(start) - set(names)
        if unknown:
            raise EstimationError(f"start values for unknown parameters {sorted(unknown)}")
        for name, value in start.items():
            values[names.index(name)] = float(value)
        return values, tuple(start)
    vector = np.asarray(start, dtype=float)
    if vector.shape != values.shape:
        raise EstimationError(f"start has shape {vector.shape}; the filter-error estimate has "
                              f"{values.size} parameters ({', '.join(names)})")
    return vector.copy(), tuple(names)
