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

from rotorid.errors import IdentifiabilityWarning
from rotorid.estimation.estimate import Estimate
from rotorid.model.structure import ModelStructure
from rotorid.plugin.manager import create
from rotorid.verification.simulation_fit import SimulationFit, fit_unless_diverging


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
        """The ``result.json`` record: per estimator its estimate and the simulation's fit
        (``null`` where it diverges); the fits' wall times go to the record's ``timing``."""
        return {name: {"estimate": estimate.as_dict(),
                       "simulation": (None if self.simulation[name] is None
                                      else self.simulation[name].summary())}
                for name, estimate in self.estimates.items()}


def compare_estimators(names, case_estimator: str, structure: ModelStructure,
                       estimate: Estimate, simulation: SimulationFit) -> EstimatorComparison:
    """Fit ``structure`` with each estimator of ``names`` other than ``case_estimator`` on
    the maneuvers of ``simulation`` (module docstring); the case estimator's fit
    ``estimate`` and its ``simulation`` are reused."""
    maneuvers = simulation.maneuvers
    start = estimate.restricted(structure.parameter_names).as_mapping()
    estimates, seconds = {case_estimator: estimate}, {case_estimator: 0.0}
    simulations = {case_estimator: simulation}
    for name in names:
        if name == case_estimator:
            continue
        clock = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            estimates[name] = create("estimators", name).estimate(structure, maneuvers,
                                                                  start=start)
        seconds[name] = time.perf_counter() - clock
        simulations[name] = fit_unless_diverging(
            structure, estimates[name].restricted(structure.parameter_names).values, maneuvers)
    return EstimatorComparison(estimates, simulations, seconds)
