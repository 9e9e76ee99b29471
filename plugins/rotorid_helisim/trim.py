"""Trim of the truth model in steady straight flight.

A trim is a state with zero body, flap and inflow accelerations at zero body rates. Unknowns:
the four blade angles, θ, φ, the MBC flap angles and the inflow states; the body velocity
follows from the flight condition:

* ``airspeed_kt``: horizontal true airspeed (kt); ``climb_rate_mps``: vertical speed (m/s, up
  positive); ``sideslip_deg``: aerodynamic sideslip, v = V·sin β (V the total airspeed);
* the body velocity is the earth-axis velocity (V_h, 0, −climb) seen from the trimmed attitude,
  the heading relative to the track giving the sideslip (for level flight with zero sideslip:
  v = 0, w = u·tanθ/cosφ, reference §2.0). No wind: air and ground velocities agree.

The solver is a damped Newton iteration with a finite-difference Jacobian evaluated in one
batched model call, continued in airspeed from hover in steps of at most 20 kt.
"""

from __future__ import annotations

import math

import attrs
import numpy as np
from rotorid.errors import TrimError
from rotorid.units import KNOT

from .model import Bo105Model
from .parameters import BLADE_ANGLES, STICKS

_MAX_STEP_KT = 20.0
#: Highest airspeed a trim is attempted at, kt: well beyond the Bo-105's never-exceed speed
#: (about 145 kt), so that an absurd request is refused before any continuation step.
MAX_AIRSPEED_KT = 200.0
_TOLERANCE = 1e-10

#: The study's named flight conditions, airspeed in kt ("forward" is the 70 kt study point).
NAMED_CONDITIONS = {"hover": 0.0, "forward": 70.0}


def resolve_airspeed(condition: str | None, airspeed_kt: float | None) -> float:
    """Airspeed in kt from a named condition (``hover``, ``forward``) or an explicit value.

    Exactly one of the two must be given; raises TrimError otherwise.
    """
    if (condition is None) == (airspeed_kt is None):
        raise TrimError("give a flight condition: 'hover', 'forward' (70 kt) or "
                        "--airspeed-kt V, exactly one of them")
    if condition is not None:
        try:
            return NAMED_CONDITIONS[condition]
        except KeyError:
            raise TrimError(f"unknown flight condition {condition!r}; use "
                            f"{', '.join(NAMED_CONDITIONS)} or --airspeed-kt") from None
    return float(airspeed_kt)


@attrs.frozen(eq=False)
class Trim:
    """A trimmed flight condition of :class:`~.model.Bo105Model`.

    Attributes:
        airspeed_kt, climb_rate_mps, sideslip_deg: the requested flight condition.
        state: (n_states,) trimmed state vector, SI.
        state_names: names of ``state``.
        stick: (4,) stick positions [long, lat, coll, ped] in % of travel.
        blade_angles_deg: (4,) θ0, θ1s, θ1c, θ0T in deg.
        theta_deg, phi_deg: pitch and roll attitude in deg.
        power_kw: main plus tail rotor power in kW.
        iterations: Newton iterations used in the last continuation step.
    """

    airspeed_kt: float
    climb_rate_mps: float
    sideslip_deg: float
    state: np.ndarray
    state_names: tuple
    stick: np.ndarray
    blade_angles_deg: np.ndarray
    theta_deg: float
    phi_deg: float
    power_kw: float
    iterations: int

    def as_dict(self) -> dict:
        """JSON-ready summary (floats and lists)."""
        return {
            "airspeed_kt": self.airspeed_kt,
            "climb_rate_mps": self.climb_rate_mps,
            "sideslip_deg": self.sideslip_deg,
            "theta_deg": self.theta_deg,
            "phi_deg": self.phi_deg,
            "power_kw": self.power_kw,
            "stick_percent": dict(zip(STICKS, map(float, self.stick))),
            "blade_angles_deg": dict(zip(BLADE_ANGLES, map(float, self.blade_angles_deg))),
            "state": dict(zip(self.state_names, map(float, self.state))),
        }

    def report(self) -> str:
        """Human-readable multi-line summary."""
        b = self.blade_angles_deg
        s = self.stick
        return "\n".join([
            f"trim at {self.airspeed_kt:g} kt, climb {self.climb_rate_mps:g} m/s, "
            f"sideslip {self.sideslip_deg:g} deg",
            f"  attitude   theta {self.theta_deg:7.2f} deg   phi {self.phi_deg:7.2f} deg",
            f"  blades     theta0 {b[0]:6.2f}  theta1s {b[1]:6.2f}  theta1c {b[2]:6.2f}  "
            f"theta0T {b[3]:6.2f} deg",
            f"  stick      long {s[0]:6.1f}  lat {s[1]:6.1f}  coll {s[2]:6.1f}  ped {s[3]:6.1f} %",
            f"  power      {self.power_kw:.0f} kW",
        ])


