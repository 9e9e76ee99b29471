"""One Levenberg-Marquardt run of the maximum-likelihood output-error method.

Cost J(Θ) = det R with R = (1/N) Σ (z − y)(z − y)ᵀ re-estimated at every evaluation
(relaxation). With R held at its current value the Gauss-Newton information matrix and
gradient are (paper eqs. 8-9)

    F = Σ (∂y/∂Θ)ᵀ R⁻¹ (∂y/∂Θ)        G = −Σ (∂y/∂Θ)ᵀ R⁻¹ (z − y)

and the step solves (F + λ·D) ΔΘ = −G with D = diag(F) (Marquardt's scaling, so that parameters
of very different magnitudes converge together). A step that raises the cost is never taken:
λ grows by ``factor`` and the step is recomputed and re-simulated; after an accepted step λ
shrinks by ``factor``. Bounds (delays ≥ 0, optional sign priors) are respected by the step
itself: parameters at a bound whose step points outward are frozen for that step, and the step
is shortened so that no parameter crosses its bound.

Besides the observed change of det R, the run stops when the change that the Gauss-Newton
model predicts for the next (bounded, λ = 0) step is below the cost tolerance: with R fixed,
d ln det R = dQ/N for Q = Σ eᵀR⁻¹e, so the predicted relative change is −(2GᵀΔ + ΔᵀFΔ)/N.
This test uses the F and G that the next step needs anyway, so a converged run ends with F at
its final values without one more sensitivity evaluation. A shortened step along the
Gauss-Newton step never predicts a rise; a projected one can (it is then no descent step, and
the model says nothing about convergence), so a predicted rise beyond the tolerance does not
stop the run.
"""

from __future__ import annotations

from collections.abc import Callable

import attrs
import numpy as np
from rotorid.errors import EstimationError, SimulationDivergedError
from rotorid.estimation.models import gauss_newton_products
from rotorid.estimation.steps import bounded_step

_MAX_LAMBDA = 1e12
#: Simulated outputs beyond this multiple of the largest measured value count as divergence.
DIVERGENCE_FACTOR = 100.0
#: Floor of R relative to each output's mean square (keeps det R > 0 on noise-free data).
NOISE_FLOOR = 1e-16
#: An eigenvalue of R's correlation matrix below this fraction of the largest marks outputs
#: whose residuals are linearly dependent to working precision.
DEPENDENT_RESIDUALS = 1e-8


@attrs.frozen
class Settings:
    """Stopping rules and LM constants of one run."""

    max_iterations: int = 50
    cost_tolerance: float = 1e-7     # relative change of det R between accepted steps
    step_tolerance: float = 1e-9     # relative parameter change
    initial_lambda: float = 1e-3
    factor: float = 10.0
    noise: str = "full"              # "full" or "diagonal" R
    max_tries: int = 12              # λ increases per iteration before giving up
    shorten_steps: bool = True       # bounded_step's rule at the bounds (False: projection)


@attrs.frozen
class Progress:
    """Reported after every accepted iteration."""

    iteration: int
    cost: float
    rmse: float
    lm_lambda: float
    values: np.ndarray


@attrs.frozen(eq=False)
class RunResult:
    """Outcome of one run; ``information`` is F at the final values, ``residual_rms`` the
    root mean square of each output's unweighted residual there, (n_o,) in its unit."""

    values: np.ndarray
    cost: float
    rmse: float
    noise_covariance: np.ndarray
    information: np.ndarray
    cost_history: tuple
    rmse_history: tuple
    iterations: int
    converged: bool
    stop_reason: str
    residual_rms: np.ndarray


