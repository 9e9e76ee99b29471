"""The steady-state Kalman filter of a batch of discrete systems, complex-step safe.

For x_n+1 = Φ x_n + w_n, y_n = H x_n + v_n with cov w = Q and cov v = R (diagonal), the a
priori state covariance P solves the discrete algebraic Riccati equation

    P = Φ P Φᵀ − Φ P Hᵀ (H P Hᵀ + R)⁻¹ H P Φᵀ + Q,

the innovations have the covariance B = H P Hᵀ + R and the filter gain is K = P Hᵀ B⁻¹.
P comes from the structured doubling algorithm (Chu, Fan & Lin), which needs only products and
inverses: it runs on complex parameter directions, so the derivatives of P, B and K follow by
the complex step, and it converges quadratically also when Φ is unstable (a stabilising
solution exists when (Φ, Q) is stabilisable and (H, Φ) detectable).
"""

from __future__ import annotations

import attrs
import numpy as np
from rotorid.errors import EstimationError

#: Doubling steps allowed; each squares the closed-loop contraction.
MAX_DOUBLINGS = 60
#: Relative change of P (real and imaginary parts) at which the doubling stops.
TOLERANCE = 1e-13


@attrs.frozen(eq=False)
class SteadyStateFilter:
    """Per direction (leading axis D): ``covariance`` P (D, S, S), ``innovation`` B
    (D, n_o, n_o) and ``gain`` K (D, S, n_o)."""

    covariance: np.ndarray
    innovation: np.ndarray
    gain: np.ndarray


def _t(a):
    return np.swapaxes(a, -1, -2)


def _relative_change(new, old) -> float:
    change = 0.0
    for part in (np.real, np.imag):
        scale = np.max(np.abs(part(new)), initial=0.0)
        if scale > 0:
            change = max(change, np.max(np.abs(part(new) - part(old))) / scale)
    return change


def steady_state_filter(transition, output, process, measurement) -> SteadyStateFilter:
    """The steady-state filter of Φ (D, S, S), H (D, n_o, S), Q (D, S, S) and the diagonal of
    R (D, n_o) (all > 0); real or complex.

    Raises:
        EstimationError: the doubling does not converge (no stabilising solution).
    """
    a = _t(transition)
    g = _t(output) @ (output / measurement[..., :, None])        # Hᵀ R⁻¹ H
    h = process
    identity = np.eye(a.shape[-1])
    for _ in range(MAX_DOUBLINGS):
        w = np.linalg.inv(identity + g @ h)
        aw = a @ w
        h_next = h + _t(a) @ h @ w @ a
        g = g + aw @ g @ _t(a)
        a = aw @ a
        converged = _relative_change(h_next, h) < TOLERANCE
        h = h_next
        if converged:
            break
    else:
        raise EstimationError(
            "the Kalman filter's Riccati equation did not converge: the model has a mode that "
            "neither the process noise excites nor the outputs observe; add process noise on "
            "that mode's states or start from other values")
    covariance = 0.5 * (h + _t(h))
    innovation = output @ covariance @ _t(output) + measurement[..., :, None] * np.eye(
        output.shape[-2])
    gain = covariance @ _t(output) @ np.linalg.inv(innovation)
    return SteadyStateFilter(covariance, innovation, gain)
