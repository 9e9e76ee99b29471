"""The delayed linear model as one first-order discrete system per parameter direction.

:func:`rotorid.simulation.discretisation.discrete_maps` gives the exact lagged recursion of the
delayed model between samples (delays as lags plus fractional-interval integrals)::

    x_n+1 = Σ_j Ps[j] x_n−j + Σ_j Pu[j] u_n−j       y_n = Σ_j Cs[j] x_n−j + Σ_j Du[j] u_n−j

Stacking x_n with the delayed state samples the maps read gives the delay-free companion system
z_n+1 = Φ z_n + Σ_j Pu[j] u_n−j, y_n = H z_n + Σ_j Du[j] u_n−j, on which the Kalman filter runs
unchanged: the delays are states of the filter. Process noise enters the physical states only;
a disturbance acceleration held over the sample enters them through the maps' Pe.
States the outputs cannot see (:func:`seen_states`) are left out: they change no output, and
an unobserved mode that is not stable would leave the filter without a steady state.

For sensitivities the system is built for complex parameter vectors θ + i·h·e_k, one per
direction k, from the maps' derivatives (the complex step of the discretisation itself).

A filter that takes its measurement update at every N-th sample only (records low-passed to a
band N times narrower than their Nyquist frequency) runs on the system lifted over N samples
(:func:`lifted`): one step of it is N steps of the system with every recorded input, so the
inputs between the updates need no hold assumption.
"""

from __future__ import annotations

import attrs
import numpy as np
from rotorid.model.structure import ModelStructure
from rotorid.simulation.discretisation import COMPLEX_STEP, discrete_maps


def seen_states(structure: ModelStructure) -> np.ndarray:
    """(n,) True for the states the outputs see, directly or through other states, in the
    structure's pattern (every free parameter taken as non-zero)."""
    a, _, c, _ = structure.matrices(np.ones(structure.n_parameters))
    seen = np.any(c != 0, axis=0)
    while True:
        wider = seen | np.any(a[seen] != 0, axis=0)
        if np.array_equal(wider, seen):
            return seen
        seen = wider


@attrs.frozen(eq=False)
class CompanionSystem:
    """Per direction (leading axis D), S companion states, T input taps.

    Attributes:
        states: indices of the structure's states the system keeps (the seen ones); they are
            its first companion states.
        transition: Φ (D, S, S).
        output: H (D, p, S), p the structure's outputs.
        taps: ((lag, control column), …) the inputs u_n−lag the forcing reads.
        state_forcing: (D, T, S) weights: the state forcing at n is lagged(u)[n] @ weights.
        output_forcing: (D, T, p) the same for the outputs' direct terms.
        equation_forcing: (D, S, e) the companion states' gain from an acceleration held over
            the sample on each equation row (the maps' Pe).
    """

    states: np.ndarray
    transition: np.ndarray
    output: np.ndarray
    taps: tuple
    state_forcing: np.ndarray
    output_forcing: np.ndarray
    equation_forcing: np.ndarray

    @property
    def size(self) -> int:
        return self.transition.shape[-1]


def _directions(nominal: dict, derivative: dict, extra: int, varied: bool) -> dict:
    """lag → (D, rows, C): the nominal map, or its complex-step directions followed by ``extra``
    copies of the nominal map (directions of parameters the maps do not depend on)."""
    if not varied:
        return {lag: m[None] for lag, m in nominal.items()}
    return {lag: np.concatenate([m[None] + 1j * COMPLEX_STEP * derivative[lag],
                                 np.broadcast_to(m, (extra,) + m.shape)])
            for lag, m in nominal.items()}


def _columns(stack: np.ndarray) -> np.ndarray:
    return np.flatnonzero(np.any(stack.reshape(-1, stack.shape[-1]) != 0, axis=0))


