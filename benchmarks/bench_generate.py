"""Time to generate both conditions' data sets (hover and 70 kt: 40 maneuvers).

Measures, in one run and on the same truth model:

* batched: both conditions' 40 maneuvers flown as one batch (what ``HelisimSource`` does);
* baseline: the same 40 maneuvers flown one by one (``--baseline one-by-one``, the default,
  several minutes) or one batch per condition (``--baseline per-condition``).

Prints both wall times and their ratio. Target: batched ≤ 60 s on 2 cores.

    .venv/bin/python benchmarks/bench_generate.py [--baseline per-condition] [--quick]
"""

from __future__ import annotations

import argparse
import os
import platform
import time

from rotorid_helisim.datasets import Job, fly_jobs, maneuver_specs
from rotorid_helisim.source import HelisimSource, resolve_case


def _jobs(source, settings):
    jobs = []
    for case in settings:
        config = resolve_case(case)
        point = source.trim(config.airspeed_kt)
        jobs.append(Job(point.state, point.stick, config))
    return jobs


def _timed(function):
    start = time.perf_counter()
    result = function()
    return time.perf_counter() - start, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", choices=("one-by-one", "per-condition"),
                        default="one-by-one")
    parser.add_argument("--quick", action="store_true", help="duration scale 0.3 records")
    args = parser.parse_args()
    extra = {"quick": True} if args.quick else {}
    cases = [{"condition": name, **extra} for name in ("hover", "forward")]

    source = HelisimSource()
    trim_time, jobs = _timed(lambda: _jobs(source, cases))
    batched, sets = _timed(lambda: fly_jobs(source.plant, jobs))
    count = sum(len(s) for s in sets)

    if args.baseline == "per-condition":
        baseline = sum(_timed(lambda job=job: fly_jobs(source.plant, [job]))[0] for job in jobs)
    else:
        baseline = 0.0
        for job, case in zip(jobs, cases):
            for spec in maneuver_specs(job.config):
                config = resolve_case({**case, "kinds": [spec.kind],
                                       "axes": [spec.axis], "directions": [spec.direction]})
                single = Job(job.trim_state, job.trim_stick, config)
                baseline += _timed(lambda single=single: fly_jobs(source.plant, [single]))[0]

    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"python {platform.python_version()}")
    print(f"trims (2 conditions):               {trim_time:7.2f} s")
    print(f"batched, {count} maneuvers:            {batched:7.2f} s  (target ≤ 60 s)")
    print(f"baseline ({args.baseline}):    {baseline:9.2f} s")
    print(f"speed-up of batching:               {baseline / batched:7.1f} ×")


if __name__ == "__main__":
    main()
