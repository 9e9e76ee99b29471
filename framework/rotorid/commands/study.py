"""``rotorid study``: run the paper's pipeline for the hover and/or 70 kt cases."""

from __future__ import annotations

NAME = "study"
HELP = ("identify, reduce, add delays and verify: the built-in cases hover and forward "
        "(70 kt), all of them, or case TOML files")


def add_arguments(parser) -> None:
    parser.add_argument("cases", nargs="+", metavar="CASE",
                        help="hover, forward, all, or a case TOML file")
    parser.add_argument("--out", required=True, help="results directory")
    parser.add_argument("--quick", action="store_true",
                        help="reduced but honest run: shorter records, reduction stopped by "
                             "the criteria (a few minutes on 2 cores)")
    parser.add_argument("--seed", type=int, help="noise seed of generated data")
    parser.add_argument("--resume", action="store_true",
                        help="reuse the finished steps found in --out")
    parser.add_argument("--executor", choices=("serial", "process", "dask"), default="process",
                        help="how independent cases run (default: a local process pool)")
    parser.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://HOST:8786")
    parser.add_argument("--no-figures", action="store_true", help="skip figures and report")


def _executor(args):
    if args.executor == "serial":
        return None
    if args.executor == "process":
        return "process"
    from ..errors import PluginError

    if not args.scheduler:
        raise PluginError("--executor dask needs --scheduler tcp://HOST:PORT")
    try:
        from dask.distributed import Client
    except ImportError:
        raise PluginError("Dask is not installed; pip install 'rotorid[dask]'") from None
    return Client(args.scheduler).get_executor()


def run(args) -> int:
    from ..flightcase import BUILTIN, FlightCase
    from ..study import Study

    names = list(BUILTIN) if args.cases == ["all"] else args.cases
    cases = [FlightCase.load(name) for name in names]
    if args.quick:
        cases = [case.quick() for case in cases]
    if args.seed is not None:
        cases = [case.with_seed(args.seed) for case in cases]
    results = Study(cases, args.out, executor=_executor(args), resume=args.resume,
                    figures=not args.no_figures).run()
    for name, result in results.items():
        path = result.path
        delayed = result.estimates["with delays"]
        print(f"{name}: {path.selected.n_parameters} parameters after removing "
              f"{len(path.removed)} (step {path.selected_index} of {len(path.steps) - 1}); "
              f"RMSE without delays {result.estimates['no delays'].rmse:.4f}, "
              f"with delays {delayed.rmse:.4f}")
    if not args.no_figures:
        print(f"report: {args.out}/report.html")
    return 0
