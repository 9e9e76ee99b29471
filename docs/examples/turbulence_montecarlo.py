"""Monte Carlo of output error and filter error in turbulence: Cramér-Rao bounds against spread.

Every run flies the hover case's longitudinal identification multisteps (3211 and 2311 on the
longitudinal stick and the collective, both directions) with its own seed, so gusts and sensor
noise are both drawn anew (``HelisimSource.noise_realisations`` in turbulence, the data factory
``rotorid montecarlo`` uses), and fits the fully populated longitudinal structure (15
derivatives, states u w q θ, outputs ax az q θ) with both estimators (filter error with
coloured disturbances on the u, w and q equations) through
:func:`rotorid.study.montecarlo.monte_carlo`, the engine of ``rotorid montecarlo``. Per key
derivative it prints the runs' mean and standard deviation, the mean Cramér-Rao bound and their
ratio (1 for honest bounds), over all runs and over the converged ones, writes
``<out>/<estimator>.json`` and the figure ``<out>/turbulence_montecarlo.png``.

``--truth`` chooses what flies: the nonlinear truth model (default), its linearisation with
the rotor residualised (``linear``: the same loops, gusts and sensors, lateral coupling
included), that linearisation's longitudinal part alone (``linear-longitudinal``, which the
structure represents exactly) or the linearisation with the rotor, inflow and actuator states
kept (``linear-rotor``; :class:`rotorid_helisim.linear_truth.LinearisedPlant`).

This is the reduced problem: the six-dof structure with delays takes minutes per filter-error
fit on a shared 2-core machine, 30 runs of it hours. Run from the repository root::

    python docs/examples/turbulence_montecarlo.py [--runs 30] [--turbulence moderate]
        [--truth nonlinear] [--duration-scale 1.0] [--cutoff HZ [--decimate N]]
        [--longest-correlation T_w=3,...] [--executor process] [--out montecarlo-turbulence]

``--cutoff HZ`` fits records low-passed at HZ and kept at every N-th sample
(:func:`rotorid.resampling.decimated`; N by default the largest whose Nyquist frequency is
at least HZ, which keeps the sensor noise white). ``--longest-correlation`` limits filter
error's correlation times named (its ``longest_correlation`` option).
"""

from __future__ import annotations

import argparse
import functools
import json
from collections.abc import Callable
from pathlib import Path

import attrs
import numpy as np
import rotorid
from rotorid import FlightCondition, ManeuverSet, ModelStructure
from rotorid.cli.arguments import correlation_limits
from rotorid.resampling import decimated
from rotorid.study.montecarlo import PreparedRealisations, monte_carlo
from rotorid.study.truth import truth_derivatives
from rotorid_helisim.linear_truth import TRUTHS, source_flown_by

KEY = ("M_q", "M_long", "Z_w", "Z_coll")
#: Estimators and their options: filter error with a coloured disturbance on each equation
#: of the structure in place of white process noise (docs/estimation.md); its disturbance
#: sizes and correlation times creep for many iterations after the derivatives settle.
ESTIMATORS = {"output-error": {},
              "filter-error": {"process_noise": (), "disturbances": ("u", "w", "q"),
                               "max_iterations": 200}}


@attrs.frozen
class StartInTrim:
    """``data(seed)`` without the maneuvers' initial states: the flights start in trim (the
    recorded six-dof initial state is zero), which the longitudinal structure takes as its
    own zero initial state."""

    data: Callable[[int], ManeuverSet]

    def __call__(self, seed: int) -> ManeuverSet:
        flown = self.data(seed)
        assert all(not np.any(m.initial_state) for m in flown)
        return ManeuverSet([attrs.evolve(m, initial_state=None) for m in flown],
                           hold=flown.hold)


