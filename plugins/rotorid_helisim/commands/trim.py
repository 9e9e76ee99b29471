"""``rotorid trim``: trim the nonlinear Bo-105 truth model and print the trim."""

from __future__ import annotations

import json



def add_arguments(parser) -> None:
    parser.add_argument("condition", nargs="?", choices=("hover", "forward"),
                        help="named flight condition (forward = 70 kt)")
    parser.add_argument("--airspeed-kt", type=float, help="horizontal airspeed in kt")
    parser.add_argument("--climb-rate", type=float, default=0.0, help="climb rate in m/s")
    parser.add_argument("--sideslip", type=float, default=0.0, help="sideslip angle in deg")
    parser.add_argument("--inflow", choices=("baseline", "pitt-peters"), default="baseline",
                        help="main-rotor inflow model (default: baseline)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")


def run(args) -> int:
    from ..model import Bo105Model
    from ..parameters import Bo105Config
    from ..trim import resolve_airspeed, trim

    airspeed = resolve_airspeed(args.condition, args.airspeed_kt)
    model = Bo105Model(Bo105Config(inflow=args.inflow))
    result = trim(model, airspeed, args.climb_rate, args.sideslip)
    print(json.dumps(result.as_dict(), indent=2) if args.json else result.report())
    return 0
