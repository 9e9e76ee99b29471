"""The Study: the paper's pipeline for each flight case, with persistence and resume.

For every :class:`~rotorid.study.case.FlightCase`::

    data source ─► identification multisteps + verification sweeps (+ trim, truth model)
    fully populated structure ─► reduction loop (criteria plugins) ─► selected structure
    + delays on the surviving rotor-affected derivatives ─► re-estimation ─► delay profiles
    verification: time-domain metrics and sweep frequency responses of both models
    (+ with [compare] frequency: each model's structure fitted to the sweeps' responses)
    (+ with [compare] estimators: the model with delays fitted by each listed estimator)
    ─► CaseResult ─► result.json, figures, report

Results live in ``<out>/<case>/``: ``data/`` (what the data source stores), ``steps/`` (one
JSON per finished reduction step, the resume points), ``delays.json``, ``result.json``,
figures and the report (:mod:`rotorid.study.persistence`). Every file is written atomically;
a rerun with ``resume=True`` skips what is done.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from pathlib import Path
from typing import Protocol

import attrs

from rotorid.data import ALL_CHANNELS, ManeuverSet
from rotorid.errors import (DataError, DataWarning, EstimationError, IdentifiabilityWarning,
                            RotoridError, RotoridWarning, StudyError)
from rotorid.estimation.data_checks import check_fit_data
from rotorid.estimation.reduction import ReductionPath, ReductionStep, reduce
from rotorid.estimation.sanity import check_before_fit
from rotorid.estimation.state_estimates import StateEstimates
from rotorid.executors import check_executor, failure_error, run_tasks
from rotorid.lease import hold_lease
from rotorid.model.derivatives import delayed_derivative
from rotorid.model.modelfile import case_model
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.plugin.contracts import CaseData
from rotorid.plugin.manager import create, notify, using
from rotorid.plugin.returns import returned
from rotorid.progress import Countdown, counted
from rotorid.study.case import FlightCase
from rotorid.study.checks import check_case, check_cases
from rotorid.study.comparison import compare_frequency_fit
from rotorid.study.delays import delay_profiles, with_delays
from rotorid.study.estimator_comparison import EstimatorComparison, compare_estimators
from rotorid.study.hybrid_comparison import HybridComparison, compare_hybrid, mean_cost
from rotorid.study.persistence import load_steps, prepare_directory, save_result, save_step
from rotorid.study.result import MODELS, CaseResult
from rotorid.study.truth import truth_derivatives, truth_equivalent_delays
from rotorid.verification.handling_qualities import handling_qualities_table
from rotorid.verification.pairs import default_pairs
from rotorid.verification.producible import producible_pairs
from rotorid.verification.simulation_fit import SimulationFit, simulation_fit
from rotorid.verification.verify import verify_model

Progress = Callable[[str, str], None]
#: How a study's task names a case in progress lines and errors.
_CASE_LABEL = "case {}".format


def log_progress(case: str, message: str) -> None:
    """Default progress reporter: ``[case] message`` at INFO level on the ``rotorid.study``
    logger (the ``rotorid`` command shows it on stderr; in Python enable it with
    ``logging.basicConfig(level=logging.INFO)``)."""
    logging.getLogger("rotorid.study").info("[%s] %s", case, message)


def _silent(case: str, message: str) -> None:
    """Progress reporter that drops every message."""


class ReportWriter(Protocol):
    """What writes figures and reports from results (:class:`rotorid.report.html.StudyReport`);
    the pipeline calls it and never imports it."""

    def write_case(self, result: CaseResult, directory: Path,
                   progress: Callable[[str], None] | None = None) -> object:
        """Figures, tables and the report of one case, in its results ``directory``;
        ``progress(message)`` takes progress lines of the case (optional)."""

    def write_study(self, results: Mapping[str, CaseResult], out_dir: Path) -> object:
        """The study's overview report in ``out_dir``."""


