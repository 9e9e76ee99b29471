"""Wall time of the frequency-domain fit against the time-domain fit, in the same run.

Both fit the fully populated 60-derivative structure from zero to the quick hover case's data
(the built-in truth model, noise seed 0): the ``output-error`` estimator to the 16 multisteps
(equation-error start, horizon continuation), the ``frequency-response`` estimator to the
frequency responses of the 4 sweeps (every output over every swept input with coherent
frequencies, equation-error start on the sweeps). The frequency fit is timed with the
responses it needs (the J points and the cross-spectral mixing of every pair) and without
them, and the fit from the study comparison's ``FREQUENCY_STARTS`` starts (the equation-error
start and varied ones, :mod:`rotorid.study.comparison`) on the same responses. Each is the
median of ``--repeats`` runs. Target on 2 cores: the frequency fit with its responses ≤ 5 s.

Run:  .venv/bin/python benchmarks/bench_frequency.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
import warnings

TARGET_S = 5.0


def _median_time(function, repeats: int):
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    import rotorid
    from rotorid.errors import IdentifiabilityWarning
    from rotorid.study.case import FlightCase
    from rotorid.study.comparison import FREQUENCY_STARTS
    from rotorid.study.pipeline import base_structure, load_data

    case = FlightCase.load("hover").quick()
    with tempfile.TemporaryDirectory() as out:
        data, condition = load_data(case, f"{out}/data")
    multisteps, sweeps = data.identification, data.verification
    structure = base_structure(case, condition, multisteps.units)
    time_domain = rotorid.create("estimators", "output-error")
    frequency = rotorid.create("estimators", "frequency-response")
    several = rotorid.create("estimators", "frequency-response", starts=FREQUENCY_STARTS)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        t_time, oe = _median_time(lambda: time_domain.estimate(structure, multisteps),
                                  args.repeats)
        t_total, fr = _median_time(lambda: frequency.estimate(structure, sweeps), args.repeats)
        t_data, fit_data = _median_time(lambda: frequency.fit_data(sweeps), args.repeats)
        start = fr.start
        t_fit, _ = _median_time(lambda: frequency.estimate(structure, fit_data, start=start),
                                args.repeats)
        t_starts, multi = _median_time(lambda: several.estimate(structure, fit_data,
                                                                start=start), args.repeats)
    pairs = sum(1 for p in fit_data if not isinstance(p, str))
    print(f"load average {os.getloadavg()[0]:.2f}; {structure.n_parameters} parameters, "
          f"median of {args.repeats}")
    print(f"time domain  (output error, {len(multisteps)} multisteps): {t_time:6.2f} s, "
          f"{oe.iterations} iterations, RMSE {oe.rmse:.3f}")
    print(f"frequency    ({len(sweeps)} sweeps, {pairs} pairs, {fr.n_samples} J points): "
          f"{t_total:6.2f} s with responses ({t_data:.2f} s responses + {t_fit:.2f} s fit), "
          f"{fr.iterations} iterations, J {fr.cost:.0f} ({fr.stop_reason})")
    print(f"ratio frequency/time {t_total / t_time:.2f} with responses, "
          f"{t_fit / t_time:.2f} fit alone")
    print(f"frequency fit from {FREQUENCY_STARTS} starts (the study comparison's): "
          f"{t_starts:6.2f} s, J {multi.cost:.0f}")
    print(f"target frequency fit with responses ≤ {TARGET_S:.0f} s: "
          f"{'met' if t_total <= TARGET_S else 'NOT met'}")


if __name__ == "__main__":
    main()
