"""Main-rotor inflow models (non-dimensional, positive down through the disc, hub axes).

* Baseline (reference §1): dynamic uniform inflow (8/3π)·λ0' + 2V_T·λ0 = C_T, with the
  quasi-steady Coleman fore-aft gradient λ1c_w = λ0·tan(χ/2) in wind axes (K = 1), λ1s_w = 0,
  and no moment forcing.
* Pitt–Peters (reference §2.3): three states λ0, λ1s, λ1c, M·λ' + V·L⁻¹·λ = [C_T, C_1s, C_1c].

The wind axes are turned from the hub axes by the hub sideslip δ = atan2(μy, μx). Writing
X = tan(χ/2) = μ / (V_T + |λ_tot|) with χ = atan(μ/|λ_tot|), the products X·cosδ = μx/(V_T + |λ_tot|)
and X·sinδ = μy/(V_T + |λ_tot|) are smooth through hover, so the rotation is done on them.
"""

from __future__ import annotations

import numpy as np

#: Apparent-mass coefficient of the uniform inflow, 8/(3π).
UNIFORM_MASS = 8.0 / (3.0 * np.pi)
#: Apparent-mass coefficient of the harmonic inflow, 16/(45π).
HARMONIC_MASS = 16.0 / (45.0 * np.pi)
_SKEW = 15.0 * np.pi / 64.0


def _skew_components(lambda0, mu):
    """(V_T, λ_tot, X·cosδ, X·sinδ), each (B,), for hub velocity mu (B, 3) over ΩR."""
    lam_tot = lambda0 - mu[:, 2]
    mu2 = mu[:, 0] ** 2 + mu[:, 1] ** 2
    vt = np.sqrt(mu2 + lam_tot**2)
    denom = vt + np.abs(lam_tot)
    return vt, lam_tot, mu[:, 0] / denom, mu[:, 1] / denom


def baseline_harmonics(lambda0, mu):
    """Quasi-steady (λ1s, λ1c) of the baseline model, each (B,), from λ0 (B,) and mu (B, 3).

    λ1c_w = λ0·tan(χ/2) along the wind; in hub axes λ1c = λ0·X·cosδ, λ1s = −λ0·X·sinδ
    (the downstream edge of the disc lies at ψ = −δ).
    """
    _, _, xc, xs = _skew_components(lambda0, mu)
    return -lambda0 * xs, lambda0 * xc


def uniform_inflow_rate(lambda0, mu, thrust):
    """dλ0/dψ of the uniform inflow: (C_T − 2V_T·λ0)·3π/8, shape (B,)."""
    vt, _, _, _ = _skew_components(lambda0, mu)
    return (thrust - 2.0 * vt * lambda0) / UNIFORM_MASS


def pitt_peters_rate(inflow, mu, forcing):
    """dλ/dψ of the three-state Pitt–Peters model, shape (B, 3).

    Args:
        inflow: (B, 3) λ0, λ1s, λ1c in hub axes (ψ = 0 aft).
        mu: (B, 3) hub velocity over ΩR.
        forcing: (B, 3) C_T, C_1s, C_1c (C_1s, C_1c: lift-moment coefficients, = −C_L, −C_M).
    """
    lambda0 = inflow[:, 0]
    vt, lam_tot, xc, xs = _skew_components(lambda0, mu)
    vm = (mu[:, 0] ** 2 + mu[:, 1] ** 2 + lam_tot * (lam_tot + lambda0)) / vt
    gain = np.empty((inflow.shape[0], 3, 3))
    # L in hub axes (order λ0, λ1s, λ1c): the wind-axis matrix of reference §2.3 turned by δ.
    gain[:, 0, 0] = 0.5
    gain[:, 0, 1] = _SKEW * xs
    gain[:, 0, 2] = -_SKEW * xc
    gain[:, 1, 0] = -_SKEW * xs
    gain[:, 1, 1] = 2.0 + 2.0 * (xc**2 - xs**2)
    gain[:, 1, 2] = 4.0 * xc * xs
    gain[:, 2, 0] = _SKEW * xc
    gain[:, 2, 1] = 4.0 * xc * xs
    gain[:, 2, 2] = 2.0 + 2.0 * (xs**2 - xc**2)
    flow = np.linalg.solve(gain, inflow[:, :, None])[:, :, 0]
    flow *= np.stack([vt, vm, vm], axis=1)
    mass = np.array([UNIFORM_MASS, HARMONIC_MASS, HARMONIC_MASS])
    return (forcing - flow) / mass
