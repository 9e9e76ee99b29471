"""The ``filter-error`` estimator: maximum likelihood with process and measurement noise.

The model is the structure's exact discrete recursion (delays included, :mod:`.system`) with
white process noise on the physical states and white measurement noise on the outputs::

    x_n+1 = Φ x_n + Σ_j Pu[j] u_n−j + F w_n      y_n = H x_n + Σ_j Du[j] u_n−j
    z_n = y_n + v_n      w_n ~ N(0, I), v_n ~ N(0, R)

F is diagonal over the process-noise states (``F_<state>``: standard deviation of the noise
added to that state over one sample, structure units; by default the states of the structure's
force and moment equations) and R diagonal over the structure's outputs (``R_<output>``, the
measurement-noise variance, units²). States, controls and outputs are the structure's own
(:attr:`~rotorid.model.structure.ModelStructure.states` …), so any linear structure fits.
Both are estimated with the derivatives and delays. Optional coloured disturbances, states of
the filter with their own sizes and correlation times, add accelerations to chosen equations
or translational gusts acting through the derivatives
(:meth:`FilterErrorProblem._coloured_inputs`). The steady-state Kalman filter
(:mod:`.riccati`, :mod:`.kalman`) turns the data into innovations ν_n with covariance
B = H P Hᵀ + R; the negative log-likelihood is

    L = ½ Σ_n ν_nᵀ B⁻¹ ν_n + ½ N ln det B.

Levenberg-Marquardt (the output-error plugin's, on the cost exp(2L/N), which is e^{n_o}·det B
at the optimum) steps with the Fisher information

    M_ij = Σ_n ∂ν_nᵀ/∂θ_i B⁻¹ ∂ν_n/∂θ_j + ½ N tr(B⁻¹ ∂B/∂θ_i B⁻¹ ∂B/∂θ_j)

and the exact gradient of L. The sensitivities ∂ν/∂θ and ∂B/∂θ are exact: the complex step
through the discretisation and the doubling algorithm of the Riccati equation gives the
derivatives of Φ, H, K and B, and one batched pass runs the predicted states' sensitivities
through the filter's own recursion (:mod:`.kalman`). M is also the information matrix
of the Cramér-Rao bounds. Because the filter is stable whatever the model's stability, an
unstable model is identified directly, on the full records. Start values come from
:mod:`.starts`, each maneuver's own parameters (initial states, output biases) from
:mod:`.maneuver_parameters`; a nonlinear model of one's own goes to :mod:`.nonlinear`.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from concurrent.futures import ThreadPoolExecutor

import attrs
import numpy as np
from rotorid import blas
from rotorid.data import ManeuverSet
from rotorid.errors import EstimationError, IdentifiabilityWarning, SimulationDivergedError
from rotorid.estimation.estimate import Estimate
from rotorid.estimation.fit_notes import fast_modes_note
from rotorid.estimation.models import LinearModel
from rotorid.estimation.state_estimates import StateEstimates
from rotorid.estimation.whiteness import whiteness_note
from rotorid.model.parameter_units import rate_unit
from rotorid.model.structure import ModelStructure
from rotorid.plugin.manager import create, notify
from rotorid.progress import ordinal
from rotorid.simulation.discretisation import COMPLEX_STEP
from rotorid.units import rmse_reference_factors
from rotorid_output_error.levenberg_marquardt import Settings, run

from .correlation_limits import (
    UNLIMITED_CORRELATION,
    check_limited,
    correlation_limits,
    correlation_names,
    longest_correlations,
)
from .kalman import Records, innovation_blocks
from .likelihood import InnovationLikelihood, covariance_terms
from .maneuver_parameters import (
    ManeuverParameters,
    chosen_initial_states,
    filter_state_names,
    initial_state_option,
)
from .riccati import steady_state_filter
from .starts import (
    CORRELATION_START,
    given_process_noise_start,
    gust_start,
    matched_biases,
    matched_measurement_noise,
    measurement_noise_start,
    process_noise_start,
    with_start,
)
from .system import (companion_system, disturbance_noise, lifted, seen_states,
                     with_disturbances)

NAME = "filter-error"
#: Lower bound of a measurement-noise variance relative to its start value, or to half the
#: output's mean square first difference where that is larger (a standard deviation of 1 % of
#: the start's). Lower, a still-air fit on decimated hover records drove
#: R_az and R_r to 10⁻⁸ of their starts, where the filter trusts those outputs exactly and its
#: Riccati equation stopped converging (docs/estimation.md).
VARIANCE_FLOOR = 1e-4
#: Stage name of the first fit of a gust fit started from equation error (its progress lines).
GUST_FREE_STAGE = "gust-free start"
#: Lower bound of a disturbance's size relative to its start: at zero its driving variance
#: D²(1 − a²) has zero gradient in D, so a fit that reached zero could never leave it.
_SIZE_FLOOR = 1e-4
#: Shortest correlation time of a gust, in measurement updates (samples unless ``update_every``):
#: the outputs reading a gust's derivative terms (the accelerometers) see it directly, so a gust
#: of a few updates' correlation is their measurement noise; with one sample allowed the linear
#: tests' fit went there (Tg_w 0.027 s, R_az at its floor) and the filter's covariance
#: overflowed.
_SHORTEST_GUST_SAMPLES = 10


def _state_names(option: str):
    """The converter of the option ``option``: a state name or names → a tuple of distinct
    names (None stays None), refusing repeats in the option's own name."""
    def convert(value) -> tuple[str, ...] | None:
        if value is None:
            return None
        states = (value,) if isinstance(value, str) else tuple(value)
        if len(set(states)) != len(states) or not all(isinstance(s, str) for s in states):
            raise EstimationError(f"{option} must name distinct states, got {list(states)}")
        return states
    return convert


