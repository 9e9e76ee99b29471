"""The steady-state Kalman filter run over a batch of maneuvers and parameter directions.

Predictor form, with x̃_n the state predicted from the samples before n::

    ν_n = z_n − H x̃_n − Σ_j Du[j] u_n−j                 (innovation)
    x̃_n+1 = Φ (x̃_n + K ν_n) + Σ_j Pu[j] u_n−j

Maneuvers run side by side (time-major, padded to the longest; padded innovations are zero),
each from its initial state; the directions (leading axis D) are complex-step parameter
directions or a single nominal system.
"""

from __future__ import annotations

from collections.abc import Iterator

import attrs
import numpy as np
from rotorid.data import ManeuverSet
from rotorid.errors import DataError

from .riccati import SteadyStateFilter
from .system import CompanionSystem, lagged_inputs

#: Time samples per block handed to the caller.
BLOCK = 128


@attrs.frozen(eq=False)
class Records:
    """The maneuvers stacked time-major: ``inputs`` (N, M, 4), ``outputs`` (N, M, 8),
    ``mask`` (N, M) True on recorded samples, ``x0`` (M, 8) initial states, ``dt`` s."""

    dt: float
    inputs: np.ndarray
    outputs: np.ndarray
    mask: np.ndarray
    x0: np.ndarray
    lengths: tuple

    @classmethod
    def from_maneuvers(cls, maneuvers: ManeuverSet) -> "Records":
        """Stack ``maneuvers``; they must share one sample time."""
        dts = [m.dt for m in maneuvers]
        if max(dts) - min(dts) > 1e-9 * max(dts):
            raise DataError(f"the filter-error estimator needs one sample time for all "
                            f"maneuvers, got {sorted(set(round(d, 9) for d in dts))} s; "
                            f"resample them first")
        lengths = tuple(m.n_samples for m in maneuvers)
        n, count = max(lengths), len(maneuvers)
        inputs, outputs = np.zeros((n, count, 4)), np.zeros((n, count, 8))
        mask = np.zeros((n, count), dtype=bool)
        for b, m in enumerate(maneuvers):
            inputs[: m.n_samples, b] = m.inputs
            outputs[: m.n_samples, b] = m.outputs
            mask[: m.n_samples, b] = True
        x0 = np.array([np.zeros(8) if m.initial_state is None else m.initial_state
                       for m in maneuvers])
        return cls(float(np.mean(dts)), inputs, outputs, mask, x0, lengths)

    @property
    def n_samples(self) -> int:
        """Recorded samples over all maneuvers."""
        return int(self.mask.sum())

    def split(self, innovations: np.ndarray) -> list[np.ndarray]:
        """Time-major (N, M, 8) → one (N_i, 8) array per maneuver."""
        return [innovations[:n, b] for b, n in enumerate(self.lengths)]


def innovation_blocks(system: CompanionSystem, steady: SteadyStateFilter,
                      records: Records) -> Iterator[tuple[int, np.ndarray]]:
    """Yield ``(first, ν)`` with ν (L, D, M, 8) the innovations of samples first … first+L−1."""
    lagged = lagged_inputs(records.inputs, system.taps)
    n, count = records.mask.shape
    state = np.zeros((system.transition.shape[0], count, system.size),
                     dtype=system.transition.dtype)
    state[:, :, :8] = records.x0
    to_output = np.swapaxes(system.output, -1, -2)
    to_next = np.swapaxes(system.transition, -1, -2)
    correction = np.swapaxes(system.transition @ steady.gain, -1, -2)      # (ΦK)ᵀ
    for first in range(0, n, BLOCK):
        stop = min(first + BLOCK, n)
        block = np.empty((stop - first,) + state.shape[:2] + (8,), dtype=state.dtype)
        for k in range(first, stop):
            innovation = (records.outputs[k] - state @ to_output
                          - lagged[k] @ system.output_forcing) * records.mask[k][:, None]
            block[k - first] = innovation
            state = state @ to_next + lagged[k] @ system.state_forcing + innovation @ correction
        yield first, block
