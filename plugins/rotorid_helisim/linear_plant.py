"""A linear stand-in plant: Padfield's Helisim Bo-105 hover model with actuator lags.

It offers the plant interface the flight harness flies (``state_names``, ``n_states``,
``derivatives(x, stick)``, ``measurements(x, stick)`` and a trim state and stick), so the
harness, loops and sensors can be tested against a model with a known linear solution.

* Rigid body: the hover A and B of truth-model.md §6 (Padfield 2007, pp. 287–291), states
  ``[u w q θ v p φ r]`` in SI, B per rad of blade angle ``[θ0 θ1s θ1c θ0T]``; plus heading,
  ψ̇ = (q·sinΦ0 + r·cosΦ0)/cosΘ0 linearised about trim.
* Actuators: a first-order lag of :data:`ACTUATOR_TIME_CONSTANT` s from each stick to its
  actuator state (in % of travel), within the 0.02–0.04 s of truth-model.md §1.
* Gearing: :data:`GEARING_DEG_PER_PERCENT` deg of blade angle per % of stick (the truth model's
  stick mixing, docs/truth-model.md), with the signs of the stick conventions: long forward →
  θ1s < 0 (nose down), lat right → θ1c < 0 (roll right), coll up → θ0 > 0, right pedal →
  θ0T < 0 (nose right).
* Trim: Θ0 = 2.2°, Φ0 = −2.6° (the attitudes the Helisim gravity terms imply, truth-model.md
  §2.0), zero body velocities, sticks at :data:`TRIM_STICK` %.
"""

from __future__ import annotations

import math

import attrs
import numpy as np
from rotorid.units import G_SI

#: Hover A, rows/columns [u w q θ v p φ r] (truth-model.md §6), SI.
HOVER_A = np.array([
    [-0.0211, 0.0113, 0.7086, -9.803, -0.017, 0.0183, 0.0, 0.0],
    [0.0091, -0.322, -0.0311, -0.3838, -0.0008, -0.0006, 0.4445, 0.0],
    [0.1045, -0.0151, -3.747, 0.0, 0.09, -0.0972, 0.0, 0.0],
    [0.0, 0.0, 0.999, 0.0, 0.0, 0.0, 0.0, 0.0453],
    [0.017, -0.001, 0.0182, 0.0168, -0.0405, -0.7365, 9.793, 0.1017],
    [0.3402, 0.0155, 0.3688, 0.0, -0.4114, -14.19, 0.0, 0.1277],
    [0.0, 0.0, -0.0017, 0.0, 0.0, 1.0, 0.0, 0.0392],
    [0.0607, 0.0088, 0.0656, 0.0, -0.0173, -2.43, 0.0, -0.3185],
])
#: Hover B, rows [u w q θ v p φ r], columns [θ0 θ1s θ1c θ0T] per rad (truth-model.md §6).
HOVER_B = np.array([
    [3.653, -8.477, 3.308, 0.0],
    [-92.96, -0.002, -0.0004, 0.0],
    [-5.681, 45.0, -17.56, 0.0],
    [0.0, 0.0, 0.0, 0.0],
    [-0.5527, -3.308, -8.477, 5.043],
    [4.993, -66.37, -170.1, 6.197],
    [0.0, 0.0, 0.0, 0.0],
    [19.73, -11.8, -30.24, -15.46],
])
HELISIM_ORDER = ("u", "w", "q", "theta", "v", "p", "phi", "r")
BODY_STATES = ("u", "v", "w", "p", "q", "r", "phi", "theta", "psi")
ACTUATOR_STATES = ("act_long", "act_lat", "act_coll", "act_ped")
ACTUATOR_TIME_CONSTANT = 0.03  #: s
#: deg of blade angle per % of stick travel, for [long lat coll ped].
GEARING_DEG_PER_PERCENT = (0.12, 0.08, 0.12, 0.14)
#: Blade angle [θ0 θ1s θ1c θ0T] per % of [long lat coll ped], signs per the stick conventions.
_GEAR_SIGNS = np.array([
    [0.0, 0.0, 1.0, 0.0],
    [-1.0, 0.0, 0.0, 0.0],
    [0.0, -1.0, 0.0, 0.0],
    [0.0, 0.0, 0.0, -1.0],
])
TRIM_STICK = (50.0, 50.0, 50.0, 50.0)  #: %
TRIM_THETA_DEG = 2.2
TRIM_PHI_DEG = -2.6


