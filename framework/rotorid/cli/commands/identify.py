"""``rotorid identify``: estimate the parameters of a model file from maneuver files.

Usage::

    rotorid identify MODEL.toml DATA... [--estimator output-error] [--out result.json]
                     [--outputs ax,az,...] [--noise full|diagonal] [--max-iterations N]
                     [--start auto|initial|equation-error|output-error]
                     [--enforce-signs] [--output-biases] [--initial-states]
                     [--coloured-residuals]
                     [--hold zoh|foh] [--trim first-second|CH=VALUE,...]
                     [--resample linear|decimate] [--sample-time S]
                     [--actuator-lag S [--actuator-inputs long,lat]]
                     [--process-noise w,q|none] [--disturbances p,q,r] [--gusts u,v,w]
                     [--longest-correlation T_w=3,...] [--update-every N] [--states DIR]
                     [--pairs q/long,p/lat] [--band LOW,HIGH] [--quiet] [--strict] [--force]

``MODEL.toml`` is a model file (:mod:`rotorid.model.modelfile`); its initial values are the start
values (all zero: the estimator chooses its own start, see docs/estimation.md). MODEL may
instead name a model of one's own by reference, ``package.module:Name`` or
``path/to/file.py:Name`` (:mod:`rotorid.model.reference`, docs/models.md); the files keep the
columns it reads (an :class:`~rotorid.estimation.integrated.IntegratedModel`'s ``columns``:
the file's own names, such as ``VTAS_mps``, that its channel map links to its signals), and
the model converts them from the units its map declares. DATA are
maneuver files (CSV, NPZ, MAT), directories or glob patterns of the ``files`` data source; they
are converted to the model's unit system, after the trim removal and resampling asked for
(:mod:`rotorid.ingestion`), and through the actuators' known lag with ``--actuator-lag``
(:mod:`rotorid.actuators`; recorded as ``actuator_lag_s``, ``rotorid verify`` then lags the
sweeps alike). The trim removal and resampling are recorded too (``ingestion``), and
``rotorid verify`` reads the sweeps with them; so are the estimator options the command line
set (``estimator_options``: the noise model, outputs, start …), to repeat the fit.
``--process-noise``, ``--disturbances``, ``--gusts``, ``--longest-correlation`` and
``--update-every`` set the ``filter-error`` estimator's noise model (docs/estimation.md,
"Filter error"); with another estimator they are a usage error that
says to add ``--estimator filter-error``. ``--states DIR`` writes the filter's state
estimates x̂(n|n) of every maneuver (the states the outputs see, then the disturbances
``d_<state>`` and gusts ``g_<state>``: the turbulence as the identified model sees it) as
``DIR/<maneuver>.csv`` maneuver files (header ``content: state estimates``, ``state_units``,
``standard_deviation``) and ``DIR/<maneuver>.png`` figures
(:mod:`rotorid.estimation.state_estimates`); a file of those names already in DIR (a data
directory given by mistake) stops the command before the fit, unless ``--force``. The report goes to stdout; stderr gets one line per
accepted iteration (unless ``--quiet``; an observer plugin of the
``rotorid_estimation_iteration`` hook, so it works with any estimator that reports through
it), the kinematic consistency fits and one line per warning: the sanity checks of the data
before the fit (:mod:`rotorid.estimation.sanity`; the derivatives of an input that never moves
are dropped before the fit), an unidentifiable parameter combination. The report ends with the
data checks' warnings again. The estimate is written atomically as JSON (the format of
:meth:`rotorid.estimation.estimate.Estimate.as_dict`, plus ``data_warnings``: the text of each
warning about the data before the fit, and ``structure``: the model file's path relative
to the JSON file, so that ``rotorid verify RESULT.json SWEEPS...`` finds it; for a reference,
``model``: the reference, a file's path made relative the same way).
"""

from __future__ import annotations

import json
import math
import os
import sys
import warnings
from pathlib import Path

