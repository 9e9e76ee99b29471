"""Filter error for a nonlinear model of one's own: its own equations predict, the gain of its
linearisation corrects.

At each parameter vector the model is linearised about the first maneuver's initial state and
first input (central differences in the states, batched), discretised exactly (Φ = e^(A·dt)),
and the steady-state Kalman filter of that linear model (white process noise ``F_<state>`` on
chosen states, per sample; measurement noise ``R_<output>``; :mod:`.riccati`) gives the gain K
and the innovation covariance B. Every record is then filtered with the model itself::

    ν_n = z_n − h(t_n, x̃_n, u_n)      x̂_n = x̃_n + K ν_n
    x̃_n+1 = x̂_n advanced over one sample by the model's integration (scheme, sub-steps, hold)

This is the steady-state form of the extended Kalman filter used for filter error on nonlinear
models (Jategaonkar, *Flight Vehicle System Identification*, ch. 5): the gain is held along the
record, which suits maneuvers about one trim. The cost, the Fisher information and the
Levenberg-Marquardt steps are the linear filter error's (:mod:`.estimator`); the sensitivities
of ν and B are central differences of one batched run of every perturbed parameter vector,
gain included (relative step ``step``, as :class:`rotorid.estimation.integrated.IntegratedModel`
uses for output error).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from rotorid import blas
from rotorid.errors import DataError, EstimationError
from rotorid.estimation.estimate import Estimate
from rotorid.estimation.integrated import IntegratedModel
from rotorid.estimation.state_estimates import StateEstimates
from rotorid.model.nonlinear import NonlinearModel
from rotorid.simulation.integrators import integrate
from rotorid.units import rmse_reference_factors
from rotorid_output_error.levenberg_marquardt import Settings

from .estimator import VARIANCE_FLOOR, filter_error_estimate, run_fit
from .likelihood import InnovationLikelihood, covariance_terms
from .riccati import steady_state_filter
from .starts import (
    PROCESS_START,
    given_process_noise_start,
    matched_measurement_noise,
    measurement_noise_start,
    with_start,
)

#: Relative central-difference step of the linearisation in the states: h = step·max(|x|, 1).
_LINEARISATION_STEP = 1e-6


class NonlinearFilterErrorProblem(InnovationLikelihood):
    """Cost, innovations and Fisher information of a nonlinear model on one maneuver set, in
    the form :func:`rotorid_output_error.levenberg_marquardt.run` drives.

    Args:
        model: the model as an :class:`IntegratedModel` (channels, initial conditions,
            integration), set up for ``maneuvers``.
        process_noise: states with white process noise ``F_<state>`` (state units per
            sample).
        step: relative central-difference step of the sensitivities, h = step·max(|ψ|, 1)
            for the model's parameters and step·ψ for F and R.
    """

    def __init__(self, model: IntegratedModel, maneuvers, process_noise: tuple[str, ...],
                 settings, step: float = 1e-6):
        self.model = model
        self.settings = settings
        self.step = float(step)
        self.hold = maneuvers.hold
        self.records = model.records(maneuvers)
        dts = [r.dt for r in self.records]
        if max(dts) - min(dts) > 1e-9 * max(dts):
            raise DataError(f"the filter-error estimator needs one sample time for all "
                            f"maneuvers, got {sorted(set(round(d, 9) for d in dts))} s; "
                            f"resample them first")
        self.dt = float(np.mean(dts))
        states = model.signals.states
        unknown = [s for s in process_noise if s not in states]
        if unknown:
            raise EstimationError(f"process_noise names {', '.join(unknown)}, not states of "
                                  f"the model ({', '.join(states.names)})")
        self.process_noise = tuple(process_noise)
        self.noise_rows = states.indices(self.process_noise)
        self.lengths = tuple(r.inputs.shape[0] for r in self.records)
        self.maneuver_names = maneuvers.names
        n, count = max(self.lengths), len(self.records)
        self.outputs = np.zeros((n, count, len(model.output_names)))
        self.mask = np.zeros((n, count), dtype=bool)
        for b, z in enumerate(model.measured(maneuvers)):
            self.outputs[: z.shape[0], b] = z
            self.mask[: z.shape[0], b] = True
        self.n_samples = int(self.mask.sum())
        self.n_model = len(model.parameter_names)
        self.output_names = model.output_names
        self.output_units = model.output_units
        self.parameter_names = (tuple(model.parameter_names)
                                + tuple(f"F_{s}" for s in self.process_noise)
                                + tuple(f"R_{o}" for o in self.output_names))
        self.parameter_units = {
            **model.parameter_units,
            **{f"F_{s}": states[s].unit for s in self.process_noise},
            **{f"R_{o.name}": f"({o.unit})²" if o.unit else "" for o in model.signals.outputs}}
        scale = rmse_reference_factors(self.output_units)
        self.rmse_scale = np.ones(len(self.output_names)) if scale is None else scale

    # ------------------------------------------------------------------ the filter
    def _parts(self, batch: np.ndarray):
        k, f = self.n_model, len(self.process_noise)
        return batch[:, :k], batch[:, k:k + f], batch[:, k + f:]

    def _gains(self, theta: np.ndarray, start: np.ndarray, f: np.ndarray, r: np.ndarray):
        """The steady-state filter (gain K (B, n, p), innovation covariance B (B, p, p), a
        priori covariance P (B, n, n)) of the model linearised about the first record's
        ``start`` states (B, n) and first input, per row."""
        first = self.records[0]
        rows, n = start.shape
        h = _LINEARISATION_STEP * np.maximum(np.abs(start), 1.0)                 # (B, n)
        shifts = np.concatenate([np.eye(n)[None] * h[:, None, :],
                                 -np.eye(n)[None] * h[:, None, :]], axis=1)      # (B, 2n, n)
        x = (start[:, None, :] + shifts).reshape(-1, n)
        count = 2 * n * rows
        t = np.full(count, first.t0)
        u = np.broadcast_to(first.inputs[0], (count, first.inputs.shape[1]))
        th = np.repeat(theta, 2 * n, axis=0)
        with np.errstate(all="ignore"):
            slope = np.asarray(self.model.model.derivatives(t, x, u, th)).reshape(rows, 2, n, n)
            read = np.asarray(self.model.model.outputs(t, x, u, th)).reshape(rows, 2, n, -1)
        width = 2 * h[:, :, None]
        a = np.swapaxes((slope[:, 0] - slope[:, 1]) / width, 1, 2)                # (B, n, n)
        c = np.swapaxes((read[:, 0] - read[:, 1]) / width, 1, 2)                  # (B, p, n)
        if not (np.all(np.isfinite(a)) and np.all(np.isfinite(c))):
            raise EstimationError("the model's linearisation about the first maneuver's "
                                  "initial state is not finite")
        transition = scipy.linalg.expm(a * self.dt)
        process = np.zeros((rows, n, n))
        process[:, self.noise_rows, self.noise_rows] = f**2
        return steady_state_filter(transition, c, process, r)

    def run(self, batch: np.ndarray):
        """Innovations (N, M, B, p) and their covariances (B, p, p) of B parameter vectors
        (batch (B, P)); padded samples are zero, a row that blew up is not finite."""
        innovations, steady, _ = self._filter(batch)
        return innovations, steady.innovation

    def _filter(self, batch: np.ndarray, keep_states: bool = False):
        """The filter run over every record for each row of ``batch`` (B, P): innovations
        (N, M, B, p), the steady-state filter, and with ``keep_states`` the corrected states
        x̂(n|n) (N, M, B, n) (else None)."""
        psi, f, r = self._parts(np.asarray(batch, dtype=float))
        theta, states = self.model.expand(psi, self.records)
        steady = self._gains(theta, states[0], f, r)
        count, rows = len(self.records), batch.shape[0]
        members = list(range(count))
        inputs, t0, x, rows_theta = self.model.stacked(self.records, members, theta, states)
        gains = np.tile(steady.gain, (count, 1, 1))                              # (M·B, n, p)
        measured = np.repeat(self.outputs, rows, axis=1)                         # (N, M·B, p)
        samples = inputs.shape[0]
        result = np.empty((samples, count * rows, len(self.output_names)))
        kept = np.empty((samples,) + x.shape) if keep_states else None
        with np.errstate(all="ignore"):
            for k in range(samples):
                predicted = self.model.model.outputs(t0 + k * self.dt, x, inputs[k],
                                                     rows_theta)
                result[k] = measured[k] - predicted
                corrected = x + np.einsum("bij,bj->bi", gains, result[k])
                if keep_states:
                    kept[k] = corrected
                if k + 1 < samples:
                    x = integrate(self.model.model.derivatives, t0 + k * self.dt, self.dt,
                                  corrected, inputs[k:k + 2], rows_theta, self.hold,
                                  self.model.integration)[1]
        result = result.reshape(samples, count, rows, -1) * self.mask[:, :, None, None]
        if keep_states:
            kept = kept.reshape(samples, count, rows, -1)
        return result, steady, kept

    def state_estimates(self, values) -> StateEstimates:
        """The filter's estimates x̂(n|n) of the model's states at every sample of each
        maneuver at ``values``, with the standard deviations of the steady-state filtered
        covariance P − K B Kᵀ (of the linearisation the gain comes from)."""
        _, steady, kept = self._filter(np.asarray(values, dtype=float)[None], keep_states=True)
        gain = steady.gain[0]
        covariance = steady.covariance[0] - gain @ steady.innovation[0] @ gain.T
        states = self.model.signals.states
        return StateEstimates(
            states.names, [s.unit for s in states], self.maneuver_names,
            [r.t0 + np.arange(n) * self.dt for r, n in zip(self.records, self.lengths)],
            [kept[:n, b, 0] for b, n in enumerate(self.lengths)],
            np.sqrt(np.clip(np.diag(covariance), 0.0, None)),
            method="extended Kalman filter x̂(n|n), steady-state gain")

    # ------------------------------------------------------------------ the problem
    @property
    def sample_time(self) -> float:
        """The records' sample interval, s (the name the linear problem gives it)."""
        return self.dt

    def innovations(self, values) -> tuple[np.ndarray, np.ndarray]:
        """Time-major innovations (N, M, p) and their covariance B (p, p) at ``values``."""
        nu, b = self.run(np.asarray(values, dtype=float)[None])
        return nu[:, :, 0], b[0]

    def per_maneuver(self, innovations: np.ndarray) -> list[np.ndarray]:
        """Time-major (N, M, p) innovations → one (N_i, p) array per maneuver."""
        return [innovations[:n, i] for i, n in enumerate(self.lengths)]

    def steps(self, values: np.ndarray) -> np.ndarray:
        """Central-difference steps (P,): step·max(|ψ|, 1) for the model's parameters,
        step·value for F and R (kept positive)."""
        h = self.step * np.abs(values)
        h[: self.n_model] = self.step * np.maximum(np.abs(values[: self.n_model]), 1.0)
        return np.where(h > 0, h, self.step)

    def gauss_newton(self, values, b: np.ndarray, residuals):
        """Fisher information M (P, P) and gradient G (P,) of L at ``values`` (as the linear
        filter error's), from central differences of one batched run."""
        values = np.asarray(values, dtype=float)
        p = values.size
        h = self.steps(values)
        shifts = np.eye(p) * h
        nu, covariances = self.run(np.vstack([values + shifts, values - shifts]))
        if not np.all(np.isfinite(nu)):
            raise EstimationError("a perturbed parameter vector gives no finite innovations; "
                                  "the model diverges next to these values")
        d_nu = (nu[:, :, :p] - nu[:, :, p:]) / (2 * h[None, None, :, None])       # (N, M, P, p)
        d_b = (covariances[:p] - covariances[p:]) / (2 * h[:, None, None])       # (P, p, p)
        b_inv = np.linalg.inv(b)
        innovations = np.concatenate([np.pad(e, ((0, self.outputs.shape[0] - e.shape[0]),
                                                 (0, 0)))[:, None] for e in residuals], axis=1)
        weighted = d_nu @ b_inv                                                  # (N, M, P, p)
        information = np.einsum("nmip,nmjp->ij", weighted, d_nu)
        gradient = np.einsum("nmip,nmp->i", weighted, innovations)
        extra = covariance_terms(d_b, b, residuals, self.n_samples)
        return information + extra[0], gradient + extra[1]


