"""Sanity checks of maneuver data before a fit, reported as :class:`~rotorid.errors.DataWarning`.

Unlike :mod:`rotorid.estimation.data_checks` (data a fit cannot use at all, refused), these
find data a fit would use and be misled by; each warning gives the numbers and the fix:

- an input that never moves: none of its derivatives can be estimated, so
  :func:`without_unexcited` drops them from the structure before the first fit;
- outputs that are not perturbations from trim: ``az`` holding 1 g, other outputs starting
  far from zero (an offset, an absolute attitude);
- an implausible unit scale: angular rates far too small (rad/s declared as deg/s) or too
  large (deg/s declared as rad/s) for a maneuver that moves the controls; an angle beyond
  180° from zero (deg read as rad);
- a sensor that sits on one value for several samples: at its extreme (saturated or clipped)
  or elsewhere (a dropout held at the last value);
- rates and accelerations that do not integrate to the attitudes and velocities
  (:mod:`rotorid.estimation.kinematics`).
"""

from __future__ import annotations

import contextlib
import logging
import math
import warnings

import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import DataWarning
from rotorid.estimation.data_checks import is_constant
from rotorid.estimation.kinematics import WHERE_UNITS, check_kinematics
from rotorid.ingestion import moment_text
from rotorid.model.signals import ModelSignals
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.units import CHANNEL_KINDS, unit_system

#: Seconds at the start of a maneuver whose mean is its starting level.
START_WINDOW = 1.0
#: An output whose starting level exceeds this fraction of its swing is offset …
OFFSET_FRACTION = 0.25
#: … when the level is also this many standard deviations of the start window from zero.
OFFSET_NOISE_RATIO = 3.0
#: ``az`` whose median lies within this fraction of g of ±1 g includes gravity.
ONE_G_TOLERANCE = 0.2
#: Identical consecutive samples that make a flat run (clipping or a dropout).
FLAT_RUN = 5
#: Plausible range of the largest angular rate of a maneuver that moves the controls, deg/s.
PLAUSIBLE_RATE_DEG = (1.0, 400.0)
#: No identification maneuver moves a flow angle or attitude further than this from trim, deg.
PLAUSIBLE_ANGLE_DEG = 180.0
RATE_CHANNELS = ("q", "p", "r")


def _warn(message: str) -> None:
    warnings.warn(message, DataWarning, stacklevel=3)


def unexcited_inputs(maneuvers: ManeuverSet) -> dict[str, float]:
    """Inputs that hold one value in every maneuver: name → that value."""
    inputs = np.concatenate([m.inputs for m in maneuvers])
    return {name: float(column[0]) for name, column in zip(maneuvers.input_names, inputs.T)
            if is_constant(column)}


def without_unexcited(structure: ModelStructure | None, maneuvers: ManeuverSet,
                      read: tuple[str, ...] | None = None) -> ModelStructure | None:
    """Warn about every input that never moves; return ``structure`` without the free
    derivatives of those inputs (they cannot be estimated), saying which were dropped.
    ``None`` (a model of one's own) is returned as it is, after the warnings about the
    inputs it reads (``read``; every input when None)."""
    for name, value in unexcited_inputs(maneuvers).items():
        held = f"input {name!r} never moves (constant {value:.6g} in every maneuver)"
        if structure is None:
            if read is None or name in read:
                _warn(f"{held}: the model's parameters of how it acts cannot be estimated; "
                      f"leave them out of the model or add a maneuver that moves {name}")
            continue
        dropped = [d.name for d in structure.free_derivatives if d.variable == name]
        if dropped:
            structure = structure.without(*dropped)
            _warn(f"{held}: its derivatives cannot be estimated, so the structure drops "
                  f"{', '.join(dropped)} before the first fit; add a maneuver that moves "
                  f"{name} to identify them")
    return structure