def process_noise_states(structure: ModelStructure, names: tuple[str, ...] | None,
                         option: str = "process_noise",
                         accelerations: bool = False) -> tuple[str, ...]:
    """The states the process noise (or the disturbances) enter, in the structure's state
    order: ``names``, or by default the states of the structure's force and moment equations
    that the outputs see (:func:`seen_states`; noise on a state they cannot see changes no
    innovation, and leaves the filter without a steady state when that state's mode is not
    stable); ``option`` names the setting in errors. With ``accelerations`` (disturbances:
    accelerations of their states' equations) a state no output sees may also be named if an
    accelerometer reads its equation (az reads the w equation's disturbance when a reduction
    has removed every derivative of w)."""
    seen = seen_states(structure)
    if names is None:
        return tuple(structure.states[i] for i in structure.equation_rows if seen[i])
    if accelerations:
        seen = seen | np.any(structure.known_terms().measured != 0, axis=0)
    unknown = [s for s in names if s not in structure.states]
    if unknown:
        raise EstimationError(f"{option} names {', '.join(unknown)}, not states of the "
                              f"structure ({', '.join(structure.states)}); choose among those")
    unseen = [s for s in names if not seen[structure.states.index(s)]]
    if unseen:
        raise EstimationError(f"{option} names {', '.join(unseen)}, which no output of "
                              f"the structure sees (noise there changes no innovation); leave "
                              f"{'it' if len(unseen) == 1 else 'them'} out")
    return tuple(s for s in structure.states if s in names)


def gust_states(structure: ModelStructure, names: tuple[str, ...]) -> tuple[str, ...]:
    """The states ``names`` that get a translational gust, in the structure's state order,
    checked: a gust acts as the state's negative in its derivative terms, which the filter
    makes exact over a sample only when no known term (gravity, kinematics) and no delayed
    derivative reads the state."""
    states = process_noise_states(structure, names, "gusts") if names else ()
    known = structure.known_terms().a
    for state in states:
        if np.any(known[:, structure.states.index(state)] != 0):
            raise EstimationError(f"gusts names {state}, which known terms of the structure "
                                  f"read (a gust does not act on them); leave it out")
        delayed = [d.name for d in structure.derivatives
                   if d.variable == state and d.delay is not None]
        if delayed:
            raise EstimationError(f"gusts names {state}, which the delayed derivatives "
                                  f"{', '.join(delayed)} read; a gust acts without delay, so "
                                  f"remove their delays or leave {state} out")
    return states


def _accelerations_limits(limits: Mapping[str, float], accelerated: tuple[str, ...]
                          ) -> dict[str, float]:
    """``limits`` for the gust-free first fit (:meth:`FilterErrorEstimator._gust_free_start`):
    each ``accelerated`` gust's limit becomes its acceleration's ``T_<state>`` (the smaller
    where a disturbance on that state has one too); other gusts' limits go with the gusts."""
    kept = {name: limit for name, limit in limits.items() if not name.startswith("Tg_")}
    for state in accelerated:
        if f"Tg_{state}" in limits:
            kept[f"T_{state}"] = min(limits[f"Tg_{state}"], kept.get(f"T_{state}", np.inf))
    return kept


def _noise_held(problem: "FilterErrorProblem", values: np.ndarray, bounds):
    """``bounds`` with the noise parameters (F, D, G, T, R) held at ``values``: the first
    stage of a fit with per-maneuver parameters. Fitted together from the start, the first
    steps trade a record's offsets against the process noise, and an F that reaches its
    bound 0 never leaves it (F enters as F², whose gradient vanishes there): on doublet data
    with sensor biases the fit stopped at F_w = 0, its cost 8 % above the truth's."""
    lower, upper = (np.array(b, dtype=float) for b in bounds)
    noise = slice(problem.n_structure, problem.n_global)
    lower[noise] = upper[noise] = values[noise]
    return lower, upper


def _equation_columns(structure: ModelStructure, states: tuple[str, ...]) -> list[int]:
    """The equation column (``structure.equation_rows`` order) of each disturbance state."""
    equations = [structure.states[i] for i in structure.equation_rows]
    others = [s for s in states if s not in equations]
    if others:
        raise EstimationError(f"disturbances name {', '.join(others)}, which have no equation "
                              f"of derivatives (a disturbance is an acceleration of one); "
                              f"choose among {', '.join(equations)}")
    return [equations.index(s) for s in states]


def _whole_number(instance, attribute, value):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise EstimationError(f"{attribute.name} must be a whole number ≥ 1 (samples per "
                              f"measurement update), got {value!r}")


#: Where the derivatives and delays start (the ``start`` option).
START_CHOICES = ("auto", "initial", "equation-error", "output-error")
#: The note of a fit from equation error (white process noise only) that ended with a sign
#: violation or without converging: the free F may have followed the data there.
POORER_OPTIMUM_ADVICE = (
    "from equation error this fit ended with sign violations or without converging, which "
    "can mean a poorer optimum where the process noise follows the data; with little "
    "process noise, a start from an output-error fit (start = 'output-error', rotorid "
    "identify --start output-error) may reach a likelier one: compare the costs")


def _start_choice(instance, attribute, value):
    if value not in START_CHOICES:
        raise EstimationError(f"start must be one of {', '.join(map(repr, START_CHOICES))}, "
                              f"got {value!r}")


@attrs.frozen(eq=False)
class NoiseParameters:
    """A filter-error parameter vector in parts: the structure's parameters, the white
    process noise F (one per process-noise state), the coloured disturbances' (accelerations,
    then gusts) stationary standard deviations D and correlation times T (s), and the
    measurement-noise variances R."""

    structure: np.ndarray
    process: np.ndarray
    disturbance: np.ndarray
    correlation_time: np.ndarray
    measurement: np.ndarray


