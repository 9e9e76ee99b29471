"""Tail rotor, fuselage, tailplane and fin loads in body axes (x forward, y right, z down).

All functions take batches: body velocity ``vel`` (B, 3) in m/s and body rates ``omega`` (B, 3)
in rad/s, and return forces (B, 3) in N and moments about the CG (B, 3) in N m.
"""

from __future__ import annotations

import numpy as np


def cross(a, b):
    """Row-wise cross product a × b of (B, 3) arrays (either may be a (3,) vector)."""
    a = np.asarray(a)
    b = np.asarray(b)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def point_velocity(vel, omega, position):
    """Velocity (B, 3) of the airframe point at ``position`` (3,) m: V + ω × r."""
    return vel + cross(omega, position)


def moment_about_cg(force, position):
    """Moment (B, 3) about the CG of ``force`` (B, 3) applied at ``position`` (3,)."""
    return cross(position, force)


def _polynomial(coefficients, x):
    c0, c1, c2, c3 = coefficients
    return c0 + x * (c1 + x * (c2 + x * c3))


def fuselage_loads(vel, config):
    """Padfield Bo-105 fuselage polynomials scaled with dynamic pressure, applied at the CG.

    α = atan2(w, u) and β = atan2(v, √(u² + w²)) are smoothly saturated at the fits' validity
    limit (A·tanh(angle/A)); the pitch and yaw moments carry the calibration factors of
    reference §2.0. Returns (force, moment), each (B, 3).
    """
    u, v, w = vel.T
    speed2 = u * u + v * v + w * w
    limit = config.fuselage_angle_limit
    alpha = limit * np.tanh(np.arctan2(w, u) / limit)
    beta = limit * np.tanh(np.arctan2(v, np.sqrt(u * u + w * w)) / limit)
    scale = speed2 / config.fuselage_reference_speed**2
    force = scale[:, None] * np.stack([
        _polynomial(config.fuselage_x, alpha),
        _polynomial(config.fuselage_y, beta),
        _polynomial(config.fuselage_z, alpha),
    ], axis=1)
    moment = scale[:, None] * np.stack([
        np.zeros_like(u),
        config.fuselage_pitch_scale * _polynomial(config.fuselage_m, alpha),
        config.fuselage_yaw_scale * _polynomial(config.fuselage_n, beta),
    ], axis=1)
    return force, moment


def _surface_coefficient(angle, slope, limit):
    """Linear lift coefficient slope·angle, smoothly capped at ±limit."""
    return limit * np.tanh(slope * angle / limit)


def tailplane_loads(vel, omega, config):
    """Two tailplane halves at (x, ±y, z); no main-rotor downwash (reference §2.0, K = 0).

    Lift ½ρV²(S/2)C_L normal to the local flow in the x–z plane, C_L = a(α + i) capped.
    """
    x, y, z = config.tailplane_position
    force_total = np.zeros_like(vel)
    moment_total = np.zeros_like(vel)
    for side in (y, -y):
        position = (x, side, z)
        local = point_velocity(vel, omega, position)
        u, w = local[:, 0], local[:, 2]
        alpha = np.arctan2(w, u)
        cl = _surface_coefficient(alpha + config.tailplane_incidence,
                                  config.tailplane_lift_slope, config.surface_lift_limit)
        # lift = ½ρ V² S C_L along (w, 0, −u)/V
        k = 0.5 * config.air_density * 0.5 * config.tailplane_area * cl * np.hypot(u, w)
        force = np.stack([k * w, np.zeros_like(u), -k * u], axis=1)
        force_total += force
        moment_total += moment_about_cg(force, position)
    return force_total, moment_total


def fin_loads(vel, omega, config):
    """Fin side force −½ρV²·S·C(β_fin − i_fin) normal to the local flow in the x–y plane.

    At zero sideslip the fin pushes the tail towards +y (reference §2.0).
    """
    local = point_velocity(vel, omega, config.fin_position)
    u, v = local[:, 0], local[:, 1]
    beta = np.arctan2(v, u)
    cy = _surface_coefficient(beta - config.fin_incidence, config.fin_lift_slope,
                              config.surface_lift_limit)
    # side force = ½ρ V² S C along (v, −u, 0)/V
    k = 0.5 * config.air_density * config.fin_area * cy * np.hypot(u, v)
    force = np.stack([k * v, -k * u, np.zeros_like(u)], axis=1)
    return force, moment_about_cg(force, config.fin_position)


def tail_rotor(vel, omega, theta0t, lambda0t, config):
    """Tail rotor with uniform inflow and zero twist (reference §2.4), thrust along +y.

    Args:
        theta0t: (B,) collective in rad; lambda0t: (B,) inflow ratio (state).
    Returns:
        force (B, 3), moment (B, 3), dλ0T/dt (B,) in 1/s (1-state momentum inflow with the
        apparent mass 8/(3π)), power (B,) in W.
    """
    tip = config.tail_omega * config.tail_radius
    local = point_velocity(vel, omega, config.tail_position)
    mu2 = (local[:, 0] ** 2 + local[:, 2] ** 2) / tip**2
    mu_z = -local[:, 1] / tip
    sigma_a = config.tail_solidity * config.tail_lift_slope
    ct = 0.5 * sigma_a * (theta0t * (1.0 / 3.0 + 0.5 * mu2) + 0.5 * (mu_z - lambda0t))
    mass_flow = np.sqrt(mu2 + (lambda0t - mu_z) ** 2)
    rate = config.tail_omega * (ct - 2.0 * mass_flow * lambda0t) * (3.0 * np.pi / 8.0)
    area_dyn = config.air_density * np.pi * config.tail_radius**2 * tip**2
    thrust = ct * area_dyn
    force = np.zeros_like(vel)
    force[:, 1] = thrust
    drag = config.profile_drag[0]
    power = thrust * (lambda0t - mu_z) * tip + (
        config.tail_solidity * drag / 8.0 * (1.0 + 4.6 * mu2) * area_dyn * tip)
    return force, moment_about_cg(force, config.tail_position), rate, power
