"""Fixed-step explicit Runge-Kutta integration of nonlinear models over held, sampled inputs.

Between two samples t_n and t_n+1 = t_n + T the state advances in ``substeps`` steps of
h = T/substeps of an explicit Runge-Kutta scheme (nodes c, matrix a, weights b; classical RK4
by default). A stage at t_n + σ sees the input the data's hold implies:

* zero-order hold (``"zoh"``): u(t_n + σ) = u_n,
* first-order hold (``"foh"``): u(t_n + σ) = u_n + (σ/T)·(u_n+1 − u_n),

so RK4 under FOH evaluates u_n, (u_n + u_n+1)/2 and u_n+1, and under ZOH u_n in every stage.
Every function works on a batch of B independent rows (parameter vectors, maneuvers); arrays
are time-major: inputs (N, B, m), states (N, B, n). A row that leaves the finite numbers stays
non-finite (NaN or inf) to the end instead of raising: the caller decides what that means.
"""

from __future__ import annotations

from collections.abc import Callable

import attrs
import numpy as np

from rotorid.data import HOLDS
from rotorid.errors import StructureError


@attrs.frozen
class RungeKutta:
    """Butcher tableau of an explicit scheme: ``nodes`` c_i, lower-triangular ``matrix`` rows
    a_i (stage i uses the i earlier stages) and ``weights`` b_i."""

    name: str
    nodes: tuple[float, ...]
    matrix: tuple[tuple[float, ...], ...]
    weights: tuple[float, ...]


SCHEMES = {
    "euler": RungeKutta("euler", (0.0,), ((),), (1.0,)),
    "heun": RungeKutta("heun", (0.0, 1.0), ((), (1.0,)), (0.5, 0.5)),
    "rk4": RungeKutta("rk4", (0.0, 0.5, 0.5, 1.0), ((), (0.5,), (0.0, 0.5), (0.0, 0.0, 1.0)),
                      (1 / 6, 1 / 3, 1 / 3, 1 / 6)),
}


def _known_scheme(instance, attribute, value):
    if value not in SCHEMES:
        raise StructureError(f"unknown integration scheme {value!r}; use one of "
                             f"{', '.join(SCHEMES)}")


def _positive(instance, attribute, value):
    if value < 1:
        raise StructureError(f"substeps must be at least 1 per sample interval, got {value}")


@attrs.frozen
class Integration:
    """How a model is integrated: ``scheme`` (a :data:`SCHEMES` name) and ``substeps`` per
    sample interval (raise them for dynamics fast against the sample time)."""

    scheme: str = attrs.field(default="rk4", validator=_known_scheme)
    substeps: int = attrs.field(default=1, validator=_positive)

    @property
    def tableau(self) -> RungeKutta:
        return SCHEMES[self.scheme]


def _stage_inputs(inputs: np.ndarray, hold: str, integration: Integration):
    """Per sub-step, per stage: the held inputs of every interval, (N − 1, B, m)."""
    if hold not in HOLDS:
        raise StructureError(f"unknown input hold {hold!r}; use 'zoh' or 'foh'")
    start, change = inputs[:-1], inputs[1:] - inputs[:-1]
    cache = {}

    def at(fraction):
        if hold == "zoh" or fraction == 0.0:
            return start
        if fraction not in cache:
            cache[fraction] = start + fraction * change
        return cache[fraction]

    substeps = integration.substeps
    return [[at((j + c) / substeps) for c in integration.tableau.nodes] for j in range(substeps)]


def integrate(derivatives: Callable, t0, dt: float, x0, inputs, theta, hold: str = "zoh",
              integration: Integration = Integration()) -> np.ndarray:
    """States at every sample of B rows.

    Args:
        derivatives: ``f(t (B,), x (B, n), u (B, m), theta (B, p)) -> ẋ (B, n)``.
        t0: (B,) time of the first sample of each row, s.
        dt: sample time T, s (common to all rows).
        x0: (B, n) states at the first sample.
        inputs: (N, B, m) sampled inputs.
        theta: (B, p) parameters of each row.
    Returns:
        (N, B, n) states; x[0] = x0.
    """
    return _run(derivatives, None, t0, dt, x0, None, inputs, theta, None, hold, integration)[0]