class FilterErrorProblem(InnovationLikelihood):
    """Cost, innovations and Fisher information of one structure on one maneuver set, in the
    form :func:`rotorid_output_error.levenberg_marquardt.run` drives."""

    def __init__(self, structure: ModelStructure, maneuvers: ManeuverSet,
                 process_noise: tuple[str, ...], settings: Settings,
                 disturbances: tuple[str, ...] = (), gusts: tuple[str, ...] = (),
                 initial_states=False, output_biases: bool = False, update_every: int = 1):
        self.structure = structure
        self.hold = maneuvers.hold
        records = Records.from_maneuvers(maneuvers, structure)
        #: sample time of the records (s): the model and the disturbances step at it
        self.sample_time = records.dt
        self.update_every = update_every
        #: the records at the filter's measurement updates (every ``update_every``-th sample)
        self.records = records.lifted(update_every)
        #: half each output's mean square first difference at the updates (p,), units²: the
        #: measurement noise's start and the lower limit of its floor
        self.first_difference_variance = measurement_noise_start(self.records)
        self.settings = settings
        self.n_samples = self.records.n_samples
        self.process_noise = process_noise
        self.kept_indices = np.flatnonzero(seen_states(structure))
        kept = [structure.states[i] for i in self.kept_indices]
        self.noise_rows = [kept.index(s) for s in process_noise]
        self.disturbances = disturbances
        self.disturbance_columns = _equation_columns(structure, disturbances)
        self.disturbance_reading = structure.known_terms().measured[
            :, [structure.states.index(s) for s in disturbances]]
        self.gusts = gusts
        self.gust_columns = [kept.index(s) for s in gusts]
        self.gust_known_reading = structure.known_terms().c[
            :, [structure.states.index(s) for s in gusts]]
        self.n_structure = structure.n_parameters
        self.output_names = structure.outputs
        self.parameter_names = (tuple(structure.parameter_names)
                                + tuple(f"F_{s}" for s in process_noise)
                                + tuple(f"D_{s}" for s in disturbances)
                                + tuple(f"G_{s}" for s in gusts)
                                + correlation_names(disturbances, gusts)
                                + tuple(f"R_{o}" for o in structure.outputs))
        self.n_global = len(self.parameter_names)
        available = filter_state_names(tuple(kept), disturbances, gusts)
        #: the filter's states an initial value or an estimate is given for
        self.available_states = available
        self.maneuver_names = maneuvers.names
        #: (N_i,) each maneuver's sample times, s
        self.times = [m.time for m in maneuvers]
        self.maneuver_parameters = ManeuverParameters.of(
            maneuvers.names, available, len(disturbances) + len(gusts),
            chosen_initial_states(initial_states, available, structure.states),
            structure.outputs, output_biases)
        self.parameter_names += self.maneuver_parameters.names
        signals = structure.signals
        self.output_units = signals.outputs.units
        self.parameter_units = {
            **{f"F_{s}": signals.states[s].unit for s in process_noise},
            **{f"D_{s}": rate_unit(signals.states[s].unit) for s in disturbances},
            **{f"G_{s}": signals.states[s].unit for s in gusts},
            **{f"T_{s}": "s" for s in disturbances},
            **{f"Tg_{s}": "s" for s in gusts},
            **{f"R_{o.name}": f"({o.unit})²" for o in signals.outputs},
            **self.maneuver_parameters.units(structure)}
        # The innovations' RMSE counts each output in its reference unit (a pure number).
        scale = rmse_reference_factors(self.output_units)
        self.rmse_scale = np.ones(len(self.output_names)) if scale is None else scale

    def split(self, values) -> NoiseParameters:
        """The parts of a parameter vector (the per-maneuver parameters left out)."""
        n_coloured = len(self.disturbances) + len(self.gusts)
        sizes = np.cumsum([self.n_structure, len(self.noise_rows), n_coloured, n_coloured])
        return NoiseParameters(*np.split(np.asarray(values)[: self.n_global], sizes))

    def record_terms(self, values, system) -> dict:
        """The filter's start x̃_0 (M, S) and the output biases (M, p) at ``values``, as
        keywords of :func:`.kalman.innovation_blocks` (none without per-maneuver
        parameters)."""
        parts = self.maneuver_parameters
        if not parts.size:
            return {}
        default = np.zeros((len(self.records.lengths), system.size))
        default[:, : system.states.size] = self.records.x0[:, system.states]
        tail = np.asarray(values, dtype=float)[self.n_global:]
        return {"start": parts.filter_start(tail, default),
                "biases": parts.output_biases(tail, len(self.output_names))}

    def filter(self, values, directions: bool = False):
        """The companion system (with its disturbance states) and its steady-state filter at
        ``values``; with ``directions`` one complex-step direction per parameter (leading
        axis)."""
        parts = self.split(np.asarray(values, dtype=float))
        f, sigma, tau, r = (parts.process, parts.disturbance, parts.correlation_time,
                            parts.measurement)
        n_f, n_d = f.size, sigma.size
        system = companion_system(self.structure, parts.structure, self.sample_time, self.hold,
                                  n_f + 2 * n_d + r.size if directions else None)
        n_dir = system.transition.shape[0]
        dtype = system.transition.dtype
        q_dir = np.repeat((f**2)[None].astype(dtype), n_dir, axis=0)
        tau_dir = np.repeat(tau[None].astype(dtype), n_dir, axis=0)
        r_dir = np.repeat(r[None].astype(dtype), n_dir, axis=0)
        k = self.n_structure
        if directions:
            # ∂(F²)/∂F = 2F as the imaginary part, the real part left exactly F² (the complex
            # square (F + ih)² would add −h², a negative variance where F = 0)
            q_dir[k + np.arange(n_f), np.arange(n_f)] += 2j * COMPLEX_STEP * f
            tau_dir[k + n_f + n_d + np.arange(n_d), np.arange(n_d)] += 1j * COMPLEX_STEP
            r_dir[k + n_f + 2 * n_d + np.arange(r.size), np.arange(r.size)] += 1j * COMPLEX_STEP
        decay = np.exp(-self.sample_time / tau_dir)
        # stationary standard deviation D: driving variance D²(1 − a²), its D-derivative
        # 2D(1 − a²) added the same way as F's
        d_dir = (sigma**2 * (1 - decay**2)).astype(dtype)
        if directions:
            d_dir[k + n_f + np.arange(n_d), np.arange(n_d)] += (
                2j * COMPLEX_STEP * sigma * (1 - decay[0].real**2))
        inputs, reading = self._coloured_inputs(system)
        system = with_disturbances(system, inputs, reading, decay)
        process = np.zeros((n_dir, system.size, system.size), dtype=system.transition.dtype)
        process[:, self.noise_rows, self.noise_rows] = q_dir
        if n_d:
            process += disturbance_noise(inputs, d_dir)
        system, process = lifted(system, process, self.update_every, self.structure.n_controls)
        return system, steady_state_filter(system.transition, system.output, process, r_dir)

    def _coloured_inputs(self, system) -> tuple[np.ndarray, np.ndarray]:
        """How the coloured disturbances enter ``system``: state inputs (D, S, m) and output
        readings (D, p, m), the accelerations first, then the gusts.

        An acceleration d constant over a sample adds Pe·e_j·d (Pe = ∫₀^dt e^(As) ds on the
        equation rows, the system's ``equation_forcing``), and the outputs reading that
        equation (the accelerometers) read d. A translational gust g acts as
        the state's negative in every derivative term: constant over a sample it adds
        −(Φ − I)·e_j·g (Φ − I = Γ·A, Γ = ∫₀^dt e^(As) ds; exact because no known term and no
        delayed derivative reads the state, :func:`gust_states`), and the outputs read
        −(H − C0)·e_j·g, their derivative terms only (an output measuring the state itself
        measures the aircraft's motion, not the air's). :func:`.system.with_disturbances`
        applies these columns to each disturbance's mean over the interval.
        """
        n_dir, size = system.transition.shape[:2]
        accelerations = system.equation_forcing[:, :, self.disturbance_columns]
        columns = self.gust_columns
        gusts = -(system.transition[:, :, columns] - np.eye(size)[:, columns])
        reading = -(system.output[:, :, columns] - self.gust_known_reading)
        return (np.concatenate([accelerations, gusts], axis=2),
                np.concatenate([np.broadcast_to(self.disturbance_reading,
                                                (n_dir,) + self.disturbance_reading.shape),
                                reading], axis=2))

    def innovations(self, values) -> tuple[np.ndarray, np.ndarray]:
        """Time-major innovations (N, M, p) and their covariance B (p, p) at ``values``."""
        system, steady = self.filter(values)
        blocks = [block for _, block, _, _ in innovation_blocks(
            system, steady, self.records, **self.record_terms(values, system))]
        return np.concatenate(blocks), steady.innovation[0]

    def per_maneuver(self, innovations: np.ndarray) -> list[np.ndarray]:
        """Time-major (N, M, p) innovations → one (N_i, p) array per maneuver."""
        return self.records.split(innovations)

    def state_estimates(self, values) -> StateEstimates:
        """The filter's estimates x̂(n|n) = x̃_n + K ν_n at every measurement update of each
        maneuver at ``values``: the states the outputs see, then the disturbances and gusts
        (:func:`.maneuver_parameters.filter_state_names`), with the standard deviations of
        the steady-state filtered covariance P − K B Kᵀ."""
        system, steady = self.filter(values)
        gain = steady.gain[0]
        filtered = np.concatenate([
            predicted + innovations @ gain.T for _, innovations, _, predicted in
            innovation_blocks(system, steady, self.records, **self.record_terms(values, system))])
        n_kept, n_coloured = len(self.kept_indices), len(self.disturbances) + len(self.gusts)
        columns = np.r_[np.arange(n_kept), system.size - n_coloured + np.arange(n_coloured)]
        covariance = steady.covariance[0] - gain @ steady.innovation[0] @ gain.T
        states = self.structure.signals.states
        units = ([states[self.structure.states[i]].unit for i in self.kept_indices]
                 + [rate_unit(states[s].unit) for s in self.disturbances]
                 + [states[s].unit for s in self.gusts])
        every = self.update_every
        return StateEstimates(
            self.available_states, units, self.maneuver_names,
            [time[::every] for time in self.times],
            [f[:, columns] for f in self.records.split(filtered)],
            np.sqrt(np.clip(np.diag(covariance)[columns], 0.0, None)),
            method=f"Kalman filter x̂(n|n), steady-state gain"
                   f"{f', updated at every {ordinal(every)} sample' if every > 1 else ''}")

    def gauss_newton(self, values, b: np.ndarray, residuals):
        """Fisher information M (P, P) and gradient G (P,) of L at ``values`` (module
        docstring); ``b`` and ``residuals`` are B and the innovations there."""
        system, steady = self.filter(values, directions=True)
        p = self.n_global
        whiten = np.linalg.inv(np.linalg.cholesky(b)).T              # B⁻¹ = W Wᵀ, W = L⁻ᵀ
        terms = self.record_terms(values, system)
        patterns = self._whitened_patterns(system, steady, whiten) if terms else None

        def products(first, block, d_block):
            flat = d_block.reshape(-1, p)                                # (L·M·p_out, P)
            parts = [flat.T @ flat, flat.T @ block.reshape(-1)]
            if patterns is not None:                 # the maneuvers' own parameters' terms
                z = patterns[first:first + block.shape[0]]                # (L, p_out, q)
                parts += [np.einsum("lmyd,lyq->mdq", d_block, z),
                          np.einsum("lmy,lyq->mq", block, z)]
            return parts

        # the products of one block run on a second thread while the filter steps the next
        with ThreadPoolExecutor(max_workers=1) as pool:
            parts = [pool.submit(products, first, block, d_block) for first, block, d_block, _
                     in innovation_blocks(system, steady, self.records, whiten, **terms)]
            sums = [sum(part) for part in zip(*(part.result() for part in parts))]
        information, gradient = sums[:2]
        extra = covariance_terms(steady.innovation.imag / COMPLEX_STEP, b, residuals,
                                 self.n_samples)
        information, gradient = information + extra[0], gradient + extra[1]
        if patterns is None:
            return information, gradient
        return self._with_maneuver_terms(information, gradient, patterns, *sums[2:])

    def _whitened_patterns(self, system, steady, whiten: np.ndarray) -> np.ndarray:
        """Wᵀ Z (N, p, q): the whitened innovations' sensitivities to one maneuver's own
        parameters (:meth:`ManeuverParameters.patterns`) at the nominal filter."""
        transition, output = system.transition[0].real, system.output[0].real
        correction = transition @ steady.gain[0].real                              # ΦK
        patterns = self.maneuver_parameters.patterns(
            transition - correction @ output, output, correction, self.records.mask.shape[0])
        return np.einsum("yk,nyq->nkq", whiten, patterns)

    def _with_maneuver_terms(self, information, gradient, patterns, cross, own_gradient):
        """The information and gradient over every parameter: the global block, the
        cross terms ``cross`` (M, P, q), each maneuver's own block (its patterns' Gram matrix
        up to its length) and ``own_gradient`` (M, q)."""
        count, p, q = cross.shape
        gram = np.cumsum(np.einsum("nyq,nyr->nqr", patterns, patterns), axis=0)
        full = np.zeros((p + count * q, p + count * q))
        full[:p, :p] = information
        for m, length in enumerate(self.records.lengths):
            own = slice(p + m * q, p + (m + 1) * q)
            full[:p, own] = cross[m]
            full[own, :p] = cross[m].T
            full[own, own] = gram[length - 1]
        return full, np.concatenate([gradient, own_gradient.ravel()])