def _start(record: np.ndarray, dt: float) -> tuple[float, float]:
    """Mean and standard deviation of one channel's ``record`` (N,) over its first second."""
    n = max(2, int(round(START_WINDOW / dt)) + 1)
    window = record[:n]
    return float(np.mean(window)), float(np.std(window))


def _largest_offset(maneuvers: ManeuverSet, records) -> tuple[int, tuple] | None:
    """(how many maneuvers, the largest (|level|, level, swing, maneuver name)) of one channel
    whose first second sits away from zero against its swing; ``records`` gives the channel
    per maneuver. None when none does."""
    offsets = []
    for m, record in zip(maneuvers, records):
        level, noise = _start(record, m.dt)
        swing = float(np.ptp(record))
        if abs(level) > OFFSET_FRACTION * swing and abs(level) > OFFSET_NOISE_RATIO * noise \
                and swing > 0:
            offsets.append((abs(level), level, swing, m.name))
    return (len(offsets), max(offsets)) if offsets else None


def _check_gravity(maneuvers: ManeuverSet, own_model: bool = False) -> bool:
    """Warn when ``az`` includes 1 g; return whether it did. For a model of one's own
    (``own_model``), which may read totals, the warning says when to ignore it."""
    system = unit_system(maneuvers.units)
    if "az" not in maneuvers.output_names:
        return False
    az = np.concatenate([m.channel("az") for m in maneuvers])
    median = float(np.median(az))
    if abs(abs(median) - system.g) > ONE_G_TOLERANCE * system.g:
        return False
    unit = system.label("az")
    removed = _stated_trim(maneuvers, "az")
    shown = (f"--trim az={median + removed:.4g}, which includes the {removed:.4g} {unit} "
             f"already removed" if removed else f"--trim az={median:.4g}")
    _warn(f"output 'az' holds 1 g (median {median:.4g} {unit}, g = {system.g:.4g} {unit}): "
          f"outputs are perturbations from trim; remove the trim (rotorid identify --trim "
          f"first-second, or {shown})"
          + ("; a model of one's own that reads the total acceleration can ignore this"
             if own_model else ""))
    return True


def _stated_trim(maneuvers: ManeuverSet, channel: str) -> float:
    """The trim value every maneuver had taken off ``channel`` when reading (their
    ``trim_removed`` metadata), in the maneuvers' units; 0 when they differ or none was."""
    values = set()
    for m in maneuvers:
        removed = m.metadata.get("trim_removed")
        stated_in = m.metadata.get("trim_units", maneuvers.units)
        if not isinstance(removed, dict) or channel not in removed:
            return 0.0
        if unit_system(stated_in).name != unit_system(maneuvers.units).name:
            return 0.0
        values.add(float(removed[channel]))
    return values.pop() if len(values) == 1 else 0.0


def _unit(maneuvers: ManeuverSet, name: str, signals: ModelSignals | None) -> str:
    """`` ft/s``: the unit of output ``name`` with a leading space, from the model's
    ``signals`` where they declare it, else the shipped channel's; empty for a channel of
    one's own that no signals declare."""
    if signals is not None and name in signals.all:
        return f" {signals.all[name].unit}"
    return f" {unit_system(maneuvers.units).label(name)}" if name in CHANNEL_KINDS else ""


def _check_offsets(maneuvers: ManeuverSet, skip: tuple[str, ...],
                   signals: ModelSignals | None) -> None:
    for column, name in enumerate(maneuvers.output_names):
        found = None if name in skip else _largest_offset(
            maneuvers, [m.outputs[:, column] for m in maneuvers])
        if found is None:
            continue
        count, (_, level, swing, where) = found
        unit = _unit(maneuvers, name, signals)
        kind = " (an absolute attitude?)" if name in ("theta", "phi") else ""
        _warn(f"output {name!r} starts away from zero in {count} of {len(maneuvers)} "
              f"maneuvers{kind}: {level:.4g}{unit} (mean of the first {START_WINDOW:g} s of "
              f"{where}) against a swing of {swing:.4g}{unit}; outputs are perturbations "
              f"from trim: remove the trim (rotorid identify --trim first-second, or "
              f"--trim {name}=VALUE) or estimate output biases (--output-biases)")