#: Options of the linear estimator that a nonlinear model does not take, and what to do.
_LINEAR_ONLY = {
    "disturbances": "model a coloured disturbance as states of the model",
    "gusts": "model gusts as states of the model",
    "longest_correlation": "give the model's own correlation-time parameter an upper bound "
                           "(its Parameter's upper)",
    "initial_states": "estimate initial states through the model's InitialConditions",
    "output_biases": "add bias parameters to the model's outputs",
}


def nonlinear_problem(estimator, model, maneuvers) -> NonlinearFilterErrorProblem:
    """The filter-error problem of a nonlinear model of one's own (a :class:`NonlinearModel`
    or its :class:`IntegratedModel`) on ``maneuvers`` with the options of ``estimator``; F on
    ``process_noise``, by default the states an output of the same name measures."""
    if isinstance(model, NonlinearModel):
        model = IntegratedModel(model)
    if not isinstance(model, IntegratedModel):
        raise EstimationError(f"the filter-error estimator identifies a linear model structure "
                              f"(ModelStructure) or a nonlinear model of one's own, not "
                              f"{type(model).__name__}")
    used = [n for n in _LINEAR_ONLY if getattr(estimator, n)]
    if used:
        raise EstimationError(f"filter error on a nonlinear model does not take "
                              f"{', '.join(used)}: " + "; ".join(_LINEAR_ONLY[n] for n in used))
    model = model.for_maneuvers(maneuvers)
    outputs = model.output_names
    states = model.signals.states.names
    process = (tuple(s for s in states if s in outputs) if estimator.process_noise is None
               else estimator.process_noise)
    settings = Settings(estimator.max_iterations, estimator.cost_tolerance,
                        estimator.step_tolerance, shorten_steps=False)
    return NonlinearFilterErrorProblem(model, maneuvers, process, settings)


