"""The Study: the paper's pipeline for each flight case, with persistence and resume.

For every :class:`~rotorid.study.case.FlightCase`::

    data source ─► identification multisteps + verification sweeps
    fully populated structure ─► reduction loop (criteria plugins) ─► selected structure
    + delays on the surviving rotor-affected derivatives ─► re-estimation
    verification: time-domain metrics and sweep frequency responses of both models
    ─► CaseResult ─► result.json, figures, report

Results live in ``<out>/<case>/``: ``data/`` (the maneuvers), ``steps/`` (one JSON per
finished reduction step, the resume points), ``delays.json``, ``result.json``, figures and
the report. Every file is written atomically; a rerun with ``resume=True`` skips what is done.
"""

from __future__ import annotations

import json
import logging
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from typing import Protocol
from concurrent.futures import Executor
from pathlib import Path

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import (
    DataError,
    EstimationError,
    IdentifiabilityWarning,
    RotoridError,
    SimulationDivergedError,
    StudyError,
)
from rotorid.estimation.estimate import Estimate
from rotorid.estimation.reduction import ReductionPath, ReductionStep, reduce
from rotorid.executors import check_executor, failure_error, run_tasks
from rotorid.io import atomic_write, jsonable
from rotorid.model.modelfile import parse_model
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.notebook import case_result_html, case_result_summary
from rotorid.plugin.contracts import Removal
from rotorid.plugin.manager import create, notify, using
from rotorid.simulation.simulator import simulate
from rotorid.study.case import FlightCase
from rotorid.verification.compare import VerificationResult, verify_model
from rotorid.verification.equivalent_delays import (
    ROTOR_DERIVATIVES,
    EquivalentDelays,
    equivalent_delays,
)
from rotorid.verification.metrics import TimeDomainMetrics, time_domain_metrics

MODELS = ("no delays", "with delays")
#: Derivatives the paper checks for sign and magnitude (truth-model.md §8).
KEY_DERIVATIVES = ("M_w", "L_v", "N_v", "Z_w", "M_u", "X_u", "X_v", "Y_u", "Y_v")


def log_progress(case: str, message: str) -> None:
    """Default progress reporter: ``[case] message`` at INFO level on the ``rotorid.study``
    logger (the ``rotorid`` command shows it on stderr; in Python enable it with
    ``logging.basicConfig(level=logging.INFO)``)."""
    logging.getLogger("rotorid.study").info("[%s] %s", case, message)


@attrs.frozen(eq=False)
class CaseResult:
    """Everything one flight case produced (immutable)."""

    case: FlightCase
    condition: FlightCondition
    identification: ManeuverSet
    verification_data: ManeuverSet
    path: ReductionPath
    structures: Mapping[str, ModelStructure]      # by model label (MODELS)
    estimates: Mapping[str, Estimate]
    time_metrics: Mapping[str, TimeDomainMetrics]
    verification: Mapping[str, VerificationResult]
    truth_derivatives: Mapping[str, float] | None
    seconds: Mapping[str, float]
    dropped_delays: tuple[str, ...] = ()
    resumed_steps: int = 0           # finished reduction steps reused from an earlier run
    truth_delays: EquivalentDelays | None = None   # the truth model's equivalent delays

    @property
    def name(self) -> str:
        return self.case.name

    def __repr__(self) -> str:
        return case_result_summary(self)

    def _repr_html_(self) -> str:
        return case_result_html(self)

    def simulated(self, model: str, maneuvers: ManeuverSet | None = None) -> list[np.ndarray]:
        """Outputs of one identified model on ``maneuvers`` (default: identification data)."""
        data = self.identification if maneuvers is None else maneuvers
        return simulate(self.structures[model], self.estimates[model].values, data)

    def key_derivatives(self) -> dict:
        """Identified key derivatives of the delayed model, and the truth's linearisation."""
        estimate = self.estimates["with delays"]
        table = {}
        for name in KEY_DERIVATIVES:
            identified = (estimate.value(name) if name in estimate.parameter_names else None)
            truth = None if self.truth_derivatives is None else self.truth_derivatives.get(name)
            table[name] = {"identified": identified, "truth_linearisation": truth}
        return table

    def as_dict(self) -> dict:
        """The ``result.json`` record."""
        path = self.path
        return {
            "case": self.case.as_dict(),
            "condition": attrs.asdict(self.condition),
            "reduction": {"rule": path.rule, "rmse_tolerance": path.rmse_tolerance,
                          "selected_step": path.selected_index,
                          "removed": list(path.removed),
                          "steps": [s.summary() for s in path.steps]},
            "selected_structure": list(self.structures["no delays"].names),
            "estimates": {label: e.as_dict() for label, e in self.estimates.items()},
            "time_metrics": {label: m.summary() for label, m in self.time_metrics.items()},
            "frequency_verification": {label: v.summary()
                                       for label, v in self.verification.items()},
            "key_derivatives": self.key_derivatives(),
            "dropped_delays": list(self.dropped_delays),
            "truth_equivalent_delays": (None if self.truth_delays is None
                                        else self.truth_delays.as_dict()),
            "seconds": dict(self.seconds),
            "resumed_steps": self.resumed_steps,
        }


