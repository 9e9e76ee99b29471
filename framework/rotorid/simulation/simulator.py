"""Simulation of the delayed linear model over many maneuvers, with exact output sensitivities.

Maneuvers are grouped by sample time and simulated together (batched states), each group with
the exact discrete recursion of :mod:`rotorid.simulation.discretisation`. Sensitivities ∂y/∂θ are the
derivatives of that same recursion: the sensitivity states obey the recursion's own maps,
forced by the derivatives of the maps applied to the simulated states and inputs, batched over
maneuvers and parameters (no Python loop over parameters inside the time loop).

The lagged recursion runs in first-order (companion) form: the state is extended by the few
delayed state samples that the maps read, so that each time step is one small matrix product.
The sensitivities run in time blocks sized to stay in cache: per block, one product forms the
forcing of every maneuver and parameter, the block is stepped, and its output sensitivities
are written once into the result.

Units are the structure's (flight-test by default); the maneuvers must be in the same system.
Before t = 0 every state and input is at trim (zero perturbation). Under first-order hold a
delayed input between t = −dt and 0 is interpolated from trim to the first sample, so a record
should start in trim (as flight-test maneuvers do).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from rotorid import blas
from rotorid.data import ManeuverSet
from rotorid.errors import DataError, SimulationDivergedError, StructureError
from rotorid.executors import cpu_count
from rotorid.model.structure import ModelStructure
from rotorid.simulation.discretisation import DiscreteMaps, discrete_maps

#: A state perturbation beyond this magnitude (structure units) counts as divergence.
DIVERGENCE_LIMIT = 1e7
#: Size of the states of one time block (bytes), chosen to stay in cache.
_BLOCK_BYTES = 1 << 20
#: Longest time block (samples); divergence is checked at the end of every block.
_BLOCK_SAMPLES = 64


class _Group:
    """Maneuvers sharing one sample time, padded to a common length (time-major arrays);
    ``inputs`` holds the ``controls`` channels, in that order, those not in ``used`` (that
    the structure does not read, ``ModelStructure.read_controls``) left at trim, unread."""

    def __init__(self, dt: float, indices: list[int], maneuvers, initial_states, controls,
                 used):
        self.dt = dt
        self.indices = indices
        self.lengths = [maneuvers[i].n_samples for i in indices]
        self.names = [maneuvers[i].name for i in indices]
        n = max(self.lengths)
        self.inputs = np.zeros((n, len(indices), len(controls)))
        read = [k for k, name in enumerate(controls) if name in used]
        for b, i in enumerate(indices):
            self.inputs[: self.lengths[b], b, read] = maneuvers[i].columns(
                [controls[k] for k in read]) if read else 0.0
        self.x0 = np.array([initial_states[i] for i in indices], dtype=float)

    @property
    def n_samples(self) -> int:
        return self.inputs.shape[0]


def _nonzero_columns(matrix: np.ndarray) -> np.ndarray:
    """Columns (last axis) of ``matrix`` (…, R, C) with at least one non-zero entry."""
    return np.flatnonzero(np.any(matrix.reshape(-1, matrix.shape[-1]) != 0, axis=0))


def _taps(*families) -> list[tuple[int, int]]:
    """Sorted (lag, source) pairs that the maps read; sources 0 … n−1 are the n states, n …
    n+m−1 the m controls.

    ``families`` are (maps, offset) pairs: maps lag → (P, R, C), offset 0 for states and n for
    controls. Columns that are zero for every parameter are left out.
    """
    return sorted({(lag, offset + int(c)) for maps, offset in families
                   for lag, stack in maps.items() for c in _nonzero_columns(stack)})


def _tap_weights(taps, families, n_params: int, width: int) -> np.ndarray:
    """(K, n_params·width) weights W with Σ_lag M[lag]·z[n − lag] = lagged(z)[n] @ W.

    Entry [k, p·width + i] is M[lag][p, i, column] of tap k = (lag, column); entries
    i ≥ R (the history slots of the companion state) stay zero.
    """
    index = {tap: k for k, tap in enumerate(taps)}
    weights = np.zeros((len(taps), n_params, width))
    for maps, offset in families:
        for lag, stack in maps.items():
            for c in _nonzero_columns(stack):
                weights[index[(lag, offset + int(c))], :, :stack.shape[1]] += stack[:, :, c]
    return weights.reshape(len(taps), n_params * width)


def _sources(n_states: int, inputs: np.ndarray, states: np.ndarray | None = None) -> np.ndarray:
    """(N, B, n + m) source signals of the taps: the n states (zero where not needed), then
    the m controls; inputs (N, B, m), states (N, B, ≥ n) with the physical states first."""
    sources = np.zeros(inputs.shape[:2] + (n_states + inputs.shape[2],))
    if states is not None:
        sources[:, :, :n_states] = states[:, :, :n_states]
    sources[:, :, n_states:] = inputs
    return sources


def lagged_sources(sources: np.ndarray, taps) -> np.ndarray:
    """(N, B, K) array whose column k is source column c at sample n − lag for tap (lag, c).

    sources: (N, B, n + m) states then controls, time-major. Samples outside the record are trim
    (zero): before t = 0 by convention, after the end because only FOH reads ahead (one
    sample) and the last sample's step is never used.
    """
    n = sources.shape[0]
    out = np.zeros(sources.shape[:2] + (len(taps),))
    for k, (lag, column) in enumerate(taps):
        if abs(lag) >= n:
            continue
        if lag >= 0:
            out[lag:, :, k] = sources[:n - lag, :, column]
        else:
            out[:n + lag, :, k] = sources[-lag:, :, column]
    return out


class _Companion:
    """The lagged recursion in first-order form over z_n = [x_n; x_n−l[c] for each history slot].

    Attributes:
        size: S = n + number of history slots (state column c at lag l, 1 ≤ l ≤ its depth).
        transition: (S, S) map z_n → z_n+1 without forcing (Ps[0], the history maps, shifts).
        output: (p, S) map z_n → the state part of y_n (Cs at every lag).
    """

    def __init__(self, maps: DiscreteMaps):
        n, p = maps.Ps[0].shape[0], maps.Cs[0].shape[0]
        depth: dict[int, int] = {}
        history = [(lag, columns) for lag, columns in maps.state_history.items()]
        history += [(lag, _nonzero_columns(m)) for lag, m in maps.Cs.items() if lag >= 1]
        for lag, columns in history:
            for c in columns:
                depth[int(c)] = max(depth.get(int(c), 0), lag)
        slots = {(c, lag): n + k for k, (c, lag) in enumerate(
            (c, lag) for c in sorted(depth) for lag in range(1, depth[c] + 1))}
        self.size = n + len(slots)
        self.transition = np.zeros((self.size, self.size))
        self.transition[:n, :n] = maps.Ps[0]
        self.output = np.zeros((p, self.size))
        self.output[:, :n] = maps.Cs[0]
        for (c, lag), slot in slots.items():
            self.transition[slot, c if lag == 1 else slots[(c, lag - 1)]] = 1.0
            if lag in maps.Ps:
                self.transition[:n, slot] = maps.Ps[lag][:, c]
            if lag in maps.Cs:
                self.output[:, slot] = maps.Cs[lag][:, c]


def _propagate(companion: _Companion, start: np.ndarray, forcing, n: int, emit,
               where: Callable[[int, int], str], dt: float,
               limit: float = DIVERGENCE_LIMIT) -> None:
    """Run z_k+1 = transition·z_k + forcing_k for k < n − 1, one time block at a time.

    Args:
        start: (R, S) z_0.
        forcing: ``forcing(first, stop, out)`` writes the forcing of steps first … stop − 1
            into ``out`` (stop − first, R, S) (zero in the history slots).
        n: number of samples; a block holds at most :data:`_BLOCK_SAMPLES` samples and
            :data:`_BLOCK_BYTES` of states.
        emit: ``emit(first, stop, z)`` receives z_first … z_stop−1 as (stop − first, R, S).
        where: ``where(row, column)`` names the maneuver and state of entry [row, column]
            of z in the divergence error.
        dt: sample interval, s.
        limit: magnitude counted as divergence (sensitivities of a bounded but unstable
            response may legitimately be large: they pass ``inf``, so only overflow counts).
    Raises:
        SimulationDivergedError: |z| exceeds ``limit`` or is not finite.
    """
    rows, size = start.shape
    block = max(1, min(n, _BLOCK_SAMPLES, _BLOCK_BYTES // (rows * size * 8)))
    buffer = np.empty((block + 1, rows, size))
    buffer[0] = start
    step = companion.transition.T
    product = np.empty((rows, size))
    with np.errstate(over="ignore", invalid="ignore"):
        for first in range(0, n, block):
            stop = min(first + block, n)
            length = stop - first
            forcing(first, stop, buffer[1:length + 1])
            steps = length if stop < n else length - 1
            for k in range(steps):
                # numpy's product releases the GIL (scipy's BLAS wrappers do not), so that
                # a sink's worker thread runs meanwhile.
                np.matmul(buffer[k], step, out=product)
                buffer[k + 1] += product
            peak = np.abs(buffer[steps]).max()
            if not np.isfinite(peak) or peak > limit:
                raise SimulationDivergedError(_divergence(buffer[:steps + 1], first, dt,
                                                          where, limit))
            emit(first, stop, buffer[:length])
            buffer[0] = buffer[length]


def _divergence(block: np.ndarray, first: int, dt: float, where, limit: float) -> str:
    """What diverged first in ``block`` (L, R, S), the companion states of samples first …
    first + L − 1: the entry, its magnitude and the time."""
    with np.errstate(invalid="ignore"):
        beyond = ~(np.abs(block) <= limit)
    k, row, column = np.argwhere(beyond)[0]
    return (f"simulation diverged: {where(row, column)} reaches {abs(block[k, row, column]):.3g} "
            f"(beyond {limit:g}) at t = {(first + k) * dt:.3f} s; the model is unstable for "
            f"these parameter values")


class Simulator:
    """Simulates one structure over one maneuver set; reuse it for many parameter vectors.

    Args:
        structure: the model structure.
        maneuvers: the maneuvers (their recorded inputs drive the model).
        initial_states: optional (n_maneuvers, n) initial perturbation states in structure
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
        self.groups = [_Group(dt, idx, maneuvers.maneuvers, states, structure.controls,
                              structure.read_controls) for dt, idx in groups.items()]
        # The companion states of the last parameter vector simulated, per group: an
        # estimator asks for the sensitivities at the values it has just simulated.
        self._last_states: tuple[bytes, list] | None = None

    def _initial_states(self, initial_states) -> np.ndarray:
        n, n_x = len(self.maneuvers), self.structure.n_states
        if initial_states is None:
            return np.array([m.initial_values(self.structure.states)
                             for m in self.maneuvers]).reshape(n, n_x)
        states = np.asarray(initial_states, dtype=float)
        if states.shape != (n, n_x):
            raise DataError(f"initial_states must have shape ({n}, {n_x}), one row of "
                            f"{n_x} states per maneuver, got {states.shape}")
        if not np.all(np.isfinite(states)):
            raise DataError("initial_states contain NaN or infinite values")
        return states

    # ----------------------------------------------------------------- public
    def outputs(self, values=None) -> list[np.ndarray]:
        """Simulated outputs, one (N_i, p) array per maneuver (order of the set)."""
        return self._run(values, None)[0]

    def outputs_and_sensitivities(self, values=None):
        """Outputs and ∂y/∂θ: per maneuver an (N_i, p) and an (N_i, P, p) array.

        ``sens[i][n, p, k]`` is ∂y_k(t_n)/∂θ_p (views into one batch buffer: copy them
        before modifying).
        """
        outputs, sinks = self._run(values, lambda group: _DenseSink(
            group, self.structure.n_outputs, self.n_parameters))
        sens: list = [None] * len(self.maneuvers)
        for group, sink in zip(self.groups, sinks):
            for b, (i, n) in enumerate(zip(group.indices, group.lengths)):
                sens[i] = sink.dy[:n, :, b].transpose(0, 2, 1)
        return outputs, sens

    def gauss_newton(self, values, residuals, weighting: np.ndarray):
        """Gauss-Newton products F = Σ Jᵀ Q J and G = −Σ Jᵀ Q e, without storing J = ∂y/∂θ.

        Args:
            values: parameter vector or mapping (see :meth:`outputs`).
            residuals: per maneuver (N_i, p) residuals e = z − y at ``values``.
            weighting: (p, p) symmetric positive semi-definite Q (for the output-error cost,
                R⁻¹ with the output weights).
        Returns:
            F (P, P) and G (P,), summed over every sample of every maneuver. Each time block
            of the sensitivities is folded into F and G while it is in cache: the (N·p, P)
            sensitivities never exist as a whole.
        """
        if len(residuals) != len(self.maneuvers):
            raise DataError(f"{len(residuals)} residual arrays for {len(self.maneuvers)} "
                            "maneuvers")
        n_y = self.structure.n_outputs
        if np.shape(weighting) != (n_y, n_y):
            raise DataError(f"the weighting must be ({n_y}, {n_y}), one row and column per "
                            f"output, got shape {np.shape(weighting)}")
        leading = _direct_outputs(self.structure)
        factor = weighting_factor(weighting, leading)
        background = cpu_count() > 1
        _, sinks = self._run(values, lambda group: _InformationSink(
            group, [residuals[i] for i in group.indices], factor, self.n_parameters,
            background))
        return sum(s.f for s in sinks), sum(s.g for s in sinks)

    @property
    def n_parameters(self) -> int:
        return self.structure.n_parameters

    # ----------------------------------------------------------------- engine
    def _run(self, values, make_sink):
        """Outputs per maneuver and, with ``make_sink(group)``, the groups' filled sinks."""
        with blas.single_threaded():
            return self._run_single_threaded(values, make_sink)

    def _run_single_threaded(self, values, make_sink):
        vector = (self.structure.initial_values() if values is None
                  else self.structure.as_vector(values))
        outputs: list = [None] * len(self.maneuvers)
        sinks = []
        key = vector.tobytes()
        cached = self._last_states            # read once: another thread may replace it
        reuse = cached is not None and cached[0] == key
        last_states = []
        for g, group in enumerate(self.groups):
            maps = discrete_maps(self.structure, vector, group.dt, self.hold,
                                 with_derivatives=make_sink is not None)
            companion = _Companion(maps)
            states = cached[1][g] if reuse else self._states(maps, companion, group)
            last_states.append(states)
            y = self._outputs(maps, companion, group, states)
            for b, (i, n) in enumerate(zip(group.indices, group.lengths)):
                outputs[i] = y[:n, b]
            if make_sink is not None:
                sinks.append(make_sink(group))
                self._sensitivities(maps, companion, group, states, sinks[-1])
        self._last_states = (key, last_states)
        return outputs, sinks

    def _states(self, maps: DiscreteMaps, companion: _Companion, group: _Group) -> np.ndarray:
        """Companion states z_n of every maneuver of the group, (N, B, S)."""
        n, b, n_x = group.n_samples, len(group.indices), self.structure.n_states
        families = [({lag: m[None] for lag, m in maps.Pu.items()}, n_x)]
        taps = _taps(*families)
        weights = _tap_weights(taps, families, 1, companion.size)
        lagged = lagged_sources(_sources(n_x, group.inputs), taps)
        start = np.zeros((b, companion.size))
        start[:, :n_x] = group.x0
        states = np.empty((n, b, companion.size))

        def forcing(first, stop, out):
            np.matmul(lagged[first:stop], weights, out=out)

        def emit(first, stop, z):
            states[first:stop] = z

        states_named = self.structure.states

        def where(row, column):
            state = states_named[column] if column < n_x else "a delayed term's history"
            return f"maneuver {group.names[row]}, state {state}"

        _propagate(companion, start, forcing, n, emit, where, maps.dt)
        return states

    def _outputs(self, maps: DiscreteMaps, companion: _Companion, group: _Group,
                 states: np.ndarray) -> np.ndarray:
        """y_n = output·z_n + Σ_lag Du[lag]·u_n−lag, (N, B, p)."""
        n_x, n_y = self.structure.n_states, self.structure.n_outputs
        families = [({lag: m[None] for lag, m in maps.Du.items()}, n_x)]
        taps = _taps(*families)
        y = states @ companion.output.T
        if taps:
            y += (lagged_sources(_sources(n_x, group.inputs), taps)
                  @ _tap_weights(taps, families, 1, n_y))
        return y

    def _sensitivities(self, maps: DiscreteMaps, companion: _Companion, group: _Group,
                       states: np.ndarray, sink) -> None:
        """∂y/∂θ from the recursion's own maps, handed to ``sink`` one time block at a time.

        The sensitivity states obey the companion recursion, forced by the derivative maps
        applied to the simulated states and inputs (one matrix product per time block for
        all maneuvers and parameters); the outputs add the derivative output maps' term.
        Blocks reach the sink mapped by its ``output_map`` M (k, p), laid out (L, k, B, P),
        with a function that completes them (adds the direct term) wherever the sink works.
        """
        b = states.shape[1]
        p, size = self.n_parameters, companion.size
        n_x, n_y = self.structure.n_states, self.structure.n_outputs
        forcing_maps = [(maps.dPs, 0), (maps.dPu, n_x)]
        direct_maps = [(maps.dCs, 0), (maps.dDu, n_x)]
        taps = _taps(*forcing_maps, *direct_maps)
        lagged = lagged_sources(_sources(n_x, group.inputs, states), taps)
        direct = _DirectTerm(_tap_weights(taps, direct_maps, p, n_y), sink.output_map, p)
        forcing_weights = _tap_weights(taps, forcing_maps, p, size)
        forcing_weights = forcing_weights.reshape(len(taps), p, size)[:, direct.order]
        forcing_weights = forcing_weights.reshape(len(taps), p * size)
        output = sink.output_map @ companion.output                  # (m, S)

        def forcing(first, stop, out):
            np.matmul(lagged[first:stop].reshape(-1, len(taps)), forcing_weights,
                      out=out.reshape(-1, p * size))

        def emit(first, stop, z):
            block = np.matmul(output, z.transpose(0, 2, 1))         # (L, k, B·P)
            sink.take(first, stop, block.reshape(stop - first, -1, b, p),
                      lambda block: direct.add(block, lagged[first:stop]))

        try:
            _propagate(companion, np.zeros((b * p, size)), forcing, len(states), emit,
                       lambda row, column: f"a sensitivity (maneuvers "
                       f"{', '.join(group.names)})", maps.dt, limit=np.inf)
        finally:
            sink.close(direct.order)