# ----------------------------------------------------------------- steps
def load_data(case: FlightCase, directory: Path) -> tuple[CaseData, FlightCondition]:
    """The case's data from its data source (which may store them in ``directory``) and the
    trim: the source's, or else the case's ``[condition]`` table; both given, they must agree
    (:data:`TRIM_TOLERANCE`)."""
    source = create("data-sources", case.data_source)
    data = returned(source.case_data(_data_settings(case, source), Path(directory)), CaseData,
                    f"data source {case.data_source!r}: case_data")
    if data.condition is not None:
        if case.condition:
            _check_same_trim(case, FlightCondition.from_mapping(case.condition), data.condition)
        return data, data.condition
    if not case.condition:
        raise DataError(f"case {case.name}: the {case.data_source!r} data source gives no "
                        f"trim; add a [condition] table (airspeed_kt, theta0_deg, phi0_deg)")
    return data, FlightCondition.from_mapping(case.condition)


#: How far a case's [condition] may lie from its data source's trim: body velocities, m/s,
#: and attitudes, rad (0.1 kt and 0.01°).
TRIM_TOLERANCE = (0.05, 1.75e-4)


def _check_same_trim(case: FlightCase, stated: FlightCondition, source: FlightCondition):
    """Refuse a case whose ``[condition]`` (``stated``) is not the trim its data source gives."""
    speed, angle = TRIM_TOLERANCE

    def apart(*names):
        return max(abs(getattr(stated, name) - getattr(source, name)) for name in names)

    if apart("u0", "v0", "w0") > speed or apart("theta0", "phi0") > angle:
        raise DataError(f"case {case.name}: its [condition] ({stated.describe()}) is not the "
                        f"trim the {case.data_source!r} data source gives "
                        f"({source.describe()}); remove the [condition] table to use the "
                        f"source's trim, or make the two agree")


def _data_settings(case: FlightCase, source) -> Mapping:
    """The case's data settings, plus the structure's signals (``signals``) when the
    structure names channels beyond the helicopter's and the source reads signals (the files
    source: a maneuver then takes the model's own inputs and outputs)."""
    settings = dict(case.data_settings)
    if "signals" not in getattr(source, "ingestion_settings", ()):
        return settings
    signals = base_structure(case, FlightCondition(), "flight-test").signals
    if any(name not in ALL_CHANNELS for name in signals.all.names):
        settings["signals"] = signals
    return settings


def base_structure(case: FlightCase, condition: FlightCondition, units: str) -> ModelStructure:
    """The case's starting structure at the identified trim condition."""
    trim = {"airspeed_kt": condition.airspeed_kt, "theta0_deg": math.degrees(condition.theta0),
            "phi0_deg": math.degrees(condition.phi0)}
    return case_model(case.as_dict(), trim, units, f"case {case.name}")


def checked_structure(case: FlightCase, structure: ModelStructure, ident: ManeuverSet,
                      report: Progress) -> tuple[ModelStructure, tuple[str, ...]]:
    """``structure`` after the sanity checks of the identification data
    (:func:`~rotorid.estimation.sanity.check_before_fit`), and the text of each warning they
    gave (it also becomes a progress line); the derivatives of inputs that never move are
    dropped before the first fit."""
    with warnings.catch_warnings(record=True) as caught, _check_lines() as lines:
        warnings.simplefilter("always", DataWarning)
        checked = check_before_fit(ident, structure)
    for line in lines:
        report(case.name, line)
    return checked, _reported_warnings(case, caught, report)


@contextlib.contextmanager
def _check_lines():
    """The lines the data checks log (``rotorid.checks``, e.g. the kinematic consistency
    fits) collected while the block runs, for the case's progress instead of bare lines."""
    logger, lines = logging.getLogger("rotorid.checks"), []

    class Collector(logging.Handler):
        def emit(self, record):
            lines.append(record.getMessage())

    collector, propagate, level = Collector(logging.INFO), logger.propagate, logger.level
    logger.addHandler(collector)
    logger.propagate = False
    logger.setLevel(logging.INFO)
    try:
        yield lines
    finally:
        logger.removeHandler(collector)
        logger.propagate = propagate
        logger.setLevel(level)


