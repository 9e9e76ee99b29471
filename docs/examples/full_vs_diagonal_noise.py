"""Full against diagonal R when the output noise is correlated (docs/estimation.md).

A stable aeroplane (the fixed-wing longitudinal template at 50 m/s, SI units, 11 derivatives)
flies two 12 s records; the noise of α and a_z is correlated (correlation coefficient
``--correlation``, 0.95 by default: a vane and an accelerometer shaken by the same airframe
vibration). For each of ``--seeds`` noise seeds the output-error fit runs once with the full
noise covariance R and once with its diagonal. Printed per parameter: the truth, then for each
choice the mean Cramér-Rao bound the estimate reports and the standard deviation of the
estimates over the seeds (what the bound should predict).

    .venv/bin/python docs/examples/full_vs_diagonal_noise.py [--seeds 40] [--correlation 0.95]
"""

from __future__ import annotations

import argparse
import math
import warnings

import numpy as np
import rotorid
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.simulation.simulator import simulate

CONDITION = FlightCondition(u0=50.0, w0=2.0, theta0=math.atan2(2.0, 50.0))
TRUTH = {"X_u": -0.04, "X_w": 0.08, "X_elevator": 0.5, "X_throttle": 2.0, "Z_u": -0.3,
         "Z_w": -2.0, "Z_elevator": -6.0, "M_u": 0.01, "M_w": -0.08, "M_q": -2.5,
         "M_elevator": -12.0}
#: Noise standard deviations of u α q θ q̇ ax az (m/s, rad, rad/s, rad, rad/s², m/s², m/s²).
NOISE = np.array([0.05, 0.002, 0.003, 0.002, 0.02, 0.05, 0.1])
#: The outputs whose noise is correlated.
CORRELATED = ("alpha", "az")


def aeroplane() -> ModelStructure:
    """The fixed-wing longitudinal template reduced to the derivatives of :data:`TRUTH`."""
    structure = ModelStructure.populated(CONDITION, "fixed-wing-longitudinal", "si")
    return structure.without(*[n for n in structure.names if n not in TRUTH])


def noise_covariance(structure: ModelStructure, correlation: float) -> np.ndarray:
    """The (7, 7) measurement-noise covariance: :data:`NOISE` on the diagonal and
    ``correlation`` between the outputs :data:`CORRELATED`."""
    rho = np.eye(len(NOISE))
    i, j = (structure.outputs.index(name) for name in CORRELATED)
    rho[i, j] = rho[j, i] = correlation
    return rho * np.outer(NOISE, NOISE)


def flight_records(structure: ModelStructure, seed: int, correlation: float = 0.0
                   ) -> ManeuverSet:
    """Two records (an elevator 3211 with a throttle step, a throttle doublet with an elevator
    pulse) simulated at :data:`TRUTH`, with noise of :func:`noise_covariance`."""
    dt = 0.02
    t = np.arange(0.0, 12.0 + dt / 2, dt)

    def pulse(start, length):
        return ((t >= start) & (t < start + length)).astype(float)

    inputs = {"elevator": (0.03 * (pulse(1, 1.5) - pulse(2.5, 1) + pulse(3.5, 0.5)
                                   - pulse(4, 0.5)), 0.05 * pulse(6, 4)),
              "throttle": (-0.02 * pulse(7, 1), 0.1 * pulse(1, 5) - 0.05 * pulse(6, 3))}

    def record(name, channels):
        return Maneuver(name, t, np.zeros((t.size, 0)), np.zeros((t.size, 0)),
                        input_names=(), output_names=(), units="si", extra_channels=channels)

    blank = ManeuverSet([record(name, {"elevator": e, "throttle": th})
                         for name, (e, th) in inputs.items()])
    factor = np.linalg.cholesky(noise_covariance(structure, correlation))
    rng = np.random.default_rng(seed)
    outputs = simulate(structure, structure.as_vector(TRUTH), blank)
    return ManeuverSet([
        record(m.name, {**m.extra_channels,
                        **dict(zip(structure.outputs,
                                   (y + rng.normal(size=y.shape) @ factor.T).T))})
        for m, y in zip(blank, outputs)])


def main(argv=None) -> dict:
    """Print the table; return {"full" | "diagonal": (mean reported CR (P,), spread (P,))}."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=40)
    parser.add_argument("--correlation", type=float, default=0.95)
    args = parser.parse_args(argv)
    structure = aeroplane()
    results = {}
    for noise in ("full", "diagonal"):
        estimator = rotorid.create("estimators", "output-error", noise=noise)
        values, bounds = [], []
        for seed in range(args.seeds):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", rotorid.IdentifiabilityWarning)
                estimate = estimator.estimate(
                    structure, flight_records(structure, seed, args.correlation))
            values.append(estimate.values)
            bounds.append(estimate.cramer_rao)
        results[noise] = (np.mean(bounds, axis=0), np.std(values, axis=0, ddof=1))
    print(f"{args.seeds} seeds, noise correlation {args.correlation:g} between "
          f"{' and '.join(CORRELATED)}")
    print(f"{'parameter':<12}{'truth':>9}{'full: CR':>12}{'spread':>10}"
          f"{'diagonal: CR':>15}{'spread':>10}")
    for k, name in enumerate(structure.parameter_names):
        print(f"{name:<12}{TRUTH[name]:>9.3g}{results['full'][0][k]:>12.3g}"
              f"{results['full'][1][k]:>10.3g}{results['diagonal'][0][k]:>15.3g}"
              f"{results['diagonal'][1][k]:>10.3g}")
    return results


if __name__ == "__main__":
    main()