@attrs.frozen
class FilterErrorEstimator:
    """Maximum-likelihood filter-error estimator for linear model structures.

    Args:
        max_iterations, cost_tolerance, step_tolerance: stopping rules (as output error's).
        process_noise: states the process noise enters (one ``F_<state>`` each); default the
            states of the structure's force and moment equations.
        process_noise_start: optional ``F_<state>`` → start value (structure units per sample);
            by default F starts at a tenth of the noise size of an output measuring the state
            (:func:`process_noise_start`): a large start lets the filter follow the data and
            end in a poor local minimum.
        disturbances: states whose equations get a coloured disturbance (default none): a
            first-order Gauss-Markov acceleration with stationary standard deviation
            ``D_<state>`` (structure units per s) and correlation time ``T_<state>`` (s),
            both estimated, which the outputs reading that equation (the accelerometers) see
            too; for turbulence, whose gusts are far from white at the sample rate.
            D starts at the process-noise start per second, T at 1 s.
        gusts: states (velocities) that get a translational gust (default none): a
            first-order Gauss-Markov air velocity g acting as the state's negative in every
            derivative term (−A's column of the state times g, so through the derivatives
            themselves), with stationary standard deviation ``G_<state>`` (state units) and
            correlation time ``Tg_<state>`` (s), both estimated; G starts at
            :func:`gust_start`, Tg at 1 s.
        longest_correlation: optional ``T_<state>`` / ``Tg_<state>`` → the longest that
            correlation time may become, s (default 1000 s, no limit in practice): a
            correlation time near the record's length makes the disturbance a drift the
            derivatives can explain as well, and the two trade
            (:mod:`.correlation_limits`; a fifth of the shortest record is the documented
            rule). A start above its limit starts at the limit.
        initial_states: estimate each maneuver's initial filter state (``x0_<maneuver>_<state>``,
            module :mod:`.maneuver_parameters`): ``True`` for every state the outputs see and
            every disturbance (``d_<state>``) and gust (``g_<state>``), or the names of some;
            default none (each record starts at its recorded initial state, disturbances and
            gusts at zero). A gust slower than the records is nearly a constant per record:
            its initial value is the one to estimate.
        output_biases: estimate one constant bias per maneuver and output
            (``bias_<maneuver>_<output>``).
        enforce_signs: use the sign priors as bounds.
        update_every: take the filter's measurement update at every N-th sample only
            (default 1, every sample): the model and the disturbances still step through every
            sample with its recorded input (:func:`.system.lifted`), the innovations are formed
            at samples 0, N, 2N, …. For records low-passed to the band the structure describes
            (:func:`rotorid.resampling.low_passed`) with N their white-noise factor
            (:func:`rotorid.resampling.white_noise_factor`): the filter then weighs that band
            only, its innovations' sensor noise stays white, and the inputs between updates
            need no hold assumption, as decimated records' do. Linear structures only.
        start: ``"auto"`` (equation error when every derivative's initial value is zero, else
            the initial values), ``"initial"``, ``"equation-error"`` or ``"output-error"`` (an
            output-error fit of the structure, for data with little process noise, where a
            free F from equation error can settle in a poorer optimum) for the derivatives
            and delays. With gusts, equation error starts a first fit with accelerations in
            place of the gusts, whose derivatives and delays start the gust fit
            (:meth:`_gust_free_start`).
        callback: called with ``(stage, progress record)`` after every accepted iteration.
    """

    name = NAME
    max_iterations: int = 50
    cost_tolerance: float = 1e-7
    step_tolerance: float = 1e-9
    process_noise: tuple[str, ...] | None = attrs.field(
        default=None, converter=_state_names("process_noise"))
    process_noise_start: Mapping[str, float] | None = None
    disturbances: tuple[str, ...] = attrs.field(default=(),
                                                converter=_state_names("disturbances"))
    gusts: tuple[str, ...] = attrs.field(default=(), converter=_state_names("gusts"))
    longest_correlation: Mapping[str, float] = attrs.field(factory=dict,
                                                           converter=correlation_limits)
    initial_states: bool | tuple[str, ...] = attrs.field(default=False,
                                                         converter=initial_state_option)
    output_biases: bool = False
    enforce_signs: bool = False
    update_every: int = attrs.field(default=1, validator=_whole_number)
    start: str = attrs.field(default="auto", validator=_start_choice)
    callback: Callable | None = None

    def check_structure(self, structure) -> None:
        """Refuse, before any data exist, noise-model options that ``structure`` (a
        ModelStructure; a model of one's own is checked when fitted) cannot take: the checks
        of :meth:`_noise_states`."""
        if isinstance(structure, ModelStructure):
            self._noise_states(structure)

    def _noise_states(self, structure: ModelStructure):
        """The states of the process noise, the disturbances and the gusts in ``structure``
        (:func:`process_noise_states`, :func:`gust_states`), each option checked, the
        correlation-time limits too."""
        disturbances = process_noise_states(structure, self.disturbances, "disturbances",
                                            accelerations=True)
        gusts = gust_states(structure, self.gusts)
        check_limited(self.longest_correlation, disturbances, gusts)
        return process_noise_states(structure, self.process_noise), disturbances, gusts

    def estimate(self, structure: ModelStructure, maneuvers: ManeuverSet, *,
                 start=None) -> Estimate:
        """Fit ``structure``'s derivatives and delays, F and R to ``maneuvers``; a nonlinear
        model of one's own (or its :class:`~rotorid.estimation.integrated.IntegratedModel`)
        instead goes to :func:`.nonlinear.fit_nonlinear`.

        ``start`` overrides start values: a vector over the estimate's parameter names or a
        mapping of some of them.
        """
        if not isinstance(structure, ModelStructure):
            if self.update_every != 1:
                raise EstimationError(f"update_every = {self.update_every} is for linear "
                                      f"structures; a nonlinear model's filter updates at "
                                      f"every sample: give it decimated records instead "
                                      f"(rotorid.resampling.decimated)")
            from .nonlinear import fit_nonlinear

            return fit_nonlinear(self, structure, maneuvers, start)
        with blas.single_threaded():
            return self._fit_linear(structure, maneuvers, start)

    def _fit_linear(self, structure: ModelStructure, maneuvers: ManeuverSet, start,
                    stage: str = "") -> Estimate:
        """The fit of a linear ``structure``; its iterations are reported as ``stage``."""
        problem = self._problem(structure, maneuvers)
        values, note, given = self._start_values(problem, maneuvers, start)
        mine = not any(name in given for name in structure.parameter_names)
        from_equation_error = mine and self._wants_equation_error(structure)
        if self.start == "output-error" and mine:
            values[:problem.n_structure], note = self._output_error_start(structure, maneuvers)
        elif from_equation_error:
            first = self._gust_free_start(problem, maneuvers, start)
            if first is not None:
                values[:problem.n_structure], note = first
        values = matched_measurement_noise(problem, matched_biases(problem, values, given),
                                           given)
        bounds = self._bounds(problem, values)
        held = (_noise_held(problem, values, bounds) if problem.maneuver_parameters.size
                else None)
        result = run_fit(problem, values, bounds, self.callback, held, stage)
        estimate = filter_error_estimate(problem, result, values, bounds, note)
        if (from_equation_error and not problem.disturbances and not problem.gusts
                and (estimate.sign_violations or not estimate.converged)):
            estimate = attrs.evolve(estimate, notes=(*estimate.notes, POORER_OPTIMUM_ADVICE))
        return estimate

    def _problem(self, structure: ModelStructure, maneuvers: ManeuverSet) -> FilterErrorProblem:
        """The filter-error problem of a linear ``structure`` on ``maneuvers`` with this
        estimator's noise model and options."""
        # projected steps: in still air every F heads for its bound 0, and one F just above
        # it would otherwise shorten every step (the fit then stalls far from the optimum)
        settings = Settings(self.max_iterations, self.cost_tolerance, self.step_tolerance,
                            shorten_steps=False)
        process_noise, disturbances, gusts = self._noise_states(structure)
        return FilterErrorProblem(
            structure, maneuvers, process_noise, settings, disturbances, gusts,
            self.initial_states, self.output_biases, self.update_every)

    def state_estimates(self, structure, maneuvers: ManeuverSet,
                        estimate: Estimate) -> StateEstimates:
        """The filter's estimates x̂(n|n) along ``maneuvers`` at ``estimate``, this
        estimator's fit of ``structure`` (linear, or a nonlinear model of one's own) to them
        with its options (:meth:`FilterErrorProblem.state_estimates`,
        :meth:`.nonlinear.NonlinearFilterErrorProblem.state_estimates`). An estimate of
        other parameters or of other records (another noise model, structure, sample time or
        update rate) is refused, naming the difference."""
        if not isinstance(estimate, Estimate):
            raise EstimationError(f"state estimates need the Estimate of a filter-error fit, "
                                  f"got {type(estimate).__name__}")
        with blas.single_threaded():
            if isinstance(structure, ModelStructure):
                problem = self._problem(structure, maneuvers)
            else:
                from .nonlinear import nonlinear_problem

                problem = nonlinear_problem(self, structure, maneuvers)
            _check_estimate_of(problem, estimate)
            return problem.state_estimates(estimate.values)

    def _wants_equation_error(self, structure: ModelStructure) -> bool:
        """Whether the derivatives start from equation error (``start`` option, or "auto"
        with every derivative's initial value zero)."""
        derivatives = ~structure.is_delay()
        return bool(structure.n_parameters) and (self.start == "equation-error" or (
            self.start == "auto" and not np.any(structure.initial_values()[derivatives])))

    def _output_error_start(self, structure: ModelStructure, maneuvers: ManeuverSet
                            ) -> tuple[np.ndarray, str]:
        """Derivatives and delays (structure order) from an output-error fit of
        ``structure`` (its own start), and the start note."""
        fitted = create("estimators", "output-error",
                        output_biases=self.output_biases).estimate(structure, maneuvers)
        return (np.array([fitted.value(name) for name in structure.parameter_names]),
                f"start values from an output-error fit ({fitted.iterations} iterations, "
                f"{'converged' if fitted.converged else 'not converged'})")

    def _gust_free_start(self, problem, maneuvers, start) -> tuple[np.ndarray, str] | None:
        """Derivatives and delays (``problem.n_structure``,) from a first fit with a
        Gauss-Markov acceleration on each gust's equation in place of the gust (itself from
        equation error), and the start note; None without such gusts.

        A gust acts only through its velocity's derivatives, so from an equation-error start
        (which leaves the turbulence out, e.g. Z_w near 0 in hover) the fit can follow the
        ridge where the gust grows as those derivatives shrink, to a poorer optimum: on the
        small hover model's doublets with a 5 ft/s w gust, Z_w 0.005 and G_w 190 ft/s where
        the truth's neighbourhood is likelier by up to 16 in ln L (docs/estimation.md, "A gust's
        start"). An acceleration has no such ridge."""
        structure = problem.structure
        accelerated = tuple(s for s in problem.gusts
                            if structure.states.index(s) in structure.equation_rows)
        if not accelerated:
            return None
        initial = initial_state_option(self.initial_states)
        if not isinstance(initial, bool):     # a gust's initial value becomes its acceleration's
            initial = tuple(f"d_{n[2:]}" if n[2:] in accelerated else n for n in initial
                            if not n.startswith("g_") or n[2:] in accelerated)
        first = attrs.evolve(self, gusts=(), initial_states=initial, disturbances=(
            self.disturbances + tuple(s for s in accelerated if s not in self.disturbances)),
            longest_correlation=_accelerations_limits(self.longest_correlation, accelerated))
        gust_names = tuple(f"_g_{s}" for s in problem.gusts)
        kept = {n: v for n, v in (start if isinstance(start, Mapping) else {}).items()
                if not n.startswith(("G_", "Tg_")) and not n.endswith(gust_names)}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            fitted = first._fit_linear(structure, maneuvers, kept or None, GUST_FREE_STAGE)
        return (fitted.values[:problem.n_structure].copy(),
                f"start values from a fit with accelerations in place of the gusts on "
                f"{', '.join(accelerated)} ({fitted.iterations} iterations from equation error"
                f"{'' if fitted.converged else ', stopped unconverged: ' + fitted.stop_reason})")

    def _start_values(self, problem, maneuvers, start):
        structure = problem.structure
        names = problem.parameter_names
        initial = structure.initial_values()
        note = None
        if self._wants_equation_error(structure):
            initial = LinearModel(structure).start_values(maneuvers)
            note = "start values from equation error"
        variance = problem.first_difference_variance
        states = problem.process_noise
        given = given_process_noise_start(self.process_noise_start, states)
        missing = tuple(s for s in states if f"F_{s}" not in given)
        dt = problem.sample_time
        steps = {**process_noise_start(structure, missing, variance, dt),
                 **{name[2:]: float(value) for name, value in given.items()}}
        # default starts only where none is given (a state no output measures has none)
        chosen = set(names) if start is not None and not isinstance(start, Mapping) else set(
            start or ())
        disturbances = process_noise_start(
            structure, tuple(s for s in problem.disturbances if f"D_{s}" not in chosen),
            variance, dt, "D", "disturbances")
        gusts = gust_start(structure, tuple(s for s in problem.gusts if f"G_{s}" not in chosen),
                           problem.records)
        coloured = len(problem.disturbances) + len(problem.gusts)
        values = np.concatenate([initial, [steps[s] for s in states],
                                 [disturbances.get(s, np.nan) / dt for s in problem.disturbances],
                                 [gusts.get(s, np.nan) for s in problem.gusts],
                                 np.full(coloured, CORRELATION_START), variance,
                                 problem.maneuver_parameters.start(problem.records.x0,
                                                                   problem.kept_indices)])
        values, given = with_start(values, start, names)
        correlation = [names.index(n) for n in correlation_names(problem.disturbances,
                                                                 problem.gusts)]
        values[correlation] = [min(values[i], self.longest_correlation.get(names[i], np.inf))
                               for i in correlation]
        return values, (note if start is None else None), given

    def _bounds(self, problem, values):
        lower, upper = problem.structure.bounds(enforce_signs=self.enforce_signs)
        parts = problem.split(values)
        n_f, n_d = parts.process.size, parts.disturbance.size
        shortest = np.concatenate([np.full(len(problem.disturbances), problem.sample_time),
                                   np.full(len(problem.gusts),
                                           _SHORTEST_GUST_SAMPLES * problem.records.dt)])
        free = np.full(problem.maneuver_parameters.size, np.inf)
        # R's floor from its start, but never below the data's own first differences' (the
        # nonlinear path's floor): a fit continued from one whose R sat at its floor would
        # otherwise start a floor 10⁻⁴ lower (rotorid.estimation.continuation)
        variance = np.maximum(parts.measurement, problem.first_difference_variance)
        return (np.concatenate([lower, np.zeros(n_f), _SIZE_FLOOR * parts.disturbance, shortest,
                                VARIANCE_FLOOR * variance, -free]),
                np.concatenate([upper, np.full(n_f + n_d, np.inf),
                                longest_correlations(self.longest_correlation,
                                                     problem.disturbances, problem.gusts,
                                                     shortest),
                                np.full(parts.measurement.size, np.inf), free]))