def companion_system(structure: ModelStructure, values, dt: float, hold: str,
                     extra_directions: int | None = None) -> CompanionSystem:
    """The companion system of the states the outputs see at ``values`` (structure
    parameters); with ``extra_directions`` (an int ≥ 0) one complex direction per structure
    parameter, then that many nominal ones."""
    varied = extra_directions is not None
    maps = discrete_maps(structure, values, dt, hold, with_derivatives=varied)
    extra = extra_directions or 0
    ps = _directions(maps.Ps, maps.dPs, extra, varied)
    cs = _directions(maps.Cs, maps.dCs, extra, varied)
    pu = _directions(maps.Pu, maps.dPu, extra, varied)
    du = _directions(maps.Du, maps.dDu, extra, varied)
    depth: dict[int, int] = {}
    for family in (ps, cs):
        for lag, stack in family.items():
            for c in (_columns(stack) if lag >= 1 else ()):
                depth[int(c)] = max(depth.get(int(c), 0), lag)
    n_x, n_y = structure.n_states, structure.n_outputs
    slots = {(c, lag): n_x + k for k, (c, lag) in enumerate(
        (c, lag) for c in sorted(depth) for lag in range(1, depth[c] + 1))}
    n_dir, size = ps[0].shape[0], n_x + len(slots)
    dtype = ps[0].dtype
    transition = np.zeros((n_dir, size, size), dtype)
    output = np.zeros((n_dir, n_y, size), dtype)
    transition[:, :n_x, :n_x] = ps[0]
    if 0 in cs:
        output[:, :, :n_x] = cs[0]
    for (c, lag), slot in slots.items():
        transition[:, slot, c if lag == 1 else slots[(c, lag - 1)]] = 1.0
        if lag in ps:
            transition[:, :n_x, slot] = ps[lag][:, :, c]
        if lag in cs:
            output[:, :, slot] = cs[lag][:, :, c]
    taps = sorted({(lag, int(c)) for family in (pu, du) for lag, stack in family.items()
                   for c in _columns(stack)})
    state_forcing = np.zeros((n_dir, len(taps), size), dtype)
    output_forcing = np.zeros((n_dir, len(taps), n_y), dtype)
    for t, (lag, c) in enumerate(taps):
        if lag in pu:
            state_forcing[:, t, :n_x] = pu[lag][:, :, c]
        if lag in du:
            output_forcing[:, t, :] = du[lag][:, :, c]
    pe = _directions({0: maps.Pe}, {0: maps.dPe}, extra, varied)[0]
    equation_forcing = np.zeros((n_dir, size, pe.shape[-1]), dtype)
    equation_forcing[:, :n_x] = pe
    seen = seen_states(structure)
    keep = np.concatenate([np.flatnonzero(seen),
                           [slot for (c, _), slot in slots.items() if seen[c]]]).astype(int)
    return CompanionSystem(np.flatnonzero(seen), transition[:, keep][:, :, keep],
                           output[:, :, keep], tuple(taps), state_forcing[:, :, keep],
                           output_forcing, equation_forcing[:, keep])


def with_disturbances(system: CompanionSystem, inputs: np.ndarray, reading: np.ndarray,
                      decay: np.ndarray) -> CompanionSystem:
    """``system`` with one first-order Gauss-Markov disturbance state d_j per column of
    ``inputs`` appended: d_j,n+1 = decay[:, j]·d_j,n + η_j,n, the outputs read
    reading[:, :, j]·d_j,n, and the system's states gain inputs[:, :, j] times the
    disturbance's mean over the interval, (d_j,n + d_j,n+1)/2: (1 + decay)/2·d_j,n here and
    η_j,n/2 in the process noise (:func:`disturbance_noise`).

    A continuous Gauss-Markov process, given its values at both ends of an interval, has the
    straight line between them as its mean path (a Brownian bridge for T ≫ dt), so the mean is
    the interval's average to second order in dt. Holding d_j,n over the interval instead
    delays its effect on the states by half a sample against the outputs' direct reading of
    it, which biases the derivatives the disturbance acts through (a light aeroplane with a
    2 s vertical gust at 50 Hz: Z_w and M_w 16 % low, 2 Cramér-Rao bounds).

    Args:
        inputs: (D, S, m) per direction (complex directions carry the parameters' derivatives).
        reading: (D, p, m) or (1, p, m).
        decay: (D, m) e^(−dt/T) of each disturbance's correlation time T.
    """
    m = inputs.shape[-1]
    if not m:
        return system
    n_dir, size = system.transition.shape[:2]
    dtype = np.result_type(system.transition, inputs, decay)
    transition = np.zeros((n_dir, size + m, size + m), dtype)
    transition[:, :size, :size] = system.transition
    transition[:, :size, size:] = inputs * (0.5 * (1.0 + decay))[:, None, :]
    transition[:, size + np.arange(m), size + np.arange(m)] = decay
    output = np.concatenate([system.output, np.broadcast_to(
        reading, system.output.shape[:2] + (m,))], axis=2)
    state_forcing = np.concatenate(
        [system.state_forcing, np.zeros(system.state_forcing.shape[:2] + (m,))], axis=2)
    equation_forcing = np.concatenate(
        [system.equation_forcing, np.zeros((n_dir, m, system.equation_forcing.shape[-1]))],
        axis=1)
    return CompanionSystem(system.states, transition, output, system.taps, state_forcing,
                           system.output_forcing, equation_forcing)


