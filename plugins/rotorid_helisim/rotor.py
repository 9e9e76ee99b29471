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

#: harmonic basis (1, cosψ, sinψ) on the azimuth grid, (3, N_AZIMUTH)
_BASIS = np.stack([np.ones(N_AZIMUTH), np.cos(AZIMUTHS), np.sin(AZIMUTHS)])
#: projection of a (…, N_AZIMUTH) array on (mean, mean·cosψ, mean·sinψ)
_PROJECT = _BASIS.T / N_AZIMUTH
#: β' = Σ(dβ_k/dψ)·basis_k + (β1s·cosψ − β1c·sinψ): the second part is flap @ _TURN @ basis
_TURN = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
_R = RADII[None, None, :]


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
    harmonic = _BASIS[1:]  # (cosψ, sinψ)
    mux, muy = mu[:, 0:1], mu[:, 1:2]
    pb, qb = rates[:, 0:1], rates[:, 1:2]
    # azimuth functions, (B, N_AZIMUTH)
    beta = flap @ _BASIS
    dbeta = (flap_rate + flap @ _TURN) @ _BASIS
    theta_az = pitch[:, [0, 2, 1]] @ _BASIS
    lam_harm = inflow[:, [2, 1]] @ harmonic
    ut_az = np.hstack([muy, mux]) @ harmonic  # μx·sinψ + μy·cosψ
    rate_az = np.hstack([qb, pb]) @ harmonic  # p̄·sinψ + q̄·cosψ
    tilt = np.hstack([pb, -qb]) @ harmonic  # p̄·cosψ − q̄·sinψ
    skew = np.hstack([mux, -muy]) @ harmonic  # μx·cosψ − μy·sinψ
    # section quantities on the (B, N_AZIMUTH, radius) grid
    ut = ut_az[:, :, None] + _R * (1.0 + beta * tilt)[:, :, None]
    up = ((inflow[:, 0] - mu[:, 2])[:, None, None]
          + _R * (lam_harm + dbeta - rate_az)[:, :, None] + (beta * skew)[:, :, None])
    theta = theta_az[:, :, None] + twist * _R
    lift = theta * ut * ut - up * ut  # normal force per (½ρ(ΩR)²c·a0·R dr)
    # profile drag c_d(α)·U_T² with α·U_T = θ·U_T − U_P: polynomial, no division by U_T
    d0, d1, d2 = profile_drag
    incidence = theta * ut - up
    inplane = (d0 * ut * ut + d1 * ut * incidence + d2 * incidence * incidence
               + lift_slope * (theta * up * ut - up * up))  # opposes the rotation

    # radial integrals (lift, r·lift, in-plane, r·in-plane), then azimuth harmonics
    radial = np.stack([lift, _R * lift, inplane, _R * inplane]) @ WEIGHTS  # (4, B, N)
    harm = radial @ _PROJECT  # (4, B, 3): mean, mean·cosψ, mean·sinψ
    tilt_lift = (radial[0] * beta) @ _PROJECT

    half_sigma = 0.5 * solidity
    thrust = half_sigma * lift_slope * harm[0, :, 0]
    force = np.empty(np.shape(mu))
    force[:, 0] = half_sigma * (lift_slope * tilt_lift[:, 1] - harm[2, :, 2])
    force[:, 1] = half_sigma * (-lift_slope * tilt_lift[:, 2] - harm[2, :, 1])
    force[:, 2] = -thrust
    torque = half_sigma * harm[3, :, 0]
    roll_moment = half_sigma * lift_slope * harm[1, :, 2]
    pitch_moment = half_sigma * lift_slope * harm[1, :, 1]
    flap_forcing = (0.5 * lock_number) * harm[1] * np.array([1.0, 2.0, 2.0])
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
    out = np.empty(np.shape(flap))
    out[:, 0] = forcing[:, 0] - k * b0
    out[:, 1] = forcing[:, 1] + 2.0 * pb + dq - k * b1c - 2.0 * d1s + b1c
    out[:, 2] = forcing[:, 2] - 2.0 * qb + dp - k * b1s + 2.0 * d1c + b1s
    return out
