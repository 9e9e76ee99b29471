"""Identified models read back from result files: :func:`load_result`.

Two kinds of file hold identified models:

- the estimate JSON of ``rotorid identify`` (:meth:`~rotorid.estimation.estimate.Estimate.as_dict`
  plus ``structure``: the model file's path relative to the JSON file, or an embedded model-file
  mapping);
- a study's ``result.json``, which holds two models, ``"no delays"`` and ``"with delays"``,
  with the case's structure declaration and the trim condition.

Either gives an :class:`IdentifiedModel`: the identified structure (the derivatives the
reduction removed are gone, the estimated delays are on), its parameter values, an estimator's
own noise parameters and the estimate, and from them the state-space system
(:mod:`rotorid.model.statespace`).

Each parameter of a record has a role (:func:`parameter_role`): a parameter of the model, of
the records (output biases, initial states), or an estimator's own noise parameter. A name
that is none of these is a derivative the structure cannot hold, most likely because the
result is read with another model file than the one it was estimated with; it is refused.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

import attrs

from rotorid.data import HOLDS
from rotorid.errors import DataFileError, UsageError
from rotorid.estimation.estimate import Estimate
from rotorid.io import read_json_object
from rotorid.model.derivatives import delay_parameter, delayed_derivative
from rotorid.model.modelfile import case_model, load_model, parse_model
from rotorid.model.statespace import NamedStateSpace, state_space
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.units import unit_system

#: The models of a study's ``result.json``, the one with delays first (the default).
STUDY_MODELS = ("with delays", "no delays")
#: The ingestion settings a result records for its records (:class:`rotorid.ingestion.
#: Ingestion`), which sweeps are then read with.
INGESTION_SETTINGS = ("trim", "resample", "sample_time")
#: Parameters that belong to the identification records, not to the model: output biases and
#: initial states per maneuver.
RECORD_PARAMETER_PREFIXES = ("bias_", "x0_")
#: The roles of an estimate's parameters (:func:`parameter_role`).
PARAMETER_ROLES = ("model", "record", "noise", "unknown")


@attrs.frozen(eq=False)
class IdentifiedModel:
    """An identified model read from a result file (immutable).

    Attributes:
        structure: the identified structure (removed derivatives dropped, delays added).
        values: name → value of every parameter of ``structure`` (delays ``tau_<name>`` in s),
            in the structure's units.
        estimate: the full estimate, or None for a file that lists only values.
        source: the file read; model: the study model chosen, None for an identify result.
        noise: name → value of the estimator's own noise parameters (filter error's process
            noise ``F_<state>``, disturbances ``D_<state>`` and ``T_<state>``, gusts
            ``G_<state>`` and ``Tg_<state>``, measurement noise ``R_<output>``; units in the
            estimate's ``parameter_units``); empty for an output-error result.
        actuator_lag_s, actuator_inputs: the actuators' first-order lag (s) the records' inputs
            went through before the fit, and the inputs it acted on (None: every input);
            None without one (:mod:`rotorid.actuators`): the model maps the lagged inputs.
        ingestion: how the identification records were read (:class:`rotorid.ingestion.
            Ingestion` settings ``trim``, ``resample``, ``sample_time``, and for a study of
            files the case's ``channels`` table), so that sweeps are read the same way; empty
            where the result names none.
        hold: the identification records' input hold (``"zoh"`` or ``"foh"``), which sweeps
            recorded the same way share; ``"zoh"`` where the result names none.
    """

    structure: ModelStructure
    values: Mapping[str, float] = attrs.field(converter=dict)
    estimate: Estimate | None
    source: str
    model: str | None = None
    noise: Mapping[str, float] = attrs.field(factory=dict, converter=dict)
    actuator_lag_s: float | None = None
    actuator_inputs: tuple[str, ...] | None = None
    ingestion: Mapping[str, object] = attrs.field(factory=dict, converter=dict)
    hold: str = "zoh"

    def __repr__(self) -> str:
        label = f", model {self.model!r}" if self.model else ""
        delays = len(self.structure.free_delays)
        return (f"IdentifiedModel({self.source}{label}: {len(self.values) - delays} "
                f"derivatives, {delays} delay{'s' * (delays != 1)}, "
                f"{self.structure.units.name} units)")

    def state_space(self, pade_order: int = 0) -> NamedStateSpace:
        """The model as a named state-space system
        (:func:`rotorid.model.statespace.state_space`)."""
        return state_space(self.structure, self.values, pade_order=pade_order)

    def to_statespace(self, pade_order: int = 0):
        """The model as a :class:`scipy.signal.StateSpace`; signal names in
        ``state_space(pade_order)``."""
        return self.state_space(pade_order).to_scipy()


def to_statespace(estimate: Estimate, structure: ModelStructure, pade_order: int = 0):
    """``estimate`` of ``structure`` as a :class:`scipy.signal.StateSpace` (parameters of the
    records, such as output biases, are left out; their names: ``state_space``)."""
    return state_space(structure, model_values(structure, estimate.as_mapping()),
                       pade_order=pade_order).to_scipy()


def parameter_role(structure: ModelStructure, name: str) -> str:
    """The role of the estimated parameter ``name`` for ``structure`` (:data:`PARAMETER_ROLES`):

    - ``"model"``: a delay, or a derivative whose letter is one of the structure's equation
      letters (one the structure cannot hold is refused where it is used);
    - ``"record"``: a parameter of the identification records
      (:data:`RECORD_PARAMETER_PREFIXES`);
    - ``"noise"``: an estimator's own noise parameter, ``<P>_<signal>`` with ``P`` no equation
      letter and ``signal`` one of the structure's states or outputs (filter error's
      ``F_<state>``, ``D_<state>``, ``T_<state>``, ``G_<state>``, ``Tg_<state>``,
      ``R_<output>``);
    - ``"unknown"``: anything else, such as a derivative of another structure.
    """
    if name.startswith(RECORD_PARAMETER_PREFIXES):
        return "record"
    prefix, _, signal = name.partition("_")
    if delayed_derivative(name) is not None or prefix in structure.template.letters:
        return "model"
    if signal in (*structure.states, *structure.outputs):
        return "noise"
    return "unknown"


def model_values(structure: ModelStructure, values: Mapping[str, float]) -> dict[str, float]:
    """``values`` of the model's parameters (role ``"model"``, :func:`parameter_role`), as a
    mapping over ``structure``'s parameters."""
    return structure.as_mapping({n: v for n, v in values.items()
                                 if parameter_role(structure, n) == "model"})