#: The fast-mode note's turbulence cause, for a fit with and without a noise model.
_UNDESCRIBED_TURBULENCE = ("turbulence the noise model does not describe (other gusts or "
                           "disturbances)")
_NO_NOISE_MODEL = ("turbulence in the records, which this fit's noise model (no process noise, "
                   "disturbances or gusts) leaves out as output error does: give it gusts or "
                   "disturbances")


def _check_estimate_of(problem, estimate: Estimate) -> None:
    """Refuse an ``estimate`` that is not a fit of ``problem``: other parameters (another
    structure or noise model) or another number of innovations (other records, sample time
    or update rate)."""
    names = tuple(problem.parameter_names)
    if tuple(estimate.parameter_names) != names:
        missing = [n for n in names if n not in estimate.parameter_names]
        extra = [n for n in estimate.parameter_names if n not in names]
        parts = ([f"lacks {', '.join(missing[:6])}{' …' if len(missing) > 6 else ''}"]
                 if missing else []) + (
            [f"has {', '.join(extra[:6])}{' …' if len(extra) > 6 else ''} besides"]
            if extra else []) or ["orders its parameters otherwise"]
        raise EstimationError(
            f"the estimate {' and '.join(parts)}: state estimates need the filter-error fit "
            f"of this structure to these maneuvers with the same noise model (process_noise, "
            f"disturbances, gusts, initial_states, output_biases)")
    if estimate.n_samples != problem.n_samples:
        raise EstimationError(
            f"the estimate was fitted to {estimate.n_samples} innovations, these maneuvers "
            f"give {problem.n_samples}: give the records as fitted (the same resampling, "
            f"sample time and update_every)")