from rotorid.cli.arguments import (add_ingestion_arguments, correlation_limits,
                                   ingestion_settings, names, output_directory, output_file,
                                   seconds)
from rotorid.plugin.hookspecs import hookimpl
from rotorid.progress import counted

NAME = "identify"
HELP = ("estimate the derivatives and delays of a model file from maneuver files; print the "
        "report and write the estimate as JSON")


def _actuator_inputs(args) -> list[str] | None:
    """The inputs of ``--actuator-inputs``, or None (every input)."""
    if args.actuator_inputs is None:
        return None
    return names(args.actuator_inputs)


def _actuated(maneuvers, args):
    """``maneuvers`` with the inputs through ``--actuator-lag`` (unchanged without it)."""
    from rotorid.actuators import lagged_inputs
    from rotorid.errors import UsageError

    if args.actuator_lag is None:
        if args.actuator_inputs is not None:
            raise UsageError("--actuator-inputs needs --actuator-lag, the lag's time constant")
        return maneuvers
    return lagged_inputs(maneuvers, args.actuator_lag, _actuator_inputs(args))


def add_arguments(parser) -> None:
    parser.add_argument("model", metavar="MODEL.toml", help="model file, or a model of one's own "
                        "by reference: package.module:Name or path/to/file.py:Name")
    parser.add_argument("data", nargs="+", metavar="DATA",
                        help="maneuver files (CSV/NPZ/MAT), directories or glob patterns")
    parser.add_argument("--estimator", default="output-error",
                        help="estimator plugin (default output-error; see `rotorid plugins`)")
    parser.add_argument("--out", default="result.json", metavar="RESULT.json", type=output_file,
                        help="where to write the estimate (default ./result.json)")
    parser.add_argument("--outputs", default=None, metavar="OUT1,OUT2,...",
                        help="comma-separated outputs used in the cost (default: all of the "
                             "model's)")
    parser.add_argument("--noise", choices=("full", "diagonal"), default=None,
                        help="noise covariance R: full (default) or diagonal")
    parser.add_argument("--max-iterations", type=int, default=None, metavar="N",
                        help="iteration limit of the final run (default: the estimator's)")
    parser.add_argument("--start", default=None,
                        choices=("auto", "initial", "equation-error", "output-error"),
                        help="where the derivatives start (default auto: the model file's "
                             "initial values, or equation error when all are zero); "
                             "output-error (filter error only) starts from an output-error "
                             "fit, for data with little process noise")
    parser.add_argument("--enforce-signs", action="store_true",
                        help="use the derivatives' sign priors as bounds")
    parser.add_argument("--output-biases", action="store_true",
                        help="estimate one constant bias per maneuver and output")
    parser.add_argument("--initial-states", action="store_true",
                        help="estimate the initial perturbation state of every maneuver")
    parser.add_argument("--coloured-residuals", action="store_true",
                        help="output error: Cramér-Rao bounds for residuals correlated in "
                             "time (Morelli & Klein), not only white ones")
    parser.add_argument("--hold", choices=("zoh", "foh"), default="zoh",
                        help="input hold between samples (default zoh)")
    add_ingestion_arguments(parser)
    parser.add_argument("--actuator-lag", type=seconds, default=None, metavar="S",
                        help="the actuators' known first-order time constant in s: the inputs "
                             "go through that lag before the fit (rotorid.actuators), and the "
                             "result records it for rotorid verify")
    parser.add_argument("--actuator-inputs", default=None, metavar="IN1,IN2",
                        help="the inputs --actuator-lag acts on (default every input)")
    parser.add_argument("--process-noise", default=None, metavar="w,q|none",
                        help="filter error: the states white process noise enters (default "
                             "those of the force and moment equations; none for no white "
                             "noise)")
    parser.add_argument("--disturbances", default=None, metavar="p,q,r",
                        help="filter error: states whose equations get a Gauss-Markov "
                             "acceleration (turbulence's rotational gusts, say)")
    parser.add_argument("--gusts", default=None, metavar="u,v,w",
                        help="filter error: velocities that get a Gauss-Markov gust acting "
                             "through their derivatives")
    parser.add_argument("--longest-correlation", type=correlation_limits, default=None,
                        metavar="T_w=3,...",
                        help="filter error: the longest a disturbance's (T_<state>) or gust's "
                             "(Tg_<state>) correlation time may become, s (a fifth of the "
                             "shortest record: docs/estimation.md)")
    parser.add_argument("--update-every", type=int, default=None, metavar="N",
                        help="filter error: a measurement update at every N-th sample only "
                             "(for records low-passed to the model's band)")
    parser.add_argument("--pairs", default=None, metavar="q/long,p/lat",
                        help="frequency response: the output/input pairs fitted (default every "
                             "output over every swept input)")
    parser.add_argument("--band", default=None, metavar="OMEGA_MIN,OMEGA_MAX",
                        help="frequency response: the frequencies in rad/s a pair's fit may "
                             "reach (default its whole coherent range)")
    parser.add_argument("--states", default=None, metavar="DIR", type=output_directory,
                        help="filter error: write the filter's state estimates (the states, "
                             "the gusts and disturbances) of every maneuver to DIR as CSV "
                             "maneuver files and PNG figures")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress lines on stderr (warnings stay)")
    parser.add_argument("--force", action="store_true",
                        help="overwrite RESULT.json (and --states' files) if it exists")
    parser.add_argument("--strict", action="store_true",
                        help="exit with status 4 when the fit does not converge (the estimate "
                             "is written all the same)")


