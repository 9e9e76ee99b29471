"""Wall time of one hybrid rotor-body fit against the 6-DoF fit it starts from, same run.

The problem: the truth model's paper-size identification data of one condition (16
closed-loop 3211/2311 multisteps of 15 s at 50 Hz, every control, both directions; the
helisim data source's defaults). In the same run:

* 6-DoF: ``OutputErrorEstimator().estimate`` of the fully populated six-dof structure (60
  derivatives) from zero with its defaults (equation-error start, horizons);
* hybrid: the hybrid structure built on that estimate
  (:func:`rotorid.model.hybrid.hybrid_from_six_dof`: its derivatives without the direct roll
  and pitch rate and cyclic terms, the disc-tilt moments, the flap equations, delays on the
  cyclic into flapping), fitted from the start whose quasi-steady form is the 6-DoF estimate.

Printed: both times (median of ``--repeats``), their ratio (target ≤ 2×), both fits' RMSE and
det R, and the hybrid's flap time constant and roll/pitch terms against the truth model's
flap-coupled reference (its full linearisation with the flap rates, coning and inflow
residualised; docs/hybrid.md) and 16/(γΩ). BLAS runs on one thread.

    .venv/bin/python benchmarks/bench_hybrid.py [--condition hover|forward] [--repeats 3]
                                                [--cache DIR]
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import rotorid  # noqa: E402
from rotorid import FlightCondition, ManeuverSet, ModelStructure  # noqa: E402
from rotorid.errors import IdentifiabilityWarning  # noqa: E402
from rotorid.model.hybrid import hybrid_from_six_dof  # noqa: E402
from rotorid.study.truth import truth_derivatives  # noqa: E402
from rotorid_helisim.source import HelisimSource  # noqa: E402

#: Hybrid parameters compared with the reference: flap damping, hub moments, cyclic into flap.
KEY = ("Bc_beta1c", "Bs_beta1s", "M_beta1c", "L_beta1s", "Bc_long", "Bs_lat")


def timed_fit(structure, maneuvers):
    """(wall time in s, estimate) of one output-error fit with the estimator's defaults."""
    estimator = rotorid.create("estimators", "output-error")
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        estimate = estimator.estimate(structure, maneuvers)
    return time.perf_counter() - started, estimate


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--condition", choices=("hover", "forward"), default="hover")
    parser.add_argument("--repeats", type=int, default=3, help="fits timed (median; default 3)")
    parser.add_argument("--cache", default=None, help="data cache directory (default: a "
                                                      "temporary one)")
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory() as scratch:
        source = HelisimSource(cache_dir=args.cache or scratch)
        data = source.generate(args.condition)
    ident = ManeuverSet([m for m in data if m.metadata["kind"] != "sweep"], hold=data.hold)
    trim = source.trim(data[0].metadata["airspeed_kt"])
    condition = FlightCondition.from_airspeed(trim.airspeed_kt, trim.theta_deg, trim.phi_deg)
    six_dof = ModelStructure.six_dof(condition)
    print(f"problem: {args.condition}, {len(ident)} maneuvers × {ident[0].n_samples} samples")

    six_runs = [timed_fit(six_dof, ident) for _ in range(args.repeats)]
    six_estimate = six_runs[-1][1]
    hybrid = hybrid_from_six_dof(six_dof, six_estimate.values)
    hybrid_runs = [timed_fit(hybrid, ident) for _ in range(args.repeats)]
    estimate = hybrid_runs[-1][1]
    six_time = statistics.median(t for t, _ in six_runs)
    hybrid_time = statistics.median(t for t, _ in hybrid_runs)
    for label, runs, fit, n in (("6-DoF", six_runs, six_estimate, six_dof.n_parameters),
                                ("hybrid", hybrid_runs, estimate, hybrid.n_parameters)):
        times = [t for t, _ in runs]
        print(f"{label:7s}: {statistics.median(times):.2f} s (median of {len(times)}; "
              f"{min(times):.2f}–{max(times):.2f}), {n} parameters, {fit.iterations} "
              f"iterations, converged {fit.converged}, RMSE {fit.rmse:.4f}, "
              f"det R {fit.cost:.3e}")
    ratio = hybrid_time / six_time
    print(f"hybrid/6-DoF time: {ratio:.2f}× (target ≤ 2×: {'met' if ratio <= 2 else 'NOT met'})")

    reference = truth_derivatives(source, condition, hybrid)
    config = source.plant.config
    print(f"τ_f = −1/Bc_beta1c {-1 / estimate.value('Bc_beta1c'):.4f} s, −1/Bs_beta1s "
          f"{-1 / estimate.value('Bs_beta1s'):.4f} s; 16/(γΩ) "
          f"{16 / (config.lock_number * config.omega):.4f} s")
    for name in KEY:
        value, bound = estimate.value(name), estimate[name].cramer_rao
        print(f"  {name:10s} {value:9.4f} ± {bound:.4f}  reference {reference[name]:9.4f}  "
              f"({value / reference[name] - 1:+.1%})")
    for name in hybrid.parameter_names:
        if name.startswith("tau_"):
            print(f"  {name:13s} {estimate.value(name):.4f} s")


if __name__ == "__main__":
    main()