def unmeasured_gusts(problem) -> tuple[str, ...]:
    """The gust states of ``problem`` that no output reads directly (none named like them)."""
    reading = getattr(problem, "gust_known_reading", None)
    if reading is None:
        return ()
    return tuple(state for state, column in zip(problem.gusts, reading.T)
                 if not np.any(column != 0))


def filter_error_estimate(problem, result, start, bounds, note) -> Estimate:
    """The :class:`Estimate` of a filter-error fit ``result`` of ``problem`` (a linear or a
    nonlinear one: parameters ``R_<output>`` hold the measurement noise)."""
    lower, upper = bounds
    values, information = result.values, result.information
    at_bound = tuple(n for n, v, lo, hi in zip(problem.parameter_names, values, lower, upper)
                     if (np.isfinite(lo) and v <= lo) or (np.isfinite(hi) and v >= hi))
    notes = ([note] if note else []) + [
        "cost exp(2L/N) = det B·exp(mean νᵀB⁻¹ν); RMSE of the innovations; "
        "noise_covariance is the measurement noise R"]
    every = getattr(problem, "update_every", 1)
    if every > 1:
        notes.append(f"one measurement update per {every} samples (update_every = "
                     f"{every}): {problem.n_samples} innovations per output")
    silent = [n for n in at_bound if n.startswith("F_")]
    if silent:
        states = ", ".join(n[2:] for n in silent)
        notes.append(f"{', '.join(silent)} ended at zero: the data show no white process "
                     f"noise on {states}, so the information holds nothing about "
                     f"{'it' if len(silent) == 1 else 'them'} (infinite bounds, not a lack of "
                     f"excitation); leave {states} out of the process noise and refit, or "
                     f"model the turbulence as gusts or disturbances instead")
    faded = [n for n in at_bound if n.startswith(("D_", "G_"))]
    if faded:
        states = ", ".join(n.split("_", 1)[1] for n in faded)
        their = "its" if len(faded) == 1 else "their"
        notes.append(f"{', '.join(faded)} ended at the floor of {their} size: beside the rest "
                     f"of the noise model the data show no such disturbance or gust on "
                     f"{states}, and the bounds of its size and correlation time say nothing; "
                     f"or the fit stopped where the measurement noise took it over, a poorer "
                     f"optimum: refit from a start at the size the turbulence is expected to "
                     f"have (start = {{'{faded[0]}': …}}) and compare the costs; if that is no "
                     f"likelier, leave {states} out of the disturbances or gusts and refit")
    whitened = [f"{n} ({v:.3g} s)" for n, v, lo in zip(problem.parameter_names, values, lower)
                if n.startswith(("T_", "Tg_")) and v <= lo]
    if whitened:
        notes.append(f"{', '.join(whitened)} ended at the shortest correlation time allowed: "
                     f"the disturbance became noise that the measurement noise can take over, "
                     f"often a poorer optimum; refit from a start at the size and correlation "
                     f"time the turbulence is expected to have and compare the costs")
    drifting = [f"{n} ({v:.3g} s)" for n, v, hi in zip(problem.parameter_names, values, upper)
                if n.startswith(("T_", "Tg_")) and v >= hi]
    if drifting:
        notes.append(f"{', '.join(drifting)} ended at the longest correlation time allowed "
                     f"(longest_correlation, or {UNLIMITED_CORRELATION:g} s): the fit would "
                     f"make the disturbance slower still, a drift within the records that the "
                     f"derivatives can explain as well; every estimate and bound is the one at "
                     f"that limit")
    innovations = problem.per_maneuver(problem.innovations(values)[0])
    coloured = whiteness_note(innovations, problem.output_names, problem.sample_time * every)
    if coloured:
        notes.append(coloured)
    structure = getattr(problem, "structure", None)
    if isinstance(structure, ModelStructure):
        noisy = problem.process_noise or problem.disturbances or problem.gusts
        fast = fast_modes_note(structure, values[:structure.n_parameters], problem.sample_time,
                               _UNDESCRIBED_TURBULENCE if noisy else _NO_NOISE_MODEL)
        if fast:
            notes.append(fast)
    unmeasured = unmeasured_gusts(problem)
    if unmeasured:
        notes.append(f"no output measures {', '.join(unmeasured)}: each such gust's size G "
                     f"trades with its velocity's derivatives (a ridge; G's Cramér-Rao bound "
                     f"shows it), so those derivatives, and through them other axes, rest on "
                     f"the structure being right (docs/estimation.md, the lateral gust)")
    names = problem.parameter_names
    measurement = values[[names.index(f"R_{o}") for o in problem.output_names]]
    return Estimate.from_fit(
        problem, values, information, estimator=NAME, start=start,
        noise_covariance=np.diag(measurement), cost=result.cost,
        rmse=result.rmse, residual_rms=result.residual_rms, n_samples=problem.n_samples,
        cost_history=result.cost_history,
        rmse_history=result.rmse_history, iterations=result.iterations,
        converged=result.converged, stop_reason=result.stop_reason, at_bound=at_bound,
        notes=tuple(notes))


def run_fit(problem, values, bounds, callback=None, held=None, stage: str = ""):
    """Levenberg-Marquardt on ``problem`` from ``values`` within ``bounds``, first within
    ``held`` bounds when given, reporting every accepted iteration as ``stage`` (the
    ``rotorid_estimation_iteration`` hook; ``callback`` gets "full" for the plain fit)."""

    def progress(record):
        notify("rotorid_estimation_iteration", estimator=NAME, stage=stage,
               iteration=record.iteration, cost=record.cost, rmse=record.rmse,
               lm_lambda=record.lm_lambda)
        if callback is not None:
            callback(stage or "full", record)

    try:
        if held is not None:
            values = run(problem, values, held, progress).values
        return run(problem, values, bounds, progress)
    except SimulationDivergedError:
        raise EstimationError(f"no finite likelihood at the start values: "
                              f"{problem.failure(values)}; give other start values "
                              f"(parameters, F or R)") from None