def _frequency_options(args) -> dict:
    """``--pairs`` and ``--band``, the frequency-response estimator's (a usage error with
    another estimator or a band that is not two increasing frequencies)."""
    from rotorid.errors import UsageError

    given = {flag: getattr(args, flag) for flag in ("pairs", "band")
             if getattr(args, flag) is not None}
    if given and args.estimator != "frequency-response":
        flags = ", ".join(f"--{flag}" for flag in given)
        raise UsageError(f"{flags}: the frequency-response estimator's; add --estimator "
                         f"frequency-response")
    options: dict = {}
    if "pairs" in given:
        options["pairs"] = tuple(names(given["pairs"]))
    if "band" in given:
        try:
            low, high = (float(v) for v in given["band"].split(","))
        except ValueError:
            low = high = math.nan
        if not (0 <= low < high):
            raise UsageError(f"--band needs two frequencies in rad/s, lowest first, e.g. "
                             f"--band 0.5,12; got {given['band']!r}")
        options["band"] = (low, high)
    return options


def _modes_report(structure, estimate) -> str:
    """The identified model's modes, one line each (:mod:`rotorid.model.modes`)."""
    from rotorid.model.modes import modes

    values = [estimate[name].value for name in structure.parameter_names]  # not noise, records
    lines = ["[[Modes]] (A with delays set to zero, slowest first)"]
    for mode in modes(structure, values):
        lines.append(f"  {mode.eigenvalue_text:<22} {mode.describe():<32} "
                     f"{', '.join(mode.states)}")
    return "\n".join(lines)


def _check_outputs(chosen, outputs, model) -> None:
    """A :class:`UsageError` when ``--outputs`` names ``chosen`` outputs that ``model`` (its
    outputs ``outputs``) lacks."""
    from rotorid.errors import UsageError

    unknown = [name for name in chosen if name not in outputs]
    if unknown:
        raise UsageError(f"argument --outputs: {', '.join(map(repr, unknown))} is no output of "
                         f"{model}; its outputs are {', '.join(outputs)}")


#: The options of filter error's noise model and update rate (another estimator has none).
FILTER_ERROR_FLAGS = ("process_noise", "disturbances", "gusts", "longest_correlation",
                      "update_every")