def _check_input_offsets(maneuvers: ManeuverSet, signals: ModelSignals | None) -> None:
    """A control recorded on top of its trim acts as a constant extra input, which the
    derivatives then take up (output biases cannot: the offset is in the inputs)."""
    for column, name in enumerate(maneuvers.input_names):
        found = _largest_offset(maneuvers, [m.inputs[:, column] for m in maneuvers])
        if found is None:
            continue
        count, (_, level, swing, where) = found
        unit = (f" {signals.all[name].unit}" if signals is not None and name in signals.all
                else "")
        _warn(f"input {name!r} starts away from zero in {count} of {len(maneuvers)} "
              f"maneuvers: {level:.4g}{unit} (mean of the first {START_WINDOW:g} s of {where}) "
              f"against a swing of {swing:.4g}{unit}; inputs are perturbations from trim, and "
              f"an offset left in them biases the derivatives (output biases do not help): "
              f"remove the trim (rotorid identify --trim first-second, or --trim {name}=VALUE)")


def _check_angle_range(maneuvers: ManeuverSet) -> None:
    """An angle output (attitude, flow angle, rotor angle) beyond :data:`PLAUSIBLE_ANGLE_DEG`
    from zero: recorded in deg and read as rad (a 5° swing of α read as 5 rad)."""
    system = unit_system(maneuvers.units)
    to_deg = math.degrees(1.0) / system.angle_per_radian
    for name in maneuvers.output_names:
        if CHANNEL_KINDS.get(name) != "angle":
            continue
        largest = max(float(np.max(np.abs(m.channel(name)))) for m in maneuvers)
        if largest * to_deg > PLAUSIBLE_ANGLE_DEG:
            unit = system.label(name)
            _warn(f"output {name!r} reaches {largest:.4g} {unit} ({largest * to_deg:.4g} deg) "
                  f"from zero, beyond any maneuver's angle: was it recorded in deg and read as "
                  f"rad? Declare its unit ({WHERE_UNITS} {{\"{name}\": \"deg\"}})")


def _check_rate_scale(maneuvers: ManeuverSet) -> None:
    if all(is_constant(m.inputs) for m in maneuvers):
        return
    system = unit_system(maneuvers.units)
    to_deg = math.degrees(1.0) / system.angle_per_radian
    rates = [n for n in RATE_CHANNELS if n in maneuvers.output_names]
    if not rates:
        return
    largest = max(float(np.max(np.abs(m.columns(rates)))) for m in maneuvers) * to_deg
    unit = system.label("q")
    value = f"{largest:.3g} deg/s" if unit == "deg/s" else \
        f"{largest / to_deg:.3g} {unit} ({largest:.3g} deg/s)"
    low, high = PLAUSIBLE_RATE_DEG
    if largest < low:
        _warn(f"the largest angular rate (p, q, r) in any maneuver is {value} while the inputs "
              f"move: a maneuver for identification moves the aircraft by several deg/s; were "
              f"the rates recorded in rad/s? Declare the data's units (units: si, or "
              f"{WHERE_UNITS} {{\"q\": \"rad/s\", …}})")
    elif largest > high:
        _warn(f"the largest angular rate (p, q, r) in any maneuver is {value}, beyond any "
              f"aircraft's maneuver: were the rates recorded in deg/s? Declare the data's "
              f"units (units: flight-test, or {WHERE_UNITS} {{\"q\": \"deg/s\", …}})")


def _flat_runs(record: np.ndarray):
    """(start, length) of every run of at least :data:`FLAT_RUN` identical samples."""
    same = np.concatenate([[False], record[1:] == record[:-1], [False]])
    edges = np.flatnonzero(np.diff(same.astype(int)))
    for begin, end in zip(edges[::2], edges[1::2]):
        if end - begin + 1 >= FLAT_RUN:
            yield int(begin), int(end - begin + 1)


