"""``rotorid coefficients``: an identified aeroplane model's derivatives as non-dimensional
coefficients.

Usage::

    rotorid coefficients RESULT.json --aircraft AIRCRAFT.toml [--csv OUT.csv] [--force]
                         [--model "with delays"|"no delays"] [--structure MODEL.toml]

``AIRCRAFT.toml`` gives the mass, inertia, reference geometry and air density in SI
(:data:`rotorid.model.coefficients.AIRCRAFT_FIELDS`, at the top level or in an ``[aircraft]``
table). The coefficients are taken at the model's trim airspeed, their Cramér-Rao bounds
propagated from the estimate's (:func:`rotorid.model.coefficients.non_dimensional`;
docs/export.md, "Non-dimensional coefficients").
"""

from __future__ import annotations

NAME = "coefficients"
HELP = ("an identified aeroplane model's derivatives as non-dimensional coefficients "
        "(Cm_alpha, Cl_p …) with their Cramér-Rao bounds")


def add_arguments(parser) -> None:
    from rotorid.estimation.result_file import STUDY_MODELS

    parser.add_argument("result", metavar="RESULT.json",
                        help="a `rotorid identify` result or a study's result.json")
    parser.add_argument("--aircraft", required=True, metavar="AIRCRAFT.toml",
                        help="mass_kg, wing_area_m2, span_m, chord_m, ixx_kgm2, iyy_kgm2, "
                             "izz_kgm2, ixz_kgm2, density_kgm3")
    parser.add_argument("--csv", metavar="OUT.csv", default=None,
                        help="also write the table as CSV")
    parser.add_argument("--force", action="store_true", help="overwrite OUT.csv if it exists")
    parser.add_argument("--model", choices=STUDY_MODELS, default=None,
                        help="which model of a study result (default: with delays)")
    parser.add_argument("--structure", metavar="MODEL.toml", default=None,
                        help="model file the estimate belongs to, when the result names none")


def run(args) -> int:
    from rotorid.cli.files import refuse_overwrite
    from rotorid.errors import ExitStatus, UsageError
    from rotorid.estimation.result_file import load_result
    from rotorid.io import atomic_write, read_toml
    from rotorid.model.coefficients import Aircraft, non_dimensional, trim_speed
    from rotorid.model.modelfile import load_model

    out = None if args.csv is None else refuse_overwrite(args.csv, args.force)
    table = read_toml(args.aircraft, "aircraft file")
    aircraft = Aircraft.from_mapping(table.get("aircraft", table), args.aircraft)
    structure = None if args.structure is None else load_model(args.structure)
    identified = load_result(args.result, args.model, structure)
    if identified.estimate is None and not identified.values:
        raise UsageError(f"{args.result}: the result holds no parameter values")
    rows, skipped = non_dimensional(identified.structure, identified.values, aircraft,
                                    identified.estimate)
    if not rows:
        raise UsageError(f"{args.result}: no derivative has a non-dimensional coefficient "
                         f"({'; '.join(skipped)})")
    speed = trim_speed(identified.structure)
    print(f"at V = {speed:.4g} m/s, q̄ = {0.5 * aircraft.density_kgm3 * speed**2:.5g} Pa; per "
          f"rad, speeds per V, rates per 2V/b (p, r) or 2V/c̄ (q); a speed's coefficient "
          f"includes 2·C0")
    width = max(len(row.name) for row in rows)
    print(f"{'coefficient':{width}}  {'value':>11}  {'CR bound':>9}  derivative")
    for row in rows:
        print(f"{row.name:{width}}  {row.value:11.4g}  {row.bound:9.3g}  {row.derivative}")
    for reason in skipped:
        print(f"left out: {reason}")
    if out is not None:
        lines = ["coefficient,derivative,value,cramer_rao"] + [
            f"{row.name},{row.derivative},{row.value!r},{row.bound!r}" for row in rows]
        atomic_write(out, "\n".join(lines) + "\n")
        print(f"written to {out}")
    return ExitStatus.OK