def body_velocity(airspeed_kt, climb_rate_mps, sideslip_deg, theta, phi):
    """Body velocities (u, v, w) in m/s for the flight condition at attitude (theta, phi), rad.

    The earth-axis velocity (V_h, 0, −climb) is turned into body axes through (φ, θ, ψ), with
    the heading ψ relative to the track chosen so that v = V·sin β (the root nearer zero).
    In a purely vertical climb or descent (V_h = 0) ψ = 0 and the sideslip is undefined.
    Vectorised over theta and phi (same shape). Raises TrimError if no heading gives the
    requested sideslip.
    """
    horizontal = airspeed_kt * KNOT
    total = math.hypot(horizontal, climb_rate_mps)
    theta = np.asarray(theta, dtype=float)
    phi = np.asarray(phi, dtype=float)
    sth, cth, sph, cph = np.sin(theta), np.cos(theta), np.sin(phi), np.cos(phi)
    if horizontal > 0.0:
        # v = (sφ sθ cψ − cφ sψ)·V_h − sφ cθ·climb = V sin β  →  A cosψ + B sinψ = C
        a = sph * sth * horizontal
        b = -cph * horizontal
        c = total * math.sin(math.radians(sideslip_deg)) + sph * cth * climb_rate_mps
        ratio = c / np.hypot(a, b)
        if np.any(np.abs(ratio) > 1.0):
            raise TrimError(f"no heading gives {sideslip_deg:g} deg of sideslip at this "
                            f"attitude; reduce sideslip_deg")
        delta = np.arctan2(b, a)
        half = np.arccos(ratio)
        wrap = lambda angle: np.angle(np.exp(1j * angle))  # noqa: E731
        first, second = wrap(delta - half), wrap(delta + half)
        psi = np.where(np.abs(first) <= np.abs(second), first, second)
    else:
        psi = np.zeros_like(theta)
    sps, cps = np.sin(psi), np.cos(psi)
    vx, vz = horizontal, -climb_rate_mps
    u = cth * cps * vx - sth * vz
    v = (sph * sth * cps - cph * sps) * vx + sph * cth * vz
    w = (cph * sth * cps + sph * sps) * vx + cph * cth * vz
    return u, v, w


class _Problem:
    """Maps trim unknowns to states and residuals for one flight condition."""

    def __init__(self, model: Bo105Model, airspeed_kt, climb, sideslip):
        self.model = model
        self.condition = (airspeed_kt, climb, sideslip)
        i = model.index
        inflow_names = [n for n in model.state_names if n.startswith("lambda")]
        self.flap = [i["beta0"], i["beta1c"], i["beta1s"]]
        self.inflow = [i[n] for n in inflow_names]
        self.blades = [i[n] for n in ("theta0", "theta1s", "theta1c", "theta0T")]
        # residual rows: body accelerations, flap accelerations, inflow rates (scaled to O(1))
        rows = [i[n] for n in ("u", "v", "w", "p", "q", "r")]
        rows += [i[n] for n in ("beta0_dot", "beta1c_dot", "beta1s_dot")] + self.inflow
        self.rows = rows
        omega = model.config.omega
        self.scale = np.array([1.0] * 6 + [1.0 / omega**2] * 3 + [1.0 / omega] * len(self.inflow))
        self.n = 6 + 3 + len(self.inflow)

    def states(self, z):
        """z: (K, n) unknowns [θ0 θ1s θ1c θ0T θ φ β0 β1c β1s λ…] → states (K, n_states), stick."""
        model = self.model
        k = z.shape[0]
        x = np.zeros((k, model.n_states))
        theta, phi = z[:, 4], z[:, 5]
        u, v, w = body_velocity(*self.condition, theta, phi)
        i = model.index
        x[:, i["u"]], x[:, i["v"]], x[:, i["w"]] = u, v, w
        x[:, i["theta"]], x[:, i["phi"]] = theta, phi
        x[:, self.flap] = z[:, 6:9]
        x[:, self.inflow] = z[:, 9:]
        x[:, self.blades] = z[:, 0:4]
        stick = model.config.mixing.stick(z[:, 0:4])
        return x, stick

    def residual(self, z):
        x, stick = self.states(z)
        return self.model.derivatives(x, stick)[:, self.rows] * self.scale

    def solve(self, z0, max_iterations=40):
        z = np.array(z0, dtype=float)
        steps = np.full(self.n, 1e-7)
        for iteration in range(1, max_iterations + 1):
            batch = np.vstack([z, z + np.diag(steps)])
            res = self.residual(batch)
            f0 = res[0]
            jac = (res[1:] - f0).T / steps
            try:
                dz = -np.linalg.solve(jac, f0)
            except np.linalg.LinAlgError:
                return z, iteration, False
            norm0 = np.linalg.norm(f0)
            alpha = 1.0
            for _ in range(12):
                trial = z + alpha * dz
                if np.all(np.isfinite(trial)) and abs(trial[4]) < 1.2 and abs(trial[5]) < 1.2:
                    f1 = self.residual(trial[None, :])[0]
                    if np.all(np.isfinite(f1)) and np.linalg.norm(f1) < (1 - 1e-4 * alpha) * norm0:
                        break
                alpha *= 0.5
            else:
                return z, iteration, norm0 < 1e-9
            z = trial
            if np.max(np.abs(alpha * dz)) < _TOLERANCE:
                return z, iteration, True
        return z, max_iterations, np.linalg.norm(self.residual(z[None, :])[0]) < 1e-8