def integrate_with_tangents(derivatives: Callable, jacobians: Callable, t0, dt: float, x0,
                            x0_tangent, inputs, theta, theta_tangent, hold: str = "zoh",
                            integration: Integration = Integration()):
    """States and their derivatives with respect to P parameters ψ, exact for the scheme.

    The tangents are the derivative of the discrete scheme itself (each stage differentiated
    with the model's Jacobians), so they equal the limit of finite differences of
    :func:`integrate`.

    Args:
        jacobians: ``(t, x, u, theta) -> (∂f/∂x (B, n, n), ∂f/∂θ (B, n, p))``.
        x0_tangent: (B, n, P) ∂x0/∂ψ.
        theta_tangent: (p, P) ∂θ/∂ψ (the same for every row).
        the others: as for :func:`integrate`.
    Returns:
        states (N, B, n) and tangents (N, B, n, P).
    """
    return _run(derivatives, jacobians, t0, dt, x0, x0_tangent, inputs, theta, theta_tangent,
                hold, integration)


def _run(derivatives, jacobians, t0, dt, x0, x0_tangent, inputs, theta, theta_tangent, hold,
         integration):
    inputs = np.asarray(inputs, dtype=float)
    x = np.array(x0, dtype=float)
    theta = np.asarray(theta, dtype=float)
    t0 = np.asarray(t0, dtype=float)
    n_samples = inputs.shape[0]
    states = np.empty((n_samples,) + x.shape)
    states[0] = x
    tangents = s = None
    if jacobians is not None:
        s = np.array(x0_tangent, dtype=float)
        tangents = np.empty((n_samples,) + s.shape)
        tangents[0] = s
    stage_inputs = _stage_inputs(inputs, hold, integration)
    rk = integration.tableau
    h = dt / integration.substeps
    with np.errstate(all="ignore"):
        for n in range(n_samples - 1):
            for j, inputs_of_stages in enumerate(stage_inputs):
                t = t0 + n * dt + j * h
                us = [u[n] for u in inputs_of_stages]
                if jacobians is None:
                    x = _step(derivatives, rk, t, h, x, us, theta)
                else:
                    x, s = _tangent_step(derivatives, jacobians, rk, t, h, x, s, us, theta,
                                         theta_tangent)
            states[n + 1] = x
            if tangents is not None:
                tangents[n + 1] = s
    return states, tangents


def _step(f, rk, t, h, x, us, theta):
    slopes = []
    for c, row, u in zip(rk.nodes, rk.matrix, us):
        stage = x
        for a, k in zip(row, slopes):
            if a:
                stage = stage + (h * a) * k
        slopes.append(np.asarray(f(t + c * h, stage, u, theta), dtype=float))
    return x + h * sum(b * k for b, k in zip(rk.weights, slopes))


def _tangent_step(f, jacobians, rk, t, h, x, s, us, theta, theta_tangent):
    slopes, slope_tangents = [], []
    for c, row, u in zip(rk.nodes, rk.matrix, us):
        stage, stage_tangent = x, s
        for a, k, dk in zip(row, slopes, slope_tangents):
            if a:
                stage = stage + (h * a) * k
                stage_tangent = stage_tangent + (h * a) * dk
        time = t + c * h
        slopes.append(np.asarray(f(time, stage, u, theta), dtype=float))
        f_x, f_theta = jacobians(time, stage, u, theta)
        slope_tangents.append(f_x @ stage_tangent + f_theta @ theta_tangent)
    return (x + h * sum(b * k for b, k in zip(rk.weights, slopes)),
            s + h * sum(b * dk for b, dk in zip(rk.weights, slope_tangents)))