class Problem:
    """Residuals, cost and derivatives of one model on one maneuver set."""

    def __init__(self, model, maneuvers, measured, weights, settings: Settings,
                 rmse_scale=None):
        self.model = model
        self.maneuvers = maneuvers
        self.measured = measured
        self.weights = weights
        self.settings = settings
        # Per-output factors into the reference units that make the RMSE a pure number
        # (rotorid.units.rmse_reference_factors); ones leave it in the outputs' own units.
        self.rmse_scale = np.ones(len(weights)) if rmse_scale is None else rmse_scale
        self.n_samples = sum(z.shape[0] for z in measured)
        power = sum(np.sum((z * weights) ** 2, axis=0) for z in measured) / self.n_samples
        # R is floored at a tiny fraction of each output's power, so that an output reproduced
        # exactly (noise-free data, an unexcited channel) keeps det R and R⁻¹ finite.
        self.noise_floor = np.diag(np.maximum(NOISE_FLOOR * power, 1e-300))
        # Simulated outputs far beyond anything measured mean a diverging candidate even when
        # they stay finite: det R alone can prefer one exploding output if others shrink.
        self.output_limit = DIVERGENCE_FACTOR * np.maximum(
            np.max([np.max(np.abs(z), axis=0) for z in measured], axis=0), 1e-12)

    def noise(self, residuals) -> np.ndarray:
        """R of the weighted residuals (full or diagonal), floored."""
        r = sum(e.T @ e for e in residuals) / self.n_samples
        r = self.weights[:, None] * r * self.weights[None, :]
        r = np.diag(np.diag(r)) if self.settings.noise == "diagonal" else r
        return r + self.noise_floor

    def evaluate(self, values):
        """(cost, R, residuals z − y, rmse) at ``values``; cost = inf when the simulation
        diverges. The RMSE is that of the weighted residuals, each output scaled by its
        ``rmse_scale``."""
        try:
            outputs = self.model.simulate(values, self.maneuvers)
        except SimulationDivergedError:
            return np.inf, None, None, np.inf
        if any(np.any(np.abs(y) > self.output_limit) for y in outputs):
            return np.inf, None, None, np.inf
        with np.errstate(over="ignore", invalid="ignore"):
            residuals = [z - y for z, y in zip(self.measured, outputs)]
            r = self.noise(residuals)
        if not np.all(np.isfinite(r)):
            return np.inf, None, None, np.inf      # a model of one's own that blew up
        cost = float(np.linalg.det(r))
        if not cost > 0.0:
            return np.inf, None, None, np.inf
        stacked_rmse = float(np.sqrt(np.mean(np.diag(r - self.noise_floor)
                                             * self.rmse_scale**2)))
        return (cost if np.isfinite(cost) else np.inf), r, residuals, stacked_rmse

    def failure(self, values) -> str:
        """Why the cost at ``values`` is infinite: the maneuver and state or output that
        diverged and when, or the outputs that make R singular."""
        try:
            outputs = self.model.simulate(values, self.maneuvers)
        except SimulationDivergedError as error:
            return str(error)
        names = self.model.output_names
        for maneuver, y in zip(self.maneuvers, outputs):
            with np.errstate(invalid="ignore"):
                beyond = np.argwhere(~(np.abs(y) <= self.output_limit))
            if beyond.size:
                k, c = beyond[0]
                return (f"the simulated output {names[c]!r} of maneuver {maneuver.name} "
                        f"reaches {abs(y[k, c]):.3g} at t = {maneuver.time[k]:.3f} s, "
                        f"{DIVERGENCE_FACTOR:g} times beyond the largest measured")
        residuals = [z - y for z, y in zip(self.measured, outputs)]
        spread = np.diag(self.noise(residuals) - self.noise_floor)
        exact = [names[c] for c in np.flatnonzero(spread <= np.diag(self.noise_floor))]
        return (f"the noise covariance R is singular: the outputs {', '.join(exact) or 'all'} "
                f"are reproduced exactly (noise-free data?); {self._noise_fix()}")

    def _noise_fix(self) -> str:
        """What to do about a singular R, for this run's noise setting."""
        diagonal = "use --noise diagonal or " if self.settings.noise == "full" else ""
        return f"{diagonal}leave such outputs out with --outputs"

    def _dependent_outputs(self, r: np.ndarray, outputs) -> list[str]:
        """Those of ``outputs`` whose residuals R (their (n, n) block) finds linearly
        dependent: each with a share of at least 0.1 in a near-null eigenvector of R's
        correlation matrix."""
        scale = np.sqrt(np.diag(r))
        eigenvalues, vectors = np.linalg.eigh(r / np.outer(scale, scale))
        null = vectors[:, eigenvalues < DEPENDENT_RESIDUALS * eigenvalues.max()]
        return [outputs[k] for k in np.flatnonzero(np.any(np.abs(null) >= 0.1, axis=1))]

    def gauss_newton(self, values, r: np.ndarray, residuals):
        """F (P×P) and G (P,) at ``values`` with R held fixed; ``residuals`` z − y there.

        F = Σ (∂y/∂Θ)ᵀ Q (∂y/∂Θ) and G = −Σ (∂y/∂Θ)ᵀ Q (z − y) with Q = w R⁻¹ w, the inverse
        noise covariance of the weighted residuals seen from the unweighted ones. Raises
        :class:`EstimationError` naming the outputs when R is too near singular for Q to be
        positive definite (residuals linearly dependent: noise-free data).
        """
        weighted = np.flatnonzero(self.weights)
        names = [self.model.output_names[k] for k in weighted]
        dependent = self._dependent_outputs(r[np.ix_(weighted, weighted)], names)
        try:
            if dependent:       # decided by R's spectrum, not by how inv's round-off falls
                raise np.linalg.LinAlgError
            weighting = self.weights[:, None] * np.linalg.inv(r) * self.weights[None, :]
            np.linalg.cholesky(weighting[np.ix_(weighted, weighted)])
        except np.linalg.LinAlgError:
            raise EstimationError(
                f"the noise covariance R became singular to working precision: the residuals "
                f"of the outputs {', '.join(dependent) or 'fitted'} are linearly dependent, "
                f"the fit reproducing them almost exactly (noise-free data?); "
                f"{self._noise_fix()}") from None
        return gauss_newton_products(self.model, values, self.maneuvers, residuals, weighting)


