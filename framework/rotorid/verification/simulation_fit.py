"""A model's simulation of a set of maneuvers and how it fits them: :class:`SimulationFit`.

:func:`simulation_fit` simulates once and keeps the outputs, so that the metrics, det R and
the figures of one model all read the same simulation; :func:`fit_unless_diverging` gives
``None`` instead of raising for a model whose simulation diverges (a comparison's fitted
model, which is judged as "diverges").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import SimulationDivergedError
from rotorid.frozen import readonly_array
from rotorid.model.structure import ModelStructure
from rotorid.simulation.simulator import simulate
from rotorid.verification.metrics import TimeDomainMetrics, time_domain_metrics

#: ``simulator(structure, values, maneuvers)`` → one (N_i, n_o) output array per maneuver.
Simulator = Callable[[ModelStructure, object, ManeuverSet], Sequence[np.ndarray]]


def _arrays(outputs) -> tuple[np.ndarray, ...]:
    return tuple(readonly_array(y) for y in outputs)


@attrs.frozen(eq=False)
class SimulationFit:
    """How a model's simulation matches a set of maneuvers.

    Attributes:
        maneuvers: the maneuvers whose recorded inputs drove the model.
        outputs: one (N_i, n_o) array of simulated outputs per maneuver, in the model's units.
        metrics: RMSE, J_rms and TIC against the recorded outputs (the model's output names;
            RMSE and J_rms in reference units, :func:`time_domain_metrics`).
        det_r: det of the residual covariance Σ eᵀe / N (product of the outputs' units
            squared).
    """

    maneuvers: ManeuverSet
    outputs: tuple[np.ndarray, ...] = attrs.field(converter=_arrays)
    metrics: TimeDomainMetrics
    det_r: float

    @classmethod
    def of(cls, maneuvers: ManeuverSet, outputs: Sequence[np.ndarray],
           output_names: Sequence[str], output_units: Sequence[str] = ()) -> "SimulationFit":
        """The fit of simulated ``outputs`` (columns ``output_names`` in ``output_units``)
        to ``maneuvers``."""
        residuals = np.concatenate([m.columns(output_names) - y
                                    for m, y in zip(maneuvers, outputs)])
        covariance = residuals.T @ residuals / len(residuals)
        return cls(maneuvers, outputs,
                   time_domain_metrics(maneuvers, outputs, outputs=output_names,
                                       units=output_units),
                   float(np.linalg.det(covariance)))

    def summary(self) -> dict:
        return {"rmse": self.metrics.rmse, "det_r": self.det_r,
                "metrics": self.metrics.summary()}


def simulation_fit(structure: ModelStructure, values, maneuvers: ManeuverSet,
                   simulator: Simulator = simulate) -> SimulationFit:
    """The fit of ``structure`` at ``values`` (vector or name mapping) simulated on
    ``maneuvers`` by ``simulator`` (default the plain simulation).

    Raises:
        SimulationDivergedError: the model's response grows without bound.
    """
    return SimulationFit.of(maneuvers, simulator(structure, values, maneuvers),
                            structure.outputs, structure.signals.outputs.units)


def fit_unless_diverging(structure: ModelStructure, values, maneuvers: ManeuverSet,
                         simulator: Simulator = simulate) -> SimulationFit | None:
    """:func:`simulation_fit`, or ``None`` when the simulation diverges."""
    try:
        return simulation_fit(structure, values, maneuvers, simulator)
    except SimulationDivergedError:
        return None


__all__ = ["SimulationFit", "fit_unless_diverging", "simulation_fit"]