def _differing_selections(path: ReductionPath) -> str:
    """``"; parsimonious would select step 5"`` for the rules that select another step than
    the path's own (``[reduction] rule``), empty when all agree."""
    others = {rule: index for rule, index in path.selections().items()
              if index != path.selected_index}
    return "".join(f"; {rule} would select step {index}" for rule, index in others.items())


def _reported_warnings(case: FlightCase, caught, report: Progress) -> tuple[str, ...]:
    """The text of each of rotorid's warnings ``caught`` (others are shown as Python shows
    them), each also a progress line of the case."""
    messages = []
    for warning in caught:
        if issubclass(warning.category, RotoridWarning):
            messages.append(str(warning.message))
            report(case.name, f"warning: {messages[-1]}")
        else:
            warnings.showwarning(warning.message, warning.category, warning.filename,
                                 warning.lineno)
    return tuple(messages)


def _reduce(case: FlightCase, structure: ModelStructure, ident: ManeuverSet, estimator,
            directory: Path, resume: bool, report: Progress) -> tuple[ReductionPath, int]:
    """The reduction path of ``structure`` (continuing the finished steps saved in
    ``directory`` when resuming) and how many steps were reused. Each step's progress line
    ends with the steps left at most (one per free derivative) and the time they may take."""
    def on_step(step: ReductionStep) -> None:
        save_step(directory, step)
        removed = "full structure" if step.removal is None else (
            f"removed {step.removal.parameter} ({step.removal.criterion} "
            f"{step.removal.metric_text})")
        report(case.name, f"reduction step {step.index}: {removed}, {step.n_parameters} "
                          f"parameters, RMSE {step.rmse:.4f}, {step.estimate.iterations} iter "
                          f"{countdown.step()}")

    finished = load_steps(directory, structure) if resume else []
    if finished:
        report(case.name, f"resuming after {len(finished)} finished reduction steps")
    countdown = Countdown(len(structure.free_derivatives) + 1, done=len(finished), at_most=True)
    criteria = [create("reduction-criteria", name, **options) for name, options in case.criteria]
    with warnings.catch_warnings():
        # Reduction starts from deliberately over-parameterised structures: their unidentifiable
        # combinations are recorded in each step's estimate instead of flooding the terminal.
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        path = reduce(structure, ident, estimator, criteria,
                      continue_to_zero=case.continue_to_zero, warm_start=case.warm_start,
                      rule=case.rule, rmse_tolerance=case.rmse_tolerance, finished=finished,
                      on_step=on_step, case=case.name)
    if path.stopped:
        report(case.name, f"reduction {path.stopped}")
    return path, len(finished)


def _delays_line(estimate, dropped: tuple[str, ...]) -> str:
    """Progress line of the delay step: the delays, the RMSE and what was dropped."""
    delays = ", ".join(f"{delayed_derivative(n)} {estimate.value(n):.3f} s"
                       for n in estimate.parameter_names if delayed_derivative(n))
    line = f"delays: {delays or 'none'}; RMSE {estimate.rmse:.4f}"
    return line + (f"; dropped undetermined delays on {', '.join(dropped)}" if dropped else "")


def _profile_line(profile) -> str:
    """Progress line of one delay profile: whether a grid point fits better than the free fit
    (then the free fit is a local optimum), the RMSE cost of τ = 0."""
    best = int(profile.cost.argmin())
    line = (f"profile of {profile.delay} (free fit {profile.free_value:.3f} s, "
            f"{profile.grid.size} grid points): ")
    if profile.cost[best] < profile.free_cost:
        line += (f"fixed at {profile.grid[best]:.3f} s its det R is "
                 f"{1.0 - profile.cost[best] / profile.free_cost:.1%} below the free fit's, "
                 f"which is a local optimum (more [delays] starts may find the lower one)")
    else:
        line += "no grid point fits better than the free fit"
    if profile.grid[0] == 0.0:
        line += f"; fixed at 0 s the RMSE is {profile.relative_rmse[0]:+.2%}"
    return line


