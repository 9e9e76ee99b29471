"""Main rotor: blade-element loads and multi-blade-coordinate flap forcing (CSER, e = 0).

Conventions (docs/truth-model.md, reference §2.0): hub axes x forward, y right, z down along
the shaft; rotor anticlockwise seen from above; azimuth ψ = 0 over the tail; blade span
direction (−cosψ, sinψ, 0); flap β = β0 + β1c·cosψ + β1s·sinψ (β1c > 0 tilts the disc forward,
β1s > 0 to the left); pitch θ = θ0 + θ_tw·r + θ1s·sinψ + θ1c·cosψ; inflow (positive down)
λ_i = λ0 + r·(λ1s·sinψ + λ1c·cosψ). Everything is non-dimensional: velocities over ΩR, rates
over Ω, r over R, ( )' = d/dψ. As in Padfield's formulation, the hub yaw rate does not change
the blade section speed (the flap equations carry no yaw-rate terms either).

Section aerodynamics are linear in incidence (lift ∝ θU_T² − U_P·U_T); the profile drag
c_d(α) = d0 + d1·α + d2·α² acts on U_T², i.e. d0·U_T² + d1·U_T·(αU_T) + d2·(αU_T)² with
α·U_T = θ·U_T − U_P. All integrands are then polynomials in r of degree
≤ 5 and trigonometric polynomials in ψ of degree ≤ 7, so the 3-point Gauss–Legendre rule in r and
the 12-point uniform azimuth mean below are *exact*: the results equal the closed-form
first-harmonic expressions, without per-blade loops.
"""

from __future__ import annotations

import attrs
import numpy as np

N_AZIMUTH = 12
_R_NODES, _R_WEIGHTS = np.polynomial.legendre.leggauss(3)
#: Gauss radii on [0, 1] and their weights (sum 1).
RADII = 0.5 * (_R_NODES + 1.0)
WEIGHTS = 0.5 * _R_WEIGHTS
AZIMUTHS = 2.0 * np.pi * np.arange(N_AZIMUTH) / N_AZIMUTH

_S = np.sin(AZIMUTHS)[None, :, None]
_C = np.cos(AZIMUTHS)[None, :, None]
_R = RADII[None, None, :]
_W = WEIGHTS[None, None, :]


@attrs.frozen(eq=False)
class RotorLoads:
    """Main-rotor loads for a batch of B rotor states (all arrays of shape (B,)).

    Attributes:
        force: (B, 3) hub force coefficients in hub axes, F / (ρπR²(ΩR)²).
        torque: C_Q = Q / (ρπR²(ΩR)²R), aerodynamic torque opposing the rotation.
        thrust: C_T, positive up along the shaft.
        roll_moment: C_1s = N_b·mean ∫ lift·r·sinψ dr / (ρπR²(ΩR)²R) (Pitt–Peters forcing).
        pitch_moment: C_1c, the same with cosψ.
        flap_forcing: (B, 3) aerodynamic flap forcing in MBC, non-dimensional
            (mean f, 2·mean f·cosψ, 2·mean f·sinψ) with f = (γ/2)∫ r·(θU_T² − U_P·U_T) dr.
    """

    force: np.ndarray
    torque: np.ndarray
    thrust: np.ndarray
    roll_moment: np.ndarray
    pitch_moment: np.ndarray
    flap_forcing: np.ndarray


def _mean(a):
    """Azimuth mean and radial integral of a (B, N_AZIMUTH, 3) array → (B,)."""
    return np.einsum("bij,j->b", a, WEIGHTS) / N_AZIMUTH