def _options(args) -> dict:
    """Estimator options the user set explicitly (the estimator's defaults stand otherwise)."""
    from rotorid.errors import UsageError
    from rotorid.plugin.manager import registry

    options: dict = {}
    if args.outputs is not None:
        outputs = tuple(names(args.outputs))
        if not outputs:
            raise UsageError("--outputs names no output; give e.g. --outputs q,theta,p")
        options["outputs"] = outputs
    if args.noise is not None:
        options["noise"] = args.noise
    if args.start is not None:
        if args.start == "output-error" and args.estimator != "filter-error":
            raise UsageError("--start output-error starts filter error from an output-error "
                             "fit; with another estimator choose auto, initial or "
                             "equation-error")
        options["start"] = args.start
    if args.max_iterations is not None:
        if args.max_iterations < 1:
            raise UsageError(f"--max-iterations must be at least 1, got {args.max_iterations}")
        options["max_iterations"] = args.max_iterations
    if args.enforce_signs:
        options["enforce_signs"] = True
    if args.output_biases:
        options["output_biases"] = True
    if args.initial_states:
        options["initial_states"] = True
    if args.coloured_residuals:
        if args.estimator != "output-error":
            raise UsageError("--coloured-residuals widens output error's bounds; filter "
                             "error models the correlation as process noise instead")
        options["coloured_residuals"] = True
    options.update(_frequency_options(args))
    noise_model = [flag for flag in FILTER_ERROR_FLAGS if getattr(args, flag) is not None]
    known = registry("estimators")
    if args.estimator not in known:
        raise UsageError(f"argument --estimator: no estimator named {args.estimator!r}; "
                         f"available: {', '.join(known)} (see `rotorid plugins`)")
    if noise_model and args.estimator != "filter-error":
        given = ", ".join("--" + flag.replace("_", "-") for flag in noise_model)
        raise UsageError(f"{given}: filter error's noise model; add --estimator filter-error "
                         f"(the {args.estimator} estimator has no process noise)")
    for flag in FILTER_ERROR_FLAGS[:3]:
        value = getattr(args, flag)
        if value is not None:
            options[flag] = _states(value, flag)
    if args.longest_correlation is not None:
        options["longest_correlation"] = args.longest_correlation
    if args.update_every is not None:
        if args.update_every > 1 and args.resample == "decimate":
            raise UsageError("give --resample decimate or --update-every, not both: the "
                             "decimated records hold one sample per update already, and "
                             "--update-every is for records low-passed beforehand that keep "
                             "every sample (rotorid.resampling.low_passed)")
        if args.update_every < 1:
            raise UsageError(f"--update-every must be at least 1, got {args.update_every}")
        options["update_every"] = args.update_every
    return options


def _states(value: str, flag: str) -> tuple[str, ...]:
    """The states of a comma-separated ``--process-noise``-style list; ``none`` is none."""
    from rotorid.errors import UsageError

    if value.strip().lower() == "none":
        return ()
    states = tuple(names(value))
    if not states:
        option = "--" + flag.replace("_", "-")
        raise UsageError(f"{option} names no state; give e.g. {option} w,q, or none")
    return states


class ProgressPrinter:
    """Observer plugin: one stderr line per accepted iteration (stage, iteration, cost, RMSE)."""

    @hookimpl
    def rotorid_estimation_iteration(self, stage, iteration, cost, rmse):
        prefix = f"[{stage}] " if stage else ""
        print(f"{prefix}iteration {iteration:3d}  cost {cost:.6g}  RMSE {rmse:.5g}",
              file=sys.stderr, flush=True)


def _estimator(name: str, options: dict):
    from rotorid.errors import EstimationError
    from rotorid.plugin.manager import create

    try:
        return create("estimators", name, **options)
    except TypeError as error:
        raise EstimationError(f"estimator {name!r} does not accept the options "
                              f"{', '.join(sorted(options))}: {error}") from None


