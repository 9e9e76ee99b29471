"""A nonlinear aeroplane model of one's own, identified by ``rotorid identify`` (docs/models.md).

::

    rotorid identify docs/examples/fixed_wing_nonlinear.py:AEROPLANE records/ --out result.json

This file declares what rotorid needs and nothing more: the aeroplane's signals and parameters,
its state derivatives and outputs as functions of (t, x, u, θ) vectorised over rows
(:class:`LongitudinalAeroplane`), and how flight records are read (:data:`AEROPLANE`: the
channel map from the records' own column names and units to the signals). rotorid integrates
the model (RK4 under the records' input hold), estimates each record's initial state from a
start at its first samples, computes the sensitivities from one batched simulation and fits the
11 coefficients. There is
no integration code and no renaming of columns here.

The aeroplane is a light single-engine aeroplane in the vertical plane near 50 m/s. States:
airspeed V (m/s), angle of attack α (rad), pitch attitude θ (rad), pitch rate q (rad/s); inputs:
elevator δe (rad) and thrust T (N); outputs: V, α, θ, q, the pitch acceleration q̇ (rad/s²) and
the body-axis specific forces ax, az (m/s²). All are absolute values, not perturbations::

    C_L = C_L0 + C_Lα·α + C_Lq·q·c/(2V) + C_Lδe·δe
    C_D = C_D0 + C_Dα·α + C_Dα2·α²
    C_m = C_m0 + C_mα·α + C_mq·q·c/(2V) + C_mδe·δe

    V̇ = (T cos α − D)/m − g sin(θ − α)        α̇ = q − (L + T sin α)/(m V) + g cos(θ − α)/V
    θ̇ = q                                     q̇ = M/I_y
    ax = (T − D cos α + L sin α)/m            az = −(L cos α + D sin α)/m

with L, D = ½ρV²S·(C_L, C_D) and M = ½ρV²S·c·C_m. The start values are 20–40 % away from the
coefficients of :data:`TRUTH`.

Records are CSV files with ``time`` in s and the columns of :data:`COLUMNS` in SI units.
``python docs/examples/fixed_wing_nonlinear.py DIR`` writes two such records (an elevator 3211
and a thrust doublet, flown from level trim by the aeroplane at :data:`TRUTH` with
``scipy.integrate.solve_ivp`` and seeded sensor noise) to try the command on.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from rotorid import (
    ChannelMap,
    InitialConditions,
    IntegratedModel,
    ModelSignals,
    Parameter,
    Signal,
    SignalSet,
)

G, RHO = 9.80665, 1.225                  # m/s², kg/m³
MASS, AREA, CHORD, INERTIA = 1100.0, 16.2, 1.49, 1350.0     # kg, m², m, kg·m²
#: The coefficients that fly the example records.
TRUTH = {"C_L0": 0.25, "C_La": 4.9, "C_Lq": 7.5, "C_Lde": 0.4, "C_D0": 0.032, "C_Da": 0.05,
         "C_Da2": 1.1, "C_m0": 0.04, "C_ma": -0.75, "C_mq": -11.0, "C_mde": -1.1}
#: Start values: each coefficient of TRUTH times these factors.
START_FACTORS = (1.3, 0.8, 0.6, 1.4, 1.3, 0.7, 0.7, 1.35, 0.7, 0.65, 0.75)
#: The records' columns: name → (signal, unit).
COLUMNS = {"VTAS_mps": ("V", "m/s"), "AOA_rad": ("alpha", "rad"), "PITCH_rad": ("theta", "rad"),
           "Q_radps": ("q", "rad/s"), "QDOT_radps2": ("q_dot", "rad/s²"),
           "AX_mps2": ("ax", "m/s²"), "AZ_mps2": ("az", "m/s²"),
           "DELE_rad": ("elevator", "rad"), "THRUST_N": ("thrust", "N")}
#: Sensor noise standard deviations of the output columns (their units).
NOISE = {"VTAS_mps": 0.2, "AOA_rad": np.radians(0.1), "PITCH_rad": np.radians(0.1),
         "Q_radps": np.radians(0.2), "QDOT_radps2": np.radians(1.0), "AX_mps2": 0.05,
         "AZ_mps2": 0.1}
STATES = SignalSet([Signal("V", "m/s", "velocity", "airspeed"),
                    Signal("alpha", "rad", "angle", "angle of attack"),
                    Signal("theta", "rad", "angle", "pitch attitude"),
                    Signal("q", "rad/s", "rate", "pitch rate")])


class LongitudinalAeroplane:
    """The aeroplane of the module docstring (a :class:`rotorid.model.nonlinear.NonlinearModel`)."""

    signals = ModelSignals(
        states=STATES,
        inputs=SignalSet([Signal("elevator", "rad", "control", "elevator deflection"),
                          Signal("thrust", "N", "control", "engine thrust")]),
        outputs=SignalSet([*STATES,
                           Signal("q_dot", "rad/s²", "angular-acceleration", "pitch acceleration"),
                           Signal("ax", "m/s²", "acceleration", "longitudinal specific force"),
                           Signal("az", "m/s²", "acceleration", "normal specific force")]))
    parameters = tuple(Parameter(name, value * factor)
                       for (name, value), factor in zip(TRUTH.items(), START_FACTORS))

    def _motion(self, x, u, theta):
        """State derivatives (B, 4) and the specific forces ax, az (B,) of B rows."""
        c_l0, c_la, c_lq, c_lde, c_d0, c_da, c_da2, c_m0, c_ma, c_mq, c_mde = theta.T
        speed, alpha, pitch, rate = x.T
        elevator, thrust = u.T
        pressure = 0.5 * RHO * speed * speed * AREA
        reduced_rate = rate * CHORD / (2 * speed)
        lift = pressure * (c_l0 + c_la * alpha + c_lq * reduced_rate + c_lde * elevator)
        drag = pressure * (c_d0 + c_da * alpha + c_da2 * alpha * alpha)
        moment = pressure * CHORD * (c_m0 + c_ma * alpha + c_mq * reduced_rate
                                     + c_mde * elevator)
        cos_a, sin_a, gamma = np.cos(alpha), np.sin(alpha), pitch - alpha
        rates = np.stack([(thrust * cos_a - drag) / MASS - G * np.sin(gamma),
                          rate - (lift + thrust * sin_a) / (MASS * speed)
                          + G * np.cos(gamma) / speed,
                          rate,
                          moment / INERTIA], axis=1)
        return (rates, (thrust - drag * cos_a + lift * sin_a) / MASS,
                -(lift * cos_a + drag * sin_a) / MASS)

    def derivatives(self, t, x, u, theta):
        """(V̇, α̇, θ̇, q̇), shape (B, 4)."""
        return self._motion(x, u, theta)[0]

    def outputs(self, t, x, u, theta):
        """(V, α, θ, q, q̇, ax, az), shape (B, 7)."""
        rates, ax, az = self._motion(x, u, theta)
        return np.column_stack([x, rates[:, 3], ax, az])


#: What ``rotorid identify …fixed_wing_nonlinear.py:AEROPLANE`` fits: the aeroplane, reading
#: the records' own columns through the channel map. Each record's initial state is estimated
#: with the coefficients, starting from its first samples: taken as they are, the sensor noise
#: of one sample (0.2 m/s in V) would bias the drag coefficients by several bounds.
AEROPLANE = IntegratedModel(
    LongitudinalAeroplane(),
    channels=ChannelMap.from_mapping({column: {"signal": signal, "unit": unit}
                                      for column, (signal, unit) in COLUMNS.items()},
                                     source="fixed_wing_nonlinear.py"),
    initial=InitialConditions(estimated=STATES.names))


def trim(speed: float = 50.0) -> tuple[float, float, float]:
    """Level-flight trim of the aeroplane at :data:`TRUTH` and ``speed`` m/s: (α rad, δe rad,
    T N)."""
    from scipy.optimize import fsolve

    theta = np.array([list(TRUTH.values())])

    def residual(unknowns):
        alpha, elevator, thrust = unknowns
        x = np.array([[speed, alpha, alpha, 0.0]])
        rates = LongitudinalAeroplane().derivatives(0.0, x, np.array([[elevator, thrust]]), theta)
        return rates[0, [0, 1, 3]]

    alpha, elevator, thrust = fsolve(residual, (0.05, -0.02, 1000.0), xtol=1e-12)
    return float(alpha), float(elevator), float(thrust)


def fly(time: np.ndarray, inputs: np.ndarray, state: np.ndarray) -> np.ndarray:
    """Outputs (N, 7) of the aeroplane at :data:`TRUTH` from ``state`` (4,), the ``inputs``
    (N, 2) held constant over each sample interval, integrated by ``scipy.integrate.solve_ivp``
    (RK45, relative tolerance 1e-10) interval by interval."""
    from scipy.integrate import solve_ivp

    model, theta = LongitudinalAeroplane(), np.array([list(TRUTH.values())])
    states = [np.asarray(state, dtype=float)]
    for k in range(time.size - 1):
        u = inputs[k][None, :]
        solution = solve_ivp(lambda t, x: model.derivatives(t, x[None, :], u, theta)[0],
                             (time[k], time[k + 1]), states[-1], rtol=1e-10, atol=1e-12)
        states.append(solution.y[:, -1])
    return model.outputs(time, np.array(states), inputs, np.repeat(theta, time.size, axis=0))


def write_records(directory: str | Path, seed: int = 5, dt: float = 0.02,
                  duration: float = 8.0) -> list[Path]:
    """An elevator 3211 and a thrust doublet from level trim at 50 m/s, with sensor noise
    (:data:`NOISE`, seeded), as CSV files with the columns of :data:`COLUMNS`; returns the
    paths."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    alpha, elevator, thrust = trim()
    time = np.arange(int(round(duration / dt)) + 1) * dt
    rng = np.random.default_rng(seed)
    paths = []
    for name, column, pulses in (
            ("elevator_3211", 0, [(1.0, 1.6, 0.03), (1.6, 2.0, -0.03), (2.0, 2.2, 0.03),
                                  (2.2, 2.4, -0.03)]),
            ("thrust_doublet", 1, [(1.0, 2.5, 600.0), (2.5, 4.0, -600.0)])):
        inputs = np.tile([elevator, thrust], (time.size, 1))
        for begin, end, amplitude in pulses:
            inputs[(time >= begin) & (time < end), column] += amplitude
        outputs = fly(time, inputs, np.array([50.0, alpha, alpha, 0.0]))
        noisy = outputs + rng.normal(size=outputs.shape) * list(NOISE.values())
        table = np.column_stack([time, noisy, inputs])
        path = directory / f"{name}.csv"
        np.savetxt(path, table, delimiter=",", comments="", fmt="%.10g",
                   header=",".join(["time", *NOISE, "DELE_rad", "THRUST_N"]))
        paths.append(path)
    return paths


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description="write example records of the aeroplane")
    parser.add_argument("directory", help="where to write the CSV records")
    parser.add_argument("--seed", type=int, default=5, help="noise seed (default 5)")
    args = parser.parse_args(argv)
    for path in write_records(args.directory, args.seed):
        print(path)


if __name__ == "__main__":
    main()