def load_result(path: str | os.PathLike, model: str | None = None,
                structure: ModelStructure | None = None) -> IdentifiedModel:
    """The identified model in a ``rotorid identify`` result or a study's ``result.json``.

    Args:
        path: the JSON file.
        model: for a study result, ``"with delays"`` (default) or ``"no delays"``; an
            identify result holds one model and takes none.
        structure: the structure the estimate belongs to, overriding the one the file names
            (needed when it names none).
    """
    path = Path(path)
    record = read_json_object(path, "result file")
    if isinstance(record.get("estimates"), Mapping):
        chosen = model or STUDY_MODELS[0]
        if chosen not in record["estimates"]:
            raise UsageError(f"{path}: no model {chosen!r}; the study result holds "
                             f"{', '.join(map(repr, record['estimates']))}")
        entry = record["estimates"][chosen]
        declared = structure or _study_structure(record, entry, path)
        settings = record.get("case") if isinstance(record.get("case"), Mapping) else {}
        data = settings.get("data") if isinstance(settings.get("data"), Mapping) else {}
        ingestion = {k: data[k] for k in (*INGESTION_SETTINGS, "channels") if k in data}
        hold = checked_hold(settings.get("identification_hold") or data.get("hold"), path)
    else:
        if model is not None:
            raise UsageError(f"{path} is a `rotorid identify` result holding one model; "
                             f"choosing a model ({model!r}) applies to study results only")
        chosen, entry, settings = None, record, record
        read = record.get("ingestion")
        ingestion = ({k: v for k, v in read.items() if k in INGESTION_SETTINGS}
                     if isinstance(read, Mapping) else {})
        declared = structure or _described_structure(record, path)
        hold = checked_hold(record.get("hold"), path)
    if not isinstance(entry.get("parameters"), Mapping):
        raise DataFileError(f"{path}: no 'parameters' table; give a result written by "
                            f"`rotorid identify` or `rotorid study`")
    identified, values, noise = _identified(declared, entry, path)
    estimate = Estimate.from_dict(entry) if "parameter_names" in entry else None
    lag, inputs = settings.get("actuator_lag_s"), settings.get("actuator_inputs")
    return IdentifiedModel(identified, values, estimate, str(path), chosen, noise,
                           None if lag is None else float(lag),
                           None if inputs is None else tuple(inputs), ingestion, hold)


def checked_hold(hold: str | None, path) -> str:
    """The input hold a result file ``path`` records (``hold`` of a ``rotorid identify``
    result, a study case's ``identification_hold``), checked; ``"zoh"`` where it records
    none."""
    hold = hold or "zoh"
    if hold not in HOLDS:
        raise DataFileError(f"{path}: hold {hold!r} is not one of {', '.join(HOLDS)}")
    return hold