def _model_values(structures, estimates) -> dict:
    """Each model's own parameter vector by model label (an estimator's noise parameters, such
    as filter error's F and R, left out)."""
    return {label: estimates[label].restricted(structures[label].parameter_names).values
            for label in MODELS}


def _verify(case: FlightCase, structures, estimates, ident: ManeuverSet,
            verif: ManeuverSet | None, report: Progress) -> tuple[dict, dict]:
    """Each model's simulation of the identification data (:class:`SimulationFit`: its
    outputs and time-domain metrics) and sweep verification (when there are verification
    data), by model label. Pairs the data or the model cannot produce are skipped, with the
    reason in a progress line and in the verification's notes."""
    values = _model_values(structures, estimates)
    simulations = {label: simulation_fit(structures[label], values[label], ident)
                   for label in MODELS}
    if verif is None:
        return simulations, {}
    identified = structures["with delays"]
    selection = producible_pairs(identified, values["with delays"], verif,
                                 case.pairs or default_pairs(identified.outputs,
                                                             identified.controls))
    skipped = [f"{pair} not verified: {reason}" for pair, reason in selection.skipped.items()]
    for note in skipped:
        report(case.name, note)
    verification = {}
    for label in MODELS if selection.pairs else ():
        checked = verify_model(structures[label], values[label], verif,
                               selection.pairs, case.envelopes, band=case.band)
        verification[label] = attrs.evolve(checked, notes=[*checked.notes, *skipped])
    return simulations, verification


def _state_estimates(case: FlightCase, estimator, structure, ident: ManeuverSet, estimate,
                     report: Progress) -> StateEstimates | None:
    """The case estimator's state estimates of the model with delays along the
    identification data (``None`` from an estimator that gives none, or where it cannot:
    a progress line says why)."""
    if not hasattr(estimator, "state_estimates"):
        return None
    try:
        estimates = returned(estimator.state_estimates(structure, ident, estimate),
                             StateEstimates, f"estimator {case.estimator!r}: state_estimates")
    except EstimationError as error:
        report(case.name, f"no state estimates: {error}")
        return None
    report(case.name, f"state estimates of {', '.join(estimates.names)} along "
                      f"{counted(len(estimates.maneuvers), 'maneuver')}")
    return estimates


def _compare(case: FlightCase, structures, estimates, simulations,
             verif: ManeuverSet | None, report: Progress) -> dict:
    """The frequency-domain fit of each model beside its time-domain fit, whose metrics on
    the identification data its ``simulations`` entry holds, by model label (``{}`` unless
    the case asks for it with ``[compare] frequency``)."""
    if not case.compare_frequency:
        return {}
    if verif is None:
        raise DataError(f"case {case.name}: [compare] frequency fits the verification sweeps, "
                        f"but the case has none; add sweeps to [data] verification or drop "
                        f"[compare] frequency")
    band_max = math.inf if case.compare_band_max is None else case.compare_band_max
    comparisons = {}
    for label in MODELS:
        structure = structures[label]
        pairs = case.frequency_pairs or default_pairs(structure.outputs, structure.controls)
        simulation = simulations[label]
        comparison = compare_frequency_fit(structure, estimates[label], simulation.metrics,
                                           verif, simulation.maneuvers, pairs, band_max)
        comparisons[label] = comparison
        costs = {m: sum(c.values()) for m, c in comparison.pair_costs.items()}
        iterations = comparison.frequency_estimate.iterations
        report(case.name, f"frequency-domain fit ({label}): {iterations} iter, J "
                          f"{costs['frequency']:.1f} (time-domain fit's {costs['time']:.1f})")
    return comparisons


def _compare_estimators(case: FlightCase, structure: ModelStructure, estimate,
                        simulation: SimulationFit, report: Progress
                        ) -> EstimatorComparison | None:
    """The model with delays (its ``simulation`` of the identification data reused) fitted by
    every estimator of ``[compare] estimators`` (``None`` unless the case asks for it)."""
    if not case.compare_estimators:
        return None
    comparison = compare_estimators(case.compare_estimators, case.estimator, structure,
                                    estimate, simulation)
    for name, fitted in comparison.estimates.items():
        simulation = comparison.simulation[name]
        rmse = "diverges" if simulation is None else f"{simulation.metrics.rmse:.4f}"
        fit = ("the case's own fit" if name == case.estimator
               else f"{fitted.iterations} iter, {comparison.seconds[name]:.1f} s")
        report(case.name, f"{name} fit of the model with delays: {fit}; simulation RMSE "
                          f"{rmse}")
    return comparison


