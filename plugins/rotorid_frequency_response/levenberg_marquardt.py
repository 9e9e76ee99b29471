"""Levenberg-Marquardt with geodesic acceleration on the residual vector of J = eᵀe.

Each iteration solves (F + λ·diag F) v = −G with the Gauss-Newton F = JᵀJ and G = Jᵀe of the
exact Jacobian J = ∂e/∂θ, within the bounds (:func:`rotorid.estimation.steps.bounded_step`:
parameters at a bound whose step points outward are frozen, the step is shortened at a bound).

The cost of a structure with many weakly determined parameters has long curved valleys in
which plain Levenberg-Marquardt creeps (hundreds of steps of 10⁻⁵ relative each). The step is
therefore corrected for the valley's curvature by the *geodesic acceleration* of Transtrum and
Sethna ("Improvements to the Levenberg-Marquardt algorithm for nonlinear least-squares
minimization", arXiv:1201.5885, 2012): the residuals' second directional derivative along v,

    e_vv ≈ (2/h)·[(e(θ + h·v) − e(θ))/h − J·v],   h = ``acceleration_step``,

gives the acceleration a from (F + λ·diag F) a = −Jᵀe_vv, and the trial step is v + a/2. The
trial is taken only when the correction is small, 2‖a‖ ≤ ``acceleration_ratio``·‖v‖ (norms
scaled by sqrt(diag F)), and J falls; otherwise λ grows by ``increase`` and the step is
recomputed. After an accepted step λ shrinks by ``decrease``. A trial that does not lower J
is never taken.
"""

from __future__ import annotations

from collections.abc import Callable

import attrs
import numpy as np
from rotorid.estimation.steps import bounded_step

from .cost import Mismatch, MismatchProblem

_MAX_LAMBDA = 1e12
_MIN_LAMBDA = 1e-12


@attrs.frozen
class Settings:
    """Stopping rules and LM constants of one run."""

    max_iterations: int = 500
    cost_tolerance: float = 1e-6     # relative change of J between accepted steps
    step_tolerance: float = 1e-10    # relative parameter change
    initial_lambda: float = 1e-3
    increase: float = 3.0            # λ factor after a rejected trial
    decrease: float = 2.0            # λ divisor after an accepted step
    acceleration_step: float = 0.1   # h of the second directional derivative
    acceleration_ratio: float = 0.75  # largest 2‖a‖/‖v‖ accepted
    max_tries: int = 30              # λ increases per iteration before giving up


@attrs.frozen(eq=False)
class RunResult:
    """Outcome of one run; ``mismatch`` holds residuals and Jacobian at the final values."""

    values: np.ndarray
    mismatch: Mismatch
    cost_history: tuple[float, ...]
    iterations: int
    converged: bool
    stop_reason: str


def _accelerated_step(problem: MismatchProblem, current: Mismatch, information, gradient,
                      values, lam, bounds, settings: Settings) -> np.ndarray | None:
    """The step v + a/2 at damping ``lam`` (P,), or None when the acceleration a is too
    large against the velocity v (the quadratic model is not trusted at this λ);
    ``information`` F = JᵀJ (P, P) and ``gradient`` G = Jᵀe (P,) are those of ``current``."""
    lower, upper = bounds
    jacobian = current.jacobian
    velocity = bounded_step(information, gradient, lam, values, lower, upper)
    h = settings.acceleration_step
    ahead = problem.evaluate(np.clip(values + h * velocity, lower, upper), jacobian=False)
    if not np.all(np.isfinite(ahead.residuals)):
        return None
    curvature = (2.0 / h) * ((ahead.residuals - current.residuals) / h - jacobian @ velocity)
    acceleration = bounded_step(information, jacobian.T @ curvature, lam, values, lower,
                                upper)
    scale = np.sqrt(np.diag(information))
    if 2.0 * np.linalg.norm(scale * acceleration) > (settings.acceleration_ratio
                                                     * np.linalg.norm(scale * velocity)):
        return None
    return velocity + 0.5 * acceleration


def run(problem: MismatchProblem, start: np.ndarray, bounds, settings: Settings,
        on_progress: Callable[[int, float, float], None] | None = None) -> RunResult:
    """Levenberg-Marquardt from ``start`` within ``bounds`` ((P,), (P,)); ``on_progress``
    is called with (iteration, J, λ) after every accepted step."""
    lower, upper = bounds
    values = np.clip(np.asarray(start, dtype=float), lower, upper)
    current = problem.evaluate(values)
    costs = [current.cost]
    lam = settings.initial_lambda
    reason, converged, iteration = "iteration limit reached", False, 0
    while iteration < settings.max_iterations:
        if current.cost == 0.0:
            reason, converged = "the model reproduces the responses exactly", True
            break
        information = current.jacobian.T @ current.jacobian
        gradient = current.jacobian.T @ current.residuals
        for _ in range(settings.max_tries):
            step = _accelerated_step(problem, current, information, gradient, values, lam,
                                     bounds, settings)
            if step is not None:
                trial_values = np.clip(values + step, lower, upper)
                trial = problem.evaluate(trial_values)
                if trial.cost < current.cost:
                    break
            lam = min(lam * settings.increase, _MAX_LAMBDA)
        else:
            reason = "no step reduced J (a minimum to working precision)"
            converged = iteration > 0
            break
        iteration += 1
        change = (current.cost - trial.cost) / current.cost
        moved = np.max(np.abs(trial_values - values) / np.maximum(np.abs(values), 1e-3))
        values, current = trial_values, trial
        costs.append(current.cost)
        lam = max(lam / settings.decrease, _MIN_LAMBDA)
        if on_progress is not None:
            on_progress(iteration, current.cost, lam)
        if change < settings.cost_tolerance:
            reason, converged = "relative change of J below tolerance", True
            break
        if moved < settings.step_tolerance:
            reason, converged = "parameter step below tolerance", True
            break
    return RunResult(values, current, tuple(costs), iteration, converged, reason)