def named_model_file(path: str | os.PathLike) -> Path | None:
    """The model file that the ``rotorid identify`` result ``path`` names (its ``structure``
    path, relative to the result's folder), or None when it names none (a study result, an
    embedded structure, a model by reference)."""
    path = Path(path)
    return _model_file(read_json_object(path, "result file"), path)


def named_model_reference(path: str | os.PathLike) -> str | None:
    """The model of one's own that the ``rotorid identify`` result ``path`` names
    (``file.py:Name`` with the file relative to the result's folder, or
    ``package.module:Name``), or None when it names none."""
    path = Path(path)
    named = read_json_object(path, "result file").get("model")
    if not isinstance(named, str) or ":" not in named:
        return None
    where, _, name = named.rpartition(":")
    if where.endswith(".py") and not Path(where).is_absolute():
        where = str(path.parent / where)
    return f"{where}:{name}"


def _model_file(record: Mapping, path: Path) -> Path | None:
    described = record.get("structure")
    if not isinstance(described, str):
        return None
    model_path = Path(described)
    return model_path if model_path.is_absolute() else path.parent / model_path


def _described_structure(record: Mapping, path: Path) -> ModelStructure:
    model_file = _model_file(record, path)
    if model_file is not None:
        return load_model(model_file)
    described = record.get("structure")
    if isinstance(described, Mapping):
        return parse_model(described, f"{path} (embedded structure)")
    if isinstance(record.get("model"), str):
        raise DataFileError(f"{path}: the result is of a model of one's own "
                            f"({record['model']}), which has no linear structure: rotorid "
                            f"verify compares its simulation with sweeps; export and the "
                            f"structure-based tools need a model file")
    raise DataFileError(f"{path}: the result names no model structure; give the model file "
                        f"it was estimated with")


def _study_structure(record: Mapping, entry: Mapping, path: Path) -> ModelStructure:
    """The case's starting structure at the study's trim condition."""
    case, condition = record.get("case"), record.get("condition")
    if not isinstance(case, Mapping) or not isinstance(condition, Mapping):
        raise DataFileError(f"{path}: a study result needs its 'case' and 'condition'")
    declared = case_model(case, {"airspeed_kt": 0.0}, entry.get("units", "flight-test"),
                          f"{path} (the case's structure)")
    try:
        return attrs.evolve(declared, condition=FlightCondition(**condition))
    except TypeError as error:
        raise DataFileError(f"{path}: malformed 'condition' {dict(condition)!r}: "
                            f"{error}") from None


def _number(entry, name: str, path: Path) -> float:
    value = entry.get("value") if isinstance(entry, Mapping) else entry
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise DataFileError(f"{path}: {name} has no numeric value ({entry!r})")
    return float(value)


def _identified(structure: ModelStructure, entry: Mapping, path: Path):
    """The identified structure, its values and the estimator's noise parameters from an
    estimate record: fixed values set, free derivatives the record does not list removed,
    its delays added. A parameter of no known role is refused."""
    declared = entry.get("units")
    if declared is not None and unit_system(declared).name != structure.units.name:
        raise DataFileError(f"{path}: the estimate is in {declared!r} units but the model "
                            f"structure in {structure.units.name!r}; use the model file it "
                            f"was estimated with")
    by_role = {role: {} for role in PARAMETER_ROLES}
    for name, item in entry["parameters"].items():
        by_role[parameter_role(structure, name)][name] = _number(item, name, path)
    if by_role["unknown"]:
        raise DataFileError(
            f"{path}: parameter(s) {', '.join(by_role['unknown'])} are neither derivatives of "
            f"the model structure (equation letters {' '.join(structure.template.letters)}; "
            f"states {' '.join(structure.states)}) nor an estimator's noise parameters: the "
            f"result was most likely estimated with another model file; give that one "
            f"(structure=... or the result's 'structure')")
    parameters = by_role["model"]
    for name, value in dict(entry.get("fixed") or {}).items():
        if name in structure.names:
            structure = structure.fixing(name, _number(value, name, path))
    delays = {n: _number(e, n, path) for n, e in dict(entry.get("delays") or {}).items()}
    removed = [d.name for d in structure.free_derivatives if d.name not in parameters]
    structure = structure.without(*removed)
    structure = structure.with_delays([n for n in delays if structure.derivative(n).delay
                                       is None], missing="error")
    values = dict(parameters)
    values.update({delay_parameter(n): v for n, v in delays.items()})
    return structure, structure.as_mapping(values), by_role["noise"]


__all__ = ["IdentifiedModel", "STUDY_MODELS", "load_result", "model_values", "named_model_file",
           "parameter_role", "to_statespace"]