def _record(estimate, model: str, out: Path, data_warnings: list[str]) -> dict:
    """The estimate's record, the warnings of the checks of the data before the fit
    (``data_warnings``) and where its model came from, paths relative to the JSON file:
    ``structure`` (a model file) or ``model`` (a reference)."""
    from rotorid.model.reference import is_model_reference

    record = {**estimate.as_dict(), "data_warnings": data_warnings}
    if not is_model_reference(model):
        record["structure"] = os.path.relpath(Path(model).resolve(), out.resolve().parent)
        return record
    where, _, name = model.rpartition(":")
    if where.endswith(".py"):
        where = os.path.relpath(Path(where).resolve(), out.resolve().parent)
    record["model"] = f"{where}:{name}"
    return record


def _print_warnings(caught) -> None:
    for warning in caught:
        print(f"rotorid identify: warning: {warning.message}", file=sys.stderr, flush=True)


def data_warnings_report(messages: list[str]) -> str:
    """The report's section on the checks of the data before the fit: each warning, or that
    there was none."""
    if not messages:
        return "Data checks before the fit: no warning"
    return "\n".join([f"Data checks before the fit: {len(messages)} warning(s)",
                      *(f"    {message}" for message in messages)])


def run(args) -> int:
    from rotorid.cli.files import load_maneuvers, refuse_overwrite
    from rotorid.errors import (DataFileError, EstimationError, ExitStatus, MissingFileError,
                                RotoridWarning, UsageError)
    from rotorid.estimation.data_checks import check_fit_data
    from rotorid.estimation.estimate import Estimate
    from rotorid.estimation.result_file import INGESTION_SETTINGS
    from rotorid.estimation.sanity import check_before_fit, checks_report
    from rotorid.io import atomic_write
    from rotorid.model.modelfile import load_channel_map, load_model
    from rotorid.model.reference import is_model_reference, load_model_reference
    from rotorid.plugin.manager import new_plugin_manager, using
    from rotorid.plugin.returns import returned

    by_reference = is_model_reference(args.model)
    model = load_model_reference(args.model) if by_reference else load_model(args.model)
    if not by_reference and not model.parameter_names:
        raise DataFileError(f"{args.model}: the model has no free parameter to estimate (every "
                            f"derivative is fixed or none is declared); declare at least one "
                            f"derivative without a fixed value")
    if args.outputs is not None:
        _check_outputs(names(args.outputs), model.output_names if by_reference
                       else model.outputs, args.model)
    out = refuse_overwrite(args.out, args.force)
    if not out.parent.is_dir():
        raise MissingFileError(f"cannot write {out}: directory {out.parent} does not exist")
    manager = new_plugin_manager([] if args.quiet else [ProgressPrinter()])
    with using(manager):
        options = _options(args)
        estimator = _estimator(args.estimator, options)
        if args.states is not None and not hasattr(estimator, "state_estimates"):
            raise UsageError(f"--states: estimator {args.estimator!r} gives no state "
                             f"estimates; use --estimator filter-error")
        if hasattr(estimator, "check_structure"):     # options against the model, before data
            try:
                estimator.check_structure(model)
            except EstimationError as error:
                raise UsageError(_as_flags(str(error))) from None
        with warnings.catch_warnings(record=True) as found, checks_report(shown=not args.quiet):
            warnings.simplefilter("always", RotoridWarning)
            ingestion = ingestion_settings(args)
            if by_reference:
                ingestion["keep_columns"] = getattr(model, "columns", ())
                if hasattr(model, "channels"):     # IRIG_TIME = { signal = "time", … }
                    ingestion["channels"] = model.channels.time_links()
            else:
                ingestion["channels"] = load_channel_map(args.model)
                ingestion["signals"] = model.signals
            maneuvers = load_maneuvers(args.data, args.hold,
                                       None if by_reference else model.units.name, ingestion)
            maneuvers = _actuated(maneuvers, args)
            if args.states is not None:
                for name in maneuvers.names:
                    for suffix in (".csv", ".png"):
                        refuse_overwrite(Path(args.states) / f"{name}{suffix}", args.force)
            if not by_reference:
                check_fit_data(maneuvers, options.get("outputs"), model)
            checked = check_before_fit(maneuvers, model)
        _print_warnings(found)
        if not by_reference:
            model = checked
        elif hasattr(model, "for_maneuvers"):          # initial states estimated per record
            model = model.for_maneuvers(maneuvers)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", RotoridWarning)
            estimate = returned(estimator.estimate(model, maneuvers), Estimate,
                                f"estimator {args.estimator!r}: estimate")
    _print_warnings(caught)
    data_warnings = [str(warning.message) for warning in found]
    record = _record(estimate, args.model, out, data_warnings)
    record["estimator_options"] = options
    record["hold"] = maneuvers.hold
    read = {k: ingestion[k] for k in INGESTION_SETTINGS if ingestion.get(k) is not None}
    if read:
        record["ingestion"] = read
    if args.actuator_lag is not None:
        record["actuator_lag_s"] = args.actuator_lag
        record["actuator_inputs"] = _actuator_inputs(args)
    atomic_write(out, json.dumps(record, indent=2))
    print(estimate.report())
    if not by_reference:
        print(_modes_report(model, estimate))
    print(data_warnings_report(data_warnings))
    print(f"estimate written to {out}")
    if args.states is not None:
        _write_states(estimator, model, maneuvers, estimate, args)
    if estimate.converged:
        return ExitStatus.OK
    if args.strict:
        print(f"rotorid identify: error: the fit did not converge ({_why(estimate)})",
              file=sys.stderr)
        return ExitStatus.NOT_CONVERGED
    print(f"rotorid identify: warning: the fit did not converge ({_why(estimate)}); "
          f"--strict makes this an error", file=sys.stderr)
    return ExitStatus.OK


