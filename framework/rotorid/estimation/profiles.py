"""Delay profiles: the cost with one delay fixed on a grid and everything else refitted.

A profile likelihood shows how well the data determine a delay: a deep, narrow minimum means
the delay is fixed by the data; a shallow one means other parameters trade against it (a
gain/delay trade), whatever its Cramér-Rao bound says. Each grid point refits every other
parameter from the free fit's values (the estimator's own ones included,
:func:`~rotorid.estimation.continuation.continued_start`), so the profile is a sequence of
ordinary fits.
"""

from __future__ import annotations

from collections.abc import Sequence

import attrs
import numpy as np

from rotorid.errors import EstimationError
from rotorid.estimation.continuation import continued_start
from rotorid.estimation.estimate import Estimate
from rotorid.model.derivatives import Delay, delayed_derivative
from rotorid.model.structure import ModelStructure
from rotorid.frozen import readonly_array


@attrs.frozen(eq=False)
class DelayProfile:
    """The profile of one delay.

    Attributes:
        delay: the delay's parameter name, e.g. ``tau_M_q``.
        grid: the fixed delay values, s, shape (K,).
        cost: det R of the refit at each grid value, shape (K,).
        rmse: RMSE (eq. 18) of the refit at each grid value, shape (K,).
        converged: whether each refit converged, shape (K,).
        free_value, free_cost, free_rmse: the fit with the delay free (s, det R, RMSE).
    """

    delay: str
    grid: np.ndarray = attrs.field(converter=readonly_array)
    cost: np.ndarray = attrs.field(converter=readonly_array)
    rmse: np.ndarray = attrs.field(converter=readonly_array)
    converged: np.ndarray = attrs.field(converter=lambda v: readonly_array(v, bool))
    free_value: float
    free_cost: float
    free_rmse: float

    @property
    def relative_rmse(self) -> np.ndarray:
        """RMSE relative to the free fit's, minus one, shape (K,): 0.01 is 1 % worse."""
        return self.rmse / self.free_rmse - 1.0

    @property
    def largest_rise(self) -> float:
        """The largest :attr:`relative_rmse` of the converged refits (NaN without one): below
        about 1 % the profile is flat, and the data do not determine the delay."""
        rises = self.relative_rmse[self.converged]
        return float(rises.max()) if rises.size else float("nan")

    @property
    def rise_at_zero(self) -> float | None:
        """:attr:`relative_rmse` of the converged refit at 0 s (None without one): how much
        worse the model fits without this delay."""
        at_zero = np.flatnonzero((self.grid == 0.0) & self.converged)
        return float(self.relative_rmse[at_zero[0]]) if at_zero.size else None

    def as_dict(self) -> dict:
        return {"delay": self.delay, "grid_s": self.grid.tolist(),
                "det_r": self.cost.tolist(), "rmse": self.rmse.tolist(),
                "converged": self.converged.tolist(), "free_value_s": self.free_value,
                "free_det_r": self.free_cost, "free_rmse": self.free_rmse}

    @classmethod
    def from_dict(cls, record: dict) -> "DelayProfile":
        return cls(record["delay"], record["grid_s"], record["det_r"], record["rmse"],
                   record["converged"], record["free_value_s"], record["free_det_r"],
                   record["free_rmse"])


def fixing_delay(structure: ModelStructure, delay: str, value: float) -> ModelStructure:
    """``structure`` with delay parameter ``delay`` (``tau_<derivative>``) fixed at ``value``
    s."""
    derivative = delayed_derivative(delay)
    if derivative is None or derivative not in structure.names or \
            structure.derivative(derivative).delay is None:
        raise EstimationError(f"{delay} is not a delay of this structure; its delays: "
                              f"{', '.join(d.delay_name for d in structure.free_delays)}")
    item = structure.derivative(derivative)
    return structure.replacing(attrs.evolve(item, delay=Delay(value, fixed=True)))


def delay_profile(structure: ModelStructure, estimate: Estimate, maneuvers, estimator,
                  delay: str, grid: Sequence[float]) -> DelayProfile:
    """The profile of ``delay`` over ``grid`` (s).

    Args:
        structure: the structure ``estimate`` was fitted with (the delay free).
        estimate: its fit; each refit starts from its values.
        maneuvers: the identification maneuvers of that fit.
        estimator: an estimator plugin object (``estimate(structure, maneuvers, start=...)``).
        delay: the delay parameter, e.g. ``"tau_M_q"``.
        grid: delay values ≥ 0 s.
    """
    cost, rmse, converged = [], [], []
    for value in grid:
        fixed = fixing_delay(structure, delay, float(value))
        fit = estimator.estimate(fixed, maneuvers,
                                 start=continued_start(estimate, structure, fixed))
        cost.append(fit.cost)
        rmse.append(fit.rmse)
        converged.append(fit.converged)
    return DelayProfile(delay, np.asarray(grid, dtype=float), cost, rmse, converged,
                        float(estimate[delay].value), float(estimate.cost),
                        float(estimate.rmse))