def _first_flat_run(maneuver, column: int, unit: str):
    """(kind, description) of the first flat run of an output that varies (its ``unit`` as
    :func:`_unit` gives it), or None; kind is ``"clipped"`` at the record's extreme,
    ``"dropout"`` elsewhere."""
    record = maneuver.outputs[:, column]
    if is_constant(record):
        return None
    for start, length in _flat_runs(record):
        value = record[start]
        kind = "clipped" if value in (record.max(), record.min()) else "dropout"
        return kind, (f"{value:.6g}{unit} for {length} samples ({length * maneuver.dt:.3g} s) "
                      f"from {moment_text(maneuver.time, start)} in maneuver "
                      f"{maneuver.name!r}")
    return None


def _check_flat_runs(maneuvers: ManeuverSet, signals: ModelSignals | None) -> None:
    """Outputs that sit on one value: at the record's extreme (clipping) or not (dropout);
    one warning per output and kind, naming the first case and how many maneuvers have one."""
    advice = {"clipped": ("sits at its extreme", "a saturated or clipped sensor"),
              "dropout": ("repeats", "a dropout held at the last value")}
    for column, name in enumerate(maneuvers.output_names):
        found: dict[str, list[str]] = {}
        for m in maneuvers:
            run = _first_flat_run(m, column, _unit(maneuvers, name, signals))
            if run is not None:
                found.setdefault(run[0], []).append(run[1])
        for kind, cases in found.items():
            verb, cause = advice[kind]
            _warn(f"output {name!r} {verb} {cases[0]} ({len(cases)} of {len(maneuvers)} "
                  f"maneuvers like this): {cause}; cut the maneuver before it or leave the "
                  f"maneuver out")


@contextlib.contextmanager
def checks_report(shown: bool):
    """Unless ``shown``, the checks' report lines (the ``rotorid.checks`` logger's INFO
    messages, e.g. each kinematic fit) are left out while the block runs; their warnings
    stay."""
    log = logging.getLogger("rotorid.checks")
    level = log.level
    if not shown:
        log.setLevel(logging.WARNING)
    try:
        yield
    finally:
        log.setLevel(level)


def check_data(maneuvers: ManeuverSet, condition: FlightCondition | None = None,
               signals: ModelSignals | None = None, own_model: bool = False) -> None:
    """Issue a :class:`~rotorid.errors.DataWarning` for each finding about the outputs of
    ``maneuvers`` (everything but unexcited inputs, see :func:`without_unexcited`).
    ``condition`` is the trim the kinematic check linearises about (default: level hover);
    ``signals`` the model's, whose units the messages give for channels of its own;
    ``own_model`` for a model of one's own, which may read totals."""
    one_g = _check_gravity(maneuvers, own_model)
    _check_offsets(maneuvers, ("az",) if one_g else (), signals)
    _check_input_offsets(maneuvers, signals)
    _check_rate_scale(maneuvers)
    _check_angle_range(maneuvers)
    _check_flat_runs(maneuvers, signals)
    check_kinematics(maneuvers, condition)


def check_before_fit(maneuvers: ManeuverSet, structure, condition: FlightCondition | None = None
                     ) -> ModelStructure | None:
    """Every sanity check; returns ``structure`` (a ModelStructure) without the derivatives of
    inputs that never move (see :func:`without_unexcited`). For a model of one's own
    (anything else, or None) the checks read the records as they are and name only the
    unmoving inputs it reads (its ``signals``, where it has them); it is returned as None."""
    if isinstance(structure, ModelStructure):
        check_data(maneuvers, structure.condition, structure.signals)
        return without_unexcited(structure, maneuvers)
    check_data(maneuvers, condition, own_model=True)
    signals = getattr(structure, "signals", None)
    return without_unexcited(None, maneuvers, None if signals is None else signals.inputs.names)
