"""Wall time of one output-error fit from zero on the Bo-105-like hover problem.

The problem (``tests/hover_reference.py``): 16 closed-loop maneuvers of 15 s at 50 Hz (3211 and
2311 multisteps, both directions, every control, flown with a low-gain attitude/rate hold so the
recorded inputs are correlated with the states), 8 noisy outputs, all 60 six-DoF derivatives
plus the delays of L_lat and M_long free, every start value zero.

In the same run:

* rotorid: ``OutputErrorEstimator().estimate`` with its defaults (equation-error start,
  horizon continuation, det R cost, exact sensitivities). The time includes the start.
* reference: ``scipy.optimize.least_squares`` (trust-region reflective, delays bounded ≥ 0,
  finite-difference Jacobian) on the residuals (z − y)/σ weighted by the true noise standard
  deviations ``hover_reference.NOISE``, over the same simulation (``Simulator.outputs``). It
  starts from the same equation-error values (a zero start would give it an unstable model and
  a harder problem); that start is part of its time too. A divergent candidate simulation
  returns a large constant residual. ``--reference-max-nfev`` caps its function evaluations
  (Jacobian evaluations not counted); when the cap stops it, the speed ratio is a lower bound.

Printed: both wall times, each fit's cost det R divided by det R at the true parameters (1.0 is
the noise floor; below 1 is the usual overfit of 62 parameters), and the ratio of the times.
BLAS runs on one thread. rotorid folds the sensitivities into the information matrix on a
second thread when the machine has two cores (docs/estimation.md); the reference is serial.
Target (2 cores): rotorid ≤ 2 s, ≥ 20× faster than the reference.

``--variants`` also fits once without the equation-error start, without the horizons, and
with neither (the paper's plain procedure), to measure what each departure buys.

    .venv/bin/python benchmarks/bench_estimation.py [--repeats 3] [--reference-repeats 3]
                                                    [--reference-max-nfev N] [--variants]
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import scipy.optimize  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import rotorid  # noqa: E402
from hover_reference import NOISE, closed_loop_maneuvers, true_structure  # noqa: E402
from rotorid.errors import IdentifiabilityWarning, SimulationDivergedError  # noqa: E402
from rotorid.estimation.equation_error import equation_error_start  # noqa: E402
from rotorid.simulation.simulator import Simulator  # noqa: E402

#: Residual (in noise standard deviations) returned for a diverging candidate simulation.
DIVERGED_RESIDUAL = 1e6


def det_r(structure, values, maneuvers) -> float:
    """det R (eq. 6) of the unweighted output residuals at ``values`` over ``maneuvers``."""
    outputs = Simulator(structure, maneuvers).outputs(values)
    residuals = np.concatenate([m.outputs - y for m, y in zip(maneuvers, outputs)])
    return float(np.linalg.det(residuals.T @ residuals / len(residuals)))


#: ``--variants``: the default's two departures from the paper's procedure, one at a time.
VARIANTS = {"equation-error start, no horizons": {"horizons": ()},
            "zero start, horizons": {"start": "initial"},
            "plain (paper): zero start, no horizons": {"start": "initial", "horizons": ()}}


def rotorid_fit(structure, maneuvers, **options):
    """(wall time in s, estimate) of one fit with the output-error estimator."""
    estimator = rotorid.create("estimators", "output-error", **options)
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        estimate = estimator.estimate(structure, maneuvers)
    return time.perf_counter() - started, estimate


def reference_fit(structure, maneuvers, max_nfev, jacobian):
    """(wall time in s, scipy result) of the least-squares reference, start included."""
    simulator = Simulator(structure, maneuvers)
    measured = np.concatenate([m.outputs for m in maneuvers])
    size = measured.size

    def residuals(values):
        try:
            outputs = simulator.outputs(values)
        except SimulationDivergedError:
            return np.full(size, DIVERGED_RESIDUAL)
        weighted = ((measured - np.concatenate(outputs)) / NOISE).ravel()
        return weighted if np.all(np.isfinite(weighted)) else np.full(size, DIVERGED_RESIDUAL)

    started = time.perf_counter()
    start = equation_error_start(structure, maneuvers)
    lower, upper = structure.bounds()
    result = scipy.optimize.least_squares(residuals, np.clip(start, lower, upper),
                                          jac=jacobian, bounds=(lower, upper), method="trf",
                                          x_scale="jac", max_nfev=max_nfev)
    return time.perf_counter() - started, result


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3,
                        help="rotorid fits timed (median reported; default 3)")
    parser.add_argument("--reference-repeats", type=int, default=3,
                        help="reference fits timed (median reported; default 3)")
    parser.add_argument("--reference-max-nfev", type=int, default=None,
                        help="cap on the reference's function evaluations (default: scipy's)")
    parser.add_argument("--jacobian", choices=("2-point", "3-point"), default="2-point",
                        help="finite-difference scheme of the reference (default 2-point)")
    parser.add_argument("--seed", type=int, default=3, help="noise seed of the data")
    parser.add_argument("--variants", action="store_true",
                        help="also time the start/horizon variants once (docs/estimation.md)")
    args = parser.parse_args(argv)

    structure, truth = true_structure()
    maneuvers = closed_loop_maneuvers(structure, truth, seed=args.seed)
    zero = structure.with_initial({n: 0.0 for n in structure.parameter_names})
    floor = det_r(structure, truth, maneuvers)
    print(f"problem: {len(maneuvers)} maneuvers × {maneuvers[0].n_samples} samples, "
          f"{structure.n_parameters} parameters from zero; python {platform.python_version()}, "
          f"numpy {np.__version__}, scipy {scipy.__version__}, {os.cpu_count()} CPU(s)")

    runs = [rotorid_fit(zero, maneuvers) for _ in range(args.repeats)]
    ours = statistics.median(t for t, _ in runs)
    estimate = runs[-1][1]
    print(f"rotorid output-error: {ours:.2f} s (median of {args.repeats}; "
          f"{min(t for t, _ in runs):.2f}–{max(t for t, _ in runs):.2f}), converged "
          f"{estimate.converged}, {estimate.iterations} final iterations, "
          f"cost/cost(truth) = {estimate.cost / floor:.4f}")

    for label, options in VARIANTS.items() if args.variants else ():
        elapsed, variant = rotorid_fit(zero, maneuvers, **options)
        print(f"  variant {label}: {elapsed:.1f} s, converged {variant.converged} "
              f"({variant.stop_reason}), {variant.iterations} final iterations, "
              f"cost/cost(truth) = {variant.cost / floor:.4g}, RMSE {variant.rmse:.4g}")

    references = [reference_fit(zero, maneuvers, args.reference_max_nfev, args.jacobian)
                  for _ in range(args.reference_repeats)]
    elapsed = statistics.median(t for t, _ in references)
    result = references[-1][1]
    capped = result.status == 0
    print(f"reference least_squares ({args.jacobian}): {elapsed:.1f} s (median of "
          f"{args.reference_repeats}; {min(t for t, _ in references):.1f}–"
          f"{max(t for t, _ in references):.1f}), {result.nfev} function "
          f"and {result.njev} Jacobian evaluations, status {result.status} ({result.message}), "
          f"cost/cost(truth) = {det_r(zero, result.x, maneuvers) / floor:.4f}"
          + (" [CAPPED by --reference-max-nfev]" if capped else ""))
    print(f"speed ratio reference/rotorid: {'≥ ' if capped else ''}{elapsed / ours:.1f}×")


if __name__ == "__main__":
    main()