def disturbance_noise(inputs: np.ndarray, variance: np.ndarray) -> np.ndarray:
    """The process-noise covariance (D, S + m, S + m) of the disturbances' driving noise η_j
    (variance[:, j] each) in the system :func:`with_disturbances` builds: η_j drives d_j and,
    through half the disturbance's input column, the system's states within the same
    interval, so each adds v_j·b_j·b_jᵀ with b_j = (inputs[:, :, j]/2, e_j). A transpose, not a
    conjugate: complex directions carry derivatives (complex step).

    Args:
        inputs: (D, S, m) as for :func:`with_disturbances`; variance: (D, m).
    """
    n_dir, size, m = inputs.shape
    columns = np.concatenate([0.5 * inputs, np.broadcast_to(np.eye(m), (n_dir, m, m))], axis=1)
    return np.einsum("dam,dm,dbm->dab", columns, variance, columns)


def lifted(system: CompanionSystem, process: np.ndarray, every: int,
           n_controls: int) -> tuple[CompanionSystem, np.ndarray]:
    """``system`` and its process-noise covariance ``process`` Q (D, S, S) over ``every`` = N
    samples: the system of the samples 0, N, 2N, … whose inputs are the records' inputs in
    blocks of N (:meth:`.kalman.Records.lifted`: column r·m + c of block k is control c at
    sample kN + r, m = ``n_controls``).

    Φ_N = Φᴺ, Q_N = Σ_j Φʲ Q Φʲᵀ (j < N), and a tap (lag l, control c) of step j within the
    block forces the lifted state through Φᴺ⁻¹⁻ʲ, read from block −⌊(j − l)/N⌋ back at column
    ((j − l) mod N)·m + c; the outputs' direct taps are read at the block's first sample. The
    equation forcing stays the one-sample map (the disturbances are states of ``system``).
    """
    if every == 1:
        return system, process
    transition = system.transition
    powers = [np.broadcast_to(np.eye(system.size), transition.shape).astype(transition.dtype)]
    for _ in range(every):
        powers.append(transition @ powers[-1])
    process = sum(power @ process @ np.swapaxes(power, 1, 2) for power in powers[:every])
    state_forcing: dict = {}
    output_forcing: dict = {}

    def tap(offset: int, control: int) -> tuple[int, int]:
        return -(offset // every), (offset % every) * n_controls + control

    for t, (lag, control) in enumerate(system.taps):
        for step in range(every):
            key = tap(step - lag, control)
            row = np.einsum("ds,dis->di", system.state_forcing[:, t],
                            powers[every - 1 - step])
            state_forcing[key] = state_forcing.get(key, 0) + row
        key = tap(-lag, control)
        output_forcing[key] = output_forcing.get(key, 0) + system.output_forcing[:, t]
    taps = sorted(set(state_forcing) | set(output_forcing))
    n_dir, n_y = transition.shape[0], system.output.shape[1]
    states = np.zeros((n_dir, len(taps), system.size), transition.dtype)
    outputs = np.zeros((n_dir, len(taps), n_y), system.output_forcing.dtype)
    for k, key in enumerate(taps):
        states[:, k] = state_forcing.get(key, 0)
        outputs[:, k] = output_forcing.get(key, 0)
    return CompanionSystem(system.states, powers[every], system.output, tuple(taps), states,
                           outputs, system.equation_forcing), process