@attrs.frozen
class LinearTrim:
    """Trim of the stand-in: ``state`` (n_states,) SI and ``stick`` (4,) %."""

    state: np.ndarray
    stick: np.ndarray


class LinearHoverPlant:
    """The stand-in plant (see the module docstring); batched over rows of ``x``."""

    state_names = BODY_STATES + ACTUATOR_STATES
    n_states = len(state_names)

    def __init__(self):
        order = [self.state_names.index(name) for name in HELISIM_ORDER]
        n = self.n_states
        theta0, phi0 = math.radians(TRIM_THETA_DEG), math.radians(TRIM_PHI_DEG)
        gearing = np.radians(GEARING_DEG_PER_PERCENT) * _GEAR_SIGNS  # rad per %
        actuators = [self.state_names.index(name) for name in ACTUATOR_STATES]
        a = np.zeros((n, n))
        a[np.ix_(order, order)] = HOVER_A
        a[np.ix_(order, actuators)] = HOVER_B @ gearing
        psi = self.state_names.index("psi")
        a[psi, self.state_names.index("q")] = math.sin(phi0) / math.cos(theta0)
        a[psi, self.state_names.index("r")] = math.cos(phi0) / math.cos(theta0)
        a[actuators, actuators] = -1.0 / ACTUATOR_TIME_CONSTANT
        b = np.zeros((n, 4))
        b[actuators, range(4)] = 1.0 / ACTUATOR_TIME_CONSTANT
        self.a, self.b = a, b
        stick = np.array(TRIM_STICK)
        state = np.zeros(n)
        state[self.state_names.index("theta")] = theta0
        state[self.state_names.index("phi")] = phi0
        state[actuators] = stick
        self.trim = LinearTrim(state, stick)
        self._c, self._y0 = self._measurement_model(theta0, phi0)

    def _measurement_model(self, theta0, phi0):
        """Output matrix and trim outputs for y = [ax az q θ ay p φ r] (total, SI)."""
        g = G_SI
        names = self.state_names
        c = np.zeros((8, self.n_states))
        # Specific force = acceleration minus the linearised gravity terms.
        gravity = {
            "u": {"theta": -g * math.cos(theta0)},
            "w": {"theta": -g * math.sin(theta0) * math.cos(phi0),
                  "phi": -g * math.cos(theta0) * math.sin(phi0)},
            "v": {"theta": -g * math.sin(theta0) * math.sin(phi0),
                  "phi": g * math.cos(theta0) * math.cos(phi0)},
        }
        for row, force in ((0, "u"), (1, "w"), (4, "v")):
            c[row] = self.a[names.index(force)]
            for state, value in gravity[force].items():
                c[row, names.index(state)] -= value
        for row, name in ((2, "q"), (3, "theta"), (5, "p"), (6, "phi"), (7, "r")):
            c[row, names.index(name)] = 1.0
        y0 = np.array([g * math.sin(theta0), -g * math.cos(theta0) * math.cos(phi0), 0.0, theta0,
                       -g * math.cos(theta0) * math.sin(phi0), 0.0, phi0, 0.0])
        return c, y0

    def derivatives(self, x, stick) -> np.ndarray:
        """State derivative (B, n_states) for states ``x`` (B, n_states), sticks (B, 4) %."""
        return (x - self.trim.state) @ self.a.T + (stick - self.trim.stick) @ self.b.T

    def measurements(self, x, stick) -> np.ndarray:
        """Total outputs (B, 8) ``[ax az q θ ay p φ r]`` in SI (m/s², rad/s, rad)."""
        del stick  # the actuator lag removes any direct feed-through
        return self._y0 + (x - self.trim.state) @ self._c.T

    def linear_model(self):
        """``(A, B)`` of the perturbation dynamics, shapes (n, n) and (n, 4)."""
        return self.a.copy(), self.b.copy()
