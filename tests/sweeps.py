"""Shared test signals: Tischler's exponential sweep and first-order rate responses."""

from __future__ import annotations

import numpy as np
from scipy import signal

DT = 0.02


def log_sweep(duration=90.0, omega_min=0.3, omega_max=15.0, quiet=5.0, dt=DT):
    """Exponential sweep (C1 = 4, C2 = 0.0187) after two dwell cycles at omega_min, with
    quiet trim before and after; unit amplitude."""
    t = np.arange(0.0, duration, dt)
    k = 0.0187 * (np.exp(4.0 * t / duration) - 1.0)
    omega = np.concatenate([np.full(int(round(2 * 2 * np.pi / omega_min / dt)), omega_min),
                            omega_min + k * (omega_max - omega_min)])
    quiet_samples = np.zeros(int(round(quiet / dt)))
    return np.concatenate([quiet_samples, np.sin(np.cumsum(omega) * dt), quiet_samples])


def _discrete(numerator, denominator, dt):
    a, b, c, d = signal.tf2ss(numerator, denominator)
    return signal.cont2discrete((a, b, c, d), dt, method="zoh")[:4]


def respond(numerator, denominator, u, dt=DT, delay=0.0):
    """Samples of the response of num/den·e^{−delay·s} to u held by a zero-order hold
    (delay a multiple of dt)."""
    lag = int(round(delay / dt))
    assert abs(lag * dt - delay) < 1e-12
    shifted = np.concatenate([np.zeros(lag), u[:u.size - lag]])
    return signal.dlsim((*_discrete(numerator, denominator, dt), dt), shifted)[1][:, 0]


def analytic(numerator, denominator, omega, delay=0.0, dt=DT):
    """Exact frequency response of the sampled system :func:`respond` simulates:
    C (zI − A_d)⁻¹ B_d + D at z = e^{jωΔt}, times the delay e^{−jωτ}."""
    ad, bd, cd, dd = _discrete(numerator, denominator, dt)
    omega = np.asarray(omega, dtype=float)
    z = np.exp(1j * omega * dt)
    eye = np.eye(ad.shape[0])
    response = np.array([(cd @ np.linalg.solve(zk * eye - ad, bd) + dd)[0, 0] for zk in z])
    return response * np.exp(-1j * omega * delay)
