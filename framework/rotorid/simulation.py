"""Simulation of the delayed linear model over many maneuvers, with exact output sensitivities.

Maneuvers are grouped by sample time and simulated together (batched states), each group with
the exact discrete recursion of :mod:`rotorid.discretisation`. Sensitivities ∂y/∂θ are the
derivatives of that same recursion: the sensitivity states obey the recursion's own maps,
forced by the derivatives of the maps applied to the simulated states and inputs, batched over
maneuvers and parameters (no Python loop over parameters inside the time loop).

Units are the structure's (flight-test by default); the maneuvers must be in the same system.
Before t = 0 every state and input is at trim (zero perturbation). Under first-order hold a
delayed input between t = −dt and 0 is interpolated from trim to the first sample, so a record
should start in trim (as flight-test maneuvers do).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from . import blas
from .data import ManeuverSet
from .discretisation import DiscreteMaps, discrete_maps
from .errors import DataError, SimulationDivergedError
from .structure import ModelStructure

#: A state perturbation beyond this magnitude (structure units) counts as divergence.
DIVERGENCE_LIMIT = 1e7
_CHECK_EVERY = 50


class _Group:
    """Maneuvers sharing one sample time, padded to a common length (time-major arrays)."""

    def __init__(self, dt: float, indices: list[int], maneuvers, initial_states):
        self.dt = dt
        self.indices = indices
        self.lengths = [maneuvers[i].n_samples for i in indices]
        self.names = [maneuvers[i].name for i in indices]
        n = max(self.lengths)
        self.inputs = np.zeros((n, len(indices), 4))
        for b, i in enumerate(indices):
            self.inputs[: self.lengths[b], b] = maneuvers[i].inputs
        self.x0 = np.array([initial_states[i] for i in indices], dtype=float)

    @property
    def n_samples(self) -> int:
        return self.inputs.shape[0]


def _shifted(array: np.ndarray, lag: int) -> np.ndarray:
    """array[n − lag] for every n, zero (trim) outside the record; time is axis 0."""
    out = np.zeros_like(array)
    n = array.shape[0]
    if lag >= 0:
        out[lag:] = array[: n - lag]
    else:
        out[: n + lag] = array[-lag:]
    return out


def _apply(maps: dict, signal: np.ndarray) -> np.ndarray:
    """Σ_lag signal[n − lag] @ M[lag]ᵀ for (8, ·) maps; signal (N, B, ·) → (N, B, 8)."""
    total = np.zeros(signal.shape[:2] + (8,))
    for lag, matrix in maps.items():
        total += _shifted(signal, lag) @ matrix.T
    return total


def _derivative_forcing(state_maps: dict, input_maps: dict, states: np.ndarray,
                        inputs: np.ndarray, state_columns: dict) -> np.ndarray | None:
    """Σ_lag dM[lag]·signal[n − lag] for every parameter, as one matrix product.

    state_maps/input_maps: lag → (P, 8, ·) derivative maps; states (N, B, 8), inputs
    (N, B, 4); state_columns: lag → columns that a lag ≥ 1 state map reads.
    Returns (N, B, P, 8), or ``None`` when there is nothing to add.
    """
    signals, blocks = [], []
    for maps, signal in ((state_maps, states), (input_maps, inputs)):
        for lag, stack in maps.items():
            columns = (state_columns.get(lag, np.arange(8)) if signal is states and lag > 0
                       else np.arange(signal.shape[2]))
            signals.append(_shifted(signal, lag)[:, :, columns])
            blocks.append(stack[:, :, columns].transpose(2, 0, 1).reshape(len(columns), -1))
    if not signals:
        return None
    n, b = states.shape[:2]
    stacked = np.concatenate(signals, axis=2).reshape(n * b, -1)
    product = stacked @ np.concatenate(blocks, axis=0)
    return product.reshape(n, b, -1, 8)


class Simulator:
    """Simulates one structure over one maneuver set; reuse it for many parameter vectors.

    Args:
        structure: the model structure.
        maneuvers: the maneuvers (their recorded inputs drive the model).
        initial_states: optional (n_maneuvers, 8) initial perturbation states in structure
            units; default: each maneuver's ``initial_state`` or trim (zeros).
    """

    def __init__(self, structure: ModelStructure, maneuvers: ManeuverSet,
                 initial_states: np.ndarray | None = None):
        if maneuvers.units != structure.units.name:
            raise DataError(f"maneuvers are in {maneuvers.units!r} units but the structure in "
                            f"{structure.units.name!r}; convert one of them first")
        self.structure = structure
        self.maneuvers = maneuvers
        self.hold = maneuvers.hold
        states = self._initial_states(initial_states)
        groups: dict[float, list[int]] = {}
        for i, m in enumerate(maneuvers):
            key = next((dt for dt in groups if abs(dt - m.dt) <= 1e-9 * dt), m.dt)
            groups.setdefault(key, []).append(i)
        self.groups = [_Group(dt, idx, maneuvers.maneuvers, states) for dt, idx in groups.items()]

    def _initial_states(self, initial_states) -> np.ndarray:
        n = len(self.maneuvers)
        if initial_states is None:
            return np.array([np.zeros(8) if m.initial_state is None else m.initial_state
                             for m in self.maneuvers])
        states = np.asarray(initial_states, dtype=float)
        if states.shape != (n, 8):
            raise DataError(f"initial_states must have shape ({n}, 8), got {states.shape}")
        if not np.all(np.isfinite(states)):
            raise DataError("initial_states contain NaN or infinite values")
        return states

    # ----------------------------------------------------------------- public
    def outputs(self, values=None) -> list[np.ndarray]:
        """Simulated outputs, one (N_i, 8) array per maneuver (order of the set)."""
        return self._run(values, with_sensitivities=False)[0]

    def outputs_and_sensitivities(self, values=None):
        """Outputs and ∂y/∂θ: per maneuver an (N_i, 8) and an (N_i, P, 8) array.

        ``sens[i][n, p, k]`` is ∂y_k(t_n)/∂θ_p (views into one batch buffer: copy them
        before modifying).
        """
        return self._run(values, with_sensitivities=True)

    # ----------------------------------------------------------------- engine
    def _run(self, values, with_sensitivities: bool):
        with blas.single_threaded():
            return self._run_single_threaded(values, with_sensitivities)

    def _run_single_threaded(self, values, with_sensitivities: bool):
        vector = (self.structure.initial_values() if values is None
                  else self.structure.as_vector(values))
        outputs: list = [None] * len(self.maneuvers)
        sens: list = [None] * len(self.maneuvers)
        for group in self.groups:
            maps = discrete_maps(self.structure, vector, group.dt, self.hold,
                                 with_derivatives=with_sensitivities)
            states = self._states(maps, group)
            y = _apply(maps.Cs, states) + _apply(maps.Du, group.inputs)
            dy = self._sensitivities(maps, group, states) if with_sensitivities else None
            for b, (i, n) in enumerate(zip(group.indices, group.lengths)):
                outputs[i] = y[:n, b]
                if dy is not None:
                    sens[i] = dy[:n, b]
        return outputs, (sens if with_sensitivities else None)

    def _history_plan(self, maps: DiscreteMaps):
        """Lags and columns of the delayed-state history, and their stacked map."""
        lags, cols, blocks = [], [], []
        for lag, columns in maps.state_history.items():
            lags.extend([lag] * len(columns))
            cols.extend(columns.tolist())
            blocks.append(maps.Ps[lag][:, columns])
        if not lags:
            return None
        return np.array(lags), np.array(cols), np.hstack(blocks).T      # (H,), (H,), (H, 8)

    def _recursion(self, maps: DiscreteMaps, forcing: np.ndarray, start: np.ndarray, where):
        """x_n+1 = Ps[0] x_n + Σ history + forcing_n over time-major (N, R, 8) arrays."""
        n = forcing.shape[0]
        plan = self._history_plan(maps)
        offset = 0 if plan is None else int(plan[0].max())
        x = np.zeros((n + offset, start.shape[0], 8))
        x[offset] = start
        step = maps.Ps[0].T
        with np.errstate(over="ignore", invalid="ignore"):
            for k in range(n - 1):
                now = offset + k
                nxt = x[now] @ step + forcing[k]
                if plan is not None:
                    lags, cols, stacked = plan
                    nxt += x[now - lags, :, cols].T @ stacked
                x[now + 1] = nxt
                if k % _CHECK_EVERY == 0 or k == n - 2:
                    peak = np.abs(nxt).max()
                    if not np.isfinite(peak) or peak > DIVERGENCE_LIMIT:
                        raise SimulationDivergedError(
                            f"simulation diverged ({where}) at t = {(k + 1) * maps.dt:.3f} s: "
                            f"state magnitude {peak:.3g} exceeds {DIVERGENCE_LIMIT:g}; "
                            f"the model is unstable for these parameter values")
        return x[offset:]

    def _states(self, maps: DiscreteMaps, group: _Group) -> np.ndarray:
        forcing = _apply(maps.Pu, group.inputs)
        return self._recursion(maps, forcing, group.x0, f"maneuvers {', '.join(group.names)}")

    def _sensitivities(self, maps: DiscreteMaps, group: _Group, states: np.ndarray):
        n, b = states.shape[:2]
        p = self.structure.n_parameters
        forcing = _derivative_forcing(maps.dPs, maps.dPu, states, group.inputs,
                                      maps.state_history)
        if forcing is None:
            forcing = np.zeros((n, b, p, 8))
        sens = self._recursion(maps, forcing.reshape(n, b * p, 8), np.zeros((b * p, 8)),
                               "sensitivities").reshape(n, b, p, 8)
        dy = None
        for lag, matrix in maps.Cs.items():
            term = _shifted(sens, lag) @ matrix.T
            dy = term if dy is None else dy + term
        direct = _derivative_forcing(maps.dCs, maps.dDu, states, group.inputs, {})
        if direct is not None:
            dy += direct
        return dy


def simulate(structure: ModelStructure, values, maneuvers: ManeuverSet,
             initial_states: np.ndarray | None = None) -> list[np.ndarray]:
    """Outputs of ``structure`` at parameter vector ``values`` for every maneuver.

    Args:
        structure: model structure.
        values: parameter vector (structure.parameter_names order), a name→value mapping,
            or ``None`` for the initial values.
        maneuvers: maneuvers whose recorded inputs drive the model.
        initial_states: optional (n_maneuvers, 8) initial states.
    Returns:
        one (N_i, 8) array per maneuver, outputs [ax az q theta ay p phi r].
    Raises:
        SimulationDivergedError: the response grows without bound.
    """
    return Simulator(structure, maneuvers, initial_states).outputs(values)


def sensitivities(structure: ModelStructure, values, maneuvers: ManeuverSet,
                  initial_states: np.ndarray | None = None
                  ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Outputs and their exact parameter sensitivities.

    Returns:
        (outputs, sensitivities): per maneuver an (N_i, 8) array and an (N_i, P, 8) array,
        ``sens[n, p, k] = ∂y_k(t_n)/∂θ_p`` with P = structure.n_parameters in
        structure.parameter_names order (delays included).
    """
    return Simulator(structure, maneuvers, initial_states).outputs_and_sensitivities(values)


def simulated_maneuvers(structure: ModelStructure, values, maneuvers: ManeuverSet,
                        suffix: str = "") -> ManeuverSet:
    """The maneuver set with its outputs replaced by the simulation (names + ``suffix``)."""
    outputs = simulate(structure, values, maneuvers)
    return ManeuverSet([m.with_outputs(y, name=m.name + suffix)
                        for m, y in zip(maneuvers, outputs)], hold=maneuvers.hold)


def stack(arrays: Sequence[np.ndarray]) -> np.ndarray:
    """Concatenate per-maneuver arrays along time (axis 0)."""
    return np.concatenate(list(arrays), axis=0)
