"""``rotorid linearize``: linear model of the Bo-105 truth model about a trim."""

from __future__ import annotations

import json



def add_arguments(parser) -> None:
    parser.add_argument("condition", nargs="?", choices=("hover", "forward"),
                        help="named flight condition (forward = 70 kt)")
    parser.add_argument("--airspeed-kt", type=float, help="horizontal airspeed in kt")
    parser.add_argument("--units", choices=("si", "flight-test"), default="si",
                        help="si: m/s, rad, per rad of blade angle (default); flight-test: "
                             "ft/s, deg, per %% stick")
    parser.add_argument("--full", action="store_true",
                        help="keep the flap and inflow states (no residualisation)")
    parser.add_argument("--inflow", choices=("baseline", "pitt-peters"), default="baseline",
                        help="main-rotor inflow model (default: baseline)")
    parser.add_argument("--json", action="store_true",
                        help="print JSON (states, controls, A, B, eigenvalues)")


def _table(row_names, column_names, matrix) -> str:
    width = max(12, *(len(c) + 2 for c in column_names))
    lines = [" " * 12 + "".join(f"{c:>{width}}" for c in column_names)]
    for name, row in zip(row_names, matrix):
        lines.append(f"{name:<12}" + "".join(f" {v:>{width - 1}.4g}" for v in row))
    return "\n".join(lines)


def run(args) -> int:
    from ..linearize import linearize
    from ..model import Bo105Model
    from ..parameters import Bo105Config
    from ..trim import resolve_airspeed, trim

    airspeed = resolve_airspeed(args.condition, args.airspeed_kt)
    model = Bo105Model(Bo105Config(inflow=args.inflow))
    linear = linearize(model, trim(model, airspeed), full=args.full, units=args.units)
    if args.json:
        print(json.dumps(linear.as_dict(), indent=2))
        return 0
    kind = "full" if linear.full else "residualised 6-DoF"
    print(f"{kind} linear model at {airspeed:g} kt, {linear.units} units")
    print("A =\n" + _table(linear.states, linear.states, linear.A))
    print("B =\n" + _table(linear.states, linear.controls, linear.B))
    print("eigenvalues:")
    for e in linear.eigenvalues:
        print(f"  {e.real:10.4f} {e.imag:+10.4f}i")
    return 0
