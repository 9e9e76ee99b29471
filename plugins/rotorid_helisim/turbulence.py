"""Dryden atmospheric turbulence: a frozen gust field convected past the helicopter.

Gusts are the air velocity (u_g, v_g, w_g) in m/s and the rotational gusts (p_g, q_g, r_g)
in rad/s, body axes, at the CG. The aerodynamics see the air-relative motion: the body
velocity minus the gust velocity and the body rates minus the rotational gusts, so every point
r of the airframe and rotor meets the gust velocity v_g + ω_g × r (:mod:`.model`).

The one-sided power spectral densities (MIL-F-8785C, Dryden form; ω in rad/s, σ² = ∫₀^∞ Φ dω)
at convection speed V::

    Φ_u = σ_u²·2L_u/(πV) / (1 + (L_u·ω/V)²)
    Φ_v = σ_v²·L_v/(πV)·(1 + 3(L_v·ω/V)²) / (1 + (L_v·ω/V)²)²       (Φ_w alike with L_w, σ_w)
    Φ_p = σ_w²·0.8·(πL_w/(4b))^(1/3) / (V·L_w) / (1 + (4bω/(πV))²)
    Φ_q = (ω/V)² / (1 + (4bω/(πV))²)·Φ_w      Φ_r = (ω/V)² / (1 + (3bω/(πV))²)·Φ_v

with b the span (here the rotor diameter). q_g = −∂w_g/∂x and r_g = ∂v_g/∂x follow from w_g
and v_g (the field ahead reaches the CG x/V later); p_g has its own white noise. The forming
filters of these spectra are stacked into one linear system, discretised exactly at the sample
time (covariance by Van Loan's method) and started in its stationary distribution; the gusts
are held constant between samples (like the stick).

Presets (MIL-F-8785C low altitude, h < 1000 ft; W20 = wind speed at 20 ft)::

    σ_w = 0.1·W20     σ_u = σ_v = σ_w / (0.177 + 0.000823·h)^0.4
    L_w = h           L_u = L_v = h / (0.177 + 0.000823·h)^1.2          (h and L in ft)

``"light"`` is W20 = 15 kt and ``"moderate"`` 30 kt, at h = :data:`PRESET_ALTITUDE_FT`. A
frozen field needs a convection speed; in hover the field drifts past at
:attr:`Turbulence.min_speed` (a light wind) instead of the zero airspeed.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Mapping

import attrs
import numpy as np
import scipy.linalg
from rotorid.errors import DataError
from rotorid.units import FOOT, KNOT

#: Wind speed at 20 ft per preset, kt (MIL-F-8785C: light 15, moderate 30, severe 45).
PRESET_W20_KT = {"light": 15.0, "moderate": 30.0}
#: Height above ground of the presets, ft.
PRESET_ALTITUDE_FT = 100.0
#: Components of a gust sample, in order.
COMPONENTS = ("u_g", "v_g", "w_g", "p_g", "q_g", "r_g")
#: Seed-sequence entry that keeps the gust draws apart from the sensor-noise draws.
_STREAM = 0x6775737


def _positive_triple(value) -> tuple[float, float, float]:
    triple = tuple(float(v) for v in value)
    if len(triple) != 3 or not all(math.isfinite(v) and v >= 0 for v in triple):
        raise DataError(f"turbulence: give three finite values ≥ 0 for (u, v, w), got {value!r}")
    return triple


def _positive(instance, attribute, value):
    if not (math.isfinite(value) and value > 0):
        raise DataError(f"turbulence: {attribute.name} must be a finite number > 0, "
                        f"got {value!r}")


@attrs.frozen
class Turbulence:
    """A Dryden gust field.

    Attributes:
        sigma: intensities (σ_u, σ_v, σ_w), m/s.
        scale: scale lengths (L_u, L_v, L_w), m, each > 0.
        span: b of the rotational gusts, m (default: the Bo-105 rotor diameter).
        min_speed: lowest convection speed of the frozen field, m/s (used in hover).
    """

    sigma: tuple = attrs.field(converter=_positive_triple)
    scale: tuple = attrs.field(converter=_positive_triple)
    span: float = attrs.field(default=9.82, converter=float, validator=_positive)
    min_speed: float = attrs.field(default=5.0, converter=float, validator=_positive)

    def __attrs_post_init__(self):
        if min(self.scale) <= 0:
            raise DataError(f"turbulence: scale lengths must be > 0 m, got {self.scale}")

    @classmethod
    def preset(cls, name: str, altitude_ft: float = PRESET_ALTITUDE_FT) -> "Turbulence":
        """MIL-F-8785C low-altitude intensities and scales (module docstring)."""
        if name not in PRESET_W20_KT:
            raise DataError(f"unknown turbulence preset {name!r}; use one of "
                            f"{', '.join(PRESET_W20_KT)}, 'still', or give sigma and scale")
        if not 0 < altitude_ft < 1000:
            raise DataError(f"the low-altitude presets hold for 0 < h < 1000 ft, got "
                            f"{altitude_ft!r}")
        sigma_w = 0.1 * PRESET_W20_KT[name] * KNOT
        factor = 0.177 + 0.000823 * altitude_ft
        sigma_uv = sigma_w / factor**0.4
        scale_uv = altitude_ft / factor**1.2 * FOOT
        return cls((sigma_uv, sigma_uv, sigma_w), (scale_uv, scale_uv, altitude_ft * FOOT))

    def speed(self, airspeed: float) -> float:
        """Convection speed V in m/s for a trim ``airspeed`` in m/s."""
        return max(float(airspeed), self.min_speed)

    def forming_filter(self, speed: float):
        """Continuous forming filter ``(A (8, 8), B (8, 4), C (6, 8))`` whose outputs, driven
        by four independent white noises of intensity π, have the Dryden spectra at ``speed``
        m/s. States: u_g; v_g (2); w_g (2); p_g; the lags of q_g and r_g."""
        (su, sv, sw), (lu, lv, lw), b, v = self.sigma, self.scale, self.span, speed
        a = np.zeros((8, 8))
        bm = np.zeros((8, 4))
        c = np.zeros((6, 8))
        # u: σ·√(2L/(πV)) / (1 + τs), τ = L/V
        a[0, 0], bm[0, 0], c[0, 0] = -v / lu, su * math.sqrt(2 * lu / (math.pi * v)) * v / lu, 1
        # v, w: σ·√(L/(πV))·(1 + √3·τs)/(1 + τs)²; states (x1, x2) with x1' = −x1/τ + k·n,
        # x2' = (x1 − x2)/τ, output k'·(x2 + √3·τ·x2') = x2·(1 − √3) + √3·x1 (scaled below)
        for row, out, sigma, length, noise in ((1, 1, sv, lv, 1), (3, 2, sw, lw, 2)):
            tau = length / v
            a[row, row] = a[row + 1, row + 1] = -1 / tau
            a[row + 1, row] = 1 / tau
            bm[row, noise] = sigma * math.sqrt(length / (math.pi * v)) / tau
            c[out, row], c[out, row + 1] = math.sqrt(3), 1 - math.sqrt(3)
        # p: own noise, first order with time constant 4b/(πV)
        tau_p = 4 * b / (math.pi * v)
        gain_p = sw * math.sqrt(0.8 / v) * (math.pi / (4 * b)) ** (1 / 6) / lw ** (1 / 3)
        a[5, 5], bm[5, 3], c[3, 5] = -1 / tau_p, gain_p / tau_p, 1
        # q = −(s/V)/(1 + τ_q·s)·w and r = +(s/V)/(1 + τ_r·s)·v: with the lag ξ = x/(1 + τs),
        # (s/(1 + τs))·x = (x − ξ)/τ
        for row, out, source, tau, sign in ((6, 4, 2, tau_p, -1), (7, 5, 1, 3 * b / (math.pi * v),
                                                                     1)):
            a[row, row] = -1 / tau
            a[row] += c[source] / tau
            c[out] = sign * (c[source] - np.eye(8)[row]) / (tau * v)
        return a, bm, c

    def psd(self, omega: np.ndarray, speed: float) -> np.ndarray:
        """Closed-form one-sided Dryden PSDs (len(ω), 6) at ω rad/s, in :data:`COMPONENTS`
        order ((m/s)²/(rad/s) and (rad/s)²/(rad/s))."""
        omega = np.asarray(omega, dtype=float)
        (su, sv, sw), (lu, lv, lw), b, v = self.sigma, self.scale, self.span, speed

        def lateral(sigma, length):
            x = (length * omega / v) ** 2
            return sigma**2 * length / (math.pi * v) * (1 + 3 * x) / (1 + x) ** 2

        phi_u = su**2 * 2 * lu / (math.pi * v) / (1 + (lu * omega / v) ** 2)
        phi_v, phi_w = lateral(sv, lv), lateral(sw, lw)
        phi_p = (sw**2 * 0.8 * (math.pi * lw / (4 * b)) ** (1 / 3) / (v * lw)
                 / (1 + (4 * b * omega / (math.pi * v)) ** 2))
        phi_q = (omega / v) ** 2 / (1 + (4 * b * omega / (math.pi * v)) ** 2) * phi_w
        phi_r = (omega / v) ** 2 / (1 + (3 * b * omega / (math.pi * v)) ** 2) * phi_v
        return np.stack([phi_u, phi_v, phi_w, phi_p, phi_q, phi_r], axis=-1)

    def gusts(self, n_samples: int, sample_time: float, airspeed: float,
              rng: np.random.Generator) -> np.ndarray:
        """Gust samples (n_samples, 6) in :data:`COMPONENTS` order at the sample instants,
        from the stationary distribution, for a trim ``airspeed`` in m/s."""
        a, b, c = self.forming_filter(self.speed(airspeed))
        transition, covariance = _discretise(a, b * math.sqrt(math.pi), sample_time)
        stationary = scipy.linalg.solve_discrete_lyapunov(transition, covariance)
        state = _square_root(stationary) @ rng.standard_normal(8)
        drive = rng.standard_normal((n_samples, 8)) @ _square_root(covariance).T
        states = np.empty((n_samples, 8))
        for k in range(n_samples):
            states[k] = state
            state = transition @ state + drive[k]
        return states @ c.T


def _discretise(a, b, dt):
    """Exact discrete transition e^{A·dt} and process covariance ∫₀^dt e^{Aσ}BBᵀe^{Aᵀσ}dσ
    (Van Loan)."""
    n = a.shape[0]
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n] = -a
    block[:n, n:] = b @ b.T
    block[n:, n:] = a.T
    exp = scipy.linalg.expm(block * dt)
    transition = exp[n:, n:].T
    covariance = transition @ exp[:n, n:]
    return transition, 0.5 * (covariance + covariance.T)


def _square_root(matrix):
    """Symmetric square root of a positive semi-definite matrix (tiny negative
    eigenvalues from rounding count as zero)."""
    values, vectors = np.linalg.eigh(matrix)
    return (vectors * np.sqrt(np.maximum(values, 0.0))) @ vectors.T


def turbulence_setting(value) -> Turbulence | None:
    """A data set's turbulence from ``None``/``"still"`` (still air), a preset name
    (``"light"``, ``"moderate"``), a :class:`Turbulence`, or a mapping of its fields
    (``sigma``, ``scale`` …, or ``preset`` with an optional ``altitude_ft``)."""
    if value is None or value == "still" or isinstance(value, Turbulence):
        return None if value == "still" else value
    if isinstance(value, str):
        return Turbulence.preset(value)
    if isinstance(value, Mapping):
        settings = dict(value)
        if "preset" in settings:
            preset = Turbulence.preset(settings.pop("preset"),
                                       settings.pop("altitude_ft", PRESET_ALTITUDE_FT))
            return attrs.evolve(preset, **settings)
        try:
            return Turbulence(**settings)
        except TypeError as error:
            raise DataError(f"turbulence settings {settings}: {error}; give sigma and scale "
                            f"(m/s, m), or a preset") from None
    raise DataError(f"turbulence must be 'still', 'light', 'moderate' or a table of settings, "
                    f"got {value!r}")


def gust_generator(seed: int, name: str) -> np.random.Generator:
    """The gust generator of maneuver ``name`` under data-set ``seed`` (a stream apart from
    the sensor noise of :func:`.sensors.noise_generator`)."""
    return np.random.default_rng(
        np.random.SeedSequence([int(seed), zlib.crc32(name.encode()), _STREAM]))
