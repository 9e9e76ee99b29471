"""Identify a nonlinear model of one's own: a longitudinal fixed-wing aircraft (docs/models.md).

The author writes the state derivatives and the outputs, vectorised over a batch of rows, and
declares signals and parameters; rotorid integrates (RK4 under the data's input hold), reads
the data through a channel map and computes the sensitivities. The aircraft is a light
single-engine aeroplane near 50 m/s with nonlinear aerodynamics; six aerodynamic coefficients
are identified from two simulated elevator maneuvers with sensor noise.

States: airspeed V (m/s), angle of attack α (rad), pitch rate q (rad/s), pitch attitude θ (rad).
Input: elevator deflection δe (rad), recorded in the maneuvers' ``long`` column in degrees
(absolute, not a perturbation). Thrust is constant and known. Aerodynamics::

    C_L = C_L0 + C_Lα·α + C_Lα2·α²             (quadratic lift curve)
    C_D = C_D0 + k·C_L²
    C_m = C_m0 + C_mα·α + C_mq·q·c/(2V) + C_mδe·δe

    V̇ = (T cos α − D)/m − g sin(θ − α)
    α̇ = q − (L + T sin α)/(m V) + g cos(θ − α)/V
    q̇ = M/I_y,   θ̇ = q

Outputs: q (rad/s), θ (rad) and the body-axis specific forces ``ax = (T − D cos α + L sin α)/m``,
``az = −(L cos α + D sin α)/m`` (m/s²), all absolute, in maneuvers with ``units="si"``.
Estimated: C_Lα, C_Lα2, C_m0, C_mα, C_mq, C_mδe; C_L0, C_D0 and k are declared fixed. Every
maneuver starts in the level trim, so the initial state is fixed at the trim state (V and α are
not measured). The model gives no Jacobians, so sensitivities are central differences of one
batched simulation.

Run it with ``python docs/examples/nonlinear_model.py [--seed 7] [--plot fit.png]``.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import rotorid
from rotorid import (
    ChannelLink,
    ChannelMap,
    InitialConditions,
    IntegratedModel,
    Maneuver,
    ManeuverSet,
    ModelSignals,
    Parameter,
    Signal,
    SignalSet,
)

G = 9.80665          # m/s²
RHO = 1.225          # kg/m³
MASS = 1100.0        # kg
WING_AREA = 16.2     # m²
CHORD = 1.49         # m
PITCH_INERTIA = 1350.0   # kg·m²
TRUTH = {"C_La": 4.9, "C_La2": -6.0, "C_m0": 0.04, "C_ma": -0.75, "C_mq": -11.0,
         "C_mde": -1.1}
#: white-noise standard deviations of q (rad/s), θ (rad), ax, az (m/s²)
NOISE = {"q": math.radians(0.2), "theta": math.radians(0.1), "ax": 0.05, "az": 0.1}
#: the elevator is recorded in the maneuvers' ``long`` column, in degrees
CHANNELS = ChannelMap([ChannelLink("long", "elevator", "deg")], source="nonlinear_model.py")


class LongitudinalAircraft:
    """The aircraft of the module docstring as a :class:`rotorid.model.nonlinear.NonlinearModel`.

    Args:
        thrust: constant thrust T in N.
    """

    signals = ModelSignals(
        states=SignalSet([Signal("V", "m/s", "velocity", "airspeed"),
                          Signal("alpha", "rad", "angle", "angle of attack"),
                          Signal("q", "rad/s", "rate", "pitch rate"),
                          Signal("theta", "rad", "angle", "pitch attitude")]),
        inputs=SignalSet([Signal("elevator", "rad", "control", "elevator deflection")]),
        outputs=SignalSet([Signal("q", "rad/s", "rate"), Signal("theta", "rad", "angle"),
                           Signal("ax", "m/s²", "acceleration"),
                           Signal("az", "m/s²", "acceleration")]))
    #: textbook first guesses, 18-100 % away from the truth; the drag polar is known
    parameters = (Parameter("C_La", 4.0), Parameter("C_La2", 0.0), Parameter("C_m0", 0.0),
                  Parameter("C_ma", -0.5), Parameter("C_mq", -6.0), Parameter("C_mde", -0.8),
                  Parameter("C_L0", 0.25, fixed=True), Parameter("C_D0", 0.032, fixed=True),
                  Parameter("k", 0.045, fixed=True))

    def __init__(self, thrust: float):
        self.thrust = float(thrust)

    def _forces(self, x, u, theta):
        """State derivatives (B, 4) and specific forces ax, az (B,) of B rows."""
        c_la, c_la2, c_m0, c_ma, c_mq, c_mde, c_l0, c_d0, k = theta.T
        speed, alpha, rate, pitch = x.T
        pressure = 0.5 * RHO * speed * speed * WING_AREA
        c_l = c_l0 + c_la * alpha + c_la2 * alpha * alpha
        lift = pressure * c_l
        drag = pressure * (c_d0 + k * c_l * c_l)
        moment = pressure * CHORD * (c_m0 + c_ma * alpha + c_mq * rate * CHORD / (2 * speed)
                                     + c_mde * u[:, 0])
        cos_a, sin_a, gamma = np.cos(alpha), np.sin(alpha), pitch - alpha
        rates = np.stack([(self.thrust * cos_a - drag) / MASS - G * np.sin(gamma),
                          rate - (lift + self.thrust * sin_a) / (MASS * speed)
                          + G * np.cos(gamma) / speed,
                          moment / PITCH_INERTIA,
                          rate], axis=1)
        inside = (speed > 5.0) & (speed < 500.0) & (np.abs(alpha) < 1.0)   # the model's domain
        rates[~inside] = np.nan
        return rates, ((self.thrust - drag * cos_a + lift * sin_a) / MASS,
                       -(lift * cos_a + drag * sin_a) / MASS)

    def derivatives(self, t, x, u, theta):
        """(V̇, α̇, q̇, θ̇), shape (B, 4)."""
        return self._forces(x, u, theta)[0]

    def outputs(self, t, x, u, theta):
        """(q, θ, ax, az), shape (B, 4)."""
        ax, az = self._forces(x, u, theta)[1]
        return np.stack([x[:, 2], x[:, 3], ax, az], axis=1)


def all_parameters(free: dict[str, float]) -> np.ndarray:
    """The full parameter row (1, 9): ``free`` values, fixed ones at their declared start."""
    return np.array([[free.get(p.name, p.start) for p in LongitudinalAircraft.parameters]])


def trim(speed: float) -> tuple[float, float, float]:
    """Level-flight trim of the true aircraft at ``speed`` (m/s): (α rad, δe rad, T N)."""
    from scipy.optimize import fsolve

    theta = all_parameters(TRUTH)

    def residual(unknowns):
        alpha, elevator, thrust = unknowns
        state = np.array([[speed, alpha, 0.0, alpha]])
        return LongitudinalAircraft(thrust).derivatives(0.0, state, np.array([[elevator]]),
                                                        theta)[0, :3]

    alpha, elevator, thrust = fsolve(residual, (0.05, -0.02, 1000.0), xtol=1e-12)
    return float(alpha), float(elevator), float(thrust)


def identifiable(aircraft: LongitudinalAircraft, speed: float, alpha: float) -> IntegratedModel:
    """The aircraft seen by the estimator: elevator from ``long`` (deg), trim initial state."""
    start = InitialConditions(fixed={"V": speed, "alpha": alpha, "q": 0.0, "theta": alpha})
    return IntegratedModel(aircraft, channels=CHANNELS, initial=start)


def flight_test(seed: int, speed: float = 50.0, dt: float = 0.02, duration: float = 12.0):
    """The identifiable aircraft at the trim thrust and state, and a doublet and a 3211 on the
    elevator (absolute deflection in deg, column ``long``) with noisy outputs (seeded)."""
    alpha, elevator, thrust = trim(speed)
    model = identifiable(LongitudinalAircraft(thrust), speed, alpha)
    t = np.arange(int(round(duration / dt)) + 1) * dt
    steps = {"doublet": [(1.0, 2.0, 3.0), (2.0, 3.0, -3.0)],
             "3211": [(1.0, 2.5, 2.5), (2.5, 3.5, -2.5), (3.5, 4.0, 2.5), (4.0, 4.5, -2.5)]}
    blank = []
    for name, pulses in steps.items():
        inputs = np.zeros((t.size, 4))
        inputs[:, 0] = math.degrees(elevator)
        for begin, end, amplitude in pulses:
            inputs[(t >= begin) & (t < end), 0] += amplitude
        blank.append(Maneuver(name, t, inputs, np.zeros((t.size, 8)), units="si"))
    blank = ManeuverSet(blank)
    rng = np.random.default_rng(seed)
    sigma = np.array(list(NOISE.values()))
    columns = [rotorid.OUTPUTS.index(name) for name in NOISE]
    maneuvers = []
    for m, y in zip(blank, model.simulate(list(TRUTH.values()), blank)):
        outputs = np.zeros((m.n_samples, 8))
        outputs[:, columns] = y + rng.normal(size=y.shape) * sigma
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
    measured = model.measured(maneuvers)
    figure, axes = plt.subplots(4, len(maneuvers), sharex=True, figsize=(10, 8), squeeze=False)
    for j, (m, y, z) in enumerate(zip(maneuvers, fitted, measured)):
        for i, signal in enumerate(LongitudinalAircraft.signals.outputs):
            axes[i, j].plot(m.time, z[:, i], lw=0.6, label="measured")
            axes[i, j].plot(m.time, y[:, i], lw=1.2, label="identified")
            axes[i, j].set_ylabel(f"{signal.name} ({signal.unit})")
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
