"""Wall time of the full hover study against one 60-derivative fit measured in the same run.

The study is the paper's whole pipeline on the built-in truth model: data generation (20
maneuvers), reduction from 60 derivatives to none, delays, time- and frequency-domain
verification, figures and report. Target on 2 cores: ≤ 5 minutes. The baseline is one
output-error fit of the fully populated structure on the same data (the unit of work the
reduction repeats about 60 times), so the ratio says how many full fits the study costs.

Run:  .venv/bin/python benchmarks/bench_study.py [--quick] [--case hover]
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings

TARGET_S = 300.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="hover")
    parser.add_argument("--quick", action="store_true", help="the --quick variant instead")
    args = parser.parse_args()

    import rotorid
    from rotorid.errors import IdentifiabilityWarning
    from rotorid.study.case import FlightCase
    from rotorid.study.pipeline import base_structure, load_data, run_case

    case = FlightCase.load(args.case)
    case = case.quick() if args.quick else case
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        result = run_case(case, out, resume=False, progress=None)
        study = time.perf_counter() - start
        data, condition = load_data(case, f"{out}/{case.name}/data")
        ident = data.identification
        structure = base_structure(case, condition, ident.units)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            start = time.perf_counter()
            rotorid.create("estimators", case.estimator).estimate(structure, ident)
            fit = time.perf_counter() - start

    print(f"case {case.name} ({'quick' if case.is_quick else 'full'}): "
          f"{len(result.path.steps)} reduction steps")
    for phase, seconds in result.seconds.items():
        print(f"  {phase:<14} {seconds:8.1f} s")
    print(f"study total       {study:8.1f} s   (target ≤ {TARGET_S:.0f} s: "
          f"{'met' if study <= TARGET_S else 'NOT met'})")
    print(f"one 60-derivative fit {fit:6.2f} s   → study = {study / fit:.0f} full fits")


if __name__ == "__main__":
    main()
