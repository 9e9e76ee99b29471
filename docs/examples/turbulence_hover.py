"""Output error against filter error on hover data flown in turbulence.

The helisim truth model is trimmed in hover and flown through the 16 identification multisteps
(3211 and 2311, both directions, every control) twice with the same seed: in still air and in
Dryden turbulence (``moderate`` by default: σ_u = σ_v = 2.65 m/s, σ_w = 1.54 m/s, L_u = L_v =
154 m, L_w = 30.5 m, rotational gusts from the 9.8 m rotor span, convected at 5 m/s;
docs/truth-model.md). The fully populated 60-derivative structure with the paper's eight
delays (start 0.05 s, at most 0.3 s) is fitted to each set with output error and with filter
error, and the key derivatives are printed beside two references:

* the truth model's residualised 6-DoF linearisation (the quasi-steady target, which a
  rigid-body model fitted to rotor-affected data does not reach even in still air), and
* the same estimator's still-air estimate (the equivalent system the data support without
  turbulence): the difference is the bias the turbulence causes.

Differences are given in the turbulent fit's Cramér-Rao bounds (CR) and in %. Run from the
repository root::

    python docs/examples/turbulence_hover.py [--turbulence light|moderate] [--seed N] [--quick]

``--quick`` shortens the records to 60 %.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
import rotorid
from rotorid import FlightCondition, ModelStructure
from rotorid.errors import IdentifiabilityWarning

KEY = ("L_p", "M_q", "L_lat", "M_long", "N_r", "N_ped", "Z_w", "Z_coll")
ESTIMATORS = ("output-error", "filter-error")


def data_sets(turbulence: str, seed: int, quick: bool):
    """(still air, turbulent) identification sets and the hover trim condition."""
    source = rotorid.create("data-sources", "helisim")
    settings = {"condition": "hover", "kinds": ["3211", "2311"], "seed": seed,
                "duration_scale": 0.6 if quick else 1.0}
    still = source.generate(settings)
    turbulent = source.generate({**settings, "turbulence": turbulence})
    first = still[0].metadata
    condition = FlightCondition.from_airspeed(0.0, first["trim_theta_deg"],
                                              first["trim_phi_deg"])
    return still, turbulent, condition, source


def truth_values(source, structure: ModelStructure) -> dict[str, float]:
    """The truth model's residualised linearisation as derivative values (structure units)."""
    linear = source.linearize(0.0, units=structure.units.name)
    a = np.asarray(linear.A) - structure.known_state_matrix()
    b = np.asarray(linear.B)
    values = {}
    for d in structure.derivatives:
        row = structure.states.index(structure.equation_of(d))
        values[d.name] = float(b[row, structure.controls.index(d.variable)]
                               if structure.is_control(d)
                               else a[row, structure.states.index(d.variable)])
    return values


def fit(name: str, structure, maneuvers):
    estimator = rotorid.create("estimators", name)
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        estimate = estimator.estimate(structure, maneuvers)
    return estimate, time.perf_counter() - started


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--turbulence", default="moderate", choices=("light", "moderate"))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)

    still, turbulent, condition, source = data_sets(args.turbulence, args.seed, args.quick)
    structure = ModelStructure.six_dof(condition).with_delays(initial=0.05, upper=0.3)
    truth = truth_values(source, structure)
    fits = {(name, air): fit(name, structure, data) for name in ESTIMATORS
            for air, data in (("still", still), ("turbulent", turbulent))}
    for (name, air), (estimate, seconds) in fits.items():
        print(f"{name:>12} {air:>9}: {seconds:5.1f} s, converged {estimate.converged}, "
              f"{estimate.iterations} iterations")
    print(f"\n{'':8}{'truth':>9}" + "".join(f"{name:>46}" for name in ESTIMATORS))
    print(f"{'':17}" + f"{'still':>10}{args.turbulence + ' ± CR, shift':>36}" * len(ESTIMATORS))
    table = {}
    for key in KEY:
        row = f"{key:8}{truth[key]:9.3f}"
        for name in ESTIMATORS:
            calm = fits[(name, "still")][0]
            rough = fits[(name, "turbulent")][0]
            value, bound = rough.value(key), rough.cramer_rao[rough.index(key)]
            shift = (value - calm.value(key)) / bound
            versus_truth = (value - truth[key]) / bound
            table[(name, key)] = {"value": value, "cr": bound, "still": calm.value(key),
                                  "shift_cr": shift, "truth_cr": versus_truth}
            row += (f"{calm.value(key):10.3f}{value:16.3f} ±{bound:7.3f} "
                    f"{shift:+7.1f} CR")
        print(row)
    print("\nvalue ± CR of the turbulent fit, then its shift from the same estimator's "
          "still-air value in CR (0 where the bound is infinite); relative shifts:")
    for name in ESTIMATORS:
        relative = np.array([abs(table[(name, k)]["value"] / table[(name, k)]["still"] - 1)
                             for k in KEY])
        print(f"{name}: |shift| median {100 * np.median(relative):.0f} %, "
              f"within 10 % for {int(np.sum(relative <= 0.1))} of {len(KEY)}")
    return table


if __name__ == "__main__":
    main()