def _direct_outputs(structure: ModelStructure) -> list[int]:
    """Outputs whose equations contain parameters directly (accelerations, state
    derivatives: those that read an equation's term sum)."""
    return np.flatnonzero(np.any(structure.known_terms().measured, axis=1)).tolist()


def weighting_factor(weighting, leading=()) -> np.ndarray:
    """M (m, n) with MᵀM = Q for a symmetric positive semi-definite Q (n, n).

    Outputs with zero weight (Q_kk = 0, their rows and columns zero) get zero columns. M is
    the transposed Cholesky factor with the ``leading`` outputs ordered first, so that their
    columns are non-zero only in the first len(leading) rows.
    """
    q = np.asarray(weighting, dtype=float)
    if q.ndim != 2 or q.shape[0] != q.shape[1] or not np.all(np.isfinite(q)):
        raise DataError(f"the weighting must be a finite square matrix, got shape {q.shape}")
    diagonal = np.diag(q)
    unused = diagonal == 0
    if np.any(diagonal < 0) or np.any(q[unused] != 0) or np.all(unused):
        raise DataError("the weighting matrix is not positive semi-definite with at least "
                        "one weighted output (negative diagonal, or a zero-weight output "
                        "coupled to others)")
    used = [k for k in range(q.shape[0]) if not unused[k]]
    order = [k for k in leading if k in used] + [k for k in used if k not in leading]
    try:
        lower = np.linalg.cholesky(q[np.ix_(order, order)])
    except np.linalg.LinAlgError as error:
        raise DataError("the weighting matrix is not positive definite on its weighted "
                        "outputs") from error
    factor = np.zeros((len(order), q.shape[0]))
    factor[:, order] = lower.T
    return factor


