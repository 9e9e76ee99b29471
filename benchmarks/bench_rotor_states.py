"""The hybrid models with measured rotor angles on the truth model's data, against the hybrid
fit without them, same run.

The problem: the truth model's paper-size identification data of one condition (16
closed-loop 3211/2311 multisteps of 15 s at 50 Hz) flown with ``rotor_channels`` (coning and
tip-path-plane tilts measured, 0.1 deg noise). In the same run, each fit started from the one
before (docs/hybrid.md):

* 6-DoF: the fully populated six-dof structure from zero;
* hybrid and hybrid-flap: :func:`rotorid.model.hybrid.hybrid_from_six_dof` on that estimate,
  the tilts unmeasured and measured;
* hybrid-inflow-flap: :func:`rotorid.model.coning_inflow.coning_inflow_from_hybrid` on the
  hybrid-flap estimate (coning measured, induced velocity not).

Printed per fit: wall time, parameters, iterations, RMSE and det R; then the flap, coning,
inflow and heave terms with their Cramér-Rao bounds beside the truth model's reference (its
full linearisation with every state the structure lacks residualised). BLAS runs on one
thread.

    .venv/bin/python benchmarks/bench_rotor_states.py [--condition hover|forward]
                                                      [--collective-step S]
                                                      [--rotor-noise DEG] [--cache DIR]
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import tempfile  # noqa: E402

from bench_hybrid import timed_fit  # noqa: E402
from rotorid import FlightCondition, ModelStructure  # noqa: E402
from rotorid.model.coning_inflow import coning_inflow_from_hybrid  # noqa: E402
from rotorid.model.hybrid import hybrid_from_six_dof  # noqa: E402
from rotorid.study.truth import truth_derivatives  # noqa: E402
from rotorid_helisim.datasets import DataSetConfig  # noqa: E402
from rotorid_helisim.source import HelisimSource  # noqa: E402

#: Terms set beside the reference, per model.
KEY = {"hybrid": ("Bc_beta1c", "Bs_beta1s", "M_beta1c", "L_beta1s"),
       "hybrid-flap": ("Bc_beta1c", "Bs_beta1s", "M_beta1c", "L_beta1s"),
       "hybrid-inflow-flap": ("Bc_beta1c", "M_beta1c", "B0_beta0", "B0_w", "B0_coll", "Vi_vi",
                              "Vi_w", "Vi_beta0", "Z_beta0", "Z_vi", "Z_w")}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--condition", choices=("hover", "forward"), default="hover")
    parser.add_argument("--collective-step", type=float, default=None, metavar="S",
                        help="multistep time step of the collective, s (default the data "
                             "set's 1 s, which hardly excites the coning and inflow)")
    parser.add_argument("--rotor-noise", type=float, default=None, metavar="DEG",
                        help="σ of the rotor channels, deg (default the data set's 0.1)")
    parser.add_argument("--cache", default=None, help="data cache directory (default: a "
                                                      "temporary one)")
    args = parser.parse_args(argv)

    steps = {} if args.collective_step is None else {"coll": args.collective_step}
    noise = ({} if args.rotor_noise is None
             else dict.fromkeys(("beta0", "beta1c", "beta1s"), args.rotor_noise))
    config = DataSetConfig.for_condition(args.condition, kinds=("3211", "2311"),
                                         rotor_channels=True, step_width=steps, noise=noise)
    with tempfile.TemporaryDirectory() as scratch:
        source = HelisimSource(cache_dir=args.cache or scratch)
        ident = source.generate(config)
    trim = source.trim(config.airspeed_kt)
    condition = FlightCondition.from_airspeed(trim.airspeed_kt, trim.theta_deg, trim.phi_deg)
    print(f"problem: {args.condition}, {len(ident)} maneuvers × {ident[0].n_samples} samples, "
          f"collective step {config.step_width['coll']} s, rotor channels' σ "
          f"{config.noise.rotor_vector[0]} deg")

    six_dof = ModelStructure.six_dof(condition)
    seconds, six_estimate = timed_fit(six_dof, ident)
    fits = {"6-DoF": (six_dof, seconds, six_estimate)}
    for template in ("hybrid", "hybrid-flap"):
        structure = hybrid_from_six_dof(six_dof, six_estimate.values, template=template)
        fits[template] = (structure, *timed_fit(structure, ident))
    flap, _, flap_estimate = fits["hybrid-flap"]
    structure = coning_inflow_from_hybrid(flap, flap_estimate.values,
                                          source.plant.config.radius)
    fits["hybrid-inflow-flap"] = (structure, *timed_fit(structure, ident))

    for label, (structure, seconds, fit) in fits.items():
        print(f"{label:18s}: {seconds:6.2f} s, {structure.n_parameters} parameters, "
              f"{fit.iterations} iterations, converged {fit.converged}, RMSE {fit.rmse:.4f}, "
              f"det R {fit.cost:.3e}")
    for label, names in KEY.items():
        structure, _, fit = fits[label]
        reference = truth_derivatives(source, condition, structure)
        print(label)
        for name in names:
            value, bound = fit.value(name), fit[name].cramer_rao
            print(f"  {name:10s} {value:9.4f} ± {bound:.4f}  reference {reference[name]:9.4f}"
                  f"  ({value / reference[name] - 1:+.1%})")


if __name__ == "__main__":
    main()