def rotor_loads(mu, rates, flap, flap_rate, inflow, pitch, *, solidity, lift_slope, twist,
                lock_number, profile_drag) -> RotorLoads:
    """Blade-element loads of the main rotor.

    Args:
        mu: (B, 3) hub velocity in hub axes over ΩR (μx, μy, μz; μz > 0 is air coming up).
        rates: (B, 3) hub angular rates in hub axes over Ω.
        flap: (B, 3) β0, β1c, β1s in rad.
        flap_rate: (B, 3) d/dψ of β0, β1c, β1s.
        inflow: (B, 3) λ0, λ1s, λ1c (positive down).
        pitch: (B, 3) θ0, θ1s, θ1c in rad.
        solidity, lift_slope, twist, lock_number: rotor data; profile_drag: (d0, d1, d2).
    """
    col = lambda a, i: a[:, i, None, None]  # noqa: E731 - (B,) column broadcast over (ψ, r)
    mux, muy, muz = col(mu, 0), col(mu, 1), col(mu, 2)
    pb, qb = col(rates, 0), col(rates, 1)
    beta = col(flap, 0) + col(flap, 1) * _C + col(flap, 2) * _S
    dbeta = (col(flap_rate, 0) + (col(flap_rate, 1) + col(flap, 2)) * _C
             + (col(flap_rate, 2) - col(flap, 1)) * _S)
    theta = col(pitch, 0) + twist * _R + col(pitch, 1) * _S + col(pitch, 2) * _C
    lam = col(inflow, 0) + _R * (col(inflow, 1) * _S + col(inflow, 2) * _C)

    ut = mux * _S + muy * _C + _R + _R * beta * (pb * _C - qb * _S)
    up = lam - muz + _R * (dbeta - pb * _S - qb * _C) + beta * (mux * _C - muy * _S)
    lift = theta * ut * ut - up * ut  # normal force per (½ρ(ΩR)²c·a0·R dr)

    half_sigma = 0.5 * solidity
    thrust = half_sigma * lift_slope * _mean(lift)
    # profile drag c_d(α)·U_T² with α·U_T = θ·U_T − U_P: polynomial, no division by U_T
    d0, d1, d2 = profile_drag
    incidence = theta * ut - up
    drag = d0 * ut * ut + d1 * ut * incidence + d2 * incidence * incidence
    inplane = drag + lift_slope * (theta * up * ut - up * up)  # opposes rotation

    normal = lift_slope * lift
    force = half_sigma * np.stack([
        _mean(normal * beta * _C - inplane * _S),
        _mean(-normal * beta * _S - inplane * _C),
        -_mean(normal),
    ], axis=1)
    torque = half_sigma * _mean(_R * inplane)
    roll_moment = half_sigma * lift_slope * _mean(_R * lift * _S)
    pitch_moment = half_sigma * lift_slope * _mean(_R * lift * _C)

    f = 0.5 * lock_number * np.einsum("bij,j->bi", _R * lift, WEIGHTS)  # (B, N_AZIMUTH)
    flap_forcing = np.stack([
        f.mean(axis=1),
        2.0 * (f * _C[:, :, 0]).mean(axis=1),
        2.0 * (f * _S[:, :, 0]).mean(axis=1),
    ], axis=1)
    return RotorLoads(force, torque, thrust, roll_moment, pitch_moment, flap_forcing)


def flap_accelerations(flap, flap_rate, forcing, rates, accelerations, flap_frequency_squared):
    """MBC flap accelerations d²/dψ² of (β0, β1c, β1s) for a centre-spring rotor.

    From the single-blade equation β'' + λβ²·β = f_aero + 2(p̄cosψ − q̄sinψ) + p̄'sinψ + q̄'cosψ
    averaged over azimuth (reference §2.2).

    Args:
        flap, flap_rate: (B, 3) β and dβ/dψ in MBC.
        forcing: (B, 3) aerodynamic forcing from :func:`rotor_loads`.
        rates: (B, 3) hub rates over Ω; accelerations: (B, 3) hub angular accelerations over Ω².
        flap_frequency_squared: λβ².
    Returns:
        (B, 3) β0'', β1c'', β1s''.
    """
    k = flap_frequency_squared
    b0, b1c, b1s = flap.T
    d1c, d1s = flap_rate[:, 1], flap_rate[:, 2]
    pb, qb = rates[:, 0], rates[:, 1]
    dp, dq = accelerations[:, 0], accelerations[:, 1]
    return np.stack([
        forcing[:, 0] - k * b0,
        forcing[:, 1] + 2.0 * pb + dq - k * b1c - 2.0 * d1s + b1c,
        forcing[:, 2] - 2.0 * qb + dp - k * b1s + 2.0 * d1c + b1s,
    ], axis=1)
