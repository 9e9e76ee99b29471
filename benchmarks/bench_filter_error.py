"""Wall time of one filter-error fit against one output-error fit on the paper-size hover problem.

The problem is bench_estimation.py's (``tests/hover_reference.py``): 16 closed-loop maneuvers
of 15 s at 50 Hz, 8 noisy outputs, all 60 six-DoF derivatives plus the delays of L_lat and
M_long free from zero. The filter-error fit adds the process noise of the six force and moment
equations and the eight measurement-noise variances (76 parameters in all). Both estimators
run with their defaults (equation-error start; output error also with its horizon
continuation), BLAS on one thread, in the same run; medians of ``--repeats`` fits.

Printed: both wall times and CPU times (the process's, both threads of a fit; on a shared
machine the CPU time is the steadier measure), iterations, each fit's largest distance from the
true derivatives in its own Cramér-Rao bounds, and the ratios filter error / output error.
Target: ≤ 3×. Also measured (no target): filter error on the records low-passed at
``--cutoff`` Hz with one measurement update per white-noise factor of samples
(``update_every``, :func:`rotorid.resampling.low_passed`), against the filter error above.

    .venv/bin/python benchmarks/bench_filter_error.py [--repeats 3] [--seed 3] [--cutoff 5]
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import rotorid  # noqa: E402
from hover_reference import closed_loop_maneuvers, true_structure  # noqa: E402
from rotorid.errors import IdentifiabilityWarning  # noqa: E402
from rotorid.resampling import low_passed, white_noise_factor  # noqa: E402

TARGET = 3.0


def timed_fit(name, structure, maneuvers, **options):
    """(wall time in s, CPU time in s, estimate) of one fit with the named estimator and
    ``options``."""
    estimator = rotorid.create("estimators", name, **options)
    started, cpu = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        estimate = estimator.estimate(structure, maneuvers)
    return time.perf_counter() - started, time.process_time() - cpu, estimate


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="fits timed per estimator")
    parser.add_argument("--seed", type=int, default=3, help="noise seed of the data")
    parser.add_argument("--cutoff", type=float, default=5.0,
                        help="Hz: low-pass of the update_every fit")
    args = parser.parse_args(argv)

    structure, truth = true_structure()
    maneuvers = closed_loop_maneuvers(structure, truth, seed=args.seed)
    zero = structure.with_initial({n: 0.0 for n in structure.parameter_names})
    load = os.getloadavg()[0]
    print(f"problem: {len(maneuvers)} maneuvers × {maneuvers[0].n_samples} samples, "
          f"{structure.n_parameters} structure parameters from zero; {os.cpu_count()} CPU(s), "
          f"load average {load:.1f}")
    every = white_noise_factor(maneuvers[0].dt, args.cutoff)
    fits = {"output-error": ("output-error", maneuvers, {}),
            "filter-error": ("filter-error", maneuvers, {}),
            f"filter-error, update_every = {every}": (
                "filter-error", low_passed(maneuvers, args.cutoff), {"update_every": every})}
    walls, cpus = {}, {}
    for name, (estimator, data, options) in fits.items():
        runs = [timed_fit(estimator, zero, data, **options) for _ in range(args.repeats)]
        walls[name] = statistics.median(wall for wall, _, _ in runs)
        cpus[name] = statistics.median(cpu for _, cpu, _ in runs)
        estimate = runs[-1][2]
        k = structure.n_parameters
        miss = np.abs(estimate.values[:k] - truth) / estimate.cramer_rao[:k]
        print(f"{name}: wall {walls[name]:.2f} s, CPU {cpus[name]:.2f} s (medians of "
              f"{args.repeats}; wall {min(w for w, _, _ in runs):.2f}–"
              f"{max(w for w, _, _ in runs):.2f}), {len(estimate.parameter_names)} parameters, "
              f"{estimate.iterations} iterations, converged {estimate.converged}, cost "
              f"{estimate.cost:.6g}; max |value − truth| / CR = "
              f"{np.max(miss[np.isfinite(miss)]):.1f}")
    for label, times in (("wall", walls), ("CPU", cpus)):
        ratio = times["filter-error"] / times["output-error"]
        print(f"ratio filter error / output error, {label} time: {ratio:.2f}× (target ≤ "
              f"{TARGET:g}×: {'met' if ratio <= TARGET else 'NOT met'})")
    banded = f"filter-error, update_every = {every}"
    for label, times in (("wall", walls), ("CPU", cpus)):
        print(f"ratio filter error at {args.cutoff:g} Hz, update_every = {every} / filter error, "
              f"{label} time: {times[banded] / times['filter-error']:.2f}×")
    print(f"load average after the runs: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