# ----------------------------------------------------------------- data
def _split(data: ManeuverSet, case: FlightCase) -> tuple[ManeuverSet, ManeuverSet]:
    ident = [m for m in data if m.metadata.get("kind") in case.identification_kinds]
    verif = [m for m in data if m.metadata.get("kind") in case.verification_kinds]
    if not ident:
        raise DataError(f"case {case.name}: no identification maneuvers of kind "
                        f"{', '.join(case.identification_kinds)} in the data")
    return (ManeuverSet(ident, hold=data.hold),
            ManeuverSet(verif, hold=data.hold) if verif else None)


def load_data(case: FlightCase, directory: Path):
    """Identification and verification maneuver sets of a case, and its flight condition."""
    settings = {k: v for k, v in case.data.items() if k != "source"}
    source = case.data["source"]
    if source == "helisim":
        generator = create("data-sources", "helisim")
        data, _ = generator.generate_into(settings, directory)
        ident, verif = _split(data, case)
        first = ident[0].metadata
        condition = FlightCondition.from_airspeed(first["airspeed_kt"],
                                                  first["trim_theta_deg"], first["trim_phi_deg"])
        return ident, verif, condition, generator
    if source == "files":
        loader = create("data-sources", "files", hold=settings.pop("hold", "zoh"))
        if "identification" not in settings:
            raise DataError(f"case {case.name}: [data] needs 'identification' (files or glob)")
        ident = loader.load(settings["identification"])
        verif = loader.load(settings["verification"]) if "verification" in settings else None
        if not case.condition:
            raise DataError(f"case {case.name}: flight data need a [condition] table "
                            f"(airspeed_kt, theta0_deg, phi0_deg)")
        return ident, verif, FlightCondition.from_mapping(case.condition), None
    raise DataError(f"case {case.name}: unknown data source {source!r}; use 'helisim' or "
                    f"'files'")


def base_structure(case: FlightCase, condition: FlightCondition, units: str) -> ModelStructure:
    """The case's starting structure at the identified trim condition."""
    import math

    mapping = {"units": units,
               "condition": {"airspeed_kt": condition.airspeed_kt,
                             "theta0_deg": math.degrees(condition.theta0),
                             "phi0_deg": math.degrees(condition.phi0)},
               "structure": dict(case.structure), "derivatives": dict(case.derivatives)}
    return parse_model(mapping, f"case {case.name}")


def truth_derivatives(generator, condition: FlightCondition, structure: ModelStructure):
    """The truth model's residualised 6-DoF derivatives in the structure's units."""
    if generator is None:
        return None
    linear = generator.linearize(condition.airspeed_kt, units=structure.units.name)
    a = np.asarray(linear.A) - structure.known_state_matrix()
    b = np.asarray(linear.B)
    values = {}
    for letter, row in (("X", "u"), ("Y", "v"), ("Z", "w"), ("L", "p"), ("M", "q"), ("N", "r")):
        i = structure.states.index(row)
        for j, state in enumerate(structure.states):
            if state in ("u", "v", "w", "p", "q", "r"):
                values[f"{letter}_{state}"] = float(a[i, j])
        for j, control in enumerate(structure.controls):
            values[f"{letter}_{control}"] = float(b[i, j])
    return values


