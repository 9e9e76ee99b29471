"""Wall time of one output-error fit of a nonlinear model of one's own (docs/models.md), and
of the filter-error fit of the same model beside it.

The problem: the aeroplane of docs/examples/fixed_wing_nonlinear.py, a light aeroplane's
longitudinal motion near 50 m/s, 4 states (V, α, θ, q), 2 inputs (elevator, thrust), 7 outputs
(V, α, θ, q, q̇, ax, az), 11 aerodynamic coefficients

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
(the issue's, 2 cores): ≤ 0.3 s. Then the filter-error fit (its defaults: process noise on the
measured states, here all four; no target) and its time against the batched output error's.

    .venv/bin/python benchmarks/bench_nonlinear.py [--repeats 3]
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import rotorid  # noqa: E402
from rotorid import InitialConditions, IntegratedModel, Maneuver, ManeuverSet  # noqa: E402


def _example():
    """docs/examples/fixed_wing_nonlinear.py: the aeroplane, its coefficients, start values,
    sensor noise and the channel map of its records' columns."""
    path = Path(__file__).resolve().parents[1] / "docs" / "examples" / "fixed_wing_nonlinear.py"
    spec = importlib.util.spec_from_file_location("fixed_wing_nonlinear_example", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


EXAMPLE = _example()


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


def flight_test(seed: int = 5):
    """The identifiable model (trim initial state) and the two noisy maneuvers, whose
    channels are the example records' columns."""
    speed = 50.0
    alpha, elevator, thrust = EXAMPLE.trim(speed)
    start = InitialConditions(fixed={"V": speed, "alpha": alpha, "theta": alpha, "q": 0.0})
    model = IntegratedModel(EXAMPLE.LongitudinalAeroplane(),
                            channels=EXAMPLE.AEROPLANE.channels, initial=start)
    t = np.arange(300) * 0.02
    blank = []
    for name, column, pulses in (
            ("elevator_3211", 0, [(0.5, 1.1, 0.03), (1.1, 1.5, -0.03), (1.5, 1.7, 0.03),
                                  (1.7, 1.9, -0.03)]),
            ("thrust_doublet", 1, [(0.5, 2.0, 600.0), (2.0, 3.5, -600.0)])):
        inputs = np.tile([elevator, thrust], (t.size, 1))
        for begin, end, amplitude in pulses:
            inputs[(t >= begin) & (t < end), column] += amplitude
        blank.append(Maneuver(name, t, np.zeros((t.size, 0)), np.zeros((t.size, 0)),
                              units="si", input_names=(), output_names=(),
                              extra_channels={"DELE_rad": inputs[:, 0],
                                              "THRUST_N": inputs[:, 1]}))
    blank = ManeuverSet(blank)
    rng = np.random.default_rng(seed)
    noise = np.array(list(EXAMPLE.NOISE.values()))
    records = []
    for m, y in zip(blank, model.simulate(list(EXAMPLE.TRUTH.values()), blank)):
        noisy = y + rng.normal(size=y.shape) * noise
        records.append(Maneuver(m.name, m.time, m.inputs, m.outputs, units="si",
                                input_names=(), output_names=(),
                                extra_channels={**m.extra_channels,
                                                **dict(zip(EXAMPLE.NOISE, noisy.T))}))
    return model, ManeuverSet(records)


def timed_fit(model, maneuvers, repeats, estimator="output-error"):
    """Median wall and CPU time (s) of ``repeats`` fits with ``estimator``, and the last
    estimate."""
    wall, cpu, estimate = [], [], None
    for _ in range(repeats):
        began, began_cpu = time.perf_counter(), time.process_time()
        estimate = rotorid.create("estimators", estimator).estimate(model, maneuvers)
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
    truth = np.array(list(EXAMPLE.TRUTH.values()))
    print(f"rotorid (batched sensitivities): {batched:.3f} s wall, {batched_cpu:.3f} s CPU, "
          f"{estimate.iterations} final iterations, converged {estimate.converged}")
    print(f"baseline (per-parameter loop):   {looped:.3f} s wall, {looped_cpu:.3f} s CPU, "
          f"converged {reference.converged}")
    print(f"ratio {looped / batched:.1f}x; estimates differ by at most "
          f"{np.max(np.abs(estimate.values - reference.values) / estimate.cramer_rao):.2g} CR "
          f"bounds; largest error {np.max(np.abs(estimate.values - truth) / estimate.cramer_rao):.2f}"
          " CR bounds")
    print(f"target <= 0.3 s: {'met' if batched <= 0.3 else 'not met'}")
    filtered, filtered_cpu, noisy = timed_fit(model, maneuvers, args.repeats, "filter-error")
    coefficients = [noisy.parameter_names.index(n) for n in EXAMPLE.TRUTH]
    print(f"filter error (process noise on V, alpha, theta, q, which go to 0 here): "
          f"{filtered:.3f} s wall, {filtered_cpu:.3f} s CPU, {noisy.iterations} iterations, "
          f"{filtered / batched:.1f}x output error's wall time; coefficients within "
          f"{np.max(np.abs(noisy.values[coefficients] - truth) / noisy.cramer_rao[coefficients]):.2f}"
          f" CR bounds of the truth")


if __name__ == "__main__":
    main()