def _initial_guess(model: Bo105Model) -> np.ndarray:
    """Hover-like default guess [θ0 θ1s θ1c θ0T θ φ β0 β1c β1s λ…] (rad, non-dimensional)."""
    n_main = sum(1 for n in model.state_names if n.startswith("lambda")) - 1
    main_inflow = [0.05] + [0.0] * (n_main - 1)
    return np.array([0.25, 0.0, 0.0, 0.18, 0.04, -0.04, 0.04, 0.0, 0.0]
                    + main_inflow + [0.06])


def trim(model: Bo105Model, airspeed_kt: float, climb_rate_mps: float = 0.0,
         sideslip_deg: float = 0.0) -> Trim:
    """Trim ``model`` in straight flight.

    Args:
        airspeed_kt: horizontal true airspeed in kt (0 = hover), 0 ≤ V ≤ MAX_AIRSPEED_KT.
        climb_rate_mps: rate of climb in m/s (negative for descent).
        sideslip_deg: aerodynamic sideslip angle in deg (|β| < 90).
    Raises:
        TrimError: no trim exists (Newton fails, a control beyond ±100 % travel, or the power
            beyond the configured limit), naming the limiting quantity.
    """
    for name, value in (("airspeed_kt", airspeed_kt), ("climb_rate_mps", climb_rate_mps),
                        ("sideslip_deg", sideslip_deg)):
        if not math.isfinite(value):
            raise TrimError(f"trim: {name} must be finite, got {value!r}")
    if airspeed_kt < 0:
        raise TrimError(f"trim: airspeed_kt must be ≥ 0 (forward flight), got {airspeed_kt}")
    if airspeed_kt > MAX_AIRSPEED_KT:
        raise TrimError(f"trim: no trim beyond {MAX_AIRSPEED_KT:g} kt (the truth model's "
                        f"envelope), got airspeed_kt {airspeed_kt:g}; give a lower airspeed")
    if abs(sideslip_deg) >= 90:
        raise TrimError(f"trim: |sideslip_deg| must be below 90, got {sideslip_deg}")
    n_steps = max(1, math.ceil(airspeed_kt / _MAX_STEP_KT))
    z = _initial_guess(model)
    speeds = np.linspace(0.0, airspeed_kt, n_steps + 1) if airspeed_kt > 0 else [0.0]
    for speed in speeds:
        problem = _Problem(model, float(speed), climb_rate_mps, sideslip_deg)
        z, iterations, converged = problem.solve(z)
        if not converged:
            raise TrimError(
                f"no trim found at {speed:g} kt (climb {climb_rate_mps:g} m/s, sideslip "
                f"{sideslip_deg:g} deg): the Newton iteration did not converge; the condition "
                f"is probably outside the flight envelope")
    x, stick = problem.states(z[None, :])
    info = model.loads(x, stick)
    state, stick, blades = x[0], stick[0], np.degrees(z[0:4])
    for array in (state, stick, blades):
        array.setflags(write=False)
    power_kw = float(info["power"][0]) / 1000.0
    result = Trim(
        airspeed_kt=float(airspeed_kt), climb_rate_mps=float(climb_rate_mps),
        sideslip_deg=float(sideslip_deg), state=state, state_names=model.state_names,
        stick=stick, blade_angles_deg=blades, theta_deg=math.degrees(z[4]),
        phi_deg=math.degrees(z[5]), power_kw=power_kw, iterations=iterations)
    _check_limits(result, model)
    return result


def _check_limits(result: Trim, model: Bo105Model) -> None:
    over = [f"{name} {value:+.0f} %" for name, value in zip(STICKS, result.stick)
            if abs(value) > 100.0]
    condition = f"{result.airspeed_kt:g} kt, climb {result.climb_rate_mps:g} m/s"
    if over:
        raise TrimError(f"no trim within the control travel at {condition}: "
                        f"{', '.join(over)} (limit ±100 %)")
    if result.power_kw > model.config.power_limit_kw:
        raise TrimError(f"no trim within the power limit at {condition}: needs "
                        f"{result.power_kw:.0f} kW, limit {model.config.power_limit_kw:.0f} kW "
                        f"(Bo105Config.power_limit_kw)")