def truth_equivalent_delays(generator, condition: FlightCondition, delayed: ModelStructure):
    """The truth model's equivalent delays (:mod:`rotorid.verification.equivalent_delays`) for the rotor
    delays the identified model kept, or ``None`` without a truth model or such delays."""
    names = [d.name for d in delayed.free_delays if d.name in ROTOR_DERIVATIVES]
    if generator is None or not names:
        return None
    units = delayed.units.name
    return equivalent_delays(generator.linearize(condition.airspeed_kt, full=True, units=units),
                             generator.linearize(condition.airspeed_kt, units=units), names)


# ----------------------------------------------------------------- persistence
def _step_file(directory: Path, index: int) -> Path:
    return directory / f"step_{index:03d}.json"


def _save_step(directory: Path, step: ReductionStep) -> None:
    removal = None if step.removal is None else attrs.asdict(step.removal)
    record = {"index": step.index, "removal": removal, "estimate": step.estimate.as_dict()}
    atomic_write(_step_file(directory, step.index), json.dumps(jsonable(record), indent=1))


def _load_steps(directory: Path, base: ModelStructure) -> list[ReductionStep]:
    steps, structure = [], base
    index = 0
    while _step_file(directory, index).is_file():
        record = json.loads(_step_file(directory, index).read_text())
        removal = None
        if record["removal"] is not None:
            removal = Removal(**{k: (np.inf if v is None else v)
                                 for k, v in record["removal"].items()})
            structure = structure.without(removal.parameter)
        estimate = (Estimate.from_dict(record["estimate"]) if structure.parameter_names
                    else None)
        if estimate is None:
            break
        steps.append(ReductionStep(index, removal, estimate, structure))
        index += 1
    return steps


def _check_configuration(directory: Path, case: FlightCase, resume: bool) -> None:
    marker = directory / "case.json"
    settings = json.dumps(jsonable(case.as_dict()), sort_keys=True)
    if marker.is_file() and resume and marker.read_text() != settings:
        raise RotoridError(f"{directory} holds results of a different configuration of case "
                           f"{case.name}; choose another --out directory or run without "
                           f"--resume to start afresh")
    if not resume:
        for old in list(directory.glob("steps/step_*.json")) + [directory / "delays.json"]:
            if old.is_file():
                old.unlink()
    atomic_write(marker, settings)


# ----------------------------------------------------------------- pipeline
class ReportWriter(Protocol):
    """What writes figures and reports from results (:class:`rotorid.report.html.StudyReport`);
    the pipeline calls it and never imports it."""

    def write_case(self, result: CaseResult, directory: Path) -> object:
        """Figures, tables and the report of one case, in its results ``directory``."""

    def write_study(self, results: Mapping[str, CaseResult], out_dir: Path) -> object:
        """The study's overview report in ``out_dir``."""


def run_case(case: FlightCase, out_dir: str | Path, resume: bool = True,
             progress: Callable[[str, str], None] | None = log_progress,
             report_writer: ReportWriter | None = None, manager=None) -> CaseResult:
    """Run one flight case end to end and write its results under ``out_dir/<case>``; with a
    ``report_writer``, also its figures and report. Plugins come from ``manager`` (a
    :func:`~rotorid.plugin.manager.new_plugin_manager`; default: the current one)."""
    with using(manager):
        return _run_case(case, out_dir, resume, progress, report_writer)