def _compare_hybrid(case: FlightCase, structures, estimates, simulations,
                    verif: ManeuverSet | None, verification, estimator, truth,
                    condition: FlightCondition, report: Progress) -> HybridComparison | None:
    """The hybrid rotor-body model beside the case's two on the pairs they were verified on
    (``None`` unless the case asks for it with ``[compare] hybrid``)."""
    if not case.compare_hybrid:
        return None
    reference = None if truth is None else (
        lambda hybrid: truth_derivatives(truth, condition, hybrid))
    criteria = ([create("reduction-criteria", name, **options)
                 for name, options in case.criteria] if case.compare_hybrid_reduction else [])
    comparison = compare_hybrid(structures, estimates, simulations, verification, verif,
                                estimator, reference, case.compare_hybrid_band_max, criteria,
                                case.rule, case.rmse_tolerance)
    taus = ", ".join(f"{t:.3f} s" for t, _ in comparison.flap_time_constants().values())
    costs = "; ".join(f"{label} {cost:.0f}" for label, costs in comparison.costs.items()
                      if (cost := mean_cost(costs)) is not None)
    if comparison.removed is not None:
        report(case.name, f"hybrid model reduced: removed "
                          f"{', '.join(comparison.removed) or 'nothing'}")
    report(case.name, f"hybrid model: {comparison.structure.n_parameters} parameters, "
                      f"{comparison.estimate.iterations} iter, RMSE "
                      f"{comparison.estimate.rmse:.4f}, flap time constants {taus}"
                      + (f"; mean J over {comparison.band.describe()}: {costs}" if costs
                         else ""))
    return comparison


def _durations(clock: dict) -> dict:
    keys = list(clock)
    return {k: clock[k] - clock[p] for p, k in zip(keys, keys[1:])}


# ----------------------------------------------------------------- one case
def run_case(case: FlightCase, out_dir: str | Path, resume: bool = True,
             progress: Progress | None = log_progress,
             report_writer: ReportWriter | None = None, manager=None) -> CaseResult:
    """Run one flight case end to end and write its results under ``out_dir/<case>``; with a
    ``report_writer``, also its figures and report. Plugins come from ``manager`` (a
    :func:`~rotorid.plugin.manager.new_plugin_manager`; default: the current one). The case
    is checked first (:func:`~rotorid.study.checks.check_case`): nothing is written for a case
    that cannot run, nor outside ``out_dir``."""
    with using(manager):
        check_case(case, f"case {case.name}")
        return _run_case(case, Path(out_dir) / case.name, resume, progress or _silent,
                         report_writer)


