"""``rotorid montecarlo``: repeat a case's final estimation with independent noise seeds."""

from __future__ import annotations

from pathlib import Path

from rotorid.cli.arguments import output_directory, run_count, seed

NAME = "montecarlo"
HELP = ("check the Cramér-Rao bounds: repeat a case's final estimation on data with "
        "independent noise seeds; per parameter the sample std next to the mean bound and the "
        "coverage of ±2 CR")


def add_arguments(parser) -> None:
    from rotorid.cli.commands.study import add_executor_arguments

    parser.add_argument("case", metavar="CASE", help="hover, forward or a case TOML file "
                                                     "(generated data)")
    parser.add_argument("--runs", type=run_count, required=True, help="number of runs (≥ 2)")
    parser.add_argument("--out", required=True, type=output_directory,
                        help="results directory; a finished study of the case there is reused "
                             "(else it is run first); montecarlo.json and the figure go to "
                             "OUT/CASE/")
    parser.add_argument("--quick", action="store_true", help="the case's --quick variant")
    parser.add_argument("--seed", type=seed,
                        help="first noise seed S; run k uses S + k (default: the case's seed)")
    parser.add_argument("--force", action="store_true",
                        help="overwrite the case's montecarlo.json if it exists")
    add_executor_arguments(parser, "runs")


def run(args) -> int:
    from rotorid.cli.files import refuse_overwrite
    from rotorid.executors import open_executor
    from rotorid.report.plots.case import save_figure
    from rotorid.report.plots.montecarlo import plot_monte_carlo
    from rotorid.study.case import FlightCase
    from rotorid.study.montecarlo import case_monte_carlo
    from rotorid.study.pipeline import log_progress

    case = FlightCase.load(args.case)
    if args.quick:
        case = case.quick()
    refuse_overwrite(Path(args.out) / case.name / "montecarlo.json", args.force)
    with open_executor(args.executor, args.scheduler) as executor:
        result = case_monte_carlo(case, args.runs, args.out, seed=args.seed,
                                  executor=executor, progress=log_progress)
    save_figure(plot_monte_carlo(result), Path(args.out) / case.name / "montecarlo")
    print(result.report())
    print(f"written: {args.out}/{case.name}/montecarlo.json, montecarlo.png, montecarlo.svg")
    return 0