def flights(turbulence: str, duration_scale: float, directory: Path, truth: str = "nonlinear"):
    """``data(seed)`` of the longitudinal identification maneuvers flown by ``truth`` and the
    trim condition."""
    source = source_flown_by(truth)
    settings = {"condition": "hover", "axes": ["long", "coll"], "turbulence": turbulence,
                "identification": ["3211", "2311"], "verification": [],
                "duration_scale": duration_scale}
    data = StartInTrim(source.noise_realisations(settings, directory))
    first = data(0)[0].metadata
    condition = FlightCondition.from_airspeed(0.0, first["trim_theta_deg"],
                                              first["trim_phi_deg"])
    return data, condition


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=30)
    parser.add_argument("--turbulence", default="moderate", choices=("light", "moderate"))
    parser.add_argument("--truth", nargs="+", default=["nonlinear"], choices=TRUTHS)
    parser.add_argument("--duration-scale", type=float, default=1.0)
    parser.add_argument("--cutoff", type=float,
                        help="Hz: fit records low-passed there and decimated")
    parser.add_argument("--decimate", type=int,
                        help="samples per kept sample, with --cutoff (default: the white-noise "
                             "factor, rotorid.resampling.white_noise_factor)")
    parser.add_argument("--initial-states", nargs="*", default=(),
                        help="filter states whose initial values filter error estimates, "
                             "e.g. d_u d_w d_q")
    parser.add_argument("--longest-correlation", type=correlation_limits, default={},
                        metavar="T_w=3,...", help="filter error's longest correlation times "
                                                  "(its longest_correlation option)")
    parser.add_argument("--executor", default=None, choices=(None, "process"))
    parser.add_argument("--out", type=Path, default=Path("montecarlo-turbulence"))
    args = parser.parse_args(argv)

    results, table = {}, {}
    print(f"{args.runs} runs, {args.turbulence} turbulence, duration scale "
          f"{args.duration_scale}")
    for truth_name in args.truth:
        out = args.out / truth_name
        out.mkdir(parents=True, exist_ok=True)
        data, condition = flights(args.turbulence, args.duration_scale, out / "data",
                                  truth_name)
        if args.cutoff is not None:
            data = PreparedRealisations(data, functools.partial(
                decimated, factor=args.decimate, cutoff_hz=args.cutoff))
        structure = ModelStructure.populated(condition, "longitudinal")
        truth = truth_derivatives(rotorid.create("data-sources", "helisim"), condition,
                                  structure)
        for name, options in ESTIMATORS.items():
            if name == "filter-error" and args.initial_states:
                options = {**options, "initial_states": tuple(args.initial_states)}
            if name == "filter-error" and args.longest_correlation:
                options = {**options, "longest_correlation": args.longest_correlation}
            result = monte_carlo(structure, data, range(args.runs), estimator=name,
                                 estimator_options=options, truth=truth,
                                 executor=args.executor,
                                 case=f"hover-{args.turbulence}-{truth_name}-{name}")
            (out / f"{name}.json").write_text(json.dumps(result.as_dict(), indent=1))
            results[(truth_name, name)] = result
            table.update({(truth_name, name, key): row
                          for key, row in _report(truth_name, name, result, truth).items()})
    _figure(results, args.out / "turbulence_montecarlo.png")
    return table


def _report(truth_name: str, name: str, result, truth: dict) -> dict:
    """Print the key derivatives' statistics and the derivatives within 30 %, over all runs
    and over the converged ones; return the key rows."""
    print(f"\n{name} on the {truth_name} truth: converged {int(result.converged.sum())} of "
          f"{result.runs}")
    print(f"{'':8}{'truth':>9}{'mean':>11}{'std':>11}{'mean CR':>11}{'std/CR':>11}")
    rows = {}
    for key in KEY:
        i = result.parameter_names.index(key)
        rows[key] = {"mean": float(result.mean[i]), "std": float(result.std[i]),
                     "mean_cr": float(result.mean_cramer_rao[i]),
                     "ratio": float(result.ratio[i]), "truth": truth[key]}
        print(f"{key:8}{truth[key]:9.3f}{rows[key]['mean']:11.3f}{rows[key]['std']:11.4f}"
              f"{rows[key]['mean_cr']:11.4f}{rows[key]['ratio']:11.2f}")
    runs = {"all runs": result}
    if 1 < result.converged.sum() < result.runs:
        runs["converged runs"] = result.converged_runs()
    for label, part in runs.items():
        ratio = part.ratio[[part.parameter_names.index(n) for n in derivatives(part)]]
        finite = ratio[np.isfinite(ratio)]
        if not finite.size:
            print(f"{label}: no derivative has finite bounds in every run")
            continue
        print(f"{label}: std/CR of the {finite.size} derivatives with finite bounds: median "
              f"{np.median(finite):.2f}, range {finite.min():.2f}–{finite.max():.2f}, within "
              f"30 % {int(np.sum(np.abs(finite - 1) <= 0.3))}")
    return rows


def derivatives(result) -> list[str]:
    """The structure's derivatives among a result's parameters (not F, D, T, R)."""
    return [n for n in result.parameter_names if n[0] in "XZM" and n[1] == "_"]


def _figure(results, path: Path) -> None:
    """std/CR per derivative of the longitudinal structure, one bar per estimator and truth."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = derivatives(next(iter(results.values())))
    figure, axis = plt.subplots(figsize=(9, 4.4), layout="constrained")
    width = 0.8 / len(results)
    for k, ((truth_name, name), result) in enumerate(results.items()):
        ratio = [result.ratio[result.parameter_names.index(n)] for n in names]
        axis.bar(np.arange(len(names)) + (k + 0.5 - len(results) / 2) * width, ratio, width,
                 label=f"{name}, {truth_name} truth")
    axis.axhline(1.0, color="k", lw=0.8)
    axis.axhspan(0.7, 1.3, color="0.85", zorder=0, label="within 30 %")
    axis.set_yscale("log")
    axis.set_xticks(np.arange(len(names)), names, rotation=45)
    axis.set_ylabel("std of the runs / mean CR bound")
    figure.legend(loc="outside lower center", ncols=3, fontsize=8)
    figure.savefig(path, dpi=110)
    plt.close(figure)


if __name__ == "__main__":
    main()