def _as_flags(message: str) -> str:
    """An estimator's message about one of its options (``gusts names v, …``) as the command
    line gives it (``--gusts names v, …``)."""
    for option in FILTER_ERROR_FLAGS:
        if message.startswith(f"{option} "):
            return f"--{option.replace('_', '-')}{message[len(option):]}"
    return message


def _write_states(estimator, model, maneuvers, estimate, args) -> None:
    """The estimator's state estimates along ``maneuvers`` at ``estimate``: one CSV maneuver
    file and one PNG figure per maneuver in ``args.states``, written atomically."""
    from rotorid.estimation.state_estimates import StateEstimates
    from rotorid.plugin.manager import create
    from rotorid.plugin.returns import returned
    from rotorid.report.plots.case import save_figure
    from rotorid.report.plots.states import plot_state_estimates, recorded_states

    estimates = returned(estimator.state_estimates(model, maneuvers, estimate), StateEstimates,
                         f"estimator {args.estimator!r}: state_estimates")
    directory = Path(args.states)
    create("data-sources", "files", hold=maneuvers.hold).save(
        estimates.as_maneuvers(maneuvers), directory)
    for maneuver in maneuvers:
        known = recorded_states(maneuver, estimates.names, estimate)
        save_figure(plot_state_estimates(estimates, maneuver.name, known),
                    directory / maneuver.name, formats=("png",))
    print(f"state estimates of {len(estimates.maneuvers)} maneuver(s) "
          f"({', '.join(estimates.names)}) written to {directory}: <maneuver>.csv and .png")


def _why(estimate) -> str:
    """Why a fit stopped unconverged, with the option that lets it go on where one does."""
    if estimate.stop_reason == "iteration limit reached":
        return (f"iteration limit reached after {counted(estimate.iterations, 'iteration')}; "
                f"--max-iterations raises it")
    return estimate.stop_reason