def fit_nonlinear(estimator, model, maneuvers, start=None) -> Estimate:
    """Filter error on a nonlinear model of one's own (a :class:`NonlinearModel` or its
    :class:`IntegratedModel`) with the options of ``estimator`` (a
    :class:`~.estimator.FilterErrorEstimator`): its parameters, F on ``process_noise``
    (default: the states an output of the same name measures) and R.

    F starts at ``process_noise_start`` or at a tenth of the measurement-noise size of the
    output of the state's name; R at half the mean square first difference of each output,
    then matched to the start innovations (as the linear estimator's).
    """
    with blas.single_threaded():
        problem = nonlinear_problem(estimator, model, maneuvers)
        model, process = problem.model, problem.process_noise
        variance = measurement_noise_start(problem)
        values, given = _start_values(estimator, problem, variance, start)
        # R's floor from the data's own first differences, not from R matched to the start's
        # innovations: from textbook guesses those are far larger, and a floor of 1e-4 of
        # them held R_theta at 4 times the sensor's variance (the fit stopped there)
        floor = VARIANCE_FLOOR * variance
        values = matched_measurement_noise(problem, values, given)
        lower, upper = model.bounds()
        n_f = len(process)
        bounds = (np.concatenate([lower, np.zeros(n_f), floor]),
                  np.concatenate([upper, np.full(n_f + floor.size, np.inf)]))
        result = run_fit(problem, values, bounds, estimator.callback)
    return filter_error_estimate(problem, result, values, bounds, None)


def _start_values(estimator, problem: NonlinearFilterErrorProblem, variance: np.ndarray,
                  start):
    """(start vector, names given explicitly): the model's starts, F as :func:`fit_nonlinear`
    says, R at ``variance`` (the outputs' first-difference start), then ``start`` (a vector
    or a mapping of some names)."""
    names = problem.parameter_names
    outputs = problem.output_names
    given_f = given_process_noise_start(estimator.process_noise_start, problem.process_noise)
    f = []
    for state in problem.process_noise:
        if f"F_{state}" in given_f:
            f.append(float(given_f[f"F_{state}"]))
        elif state in outputs:
            f.append(PROCESS_START * float(np.sqrt(variance[outputs.index(state)])))
        else:
            raise EstimationError(f"no output is named {state}, so F_{state} has no default "
                                  f"start; give process_noise_start={{'F_{state}': …}} or leave "
                                  f"{state} out of process_noise")
    values = np.concatenate([problem.model.initial_values(), f, variance])
    return with_start(values, start, names)