def _run_case(case, out_dir, resume, progress, report_writer) -> CaseResult:
    report = progress or (lambda case_name, message: None)
    directory = Path(out_dir) / case.name
    (directory / "steps").mkdir(parents=True, exist_ok=True)
    _check_configuration(directory, case, resume)
    notify("rotorid_case_started", case=case)
    clock = {"start": time.perf_counter()}
    report(case.name, f"data: {case.data.get('source')} "
                      f"({'quick' if case.is_quick else 'full'} set)")
    ident, verif, condition, generator = load_data(case, directory / "data")
    clock["data"] = time.perf_counter()
    report(case.name, f"{len(ident)} identification and {0 if verif is None else len(verif)} "
                      f"verification maneuvers; trim {condition.describe()}")
    structure = base_structure(case, condition, ident.units)
    estimator = create("estimators", case.estimator, **case.estimator_options)
    criteria = [create("reduction-criteria", name, **options) for name, options in case.criteria]

    def on_step(step: ReductionStep) -> None:
        _save_step(directory / "steps", step)
        removed = "full structure" if step.removal is None else (
            f"removed {step.removal.parameter} ({step.removal.criterion} "
            f"{step.removal.metric:.1f} %)")
        report(case.name, f"reduction step {step.index}: {removed}, {step.n_parameters} "
                          f"parameters, RMSE {step.rmse:.4f}, {step.estimate.iterations} iter")

    finished = _load_steps(directory / "steps", structure) if resume else []
    if finished:
        report(case.name, f"resuming after {len(finished)} finished reduction steps")
    with warnings.catch_warnings():
        # Reduction starts from deliberately over-parameterised structures: their unidentifiable
        # combinations are recorded in each step's estimate instead of flooding the terminal.
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        path = reduce(structure, ident, estimator, criteria,
                      continue_to_zero=case.continue_to_zero, warm_start=case.warm_start,
                      rule=case.rule, rmse_tolerance=case.rmse_tolerance, finished=finished,
                      on_step=on_step, case=case.name)
    clock["reduction"] = time.perf_counter()
    selected = path.selected
    report(case.name, f"selected step {selected.index}: {selected.n_parameters} parameters, "
                      f"RMSE {selected.rmse:.4f}")
    delayed, delayed_estimate, dropped = _with_delays(case, selected, ident, estimator,
                                                      directory)
    clock["delays"] = time.perf_counter()
    report(case.name, "delays: " + ", ".join(
        f"{n[4:]} {delayed_estimate.value(n):.3f} s" for n in delayed_estimate.parameter_names
        if n.startswith("tau_")) + f"; RMSE {delayed_estimate.rmse:.4f}"
        + (f"; dropped undetermined delays on {', '.join(dropped)}" if dropped else ""))
    structures = {"no delays": selected.structure, "with delays": delayed}
    estimates = {"no delays": selected.estimate, "with delays": delayed_estimate}
    metrics = {label: time_domain_metrics(ident, simulate(structures[label],
                                                          estimates[label].values, ident))
               for label in MODELS}
    verification = {}
    if verif is not None:
        for label in MODELS:
            verification[label] = verify_model(structures[label], estimates[label].values,
                                               verif, case.pairs, case.envelopes)
    clock["verification"] = time.perf_counter()
    result = CaseResult(case, condition, ident, verif, path, structures, estimates, metrics,
                        verification, truth_derivatives(generator, condition, structure),
                        _durations(clock), dropped, len(finished),
                        truth_equivalent_delays(generator, condition, delayed))
    atomic_write(directory / "result.json",
                 json.dumps(jsonable(result.as_dict()), indent=1, default=_json_default))
    if report_writer is not None:
        report(case.name, "figures and report")
        report_writer.write_case(result, directory)
    notify("rotorid_case_finished", case=case, result=result)
    report(case.name, f"done in {time.perf_counter() - clock['start']:.0f} s → {directory}")
    return result


