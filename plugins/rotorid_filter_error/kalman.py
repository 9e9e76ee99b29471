"""The steady-state Kalman filter run over a batch of maneuvers, with parameter sensitivities.

Predictor form, with x̃_n the state predicted from the samples before n::

    ν_n = z_n − H x̃_n − Σ_j Du[j] u_n−j                 (innovation)
    x̃_n+1 = Φ (x̃_n + K ν_n) + Σ_j Pu[j] u_n−j

Maneuvers run side by side (time-major, padded to the longest; padded innovations are zero),
each from its initial state. A system built for complex-step parameter directions (leading
axis D) gives the derivatives of its matrices, and the pass returns the innovations'
derivatives too.
"""

from __future__ import annotations

from collections.abc import Iterator

import attrs
import numpy as np
from rotorid.data import ManeuverSet
from rotorid.errors import DataError
from rotorid.model.structure import ModelStructure
from rotorid.simulation.discretisation import COMPLEX_STEP
from rotorid.simulation.simulator import lagged_sources

from .riccati import SteadyStateFilter
from .system import CompanionSystem

#: Values of one (L, M, D, S) block array of the sensitivity pass: 1 MB, so that a block's
#: arrays stay in cache (the block-wide products are memory-bound: on the paper-size problem
#: a Gauss-Newton pass took 0.06 s of CPU with 1 MB blocks and 0.10 s with 2 MB ones).
BLOCK_VALUES = 2**17
#: Time samples per block: at least (the Python overhead per block), and at most.
BLOCK_LIMITS = (4, 256)