class _DirectTerm:
    """The output maps' own parameter derivatives applied to the lagged sources, mapped by M.

    ``weights`` (K, P·p) from :func:`_tap_weights`; only its non-zero (parameter, output)
    columns are evaluated. A parameter enters one equation row, so it has at most one such
    column (its acceleration); the column adds M[:, output] times its value to the
    parameter's sensitivities. Unless M is the identity (where a column touches one output),
    the sensitivities run with the parameters reordered (``order``): those with a direct term
    first, so that the mapped term is added to a contiguous slice.
    """

    def __init__(self, weights: np.ndarray, output_map: np.ndarray, n_parameters: int):
        n_y = output_map.shape[1]
        columns = _nonzero_columns(weights)
        parameters, self.outputs = np.divmod(columns, n_y)
        if np.unique(parameters).size != parameters.size:
            raise StructureError("a parameter enters more than one output equation directly")
        self.weights = weights[:, columns]
        self.identity = (output_map.shape == (n_y, n_y)
                         and np.array_equal(output_map, np.eye(n_y)))
        self.parameters = parameters
        self.order = np.arange(n_parameters)
        if self.identity:
            return
        # _nonzero_columns returns the columns in increasing order, so the parameters are
        # sorted and occupy positions 0 … C − 1 once moved to the front.
        self.order = np.concatenate([parameters, np.setdiff1d(self.order, parameters)])
        self.mapped = output_map[:, self.outputs]                   # (m, C)
        # Rows of M the term reaches: with a factor from :func:`weighting_factor` that puts
        # the direct outputs first, only the first few.
        self.rows = int(np.max(np.flatnonzero(np.any(self.mapped != 0, axis=1)),
                               initial=-1)) + 1

    def add(self, block: np.ndarray, lagged: np.ndarray) -> None:
        """Add the term to ``block`` (L, k, B, P); ``lagged`` (L, B, K) sources of the block."""
        if not self.parameters.size:
            return
        values = lagged @ self.weights                              # (L, B, C)
        if self.identity:
            block[:, self.outputs, :, self.parameters] += values.transpose(2, 0, 1)
            return
        rows, count = self.rows, self.parameters.size
        block[:, :rows, :, :count] += self.mapped[None, :rows, None, :] * values[:, None, :, :]