def _json_default(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")


def _durations(clock: dict) -> dict:
    keys = list(clock)
    return {k: clock[k] - clock[p] for p, k in zip(keys, keys[1:])}


def _with_delays(case: FlightCase, selected: ReductionStep, ident, estimator, directory):
    """The selected structure with delays, re-estimated from the selected values.

    Delays the data cannot determine are dropped one at a time, the worst first, and the model
    re-estimated: a delay at its lower or upper bound, or whose normalised Cramér-Rao bound
    exceeds the case's Cramér-Rao threshold (a deviation from the paper, which keeps all
    eight; an undetermined delay on a weak off-axis derivative otherwise wanders to a bound).
    """
    delayed = selected.structure.with_delays(case.delay_derivatives, case.delay_initial,
                                             case.delay_upper)
    saved = directory / "delays.json"
    if saved.is_file():
        record = json.loads(saved.read_text())
        if record.get("selected_step") == selected.index:
            for name in record["dropped"]:
                delayed = delayed.without_delay(name)
            return delayed, Estimate.from_dict(record["estimate"]), tuple(record["dropped"])
    threshold = dict(case.criteria).get("cramer-rao", {}).get("threshold", 20.0)
    values = selected.estimate.as_mapping()
    dropped: list[str] = []
    while True:
        estimate = best_delayed_fit(case, estimator, delayed, ident, values)
        worst = _undetermined_delay(estimate, threshold)
        if worst is None:
            break
        dropped.append(worst[4:])
        delayed = delayed.without_delay(worst[4:])
        values = estimate.as_mapping()
    atomic_write(saved, json.dumps(jsonable({"selected_step": selected.index,
                                              "dropped": dropped,
                                              "estimate": estimate.as_dict()}), indent=1))
    return delayed, estimate, tuple(dropped)


def best_delayed_fit(case: FlightCase, estimator, delayed: ModelStructure, ident,
                     values: Mapping[str, float]) -> Estimate:
    """The delayed structure fitted from ``values`` (derivatives) with the delays at the case's
    initial value and, with ``[delays] starts = N`` > 1, from N − 1 more delay vectors drawn
    uniformly in [0, upper] (generator seeded with ``[delays] seed``); the fit with the lowest
    det R is kept and its notes say which start it came from.

    Delays make the cost multi-modal: one start can settle in a local minimum that another
    avoids (docs/study.md, quick 70 kt run).
    """
    names = [d.delay_name for d in delayed.free_delays]
    upper = 0.3 if case.delay_upper is None else float(case.delay_upper)
    rng = np.random.default_rng(case.delay_seed)
    starts = [np.full(len(names), case.delay_initial)]
    starts += [rng.uniform(0.0, upper, len(names)) for _ in range(case.delay_starts - 1)]
    base = {n: values[n] for n in delayed.parameter_names if n in values}
    best, best_index = None, 0
    for index, delays in enumerate(starts):
        try:
            estimate = estimator.estimate(delayed, ident,
                                          start={**base, **dict(zip(names, delays))})
        except SimulationDivergedError:
            if index == 0:
                raise
            continue                      # a random start the data cannot bring back
        if best is None or estimate.cost < best.cost:
            best, best_index = estimate, index
    if len(starts) == 1:
        return best
    return attrs.evolve(best, notes=best.notes + (
        f"best of {len(starts)} delay starts: start {best_index} "
        f"({'initial values' if best_index == 0 else 'random'})",))


def _undetermined_delay(estimate: Estimate, threshold: float) -> str | None:
    """The worst delay at a bound or above the Cramér-Rao threshold, or ``None``."""
    worst, worst_metric = None, threshold
    for i, name in enumerate(estimate.parameter_names):
        if not name.startswith("tau_"):
            continue
        metric = np.inf if name in estimate.at_bound else estimate.cramer_rao_pct[i]
        if metric > worst_metric or (worst is None and metric == np.inf):
            worst, worst_metric = name, metric
    return worst


# ----------------------------------------------------------------- study
def run_case_task(case: FlightCase, progress: Callable[[str, str], None] | None = log_progress,
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
                         f"{error}") from error


class Study:
    """Several flight cases run through the pipeline, each as an independent task.

    Args:
        cases: :class:`FlightCase` objects or built-in case names / case files.
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
                 progress: Callable[[str, str], None] | None = log_progress,
                 report_writer: ReportWriter | None = None, manager=None):
        self.cases = [c if isinstance(c, FlightCase) else FlightCase.load(c) for c in cases]
        names = [c.name for c in self.cases]
        if len(set(names)) != len(names):
            raise EstimationError(f"case names must be distinct, got {names}")
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
        results, failures = run_tasks(run_case_task,
                                      {c.name: ((c,), options) for c in self.cases},
                                      self.executor, label=lambda name: f"case {name}")
        if failures:
            raise failure_error("cases", results, failures, self.out_dir)
        if self.report_writer is not None:
            self.report_writer.write_study(results, self.out_dir)
        return results
