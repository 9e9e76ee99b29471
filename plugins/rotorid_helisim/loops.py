"""Low-gain stabilising loops that keep the helicopter near trim during a maneuver.

A digital controller running at the sample rate adds to each stick (in % of travel)::

    long = −Kθ·(Δθ − Δu·ω_v/g) − Kq·q        pitch attitude hold with a slow speed hold
    lat  = −Kφ·(Δφ + Δv·ω_v/g) − Kp·p        roll attitude hold with a slow side-speed hold
    coll = −Kh·Δḣ                             vertical-speed hold (ḣ up, earth axes)
    ped  = −Kψ·Δψ − Kr·r                      heading hold

The gains are designed per plant and trim from the quasi-steady rigid-body model (rotor,
inflow and actuator states residualised, truth-model.md §2.6): on each axis the on-axis rate
obeys ẋ = a·x + b·δ. An attitude loop is a PD law whose zero sits at ω_z = max(2ω_c, |a|) and
whose gain puts the broken-loop crossover at ω_c::

    L(s) = b·(Kq·s + Kθ) / (s·(s − a)),   Kθ = Kq·ω_z,   |L(jω_c)| = 1

so the rate feedback stays a fraction ω_c/|a| of the bare-airframe damping. The heave loop is
proportional with |L(jω_c)| = 1 on b/(s − a). The speed holds move the attitude reference with
bandwidth ω_v = :attr:`LoopDesign.velocity_bandwidth` (u̇ ≈ −g·Δθ, v̇ ≈ g·Δφ).

The excited axis keeps its loop but with the gentler crossover
:attr:`LoopDesign.excited_crossover` (well below 1 rad/s, truth-model.md §10); the other axes
use :attr:`LoopDesign.crossover`. The loops see the noise-free plant state (a navigation-grade
reference), so sensor noise stays a pure measurement effect and the flight is the same for
every noise draw.
"""

from __future__ import annotations

import math

import attrs
import numpy as np
from rotorid.errors import StructureError
from rotorid.units import G_SI

#: Body states the loops and the quasi-steady model use, in the plant's naming.
BODY = ("u", "v", "w", "p", "q", "r", "phi", "theta", "psi")
#: Feedback signals (SI: rad, rad/s, m/s), perturbations from trim.
FEEDBACK = ("theta", "q", "u", "phi", "p", "v", "psi", "r", "hdot")
AXES = ("long", "lat", "coll", "ped")


def _positive(instance, attribute, value):
    if not (math.isfinite(value) and value > 0):
        raise StructureError(f"LoopDesign: {attribute.name} must be a finite number > 0 rad/s, "
                             f"got {value!r}")


@attrs.frozen
class LoopDesign:
    """Loop bandwidths in rad/s.

    Attributes:
        crossover: crossover of the attitude, heading and vertical-speed loops on the axes not
            being excited.
        excited_crossover: crossover on the excited axis (gentle: well below 1 rad/s).
        velocity_bandwidth: bandwidth of the slow speed holds acting through the attitudes.
    """

    crossover: float = attrs.field(default=0.8, converter=float, validator=_positive)
    excited_crossover: float = attrs.field(default=0.5, converter=float, validator=_positive)
    velocity_bandwidth: float = attrs.field(default=0.12, converter=float, validator=_positive)


@attrs.frozen
class QuasiSteadyModel:
    """Rigid-body perturbation model about trim with the other states residualised.

    ``a`` (9, 9) over :data:`BODY` states, ``b`` (9, 4) per % of ``[long lat coll ped]``, SI.
    """

    a: np.ndarray
    b: np.ndarray

    def entry(self, row: str, column: str) -> float:
        return float(self.a[BODY.index(row), BODY.index(column)])

    def control(self, row: str, axis: str) -> float:
        return float(self.b[BODY.index(row), AXES.index(axis)])


def jacobians(plant, state, stick, step: float = 1e-6):
    """Central-difference Jacobians ``(A (n, n), B (n, 4))`` of ``plant.derivatives`` about
    (``state``, ``stick``), evaluated in one batched call. ``step`` is relative (≥ 1e-6 absolute).
    """
    state = np.asarray(state, dtype=float)
    stick = np.asarray(stick, dtype=float)
    n = state.size
    point = np.concatenate([state, stick])
    h = step * np.maximum(1.0, np.abs(point))
    shifts = np.diag(h)
    rows = np.concatenate([point + shifts, point - shifts])
    slopes = plant.derivatives(rows[:, :n], rows[:, n:])
    jac = (slopes[: n + 4] - slopes[n + 4:]) / (2 * h[:, None])
    return jac[:n].T, jac[n:].T


