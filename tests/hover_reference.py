"""A Bo-105-like hover model and closed-loop identification data for estimator tests.

The A and B matrices are Padfield's Helisim Bo-105 hover model (Padfield, *Helicopter Flight
Dynamics*, 2nd ed., 2007, pp. 287-291; SI units, per rad of blade angle; states
u w q θ v p φ r; controls θ0 θ1s θ1c θ0T), held once in ``rotorid_helisim.linear_plant``. The trim attitudes Θ0 = 2.245°, Φ0 = −2.6° are the
ones its gravity and kinematic terms imply. Stick mixing for the tests: 1 % of travel = 0.1° of
blade angle, long → −θ1s (stick forward, nose down), lat → −θ1c (stick right, roll right),
coll → θ0, ped → −θ0T (right pedal, nose right).
"""

from __future__ import annotations

import math

import numpy as np
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.simulation.discretisation import discrete_maps
from rotorid.simulation.simulator import simulate
from rotorid.units import FLIGHT_TEST, convert_state_space
from rotorid_helisim.linear_plant import HOVER_A as A_SI
from rotorid_helisim.linear_plant import HOVER_B as B_SI_BLADE

#: blade angle (rad) per % stick, columns long lat coll ped
MIXING = math.radians(0.1) * np.array([[0, 0, 1, 0], [-1, 0, 0, 0], [0, -1, 0, 0], [0, 0, 0, -1]],
                                      dtype=float)
CONDITION = FlightCondition(theta0=math.radians(2.245), phi0=math.radians(-2.6))
DELAYS = {"tau_L_lat": 0.07, "tau_M_long": 0.06}
#: white-noise standard deviations per output (ft/s², deg/s, deg), ax az q θ ay p φ r
NOISE = np.array([0.1, 0.1, 0.1, 0.05, 0.1, 0.1, 0.05, 0.1])


def true_structure() -> tuple[ModelStructure, np.ndarray]:
    """The 60-derivative structure with delays on L_lat and M_long, and its true values."""
    structure = ModelStructure.six_dof(CONDITION).with_delays(["L_lat", "M_long"])
    a, b = convert_state_space(A_SI, B_SI_BLADE @ MIXING, structure.states, structure.controls,
                               FLIGHT_TEST)
    derivative_a = a - structure.known_state_matrix()
    values = {}
    for d in structure.derivatives:
        row = structure.states.index(structure.equation_of(d))
        if structure.is_control(d):
            values[d.name] = b[row, structure.controls.index(d.variable)]
        else:
            values[d.name] = derivative_a[row, structure.states.index(d.variable)]
    values.update(DELAYS)
    return structure, structure.as_vector(values)


def multistep(kind: str, direction: int, n: int, dt: float, amplitude: float, width: float):
    """A 3211 or 2311 of ``amplitude`` and unit ``width`` (s) starting at 1 s, (n,) at ``dt``."""
    pattern = {"3211": (3, -2, 1, -1), "2311": (2, -3, 1, -1)}[kind]
    signal = np.zeros(n)
    start = int(round(1.0 / dt))
    for units in pattern:
        length = int(round(abs(units) * width / dt))
        signal[start:start + length] = direction * amplitude * np.sign(units)
        start += length
    return signal


def closed_loop_maneuvers(structure, values, seed: int = 0, duration: float = 15.0,
                          dt: float = 0.02, noise_scale: float = 1.0) -> ManeuverSet:
    """16 maneuvers (3211, 2311 × both directions × 4 controls) flown with a low-gain
    digital attitude/rate hold; recorded inputs are pilot plus feedback; outputs carry white
    noise of ``NOISE``·``noise_scale``."""
    rng = np.random.default_rng(seed)
    n = int(round(duration / dt)) + 1
    t = np.arange(n) * dt
    maps = discrete_maps(structure, values, dt, "zoh")
    lags = sorted(maps.Pu)
    # feedback (% per deg, % per deg/s): pitch/roll attitude and rate hold, yaw damper
    gain = np.zeros((4, 8))
    s = structure.states
    gain[0, s.index("theta")], gain[0, s.index("q")] = -1.0, -0.3
    gain[1, s.index("phi")], gain[1, s.index("p")] = 0.6, 0.1
    gain[3, s.index("r")] = 0.5
    gain[2, s.index("w")] = -0.5
    maneuvers = []
    for axis, control in enumerate(structure.controls):
        for kind in ("3211", "2311"):
            for direction in (1, -1):
                pilot = np.zeros((n, 4))
                pilot[:, axis] = multistep(kind, direction, n, dt, 6.0, 0.3)
                x = np.zeros((n, 8))
                u = np.zeros((n, 4))
                for k in range(n):
                    u[k] = pilot[k] - gain @ x[k]
                    if k + 1 < n:
                        nxt = maps.Ps[0] @ x[k]
                        for lag, cols in maps.state_history.items():
                            nxt += maps.Ps[lag][:, cols] @ x[k - lag, cols] * (k - lag >= 0)
                        for lag in lags:
                            if 0 <= k - lag < n and k - lag <= k:
                                nxt += maps.Pu[lag] @ u[k - lag]
                        x[k + 1] = nxt
                maneuvers.append(Maneuver(f"{kind}_{control}_{'pos' if direction > 0 else 'neg'}",
                                          t, u, np.zeros((n, 8)),
                                          {"kind": kind, "axis": control, "direction": direction}))
    clean = ManeuverSet(maneuvers)
    outputs = simulate(structure, values, clean)
    noisy = [m.with_outputs(y + rng.normal(size=y.shape) * NOISE * noise_scale)
             for m, y in zip(clean, outputs)]
    return ManeuverSet(noisy)