def _run_case(case: FlightCase, directory: Path, resume: bool, report: Progress,
              report_writer: ReportWriter | None) -> CaseResult:
    prepare_directory(directory, case, resume)
    notify("rotorid_case_started", case=case)
    clock = {"start": time.perf_counter()}
    report(case.name, f"data: {case.data_source}"
                      + (f" ({case.run_label})" if case.run_label else ""))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DataWarning)
        data, condition = load_data(case, directory / "data")
        ident = case.identification_records(data.identification)
        verif = case.verification_records(data.verification)
    reading_warnings = _reported_warnings(case, caught, report)
    clock["data"] = time.perf_counter()
    report(case.name, f"{len(ident)} identification and {0 if verif is None else len(verif)} "
                      f"verification maneuvers; trim {condition.describe(ident.units)}")
    if case.cutoff_hz is not None and case.keeps_every_sample:
        report(case.name, f"identification records low-passed at {case.cutoff_hz:g} Hz, "
                          f"every sample kept ({ident[0].dt:g} s)")
    elif case.cutoff_hz is not None:
        report(case.name, f"identification records low-passed at {case.cutoff_hz:g} Hz, "
                          f"sample time {data.identification[0].dt:g} → {ident[0].dt:g} s")
    if case.actuator_lag_s is not None:
        lagged = ", ".join(case.actuator_inputs) if case.actuator_inputs else "every input"
        report(case.name, f"{lagged} through the actuators' {case.actuator_lag_s:g} s "
                          f"first-order lag")
    structure = base_structure(case, condition, ident.units)
    check_fit_data(ident, case.estimator_options.get("outputs"), structure)
    structure, check_warnings = checked_structure(case, structure, ident, report)
    data_warnings = reading_warnings + check_warnings
    estimator = create("estimators", case.estimator, **case.estimator_options)
    path, resumed = _reduce(case, structure, ident, estimator, directory, resume, report)
    clock["reduction"] = time.perf_counter()
    selected = path.selected
    report(case.name, f"selected step {selected.index} ({path.rule}): {selected.n_parameters} "
                      f"parameters, RMSE {selected.rmse:.4f}{_differing_selections(path)}")
    delayed, delayed_estimate, dropped = with_delays(case, selected, ident, estimator,
                                                     directory)
    clock["delays"] = time.perf_counter()
    report(case.name, _delays_line(delayed_estimate, dropped))
    profiles = delay_profiles(case, selected.index, delayed, delayed_estimate, ident,
                              estimator, directory)
    clock["delay profiles"] = time.perf_counter()
    for profile in profiles:
        report(case.name, _profile_line(profile))
    structures = {"no delays": selected.structure, "with delays": delayed}
    estimates = {"no delays": selected.estimate, "with delays": delayed_estimate}
    states = _state_estimates(case, estimator, delayed, ident, delayed_estimate, report)
    simulations, verification = _verify(case, structures, estimates, ident, verif, report)
    clock["verification"] = time.perf_counter()
    comparison = _compare(case, structures, estimates, simulations, verif, report)
    if comparison:
        clock["frequency comparison"] = time.perf_counter()
    estimators = _compare_estimators(case, delayed, delayed_estimate,
                                     simulations["with delays"], report)
    if estimators is not None:
        clock["estimator comparison"] = time.perf_counter()
    truth = data.truth
    hybrid = _compare_hybrid(case, structures, estimates, simulations, verif, verification,
                             estimator, truth, condition, report)
    if hybrid is not None:
        clock["hybrid comparison"] = time.perf_counter()
    models = {label: (structures[label], values)
              for label, values in _model_values(structures, estimates).items()}
    if hybrid is not None:
        models["hybrid"] = (hybrid.structure, hybrid.values)
    result = CaseResult(
        case, condition, ident, verif, path, structures, estimates, simulations, verification,
        None if truth is None else truth_derivatives(truth, condition, structure),
        _durations(clock), dropped, resumed,
        None if truth is None else truth_equivalent_delays(truth, condition, delayed),
        comparison, profiles, estimators, data_warnings, hybrid,
        handling_qualities_table(models, verif), states)
    save_result(directory, result)
    if report_writer is not None:
        report(case.name, "figures and report")
        report_writer.write_case(result, directory,
                                 progress=lambda message: report(case.name, message))
    notify("rotorid_case_finished", case=case, result=result)
    report(case.name, f"done in {time.perf_counter() - clock['start']:.0f} s → {directory}")
    return result


# ----------------------------------------------------------------- study
def run_case_task(case: FlightCase, progress: Progress | None = log_progress,
                  **options) -> CaseResult:
    """:func:`run_case` as an independent task: a failure names the case's last progress
    message (its reduction step, when it got that far) and the error."""
    last = ["before any progress"]

    def tracking(name: str, message: str) -> None:
        last[0] = f"after “{message}”"
        if progress is not None:
            progress(name, message)

    try:
        return run_case(case, progress=tracking, **options)
    except Exception as error:
        raise StudyError(f"case {case.name} failed {last[0]}: {type(error).__name__}: "
                         f"{error}{_raised_at(error)}") from error