def predicted_change(f, g, values, bounds, n_samples: int, shorten: bool = True) -> float:
    """Relative decrease of det R predicted by the Gauss-Newton model for the bounded full step
    (``shorten`` as :func:`~rotorid.estimation.steps.bounded_step`'s)."""
    step = bounded_step(f, g, 0.0, values, *bounds, shorten=shorten)
    return float(-(2.0 * g @ step + step @ f @ step) / n_samples)


def run(problem: Problem, start: np.ndarray, bounds, on_progress: Callable | None = None,
        final_information: bool = True, start_evaluation=None) -> RunResult:
    """Levenberg-Marquardt from ``start``; see the module docstring.

    ``problem`` is a :class:`Problem` or any object with its ``settings``, ``n_samples``,
    ``evaluate``, ``gauss_newton`` and ``failure`` (the filter-error likelihood is one).

    ``final_information=False`` skips the information matrix at the final values (the
    result's ``information`` is then the one at the last Gauss-Newton point): for a stage
    whose values only start the next one. ``start_evaluation`` is ``problem.evaluate(start)``
    when the caller has it already (``start`` within ``bounds``), so that the start is not
    simulated twice.
    """
    settings = problem.settings
    lower, upper = bounds
    values = np.clip(np.asarray(start, dtype=float), lower, upper)
    cost, r, residuals, current_rmse = (problem.evaluate(values) if start_evaluation is None
                                        else start_evaluation)
    if not np.isfinite(cost):
        raise SimulationDivergedError(
            f"the start values give no finite cost: {problem.failure(values)}; if the data "
            f"are sound, start closer to a stable model (the equation-error start or a "
            f"shorter horizon)")
    costs, rmses = [cost], [current_rmse]
    lam = settings.initial_lambda
    reason, converged, iteration = "iteration limit reached", False, 0
    f, g = problem.gauss_newton(values, r, residuals)
    current = True                       # f and g belong to the current values
    while iteration < settings.max_iterations:
        accepted = False
        for _ in range(settings.max_tries):
            step = bounded_step(f, g, lam, values, lower, upper, settings.shorten_steps)
            trial = np.clip(values + step, lower, upper)
            trial_cost, trial_r, trial_residuals, trial_rmse = problem.evaluate(trial)
            if trial_cost < cost:
                accepted = True
                break
            lam = min(lam * settings.factor, _MAX_LAMBDA)
        if not accepted:
            reason = "no step reduced the cost (local minimum or noise floor)"
            converged = iteration > 0
            break
        iteration += 1
        relative_change = (cost - trial_cost) / max(cost, 1e-300)
        relative_step = np.max(np.abs(trial - values) / np.maximum(np.abs(values), 1e-3))
        values, cost, r, current_rmse = trial, trial_cost, trial_r, trial_rmse
        residuals = trial_residuals
        current = False
        costs.append(cost)
        rmses.append(current_rmse)
        lam = max(lam / settings.factor, 1e-12)
        if on_progress is not None:
            on_progress(Progress(iteration, cost, current_rmse, lam, values.copy()))
        if relative_change < settings.cost_tolerance:
            reason, converged = "relative cost change below tolerance", True
            break
        if relative_step < settings.step_tolerance:
            reason, converged = "parameter step below tolerance", True
            break
        f, g = problem.gauss_newton(values, r, residuals)
        current = True
        predicted = predicted_change(f, g, values, bounds, problem.n_samples,
                                     settings.shorten_steps)
        if abs(predicted) < settings.cost_tolerance:
            reason, converged = "predicted cost change below tolerance", True
            break
    if final_information and not current:
        f, _ = problem.gauss_newton(values, r, residuals)
    residual_rms = np.sqrt(sum(np.sum(e**2, axis=0) for e in residuals) / problem.n_samples)
    return RunResult(values, cost, current_rmse, r, f, tuple(costs), tuple(rmses), iteration,
                     converged, reason, residual_rms)
