"""``rotorid study``: run the paper's pipeline for the hover and/or 70 kt cases, case files, or
a speed sweep."""

from __future__ import annotations

from pathlib import Path

from rotorid.cli.arguments import output_directory, seed

NAME = "study"
HELP = ("identify, reduce, add delays and verify: the built-in cases hover and forward "
        "(70 kt), all of them, a speed sweep, or case TOML files")


def add_arguments(parser) -> None:
    parser.add_argument("cases", nargs="+", metavar="CASE",
                        help="hover, forward, all, speed-sweep (one hover-pipeline case per "
                             "airspeed of --speeds), or a case TOML file")
    parser.add_argument("--out", required=True, type=output_directory, help="results directory")
    parser.add_argument("--quick", action="store_true",
                        help="reduced but honest run: shorter records, reduction stopped by "
                             "the criteria (hover: about 110 s on 2 cores)")
    parser.add_argument("--seed", type=seed, help="noise seed of generated data (≥ 0)")
    parser.add_argument("--speeds", help="airspeeds of speed-sweep in kt: '0,40,80' or "
                                         "START:STOP:STEP (default 0:120:10)")
    parser.add_argument("--template", default="hover",
                        help="case that speed-sweep repeats at each airspeed: a built-in case "
                             "or a case TOML file with generated data (default hover)")
    parser.add_argument("--resume", action="store_true",
                        help="reuse the finished steps found in --out")
    add_executor_arguments(parser, "cases")
    parser.add_argument("--no-figures", action="store_true", help="skip figures and report")


def add_executor_arguments(parser, what: str) -> None:
    """``--executor`` and ``--scheduler`` (shared with ``rotorid montecarlo``)."""
    from rotorid.executors import KINDS

    parser.add_argument("--executor", choices=KINDS, default="process",
                        help=f"where the independent {what} are computed: serial (this "
                             f"process), process (a local process pool, the default) or dask "
                             f"(a Dask cluster; pip install 'rotorid[dask]')")
    parser.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://HOST:8786")


def expand_cases(names, speeds: str | None = None, template: str = "hover"):
    """Flight cases of the command line (``all`` and ``speed-sweep`` expanded), and the names
    of the speed-sweep cases among them."""
    from rotorid.errors import UsageError
    from rotorid.study.case import BUILTIN, FlightCase
    from rotorid.study.sweep import DEFAULT_SPEEDS, FAMILY, speed_sweep

    if speeds is not None and FAMILY not in names:
        raise UsageError(f"--speeds only applies to the {FAMILY} case family; add {FAMILY} to "
                         f"the cases")
    cases, swept = [], []
    for name in (list(BUILTIN) if list(names) == ["all"] else names):
        if name == FAMILY:
            family = speed_sweep(speeds or DEFAULT_SPEEDS, template)
            cases.extend(family)
            swept.extend(case.name for case in family)
        else:
            cases.append(FlightCase.load(name))
    return cases, swept


def claims_summary(result) -> str:
    """One line: how many of the case's claims (the paper's, or the guidelines for a case
    without a truth model) hold, and which do not."""
    from rotorid.study.claims import case_claims, claims_tally, claims_title

    claims = case_claims(result)
    decided, failed = claims_tally(claims)
    line = (f"{claims_title(result).removeprefix('The ')}: {len(decided) - len(failed)}/"
            f"{len(decided)} hold, {len(claims) - len(decided)} not checked")
    if failed:
        line += "; not: " + "; ".join(f"{c.claim} ({c.evidence})" for c in failed)
    return line


def run(args) -> int:
    from rotorid.executors import open_executor
    from rotorid.study.pipeline import Study
    from rotorid.report.html import StudyReport
    from rotorid.report.plots.case import save_figure
    from rotorid.report.plots.sweep import plot_speed_sweep
    from rotorid.study.sweep import FAMILY, sweep_points, write_sweep_summary

    cases, swept = expand_cases(args.cases, args.speeds, args.template)
    if args.quick:
        for case in cases:
            if not case.quick_settings:
                print(f"{case.name}: no [quick] table, so --quick leaves the case as it is")
        cases = [case.quick() for case in cases]
    if args.seed is not None:
        cases = [case.with_seed(args.seed) for case in cases]
    with open_executor(args.executor, args.scheduler) as executor:
        results = Study(cases, args.out, executor=executor, resume=args.resume,
                        report_writer=None if args.no_figures else StudyReport()).run()
    for name, result in results.items():
        path = result.path
        print(f"{name}: {path.selected.n_parameters} parameters after removing "
              f"{len(path.removed)} (step {path.selected_index} of {len(path.steps) - 1}); "
              f"{result.rmse_summary()}")
        print(f"  {claims_summary(result)}")
    if swept:
        points = sweep_points({n: results[n] for n in swept})
        written = [write_sweep_summary(points, args.out),
                   *save_figure(plot_speed_sweep(points), Path(args.out) / FAMILY)]
        print(f"speed sweep: {', '.join(str(p) for p in written)}")
    if not args.no_figures:
        print(f"report: {args.out}/report.html")
    return 0