class _DenseSink:
    """Keeps every block: ``dy`` (N, p, B, P), the unmapped output sensitivities."""

    def __init__(self, group: _Group, n_outputs: int, n_parameters: int):
        self.output_map = np.eye(n_outputs)
        self.dy = np.empty((group.n_samples, n_outputs, len(group.indices), n_parameters))

    def take(self, first: int, stop: int, block: np.ndarray, complete) -> None:
        complete(block)
        self.dy[first:stop] = block

    def close(self, order: np.ndarray) -> None:
        """The blocks came in parameter ``order``; with the identity map that is the
        structure's own."""
        assert np.array_equal(order, np.arange(order.size))


class _InformationSink:
    """Folds blocks into F = Σ JᵀJ and G = −Σ Jᵀ(M e); samples past a maneuver's end (the
    padding of shorter maneuvers in a group) are left out.

    With ``background`` the blocks are completed and folded in (mostly BLAS, which releases
    the GIL) on a second thread while the next block is propagated; one worker takes the
    blocks in order, so the sums are the same as without it.
    """

    #: Blocks handed to the worker and not yet folded in, at most.
    IN_FLIGHT = 4

    def __init__(self, group: _Group, residuals, output_map: np.ndarray, n_parameters: int,
                 background: bool):
        self.output_map = output_map
        n, b, m = group.n_samples, len(group.indices), output_map.shape[0]
        n_y = output_map.shape[1]
        self.mapped_residuals = np.zeros((n, m, b))
        for k, (e, length) in enumerate(zip(residuals, group.lengths)):
            e = np.asarray(e, dtype=float)
            if e.shape != (length, n_y):
                raise DataError(f"residuals of maneuver {group.names[k]!r} have shape "
                                f"{e.shape}, expected ({length}, {n_y})")
            self.mapped_residuals[:length, :, k] = e @ output_map.T
        self.lengths = np.array(group.lengths)
        self.padded = bool(np.any(self.lengths < n))
        self.f = np.zeros((n_parameters, n_parameters))
        self.g = np.zeros(n_parameters)
        self.worker = ThreadPoolExecutor(max_workers=1) if background else None
        self.pending: deque = deque()

    def take(self, first: int, stop: int, block: np.ndarray, complete) -> None:
        if self.worker is None:
            self._fold(first, stop, block, complete)
            return
        self.pending.append(self.worker.submit(self._fold, first, stop, block, complete))
        while len(self.pending) > self.IN_FLIGHT:
            self.pending.popleft().result()

    def _fold(self, first: int, stop: int, block: np.ndarray, complete) -> None:
        complete(block)
        if self.padded:
            for k in np.flatnonzero(self.lengths < stop):
                block[max(self.lengths[k] - first, 0):, :, k] = 0.0
        rows = block.reshape(-1, block.shape[-1])
        self.f += rows.T @ rows
        self.g -= rows.T @ self.mapped_residuals[first:stop].reshape(-1)

    def close(self, order: np.ndarray) -> None:
        """Wait for the worker, then return F and G from the blocks' parameter ``order`` to
        the structure's."""
        if self.worker is not None:
            try:
                while self.pending:
                    self.pending.popleft().result()
            finally:
                self.worker.shutdown(cancel_futures=True)
        inverse = np.argsort(order)
        self.f = self.f[np.ix_(inverse, inverse)]
        self.g = self.g[inverse]


