"""Identify a nonlinear model of one's own: longitudinal fixed-wing aircraft, RK4.

The output-error estimator works on the small model protocol of :mod:`rotorid.estimation.models`; this
example implements it for a rigid aircraft in the vertical plane (a light single-engine
aeroplane near 50 m/s) with nonlinear aerodynamics, and identifies six aerodynamic
coefficients from two simulated elevator maneuvers with sensor noise.

States (SI): airspeed V (m/s), angle of attack α (rad), pitch rate q (rad/s), pitch attitude
θ (rad). Input: elevator deflection δe, recorded in the ``long`` channel in degrees (absolute,
not a perturbation). Thrust is constant and known. Aerodynamics::

    C_L = C_L0 + C_Lα·α + C_Lα2·α²             (quadratic lift curve)
    C_D = C_D0 + k·C_L²
    C_m = C_m0 + C_mα·α + C_mq·q·c/(2V) + C_mδe·δe

    V̇ = (T cos α − D)/m − g sin(θ − α)
    α̇ = q − (L + T sin α)/(m V) + g cos(θ − α)/V
    q̇ = M/I_y,   θ̇ = q

Outputs (maneuver channels, ``units="si"``): ``q`` (rad/s), ``theta`` (rad) and the body-axis
specific forces ``ax = (T − D cos α + L sin α)/m``, ``az = −(L cos α + D sin α)/m`` (m/s²),
all absolute. Estimated: C_Lα, C_Lα2, C_m0, C_mα, C_mq, C_mδe; C_L0, C_D0 and k are known.
The model has no ``sensitivities`` method, so the estimator uses central finite differences.

Run it with ``python docs/examples/nonlinear_model.py [--seed 7] [--plot fit.png]``.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import rotorid
from rotorid import Maneuver, ManeuverSet

G = 9.80665          # m/s²
RHO = 1.225          # kg/m³
MASS = 1100.0        # kg
WING_AREA = 16.2     # m²
CHORD = 1.49         # m
PITCH_INERTIA = 1350.0   # kg·m²
KNOWN = {"C_L0": 0.25, "C_D0": 0.032, "k": 0.045}
TRUTH = {"C_La": 4.9, "C_La2": -6.0, "C_m0": 0.04, "C_ma": -0.75, "C_mq": -11.0,
         "C_mde": -1.1}
#: white-noise standard deviations of q (rad/s), θ (rad), ax, az (m/s²)
NOISE = {"q": math.radians(0.2), "theta": math.radians(0.1), "ax": 0.05, "az": 0.1}
OUTPUT_COLUMNS = [rotorid.OUTPUTS.index(name) for name in NOISE]


class LongitudinalAircraft:
    """The model protocol for the aircraft above (see the module docstring).

    Args:
        thrust: constant thrust T in N.
        initial_state: (V, α, q, θ) at the start of every maneuver, SI units.
    """

    parameter_names = tuple(TRUTH)
    output_names = tuple(NOISE)

    def __init__(self, thrust: float, initial_state):
        self.thrust = float(thrust)
        self.initial_state = tuple(float(x) for x in initial_state)

    def initial_values(self) -> np.ndarray:
        """Textbook first guesses, shape (6,); 18-100 % away from the truth."""
        return np.array([4.0, 0.0, 0.0, -0.5, -6.0, -0.8])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return np.full(6, -np.inf), np.full(6, np.inf)

    def _forces(self, values, state, elevator):
        """Derivative of (V, α, q, θ) and the specific forces (ax, az) at one instant."""
        c_la, c_la2, c_m0, c_ma, c_mq, c_mde = values
        speed, alpha, rate, pitch = state
        pressure = 0.5 * RHO * speed * speed * WING_AREA
        c_l = KNOWN["C_L0"] + c_la * alpha + c_la2 * alpha * alpha
        lift = pressure * c_l
        drag = pressure * (KNOWN["C_D0"] + KNOWN["k"] * c_l * c_l)
        moment = pressure * CHORD * (c_m0 + c_ma * alpha + c_mq * rate * CHORD / (2 * speed)
                                     + c_mde * elevator)
        cos_a, sin_a, gamma = math.cos(alpha), math.sin(alpha), pitch - alpha
        rates = ((self.thrust * cos_a - drag) / MASS - G * math.sin(gamma),
                 rate - (lift + self.thrust * sin_a) / (MASS * speed) + G * math.cos(gamma) / speed,
                 moment / PITCH_INERTIA,
                 rate)
        return rates, ((self.thrust - drag * cos_a + lift * sin_a) / MASS,
                       -(lift * cos_a + drag * sin_a) / MASS)

    def _maneuver(self, values, maneuver) -> np.ndarray:
        """Outputs (N, 4) of one maneuver by classical RK4 with the elevator held per step."""
        elevator = np.radians(maneuver.channel("long"))
        dt = maneuver.dt
        state = self.initial_state
        out = np.full((maneuver.n_samples, 4), np.nan)
        for k in range(maneuver.n_samples):
            k1, (ax, az) = self._forces(values, state, elevator[k])
            out[k] = (state[2], state[3], ax, az)
            if k + 1 == maneuver.n_samples:
                break
            k2 = self._forces(values, _step(state, k1, 0.5 * dt), elevator[k])[0]
            k3 = self._forces(values, _step(state, k2, 0.5 * dt), elevator[k])[0]
            k4 = self._forces(values, _step(state, k3, dt), elevator[k])[0]
            state = tuple(s + dt / 6 * (a + 2 * b + 2 * c + d)
                          for s, a, b, c, d in zip(state, k1, k2, k3, k4))
            if not (5.0 < state[0] < 500.0 and abs(state[1]) < 1.0):
                break      # left the model's domain: the NaN rows tell the estimator
        return out

    def simulate(self, values, maneuvers) -> list[np.ndarray]:
        """Outputs q, θ, ax, az per maneuver, (N_i, 4) arrays."""
        values = tuple(float(v) for v in values)
        return [self._maneuver(values, m) for m in maneuvers]


def _step(state, rates, h):
    return tuple(s + h * r for s, r in zip(state, rates))


def trim(speed: float) -> tuple[float, float, float]:
    """Level-flight trim of the true aircraft at ``speed`` (m/s): (α rad, δe rad, T N)."""
    from scipy.optimize import fsolve

    values = tuple(TRUTH.values())

    def residual(unknowns):
        alpha, elevator, thrust = unknowns
        model = LongitudinalAircraft(thrust, (speed, alpha, 0.0, alpha))
        return model._forces(values, model.initial_state, elevator)[0][:3]

    alpha, elevator, thrust = fsolve(residual, (0.05, -0.02, 1000.0), xtol=1e-12)
    return float(alpha), float(elevator), float(thrust)


def flight_test(seed: int, speed: float = 50.0, dt: float = 0.02, duration: float = 12.0):
    """The model with the trim thrust and state, and a doublet and a 3211 on the elevator
    (absolute deflection in deg, channel ``long``) with noisy outputs (seeded)."""
    alpha, elevator, thrust = trim(speed)
    model = LongitudinalAircraft(thrust, (speed, alpha, 0.0, alpha))
    t = np.arange(int(round(duration / dt)) + 1) * dt
    steps = {"doublet": [(1.0, 2.0, 3.0), (2.0, 3.0, -3.0)],
             "3211": [(1.0, 2.5, 2.5), (2.5, 3.5, -2.5), (3.5, 4.0, 2.5), (4.0, 4.5, -2.5)]}
    blank = []
    for name, pulses in steps.items():
        long = np.full(t.size, math.degrees(elevator))
        for begin, end, amplitude in pulses:
            long[(t >= begin) & (t < end)] += amplitude
        inputs = np.zeros((t.size, 4))
        inputs[:, 0] = long
        blank.append(Maneuver(name, t, inputs, np.zeros((t.size, 8)), units="si"))
    blank = ManeuverSet(blank)
    rng = np.random.default_rng(seed)
    sigma = np.array(list(NOISE.values()))
    maneuvers = []
    for m, y in zip(blank, model.simulate(tuple(TRUTH.values()), blank)):
        outputs = np.zeros((m.n_samples, 8))
        outputs[:, OUTPUT_COLUMNS] = y + rng.normal(size=y.shape) * sigma
        maneuvers.append(m.with_outputs(outputs))
    return model, ManeuverSet(maneuvers)


def identify(seed: int = 7):
    """(model, maneuvers, estimate) of one identification from the textbook guesses."""
    model, maneuvers = flight_test(seed)
    estimator = rotorid.create("estimators", "output-error")
    return model, maneuvers, estimator.estimate(model, maneuvers)


def plot(model, maneuvers, estimate, path: str) -> None:
    """Measured and identified outputs of every maneuver, saved to ``path`` (PNG)."""
    import matplotlib.pyplot as plt

    fitted = model.simulate(estimate.values, maneuvers)
    figure, axes = plt.subplots(4, len(maneuvers), sharex=True, figsize=(10, 8), squeeze=False)
    for j, (m, y) in enumerate(zip(maneuvers, fitted)):
        for i, (name, column) in enumerate(zip(NOISE, OUTPUT_COLUMNS)):
            axes[i, j].plot(m.time, m.outputs[:, column], lw=0.6, label="measured")
            axes[i, j].plot(m.time, y[:, i], lw=1.2, label="identified")
            axes[i, j].set_ylabel(name)
        axes[0, j].set_title(m.name)
        axes[-1, j].set_xlabel("time (s)")
    axes[0, 0].legend()
    figure.savefig(path, dpi=100)
    plt.close(figure)


def main(argv=None):
    parser = argparse.ArgumentParser(description="identify a nonlinear longitudinal aircraft")
    parser.add_argument("--seed", type=int, default=7, help="noise seed (default 7)")
    parser.add_argument("--plot", default=None, help="save measured vs identified to this PNG")
    args = parser.parse_args(argv)
    model, maneuvers, estimate = identify(args.seed)
    print(estimate.report())
    print(f"{'parameter':<10}{'truth':>10}{'estimate':>12}{'error/CR':>10}")
    for name, truth in TRUTH.items():
        i = estimate.index(name)
        print(f"{name:<10}{truth:>10.4g}{estimate.values[i]:>12.4g}"
              f"{(estimate.values[i] - truth) / estimate.cramer_rao[i]:>10.2f}")
    if args.plot:
        plot(model, maneuvers, estimate, args.plot)
    return estimate


if __name__ == "__main__":
    main()
