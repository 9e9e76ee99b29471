"""Wall time of one output-error fit of a nonlinear model of one's own (docs/models.md).

The problem: a light aeroplane's longitudinal motion near 50 m/s, 4 states (V, α, θ, q), 2
inputs (elevator, thrust), 7 outputs (V, α, θ, q, q̇, ax, az), 11 aerodynamic coefficients

    C_L = C_L0 + C_Lα·α + C_Lq·q·c/(2V) + C_Lδe·δe
    C_D = C_D0 + C_Dα·α + C_Dα2·α²
    C_m = C_m0 + C_mα·α + C_mq·q·c/(2V) + C_mδe·δe

with the nonlinear rigid-body equations in the vertical plane; 600 samples (an elevator 3211
and a thrust doublet, 6 s each at 50 Hz) with seeded white noise; every coefficient starts
20-40 % away from the truth; the initial state is the level trim.

In the same run, the same fit (``OutputErrorEstimator`` defaults, RK4 at the sample rate under
zero-order hold, central differences with the relative step 10⁻⁶):

* rotorid: ``IntegratedModel``, all 2P perturbed parameter vectors and both maneuvers in one
  batched integration per sensitivity evaluation, anticipated in every simulation (so the
  sensitivities at an accepted step cost nothing more);
* baseline: the same model and integrator behind the plain model protocol (``simulate`` only),
  so the estimator differences it one parameter at a time: 2P + 1 integrations per evaluation,
  as a hand-written model loops over its parameters.

Printed: both wall and CPU times (median of ``--repeats``; on a loaded machine the CPU time is
the fairer figure), the ratio of the wall times, the estimates' largest
difference in Cramér-Rao bounds and their largest error against the truth in bounds. Target
(the issue's, 2 cores): ≤ 0.3 s.

    .venv/bin/python benchmarks/bench_nonlinear.py [--repeats 3]
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import rotorid  # noqa: E402
from rotorid import (  # noqa: E402
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

G, RHO, MASS, AREA, CHORD, INERTIA = 9.80665, 1.225, 1100.0, 16.2, 1.49, 1350.0
TRUTH = {"C_L0": 0.25, "C_La": 4.9, "C_Lq": 7.5, "C_Lde": 0.4, "C_D0": 0.032, "C_Da": 0.05,
         "C_Da2": 1.1, "C_m0": 0.04, "C_ma": -0.75, "C_mq": -11.0, "C_mde": -1.1}
START_ERROR = (1.3, 0.8, 0.6, 1.4, 1.3, 0.7, 0.7, 1.35, 0.7, 0.65, 0.75)
#: noise standard deviations of V, α, θ, q, q̇, ax, az (SI)
NOISE = (0.2, np.radians(0.1), np.radians(0.1), np.radians(0.2), np.radians(1.0), 0.05, 0.1)
OUTPUTS = (Signal("V", "m/s", "velocity"), Signal("alpha", "rad", "angle"),
           Signal("theta", "rad", "angle"), Signal("q", "rad/s", "rate"),
           Signal("q_dot", "rad/s²", "angular-acceleration"), Signal("ax", "m/s²", "acceleration"),
           Signal("az", "m/s²", "acceleration"))


class Aeroplane:
    """The longitudinal aeroplane of the module docstring (a NonlinearModel)."""

    signals = ModelSignals(states=SignalSet(OUTPUTS[:4]),
                           inputs=SignalSet([Signal("elevator", "rad", "control"),
                                             Signal("thrust", "N", "control")]),
                           outputs=SignalSet(OUTPUTS))
    parameters = tuple(Parameter(name, value * error)
                       for (name, value), error in zip(TRUTH.items(), START_ERROR))

    def _motion(self, x, u, theta):
        """State derivatives (B, 4) and specific forces ax, az (B,)."""
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
        return rates, (thrust - drag * cos_a + lift * sin_a) / MASS, \
            -(lift * cos_a + drag * sin_a) / MASS

    def derivatives(self, t, x, u, theta):
        return self._motion(x, u, theta)[0]

    def outputs(self, t, x, u, theta):
        rates, ax, az = self._motion(x, u, theta)
        return np.column_stack([x, rates[:, 3], ax, az])


class PerParameterLoop:
    """The same model behind the plain protocol: no sensitivities, so the estimator loops;
    each simulation integrates the one parameter vector asked for."""

    def __init__(self, model: IntegratedModel):
        self.model = IntegratedModel(model.model, channels=model.channels, initial=model.initial,
                                     anticipate=False)
        self.parameter_names, self.output_names = model.parameter_names, model.output_names

    def initial_values(self):
        return self.model.initial_values()

    def bounds(self):
        return self.model.bounds()

    def measured(self, maneuvers):
        return self.model.measured(maneuvers)

    def simulate(self, values, maneuvers):
        return self.model.simulate(values, maneuvers)


#: outputs recorded in the maneuvers' own channels; V, alpha and q_dot are extra channels
FIXED_CHANNELS = ("theta", "q", "ax", "az")
CHANNELS = ChannelMap([ChannelLink("long", "elevator", "rad"), ChannelLink("coll", "thrust", "N")],
                      source="bench_nonlinear.py")


def trim(speed: float = 50.0):
    """Level trim (α, δe, T) of the true aeroplane at ``speed`` m/s."""
    from scipy.optimize import fsolve

    theta = np.array([list(TRUTH.values())])

    def residual(unknowns):
        alpha, elevator, thrust = unknowns
        x = np.array([[speed, alpha, alpha, 0.0]])
        return Aeroplane().derivatives(0.0, x, np.array([[elevator, thrust]]), theta)[0, [0, 1, 3]]

    return fsolve(residual, (0.05, -0.02, 1000.0), xtol=1e-12)


def flight_test(seed: int = 5):
    """The identifiable model (trim initial state) and the two noisy maneuvers."""
    speed = 50.0
    alpha, elevator, thrust = trim(speed)
    start = InitialConditions(fixed={"V": speed, "alpha": alpha, "theta": alpha, "q": 0.0})
    model = IntegratedModel(Aeroplane(), channels=CHANNELS, initial=start)
    t = np.arange(300) * 0.02
    blank = []
    for name, column, pulses in (
            ("elevator_3211", 0, [(0.5, 1.1, 0.03), (1.1, 1.5, -0.03), (1.5, 1.7, 0.03),
                                  (1.7, 1.9, -0.03)]),
            ("thrust_doublet", 2, [(0.5, 2.0, 600.0), (2.0, 3.5, -600.0)])):
        inputs = np.zeros((t.size, 4))
        inputs[:, 0], inputs[:, 2] = elevator, thrust
        for begin, end, amplitude in pulses:
            inputs[(t >= begin) & (t < end), column] += amplitude
        blank.append(Maneuver(name, t, inputs, np.zeros((t.size, 8)), units="si"))
    blank = ManeuverSet(blank)
    rng = np.random.default_rng(seed)
    records = []
    for m, y in zip(blank, model.simulate(list(TRUTH.values()), blank)):
        noisy = dict(zip(model.output_names, (y + rng.normal(size=y.shape) * NOISE).T))
        outputs = np.zeros((m.n_samples, 8))
        for name in FIXED_CHANNELS:
            outputs[:, rotorid.OUTPUTS.index(name)] = noisy.pop(name)
        records.append(Maneuver(m.name, m.time, m.inputs, outputs, units="si",
                                extra_channels=noisy))
    return model, ManeuverSet(records)


def timed_fit(model, maneuvers, repeats):
    """Median wall and CPU time (s) of ``repeats`` fits, and the last estimate."""
    wall, cpu, estimate = [], [], None
    for _ in range(repeats):
        began, began_cpu = time.perf_counter(), time.process_time()
        estimate = rotorid.create("estimators", "output-error").estimate(model, maneuvers)
        wall.append(time.perf_counter() - began)
        cpu.append(time.process_time() - began_cpu)
    return statistics.median(wall), statistics.median(cpu), estimate


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    model, maneuvers = flight_test()
    print(f"nonlinear fit: {len(model.parameter_names)} parameters, 4 states, "
          f"{len(model.output_names)} outputs, {maneuvers.n_samples} samples; "
          f"load average {os.getloadavg()[0]:.2f}")
    batched, batched_cpu, estimate = timed_fit(model, maneuvers, args.repeats)
    looped, looped_cpu, reference = timed_fit(PerParameterLoop(model), maneuvers, args.repeats)
    truth = np.array(list(TRUTH.values()))
    print(f"rotorid (batched sensitivities): {batched:.3f} s wall, {batched_cpu:.3f} s CPU, "
          f"{estimate.iterations} final iterations, converged {estimate.converged}")
    print(f"baseline (per-parameter loop):   {looped:.3f} s wall, {looped_cpu:.3f} s CPU, "
          f"converged {reference.converged}")
    print(f"ratio {looped / batched:.1f}x; estimates differ by at most "
          f"{np.max(np.abs(estimate.values - reference.values) / estimate.cramer_rao):.2g} CR "
          f"bounds; largest error {np.max(np.abs(estimate.values - truth) / estimate.cramer_rao):.2f}"
          " CR bounds")
    print(f"target <= 0.3 s: {'met' if batched <= 0.3 else 'not met'}")


if __name__ == "__main__":
    main()