def block_length(count: int, directions: int, size: int) -> int:
    """Time samples per block for ``count`` maneuvers, ``directions`` parameter directions
    and ``size`` companion states (:data:`BLOCK_VALUES`, within :data:`BLOCK_LIMITS`)."""
    low, high = BLOCK_LIMITS
    return int(np.clip(BLOCK_VALUES // max(count * directions * size, 1), low, high))


@attrs.frozen(eq=False)
class Records:
    """The maneuvers stacked time-major in a structure's signals: ``inputs`` (N, M, m) its
    controls, ``outputs`` (N, M, p) its outputs, ``mask`` (N, M) True on recorded samples,
    ``x0`` (M, n) initial states, ``dt`` s."""

    dt: float
    inputs: np.ndarray
    outputs: np.ndarray
    mask: np.ndarray
    x0: np.ndarray
    lengths: tuple

    @classmethod
    def from_maneuvers(cls, maneuvers: ManeuverSet, structure: ModelStructure) -> "Records":
        """Stack the channels of ``structure``'s controls and outputs from ``maneuvers``; they
        must share one sample time."""
        dts = [m.dt for m in maneuvers]
        if max(dts) - min(dts) > 1e-9 * max(dts):
            raise DataError(f"the filter-error estimator needs one sample time for all "
                            f"maneuvers, got {sorted(set(round(d, 9) for d in dts))} s; "
                            f"resample them first")
        lengths = tuple(m.n_samples for m in maneuvers)
        n, count = max(lengths), len(maneuvers)
        inputs = np.zeros((n, count, structure.n_controls))
        outputs = np.zeros((n, count, structure.n_outputs))
        mask = np.zeros((n, count), dtype=bool)
        for b, m in enumerate(maneuvers):
            inputs[: m.n_samples, b] = m.columns(structure.controls)
            outputs[: m.n_samples, b] = m.columns(structure.outputs)
            mask[: m.n_samples, b] = True
        return cls(float(np.mean(dts)), inputs, outputs, mask,
                   _initial_states(maneuvers, structure.states), lengths)

    def lifted(self, every: int) -> "Records":
        """The records as the filter with a measurement update at every ``every``-th sample
        sees them (:func:`.system.lifted`): the outputs at samples 0, N, 2N, … and per such
        sample the inputs of the N samples from it on, (N_c, M, N·m), column r·m + c being
        control c at offset r; dt N times longer."""
        if every == 1:
            return self
        steps, count, m = self.inputs.shape
        blocks = -(-steps // every)
        inputs = np.zeros((blocks * every, count, m))
        inputs[:steps] = self.inputs
        inputs = inputs.reshape(blocks, every, count, m).swapaxes(1, 2).reshape(
            blocks, count, every * m)
        return Records(self.dt * every, inputs, self.outputs[::every], self.mask[::every],
                       self.x0, tuple(-(-n // every) for n in self.lengths))

    @property
    def n_samples(self) -> int:
        """Recorded samples over all maneuvers."""
        return int(self.mask.sum())

    def split(self, innovations: np.ndarray) -> list[np.ndarray]:
        """Time-major (N, M, p) → one (N_i, p) array per maneuver."""
        return [innovations[:n, b] for b, n in enumerate(self.lengths)]


def _initial_states(maneuvers: ManeuverSet, states) -> np.ndarray:
    """(M, n): each maneuver's initial state of the structure's ``states``
    (:meth:`rotorid.data.Maneuver.initial_values`)."""
    return np.array([m.initial_values(states) for m in maneuvers]).reshape(len(maneuvers),
                                                                           len(states))


def _nominal_and_derivative(stack: np.ndarray):
    """A real stack (1, …) → (its array, None); complex directions (D, …) → (the nominal
    array, the derivatives Im/h (D, …))."""
    if np.iscomplexobj(stack):
        return stack[0].real, stack.imag / COMPLEX_STEP
    return stack[0], None


def _run(start: np.ndarray, transition_t: np.ndarray, forcing: np.ndarray) -> np.ndarray:
    """States z_0 … z_L−1 (L, R, S) of z_n+1 = z_n @ transition_t + forcing[n] from z_0 =
    ``start`` (R, S); the state after the block is left in ``start``."""
    states = np.empty(forcing.shape)
    states[0] = start
    for j in range(forcing.shape[0] - 1):
        np.matmul(states[j], transition_t, out=states[j + 1])
        states[j + 1] += forcing[j]
    start[...] = states[-1] @ transition_t + forcing[-1]
    return states


def innovation_blocks(system: CompanionSystem, steady: SteadyStateFilter, records: Records,
                      weight: np.ndarray | None = None, start: np.ndarray | None = None,
                      biases: np.ndarray | None = None
                      ) -> Iterator[tuple[int, np.ndarray, np.ndarray | None, np.ndarray]]:
    """Yield ``(first, ν, ∂ν, x̃)`` for samples first … first+L−1: innovations ν (L, M, p),
    when ``system`` and ``steady`` hold complex-step directions their derivatives ∂ν
    (L, M, p, D) (else None), and the predicted states x̃ (L, M, S); with ``weight`` W (p, p)
    ν and ∂ν are multiplied by it, ν W.
    ``start`` (M, S) is each maneuver's x̃_0 (default its recorded initial state, zero in
    the other companion states), ``biases`` (M, p) constants subtracted from its outputs.

    The step runs in closed-loop form x̃_n+1 = A x̃_n + e_n with A = Φ(I − KH) and
    e_n = Σ Pu u + ΦK (z_n − Σ Du u). The sensitivities ∂x̃ obey the same A, forced by ∂A x̃_n
    + ∂e_n, in real arithmetic: per block the predicted states are run first, then the
    forcing of every direction and the direct part of ∂ν are each one product of the block's
    regressors [u, z − Du u, x̃] with a weight matrix built once, and only the step ∂x̃ @ Aᵀ of
    all maneuvers and directions stays inside the time loop.
    """
    lagged = lagged_sources(records.inputs, system.taps)                           # (N, M, T)
    n, count = records.mask.shape
    correction = system.transition @ steady.gain                                   # ΦK
    a, d_a = _nominal_and_derivative(system.transition - correction @ system.output)
    h, d_h = _nominal_and_derivative(system.output)
    k, d_k = _nominal_and_derivative(correction)
    pu, d_pu = _nominal_and_derivative(system.state_forcing)
    du, d_du = _nominal_and_derivative(system.output_forcing)
    size, n_y = a.shape[0], h.shape[0]
    weight = np.eye(n_y) if weight is None else weight
    a_t = np.ascontiguousarray(a.T)
    if start is None:
        state = np.zeros((count, size))
        state[:, :system.states.size] = records.x0[:, system.states]
    else:
        state = np.array(start, dtype=float)
    measured = records.outputs if biases is None else records.outputs - biases
    n_dir = 1 if d_a is None else d_a.shape[0]
    if d_a is not None:
        sens = np.zeros((count * n_dir, size))                     # rows (maneuver, direction)
        # regressors [u (T), z − Du u (p), x̃ (S)] @ drive = ∂e + ∂A x̃, columns (direction, S)
        drive = np.concatenate([d_pu - d_du @ k.T, np.swapaxes(d_k, 1, 2),
                                np.swapaxes(d_a, 1, 2)], axis=1)
        drive = np.ascontiguousarray(np.moveaxis(drive, 0, 1).reshape(drive.shape[1], -1))
        # regressors @ direct = (∂(z − Du u) − ∂H x̃) W, columns (output, direction)
        direct = np.concatenate([-d_du, np.zeros((n_dir, n_y, n_y)),
                                 -np.swapaxes(d_h, 1, 2)], axis=1) @ weight
        direct = np.ascontiguousarray(np.moveaxis(direct, 0, 2).reshape(direct.shape[1], -1))
        output_weight = weight.T @ h                                               # Wᵀ H
    block = block_length(count, n_dir, size)
    for first in range(0, n, block):
        stop = min(first + block, n)
        length = stop - first
        inputs = lagged[first:stop]                                                # (L, M, T)
        mask = records.mask[first:stop, :, None]
        corrected = measured[first:stop] - inputs @ du                      # (L, M, p)
        states = _run(state, a_t, inputs @ pu + corrected @ k.T)                   # (L, M, S)
        innovations = ((corrected - states @ h.T) * mask) @ weight
        if d_a is None:
            yield first, innovations, None, states
            continue
        regressors = np.concatenate([inputs, corrected, states], axis=2).reshape(
            length * count, -1)
        d_states = _run(sens, a_t, (regressors @ drive).reshape(length, count * n_dir, size))
        d_innovations = ((regressors @ direct).reshape(length, count, n_y, n_dir)
                         - (output_weight @ np.swapaxes(
                             d_states.reshape(length * count, n_dir, size), 1, 2)
                            ).reshape(length, count, n_y, n_dir)) * mask[..., None]
        yield first, innovations, d_innovations, states
