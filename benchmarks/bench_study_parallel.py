"""Wall time of a multi-airspeed study run serially against the same study in a process pool.

The study is a speed sweep of the hover pipeline (``--quick`` variant by default) at a few
airspeeds: each airspeed is an independent case (data generation, reduction, delays,
verification; no figures). Both runs start from empty directories, in the same process
environment, one after the other. Prints both wall times, their ratio, the number of cores
and the load average, and checks that both runs produced the same numbers. Target: the pool
measurably faster than serial on 2 cores (ratio > 1; at most min(cases, cores)).

Run:  .venv/bin/python benchmarks/bench_study_parallel.py [--speeds 0,40,80,120] [--full]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np


def _timed_study(cases, executor):
    from rotorid.study.pipeline import Study

    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        results = Study(cases, out, executor=executor, resume=False, progress=None,
                        figures=False).run()
        return time.perf_counter() - start, results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speeds", default="0,40,80,120", help="airspeeds in kt")
    parser.add_argument("--full", action="store_true", help="full cases instead of --quick")
    args = parser.parse_args()

    from rotorid.executors import cpu_count
    from rotorid.study.sweep import speed_sweep

    cases = speed_sweep(args.speeds)
    cases = cases if args.full else tuple(case.quick() for case in cases)
    print(f"{len(cases)} cases ({', '.join(c.name for c in cases)}), "
          f"{'full' if args.full else 'quick'}; {cpu_count()} cores; load average before "
          f"{os.getloadavg()[0]:.1f}")
    serial, first = _timed_study(cases, None)
    print(f"serial        {serial:7.1f} s   (load average {os.getloadavg()[0]:.1f})")
    pooled, second = _timed_study(cases, "process")
    print(f"process pool  {pooled:7.1f} s   (load average {os.getloadavg()[0]:.1f})")
    same = all(np.array_equal(first[n].estimates[m].values, second[n].estimates[m].values)
               for n in first for m in first[n].estimates)
    ratio = serial / pooled
    print(f"speed-up serial/pool = {ratio:.2f}× (at most {min(len(cases), cpu_count())}×; "
          f"target > 1: {'met' if ratio > 1.0 else 'NOT met'}); identical numbers: {same}")


if __name__ == "__main__":
    main()