def quasi_steady_model(plant, state, stick) -> QuasiSteadyModel:
    """Residualise every non-body state: A_red = A_bb − A_br·A_rr⁻¹·A_rb, same for B."""
    names = tuple(plant.state_names)
    missing = [name for name in BODY if name not in names]
    if missing:
        raise StructureError(f"plant states lack {missing}; the loops need states named "
                             f"{', '.join(BODY)}")
    a, b = jacobians(plant, state, stick)
    body = [names.index(name) for name in BODY]
    rest = [i for i in range(len(names)) if i not in body]
    a_bb, b_b = a[np.ix_(body, body)], b[body]
    if rest:
        a_br, a_rr = a[np.ix_(body, rest)], a[np.ix_(rest, rest)]
        a_bb = a_bb - a_br @ np.linalg.solve(a_rr, a[np.ix_(rest, body)])
        b_b = b_b - a_br @ np.linalg.solve(a_rr, b[rest])
    return QuasiSteadyModel(a_bb, b_b)


def attitude_gains(a: float, b: float, crossover: float) -> tuple[float, float]:
    """PD gains ``(K_angle, K_rate)`` in % per rad and % per rad/s (module docstring law)."""
    if b == 0:
        raise StructureError("a control has no quasi-steady effect on its axis; cannot design "
                             "the stabilising loop (check the plant's control derivatives)")
    zero = max(2.0 * crossover, abs(a))
    k_rate = crossover * math.hypot(crossover, a) / math.hypot(crossover, zero)
    return k_rate * zero / b, k_rate / b


def heave_gain(a: float, b: float, crossover: float) -> float:
    """Proportional vertical-speed gain in % per m/s with |L(jω_c)| = 1 on b/(s − a)."""
    if b == 0:
        raise StructureError("the collective has no quasi-steady effect on the vertical speed")
    return math.hypot(crossover, a) / b


@attrs.frozen
class LoopGains:
    """Feedback gains ``matrix`` (4, 9): % of ``[long lat coll ped]`` per unit of
    :data:`FEEDBACK` (SI), applied as ``stick_loop = −matrix @ feedback``."""

    matrix: np.ndarray

    def as_dict(self) -> dict:
        """Non-zero gains by ``"<axis>/<signal>"`` (for metadata)."""
        return {f"{AXES[i]}/{FEEDBACK[j]}": float(self.matrix[i, j])
                for i, j in zip(*np.nonzero(self.matrix))}


def design_loops(model: QuasiSteadyModel, design: LoopDesign, excited: str | None,
                 theta0: float) -> LoopGains:
    """Gains for one maneuver: ``excited`` (an axis name or None) gets the gentle crossover.

    ``theta0`` is the trim pitch attitude in rad (it enters the vertical-speed effectiveness).
    """
    if excited is not None and excited not in AXES:
        raise StructureError(f"unknown axis {excited!r}; use one of {', '.join(AXES)}")

    def crossover(axis):
        return design.excited_crossover if axis == excited else design.crossover

    speed = design.velocity_bandwidth / G_SI
    matrix = np.zeros((4, len(FEEDBACK)))
    col = FEEDBACK.index
    for axis, rate, angle, velocity, sign in (("long", "q", "theta", "u", -1.0),
                                              ("lat", "p", "phi", "v", 1.0),
                                              ("ped", "r", "psi", None, 0.0)):
        k_angle, k_rate = attitude_gains(model.entry(rate, rate), model.control(rate, axis),
                                         crossover(axis))
        row = AXES.index(axis)
        matrix[row, col(angle)] = k_angle
        matrix[row, col(rate)] = k_rate
        if velocity:
            matrix[row, col(velocity)] = sign * speed * k_angle
    # ḣ ≈ u·sinΘ0 − w·cosΘ0 near trim (small Φ0): its effectiveness and damping.
    b_h = (math.sin(theta0) * model.control("u", "coll")
           - math.cos(theta0) * model.control("w", "coll"))
    matrix[AXES.index("coll"), col("hdot")] = heave_gain(model.entry("w", "w"), b_h,
                                                         crossover("coll"))
    return LoopGains(matrix)


def feedback(states: np.ndarray, trim_state: np.ndarray, state_names) -> np.ndarray:
    """Feedback signals (B, 9) in :data:`FEEDBACK` order from plant states (B, n), SI.

    ``trim_state`` is (n,) or one trim per row (B, n).
    """
    index = {name: state_names.index(name) for name in BODY}
    delta = states - trim_state

    def climb(x):
        u, v, w = (x[..., index[k]] for k in ("u", "v", "w"))
        theta, phi = x[..., index["theta"]], x[..., index["phi"]]
        return u * np.sin(theta) - np.cos(theta) * (v * np.sin(phi) + w * np.cos(phi))

    heading = (delta[:, index["psi"]] + math.pi) % (2 * math.pi) - math.pi
    columns = {name: delta[:, index[name]] for name in ("theta", "q", "u", "phi", "p", "v", "r")}
    columns["psi"] = heading
    columns["hdot"] = climb(states) - climb(trim_state)
    return np.stack([columns[name] for name in FEEDBACK], axis=1)
