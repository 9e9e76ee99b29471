"""Tail rotor, fuselage, tailplane and fin loads in body axes (x forward, y right, z down).

All functions take batches: body velocity ``vel`` (B, 3) in m/s and body rates ``omega`` (B, 3)
in rad/s, and return forces (B, 3) in N and moments about the CG (B, 3) in N m.
"""

from __future__ import annotations

import numpy as np


def cross(a, b):
    """Row-wise cross product a × b of two (B, 3) arrays."""
    out = np.empty(np.broadcast_shapes(np.shape(a), np.shape(b)))
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def skew(position):
    """(3, 3) matrix K with K·a = position × a."""
    x, y, z = position
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def point_velocity(vel, omega, position):
    """Velocity (B, 3) of the airframe point at ``position`` (3,) m: V + ω × r = V − r × ω."""
    return vel - omega @ skew(position).T


def moment_about_cg(force, position):
    """Moment (B, 3) about the CG of ``force`` (B, 3) applied at ``position`` (3,)."""
    return force @ skew(position).T


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
    force = np.empty_like(vel)
    force[:, 0] = scale * _polynomial(config.fuselage_x, alpha)
    force[:, 1] = scale * _polynomial(config.fuselage_y, beta)
    force[:, 2] = scale * _polynomial(config.fuselage_z, alpha)
    moment = np.zeros_like(vel)
    moment[:, 1] = scale * config.fuselage_pitch_scale * _polynomial(config.fuselage_m, alpha)
    moment[:, 2] = scale * config.fuselage_yaw_scale * _polynomial(config.fuselage_n, beta)
    return force, moment


def _surface_coefficient(angle, slope, limit):
    """Linear lift coefficient slope·angle, smoothly capped at ±limit."""
    return limit * np.tanh(slope * angle / limit)


def tailplane_loads(vel, omega, config):
    """Two tailplane halves at (x, ±y, z); no main-rotor downwash (reference §2.0, K = 0).

    Lift ½ρV²(S/2)C_L normal to the local flow in the x–z plane, C_L = a(α + i) capped.
    """
    x, y, z = config.tailplane_position
    sides = np.array([[x, y, z], [x, -y, z]])
    # local velocities of both halves, (2, B, 3)
    local = vel[None] - np.einsum("bj,kij->kbi", omega, np.stack([skew(r) for r in sides]))
    u, w = local[..., 0], local[..., 2]
    cl = _surface_coefficient(np.arctan2(w, u) + config.tailplane_incidence,
                              config.tailplane_lift_slope, config.surface_lift_limit)
    # lift = ½ρ V² S C_L along (w, 0, −u)/V
    k = 0.5 * config.air_density * 0.5 * config.tailplane_area * cl * np.hypot(u, w)
    force = np.zeros_like(local)
    force[..., 0] = k * w
    force[..., 2] = -k * u
    moment = moment_about_cg(force[0], sides[0]) + moment_about_cg(force[1], sides[1])
    return force[0] + force[1], moment


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
    force = np.zeros_like(vel)
    force[:, 0] = k * v
    force[:, 1] = -k * u
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
