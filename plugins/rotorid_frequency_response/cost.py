"""Tischler's mismatch cost J of a model structure against measured pairs, as least squares.

Per pair l with n_l points (Tischler & Remple, eq. 12.20)::

    J_l = (20/n_l) Σ_k W_γ [W_g (|H|_dB − |Ĥ|_dB)² + W_p (∠H − ∠Ĥ)²_deg]

with the measured Ĥ and the model's compared response H = Σ_i κ_i·H_i, its analytic responses
H_i of the pair's output to each input i (exact delays) mixed as the pair's data say
(:class:`.pairs.PairData`); the phase difference is wrapped to (−180°, 180°]. J = Σ_l J_l is the sum of squares of the residual vector

    e = [sqrt(20 W_γ W_g / n_l)·Δ|H|_dB ; sqrt(20 W_γ W_p / n_l)·Δ∠H_deg]

whose Jacobian is exact: ∂|H|_dB/∂θ = (20/ln 10)·Re(∂H/∂θ / H) and
∂∠H_deg/∂θ = (180/π)·Im(∂H/∂θ / H), with ∂H/∂θ = Σ_i κ_i·∂H_i/∂θ from
:func:`rotorid.simulation.transfer.compared_response`, which forms only the compared
entry of each point.
"""

from __future__ import annotations

from collections.abc import Sequence

import attrs
import numpy as np
from rotorid.errors import EstimationError
from rotorid.frozen import readonly_array
from rotorid.model.structure import ModelStructure
from rotorid.simulation.transfer import compared_response
from rotorid.verification.envelopes import wrap180
from rotorid_envelopes.cost import W_GAIN, W_PHASE

from .pairs import PairData

_DB_PER_NEPER = 20.0 / np.log(10.0)


@attrs.frozen(eq=False)
class Mismatch:
    """Residuals of one parameter vector: ``residuals`` (2n,), ``jacobian`` (2n, P) or None,
    ``pair_costs`` J_l per pair, in the pairs' order."""

    residuals: np.ndarray = attrs.field(converter=readonly_array)
    jacobian: np.ndarray | None = attrs.field(
        converter=lambda j: None if j is None else readonly_array(j))
    pair_costs: tuple[float, ...] = attrs.field(converter=tuple)

    @property
    def cost(self) -> float:
        """J = Σ_l J_l (inf when the model has no response somewhere on a pair's points)."""
        return float(np.sum(self.residuals ** 2)) if np.all(np.isfinite(self.residuals)) \
            else np.inf


def _structure_mixing(pair: PairData, controls: Sequence[str]) -> np.ndarray:
    """The pair's mixing (n, k) over its inputs as (n, m) over the structure's ``controls``
    (an input the structure lacks contributes nothing: the model does not respond to it)."""
    mixing = np.zeros((pair.omega.size, len(controls)), complex)
    for column, name in enumerate(pair.inputs):
        if name in controls:
            mixing[:, controls.index(name)] = pair.mixing[:, column]
    return mixing


class MismatchProblem:
    """J of ``structure`` against ``pairs``, evaluated at any parameter vector."""

    def __init__(self, structure: ModelStructure, pairs: Sequence[PairData]):
        self.structure = structure
        self.pairs = tuple(pairs)
        self.omega = np.concatenate([p.omega for p in self.pairs])
        missing = [p.pair for p in self.pairs if p.output not in structure.outputs
                   or p.control not in structure.controls]
        if missing:
            raise EstimationError(f"the structure has no response for the pair(s) "
                                  f"{', '.join(missing)} (outputs {', '.join(structure.outputs)}; "
                                  f"controls {', '.join(structure.controls)}); leave them out "
                                  f"(pairs=...)")
        self.rows = np.concatenate([np.full(p.omega.size, structure.outputs.index(p.output))
                                    for p in self.pairs])
        self.mixing = np.concatenate([_structure_mixing(p, structure.controls)
                                      for p in self.pairs])
        self.measured_db = np.concatenate([p.magnitude_db for p in self.pairs])
        self.measured_deg = np.concatenate([p.phase_deg for p in self.pairs])
        scale = np.concatenate([20.0 * p.weight / p.omega.size for p in self.pairs])
        self.scale = np.concatenate([np.sqrt(scale * W_GAIN), np.sqrt(scale * W_PHASE)])
        self.pair_index = np.concatenate([np.full(p.omega.size, i)
                                          for i, p in enumerate(self.pairs)])

    @property
    def n_points(self) -> int:
        return int(self.omega.size)

    def evaluate(self, values, jacobian: bool = True) -> Mismatch:
        """Residuals e (2n,), their Jacobian ∂e/∂θ (2n, P) when asked, and J per pair."""
        response, derivatives = compared_response(self.structure, values, self.omega,
                                                  self.rows, self.mixing, jacobian)
        with np.errstate(divide="ignore", invalid="ignore"):
            magnitude = _DB_PER_NEPER * np.log(np.abs(response)) - self.measured_db
            phase = wrap180(np.degrees(np.angle(response)) - self.measured_deg)
        residuals = self.scale * np.concatenate([magnitude, phase])
        squares = residuals ** 2
        per_point = squares[:self.n_points] + squares[self.n_points:]
        costs = tuple(float(np.sum(per_point[self.pair_index == i]))
                      for i in range(len(self.pairs)))
        if derivatives is None:
            return Mismatch(residuals, None, costs)
        with np.errstate(divide="ignore", invalid="ignore"):
            relative = derivatives / response[:, None]
        matrix = np.concatenate([_DB_PER_NEPER * relative.real,
                                 np.degrees(relative.imag)]) * self.scale[:, None]
        return Mismatch(residuals, matrix, costs)
