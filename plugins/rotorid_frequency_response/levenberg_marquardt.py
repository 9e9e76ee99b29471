"""Levenberg-Marquardt on the residual vector of the mismatch cost J = eᵀe.

Each iteration solves (F + λ·diag F) Δ = −G with the Gauss-Newton F = JᵀJ and G = Jᵀe of the
exact Jacobian J = ∂e/∂θ, within the bounds (:func:`rotorid.estimation.steps.bounded_step`:
parameters at a bound whose step points outward are frozen, the step is shortened at a
bound). A trial that does not lower
J is never taken: λ grows by ``factor`` and the step is recomputed; after an accepted step λ
shrinks by ``factor``.
"""

from __future__ import annotations

from collections.abc import Callable

import attrs
import numpy as np
from rotorid.estimation.steps import bounded_step

from .cost import Mismatch, MismatchProblem

_MAX_LAMBDA = 1e12


@attrs.frozen
class Settings:
    """Stopping rules and LM constants of one run."""

    max_iterations: int = 200
    cost_tolerance: float = 1e-6     # relative change of J between accepted steps
    step_tolerance: float = 1e-10    # relative parameter change
    initial_lambda: float = 1e-3
    factor: float = 10.0
    max_tries: int = 12              # λ increases per iteration before giving up


@attrs.frozen(eq=False)
class RunResult:
    """Outcome of one run; ``mismatch`` holds residuals and Jacobian at the final values."""

    values: np.ndarray
    mismatch: Mismatch
    cost_history: tuple[float, ...]
    iterations: int
    converged: bool
    stop_reason: str


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
        for _ in range(settings.max_tries):
            jacobian = current.jacobian
            step = bounded_step(jacobian.T @ jacobian, jacobian.T @ current.residuals, lam,
                                values, lower, upper)
            trial_values = np.clip(values + step, lower, upper)
            trial = problem.evaluate(trial_values)
            if trial.cost < current.cost:
                break
            lam = min(lam * settings.factor, _MAX_LAMBDA)
        else:
            reason = "no step reduced J (a minimum to working precision)"
            converged = iteration > 0
            break
        iteration += 1
        change = (current.cost - trial.cost) / current.cost
        moved = np.max(np.abs(trial_values - values) / np.maximum(np.abs(values), 1e-3))
        values, current = trial_values, trial
        costs.append(current.cost)
        lam = max(lam / settings.factor, 1e-12)
        if on_progress is not None:
            on_progress(iteration, current.cost, lam)
        if change < settings.cost_tolerance:
            reason, converged = "relative change of J below tolerance", True
            break
        if moved < settings.step_tolerance:
            reason, converged = "parameter step below tolerance", True
            break
    return RunResult(values, current, tuple(costs), iteration, converged, reason)
