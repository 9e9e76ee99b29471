"""Several estimators fitted to the same data (``[compare] estimators``).

The case's own estimator chooses the structure and its delays as usual. Then every other
estimator the case lists fits that final structure (the model with delays) to the same
identification maneuvers, with its default options, starting from the case estimator's
values of the structure's parameters (an estimator's own parameters, such as filter error's
process noise F and measurement noise R, from its own defaults); the case estimator's fit is
reused. Each fit is judged on its own terms (values with Cramér-Rao bounds, its cost and
RMSE: for filter error those of the innovations) and on common ones: the fitted model's
simulation of the identification maneuvers, its RMSE and det R, the determinant of the
covariance of those residuals (output error's cost).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import IdentifiabilityWarning, SimulationDivergedError
from rotorid.estimation.estimate import Estimate
from rotorid.model.structure import ModelStructure
from rotorid.plugin.manager import create
from rotorid.simulation.simulator import simulate
from rotorid.verification.metrics import TimeDomainMetrics, time_domain_metrics


@attrs.frozen(eq=False)
class SimulationFit:
    """How a fitted model's simulation matches the identification maneuvers: the metrics
    (RMSE in the outputs' units) and ``det_r``, det of the residual covariance Σ eᵀe / N
    (product of the outputs' units squared)."""

    metrics: TimeDomainMetrics
    det_r: float

    def summary(self) -> dict:
        return {"rmse": self.metrics.rmse, "det_r": self.det_r,
                "metrics": self.metrics.summary()}


@attrs.frozen(eq=False)
class EstimatorComparison:
    """The estimators' fits of one structure, by estimator name, the case's own first.

    ``simulation`` is ``None`` for a fit whose simulation diverges; ``seconds`` is each fit's
    wall time in s (0 for the case's own fit, which is reused).
    """

    estimates: Mapping[str, Estimate]
    simulation: Mapping[str, SimulationFit | None]
    seconds: Mapping[str, float]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.estimates)

    def summary(self) -> dict:
        """The ``result.json`` record: per estimator its estimate, the simulation's fit
        (``null`` where it diverges) and the fit's wall time."""
        return {name: {"estimate": estimate.as_dict(),
                       "simulation": (None if self.simulation[name] is None
                                      else self.simulation[name].summary()),
                       "seconds": self.seconds[name]}
                for name, estimate in self.estimates.items()}


def simulation_fit(structure: ModelStructure, estimate: Estimate,
                   maneuvers: ManeuverSet) -> SimulationFit | None:
    """The simulation of ``structure`` at ``estimate``'s values of its parameters against
    ``maneuvers``; ``None`` when it diverges."""
    values = estimate.restricted(structure.parameter_names).values
    try:
        outputs = simulate(structure, values, maneuvers)
    except SimulationDivergedError:
        return None
    residuals = np.concatenate([m.columns(structure.outputs) - y
                                for m, y in zip(maneuvers, outputs)])
    covariance = residuals.T @ residuals / len(residuals)
    return SimulationFit(time_domain_metrics(maneuvers, outputs),
                         float(np.linalg.det(covariance)))


def compare_estimators(names, case_estimator: str, structure: ModelStructure,
                       estimate: Estimate, maneuvers: ManeuverSet) -> EstimatorComparison:
    """Fit ``structure`` with each estimator of ``names`` other than ``case_estimator``,
    whose fit ``estimate`` is reused, on ``maneuvers`` (module docstring)."""
    start = estimate.restricted(structure.parameter_names).as_mapping()
    estimates, seconds = {case_estimator: estimate}, {case_estimator: 0.0}
    for name in names:
        if name == case_estimator:
            continue
        clock = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            estimates[name] = create("estimators", name).estimate(structure, maneuvers,
                                                                  start=start)
        seconds[name] = time.perf_counter() - clock
    return EstimatorComparison(
        estimates, {n: simulation_fit(structure, e, maneuvers) for n, e in estimates.items()},
        seconds)