def _raised_at(error: Exception) -> str:
    """Where an error rotorid did not raise on purpose (a bug, in rotorid or a plugin) came
    from: the innermost frame, and the whole traceback on stderr with ``ROTORID_TRACEBACK=1``
    set; empty for a rotorid error, whose message names the problem."""
    if isinstance(error, RotoridError) or error.__traceback__ is None:
        return ""
    if os.environ.get("ROTORID_TRACEBACK"):
        traceback.print_exception(error, file=sys.stderr)
    frame = traceback.extract_tb(error.__traceback__)[-1]
    return (f" (raised in {frame.filename}:{frame.lineno}, {frame.name}; ROTORID_TRACEBACK=1 "
            f"prints the traceback)")


class Study:
    """Several flight cases run through the pipeline, each as an independent task.

    Args:
        cases: :class:`FlightCase` objects or built-in case names / case files; all are
            checked (:func:`~rotorid.study.case.check_cases`) before any runs.
        out_dir: results directory; each case writes ``out_dir/<case>/`` (on a cluster it
            must be a directory every worker can write, e.g. a shared file system).
        executor: ``None`` runs the cases one after the other in this process; ``"process"``
            a local process pool sized to the machine; any
            :class:`concurrent.futures.Executor` (e.g. ``client.get_executor()`` of a
            ``dask.distributed.Client``) runs them there. The numbers are the same whichever
            runs them (see :mod:`rotorid.executors`).
        resume: reuse finished steps found in ``out_dir`` (off by default, as in
            ``rotorid study``).
        progress: ``progress(case, message)`` receives progress lines (it runs in the worker:
            with a process pool or Dask it must be a picklable module-level function).
        report_writer: writes each case's figures and report and the study report (e.g.
            :class:`rotorid.report.html.StudyReport`; with a process pool or Dask it must be
            picklable); ``None`` writes the results only.
        manager: the plugin manager the cases take their plugins from and notify (one built
            with :func:`~rotorid.plugin.manager.new_plugin_manager`); default the current
            one. It cannot travel to other processes: with a manager, run serially or on a
            thread pool.

    :meth:`run` raises :class:`~rotorid.errors.StudyError` when cases fail: its message names
    each failed case with its last progress message, and its ``results`` holds the cases that
    finished (their files are written too).
    """

    def __init__(self, cases: Sequence[FlightCase | str], out_dir: str | Path,
                 executor: Executor | str | None = None, resume: bool = False,
                 progress: Progress | None = log_progress,
                 report_writer: ReportWriter | None = None, manager=None):
        with using(manager):
            self.cases = [c if isinstance(c, FlightCase) else FlightCase.load(c)
                          for c in cases]
            check_cases(self.cases)
        check_executor(executor)
        if manager is not None and executor == "process":
            raise StudyError("a plugin manager cannot be sent to other processes: run a study "
                             "with manager=... serially (executor=None) or on a thread pool")
        self.out_dir = Path(out_dir)
        self.executor = executor
        self.resume = resume
        self.progress = progress
        self.report_writer = report_writer
        self.manager = manager

    def run(self) -> dict[str, CaseResult]:
        """Run every case; returns results by case name and writes the study report."""
        self.out_dir.mkdir(parents=True, exist_ok=True)
        options = dict(out_dir=self.out_dir, resume=self.resume, progress=self.progress,
                       report_writer=self.report_writer)
        if self.manager is not None:
            options["manager"] = self.manager
        tasks = {c.name: ((c,), options) for c in self.cases}
        # tasks in other processes write only while this process lives (rotorid.lease)
        holding = contextlib.nullcontext() if self.executor is None else hold_lease(self.out_dir)
        with holding as lease:
            results, failures = run_tasks(run_case_task, tasks, self.executor,
                                          label=_CASE_LABEL, lease=lease)
        if failures:
            raise failure_error("cases", results, failures, self.out_dir, _CASE_LABEL)
        if self.report_writer is not None:
            self.report_writer.write_study(results, self.out_dir)
        return results