def simulate(structure: ModelStructure, values, maneuvers: ManeuverSet,
             initial_states: np.ndarray | None = None) -> list[np.ndarray]:
    """Outputs of ``structure`` at parameter vector ``values`` for every maneuver.

    Args:
        structure: model structure.
        values: parameter vector (structure.parameter_names order), a name→value mapping,
            or ``None`` for the initial values.
        maneuvers: maneuvers whose recorded inputs drive the model.
        initial_states: optional (n_maneuvers, n) initial states.
    Returns:
        one (N_i, p) array per maneuver, outputs in ``structure.outputs`` order.
    Raises:
        SimulationDivergedError: the response grows without bound.
    """
    return Simulator(structure, maneuvers, initial_states).outputs(values)


def sensitivities(structure: ModelStructure, values, maneuvers: ManeuverSet,
                  initial_states: np.ndarray | None = None
                  ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Outputs and their exact parameter sensitivities.

    Returns:
        (outputs, sensitivities): per maneuver an (N_i, p) array and an (N_i, P, p) array,
        ``sens[n, p, k] = ∂y_k(t_n)/∂θ_p`` with P = structure.n_parameters in
        structure.parameter_names order (delays included).
    """
    return Simulator(structure, maneuvers, initial_states).outputs_and_sensitivities(values)


def simulated_maneuvers(structure: ModelStructure, values, maneuvers: ManeuverSet,
                        suffix: str = "") -> ManeuverSet:
    """The maneuver set with its outputs replaced by the simulation (names + ``suffix``)."""
    outputs = simulate(structure, values, maneuvers)
    return ManeuverSet([m.with_outputs(y, name=m.name + suffix, output_names=structure.outputs)
                        for m, y in zip(maneuvers, outputs)], hold=maneuvers.hold)


def stack(arrays: Sequence[np.ndarray]) -> np.ndarray:
    """Concatenate per-maneuver arrays along time (axis 0)."""
    return np.concatenate(list(arrays), axis=0)
