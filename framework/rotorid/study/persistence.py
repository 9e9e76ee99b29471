"""A case's results directory: the resume points and the records, all written atomically.

``<out>/<case>/`` holds ``case.json`` (the settings the results belong to), ``steps/`` (one
``step_NNN.json`` per finished reduction step), ``delays.json`` (the delayed fit of the
selected step), ``profiles.json`` (its delay profiles) and ``result.json``.
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path

import attrs
import numpy as np

from rotorid.errors import DataFileError, RotoridError
from rotorid.estimation.estimate import Estimate
from rotorid.estimation.profiles import DelayProfile
from rotorid.estimation.reduction import ReductionStep
from rotorid.plugin.contracts import Removal
from rotorid.io import atomic_write, jsonable, read_json_object
from rotorid.lease import check_owner_alive
from rotorid.model.structure import ModelStructure
from rotorid.study.case import FlightCase
from rotorid.study.result import CaseResult


def prepare_directory(directory: Path, case: FlightCase, resume: bool) -> None:
    """Create ``directory`` for ``case`` and record its settings; without ``resume`` remove
    earlier resume points. Resuming results of other settings is an error."""
    check_owner_alive(directory)
    (directory / "steps").mkdir(parents=True, exist_ok=True)
    for stale in [*directory.glob(".*.tmp"), *directory.glob("*/.*.tmp")]:
        stale.unlink()        # left by an interrupted atomic write; never a finished file
    marker = directory / "case.json"
    settings = json.dumps(jsonable(case.as_dict()), sort_keys=True)
    if marker.is_file() and resume and marker.read_text() != settings:
        raise RotoridError(f"{directory} holds results of a different configuration of case "
                           f"{case.name}; choose another --out directory or run without "
                           f"--resume to start afresh")
    if not resume:
        for old in [*directory.glob("steps/step_*.json"), directory / "delays.json",
                    directory / "profiles.json"]:
            if old.is_file():
                old.unlink()
    atomic_write(marker, settings)


def _step_file(directory: Path, index: int) -> Path:
    return directory / "steps" / f"step_{index:03d}.json"


def save_step(directory: Path, step: ReductionStep) -> None:
    """Write a finished reduction step."""
    removal = None if step.removal is None else attrs.asdict(step.removal)
    record = {"index": step.index, "removal": removal, "estimate": step.estimate.as_dict()}
    atomic_write(_step_file(directory, step.index), json.dumps(jsonable(record), indent=1))


def load_steps(directory: Path, base: ModelStructure) -> list[ReductionStep]:
    """The finished reduction steps of ``base`` saved in ``directory``, in order."""
    steps, structure = [], base
    index = 0
    while _step_file(directory, index).is_file():
        path = _step_file(directory, index)
        with _resume_record(path) as record:
            removal = None
            if record["removal"] is not None:
                removal = Removal(**{k: (np.inf if v is None else v)
                                     for k, v in record["removal"].items()})
                structure = structure.without(removal.parameter)
            estimate = Estimate.from_dict(record["estimate"])
        if not structure.parameter_names:
            break
        steps.append(ReductionStep(index, removal, estimate, structure))
        index += 1
    return steps


@contextlib.contextmanager
def _resume_record(path: Path):
    """The JSON object of a resume file; a file that cannot be read or does not hold what it
    should is named with the cause and the fix."""
    try:
        yield read_json_object(path, "resume file")
    except (RotoridError, KeyError, TypeError, ValueError, AttributeError) as error:
        cause = f"no {error}" if isinstance(error, KeyError) else str(error)
        raise DataFileError(f"cannot resume from {path}: {cause}; delete that file (it is "
                            f"recomputed) or run without --resume") from None


def load_delays(directory: Path, selected_step: int) -> tuple[tuple[str, ...], Estimate] | None:
    """The dropped delays and the delayed fit saved for ``selected_step``, or ``None``."""
    saved = directory / "delays.json"
    if not saved.is_file():
        return None
    with _resume_record(saved) as record:
        if record.get("selected_step") != selected_step:
            return None
        return tuple(record["dropped"]), Estimate.from_dict(record["estimate"])


def save_delays(directory: Path, selected_step: int, dropped: tuple[str, ...],
                estimate: Estimate) -> None:
    """Write the delayed fit of ``selected_step`` and the delays it dropped."""
    atomic_write(directory / "delays.json",
                 json.dumps(jsonable({"selected_step": selected_step, "dropped": list(dropped),
                                      "estimate": estimate.as_dict()}), indent=1))


def load_profiles(directory: Path, selected_step: int) -> tuple[DelayProfile, ...] | None:
    """The delay profiles saved for ``selected_step``, or ``None``."""
    saved = directory / "profiles.json"
    if not saved.is_file():
        return None
    with _resume_record(saved) as record:
        if record.get("selected_step") != selected_step:
            return None
        return tuple(DelayProfile.from_dict(p) for p in record["profiles"])


def save_profiles(directory: Path, selected_step: int,
                  profiles: tuple[DelayProfile, ...]) -> None:
    """Write the delay profiles of ``selected_step``'s delayed fit."""
    atomic_write(directory / "profiles.json",
                 json.dumps(jsonable({"selected_step": selected_step,
                                      "profiles": [p.as_dict() for p in profiles]}), indent=1))


def save_result(directory: Path, result: CaseResult) -> None:
    """Write ``result.json`` and, where the estimator gave them, the state estimates as
    maneuver files ``state_estimates/<maneuver>.csv``."""
    atomic_write(directory / "result.json",
                 json.dumps(jsonable(result.as_dict()), indent=1, default=_json_default))
    if result.state_estimates is not None:
        from rotorid.estimation.state_estimates import STUDY_DIRECTORY
        from rotorid.plugin.manager import create

        create("data-sources", "files", hold=result.identification.hold).save(
            result.state_estimates.as_maneuvers(result.identification),
            directory / STUDY_DIRECTORY)


def _json_default(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
