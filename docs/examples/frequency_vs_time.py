"""The frequency-domain fit beside the time-domain one, on a study's data (docs/study.md).

Reads a case directory of ``rotorid study hover --quick --no-figures --out DIR`` (``DIR/hover``;
likewise ``DIR/forward``): its data (multisteps and sweeps) and ``result.json`` (the selected
structure and the time-domain estimates). Fits the selected structure, with the delays the
study kept, to the sweeps' frequency responses from zero (equation-error start values on the
sweeps and ``--starts`` − 1 variations of them, the lowest J kept; the pairs given and the
on-axis translational accelerations, as the study's comparison), then prints for both
estimates the mismatch cost J per pair on the same measured responses and the time-domain
RMSE (the paper's eq. 18) on the multisteps, from the plain simulation and with each
multistep's input biases and output reference shifts fitted to the fixed model.

Run from the repository root::

    python docs/examples/frequency_vs_time.py DIR/hover|DIR/forward [--pairs q/long,...]
        [--band-max 10] [--paper-delays] [--starts 24]
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np
import rotorid
from rotorid.errors import IdentifiabilityWarning
from rotorid.estimation.estimate import Estimate, rmse
from rotorid.model.structure import PAPER_DELAYED
from rotorid.study.comparison import fitted_pairs
from rotorid.verification.pairs import PAPER_PAIRS
from rotorid.verification.shifts import simulate_with_shifts

#: The paper's verification pairs and the two cyclic attitude responses.
PAIRS = (*PAPER_PAIRS, "theta/long", "phi/lat")
ON_AXIS = ("q/long", "theta/long", "p/lat", "phi/lat", "az/coll", "r/ped")


def selected_structure(result: dict, estimate: Estimate,
                       paper_delays: bool = False) -> rotorid.ModelStructure:
    """The study's selected structure with the delays of ``estimate`` (with all the paper's
    delays on the derivatives it kept when ``paper_delays`` and ``estimate`` has delays)."""
    full = rotorid.ModelStructure.six_dof(rotorid.FlightCondition(**result["condition"]))
    kept = set(result["selected_structure"])
    structure = full.without(*[n for n in full.names if n not in kept])
    delays = [n[4:] for n in estimate.parameter_names if n.startswith("tau_")]
    if paper_delays and delays:
        delays = PAPER_DELAYED
    return structure.with_delays(delays, upper=0.3)


def multistep_rmse(structure, values, multisteps, shifts: bool = False) -> float | str:
    """RMSE on ``multisteps``, with each one's input biases and output shifts fitted when
    ``shifts``; "diverges" when the model's simulation does."""
    try:
        outputs = (simulate_with_shifts(structure, values, multisteps).outputs if shifts
                   else rotorid.simulate(structure, values, multisteps))
    except rotorid.SimulationDivergedError:
        return "diverges"
    return rmse(np.concatenate([m.outputs - y for m, y in zip(multisteps, outputs)]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory", type=Path, help="a case directory of a study output")
    parser.add_argument("--pairs", default=",".join(PAIRS), help="OUTPUT/INPUT pairs")
    parser.add_argument("--band-max", type=float, default=np.inf,
                        help="highest J frequency in rad/s (default: the coherent range)")
    parser.add_argument("--paper-delays", action="store_true",
                        help="fit all eight of the paper's delays, also those the study "
                             "dropped (the time-domain estimate has them at zero)")
    parser.add_argument("--starts", type=int, default=24,
                        help="starts of the frequency-domain fit (default 24, as the study)")
    args = parser.parse_args()

    result = json.loads((args.directory / "result.json").read_text())
    data = rotorid.create("data-sources", "files").load(args.directory / "data")
    sweeps = data.select(kind="sweep")
    multisteps = data.select(lambda m: m.metadata.get("kind") != "sweep")
    for label in ("no delays", "with delays"):
        time_domain = Estimate.from_dict(result["estimates"][label])
        structure = selected_structure(result, time_domain, args.paper_delays)
        estimator = rotorid.create(
            "estimators", "frequency-response",
            pairs=fitted_pairs(structure, time_domain.as_mapping(), sweeps,
                               args.pairs.split(",")),
            band=(0.0, args.band_max), starts=args.starts)
        clock = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            frequency = estimator.estimate(structure, sweeps)       # from zero
        seconds = time.perf_counter() - clock
        fit_data = estimator.fit_data(sweeps)
        costs = {"time": estimator.pair_costs(structure, time_domain.as_mapping(), fit_data),
                 "frequency": estimator.pair_costs(structure, frequency.values, fit_data)}
        print(f"[{label}] {structure.describe()}")
        print(f"  frequency fit: {frequency.iterations} iterations, {frequency.stop_reason}, "
              f"{seconds:.1f} s")
        print("  " + "; ".join(n for n in frequency.notes if n.startswith("best of")))
        print(f"  {'pair':<12}{'J time':>9}{'J freq':>9}")
        for pair in costs["time"]:
            mark = "*" if pair in ON_AXIS else " "
            print(f" {mark}{pair:<11}{costs['time'][pair]:9.1f}{costs['frequency'][pair]:9.1f}")
        for name, values in (("time", time_domain.as_mapping()), ("frequency",
                                                                   frequency.values)):
            on_axis = [c for p, c in costs[name].items() if p in ON_AXIS]
            shown = [error if isinstance(error, str) else f"{error:.3f}"
                     for error in (multistep_rmse(structure, values, multisteps, shifts)
                                   for shifts in (False, True))]
            print(f"  {name:<10} on-axis J mean {np.mean(on_axis):7.1f}, max "
                  f"{np.max(on_axis):7.1f}; multistep RMSE {shown[0]}, with biases and "
                  f"shifts fitted {shown[1]}")


if __name__ == "__main__":
    main()
