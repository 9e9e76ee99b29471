"""The delay step of the pipeline: the selected structure with delays, re-estimated.

Delays the data cannot determine are dropped one at a time, the worst first, and the model
re-estimated: a delay at its lower or upper bound, or whose normalised Cramér-Rao bound
exceeds the case's ``[delays] threshold`` (a deviation from the paper, which keeps all eight;
an undetermined delay on a weak off-axis derivative otherwise wanders to a bound).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from pathlib import Path

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import IdentifiabilityWarning, SimulationDivergedError
from rotorid.estimation.continuation import continued_start
from rotorid.estimation.estimate import Estimate
from rotorid.estimation.reduction import ReductionStep
from rotorid.model.derivatives import delayed_derivative
from rotorid.model.structure import ModelStructure
from rotorid.study.case import FlightCase
from rotorid.estimation.profiles import DelayProfile, delay_profile
from rotorid.study.persistence import load_delays, load_profiles, save_delays, save_profiles


def with_delays(case: FlightCase, selected: ReductionStep, ident: ManeuverSet, estimator,
                directory: Path) -> tuple[ModelStructure, Estimate, tuple[str, ...]]:
    """The selected structure with the case's delays, its estimate and the derivatives whose
    delays were dropped; reused from ``directory/delays.json`` when it holds this step's."""
    structure = selected.structure
    delayed = structure.with_delays(case.delayed(structure.template.name), case.delay_initial,
                                    case.delay_upper)
    saved = load_delays(directory, selected.index)
    if saved is not None:
        dropped, estimate = saved
        for name in dropped:
            delayed = delayed.without_delay(name)
        return delayed, estimate, dropped
    values = continued_start(selected.estimate, structure, delayed)
    dropped: list[str] = []
    while True:
        estimate = best_delayed_fit(case, estimator, delayed, ident, values)
        worst = undetermined_delay(estimate, case.delay_threshold)
        if worst is None:
            break
        dropped.append(worst)
        fitted, delayed = delayed, delayed.without_delay(worst)
        values = continued_start(estimate, fitted, delayed)
    save_delays(directory, selected.index, tuple(dropped), estimate)
    return delayed, estimate, tuple(dropped)


def best_delayed_fit(case: FlightCase, estimator, delayed: ModelStructure, ident: ManeuverSet,
                     values: Mapping[str, float]) -> Estimate:
    """The delayed structure fitted from ``values`` (derivatives, and the estimator's own
    parameters: :func:`~rotorid.estimation.continuation.continued_start`) with the delays at
    the case's initial value and, with ``[delays] starts = N`` > 1, from N − 1 more delay
    vectors drawn uniformly in [0, upper] (generator seeded with ``[delays] seed``); the fit
    with the lowest det R is kept and its notes say which start it came from.

    Delays make the cost multi-modal: one start can settle in a local minimum that another
    avoids (docs/study.md, quick 70 kt run).
    """
    names = [d.delay_name for d in delayed.free_delays]
    base = {n: value for n, value in values.items() if n not in names}
    best, best_index = None, 0
    for index, delays in enumerate(_delay_starts(case, len(names))):
        try:
            estimate = estimator.estimate(delayed, ident,
                                          start={**base, **dict(zip(names, delays))})
        except SimulationDivergedError:
            if index == 0:
                raise
            continue                      # a random start the data cannot bring back
        if best is None or estimate.cost < best.cost:
            best, best_index = estimate, index
    if case.delay_starts == 1:
        return best
    return attrs.evolve(best, notes=best.notes + (
        f"best of {case.delay_starts} delay starts: start {best_index} "
        f"({'initial values' if best_index == 0 else 'random'})",))


def _delay_starts(case: FlightCase, count: int) -> list[np.ndarray]:
    """The case's start vectors of ``count`` delays (s): the initial value, then random."""
    upper = 0.3 if case.delay_upper is None else float(case.delay_upper)
    rng = np.random.default_rng(case.delay_seed)
    starts = [np.full(count, case.delay_initial)]
    return starts + [rng.uniform(0.0, upper, count) for _ in range(case.delay_starts - 1)]


def undetermined_delay(estimate: Estimate, threshold: float) -> str | None:
    """The derivative of the worst delay at a bound or above the normalised Cramér-Rao
    ``threshold`` (%), or ``None``."""
    worst, worst_metric = None, threshold
    for i, name in enumerate(estimate.parameter_names):
        derivative = delayed_derivative(name)
        if derivative is None:
            continue
        metric = np.inf if name in estimate.at_bound else estimate.cramer_rao_pct[i]
        if metric > worst_metric or (worst is None and metric == np.inf):
            worst, worst_metric = derivative, metric
    return worst


def delay_profiles(case: FlightCase, selected_step: int, delayed: ModelStructure,
                   estimate: Estimate, ident: ManeuverSet, estimator,
                   directory: Path) -> tuple[DelayProfile, ...]:
    """The profile of every kept delay on ``case.delay_profile_points`` values in [0,
    ``delay_upper``] s (:func:`rotorid.estimation.profiles.delay_profile`); reused from
    ``directory/profiles.json`` when it holds ``selected_step``'s."""
    if case.delay_profile_points == 0:
        return ()
    saved = load_profiles(directory, selected_step)
    if saved is not None:
        return saved
    grid = np.linspace(0.0, case.delay_upper, case.delay_profile_points)
    with warnings.catch_warnings():
        # A delay fixed far from its optimum leaves combinations the data cannot separate;
        # the profile records the cost, not those fits' statistics.
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        profiles = tuple(delay_profile(delayed, estimate, ident, estimator, d.delay_name,
                                       grid) for d in delayed.free_delays)
    save_profiles(directory, selected_step, profiles)
    return profiles
