"""Checks of data against a model before a fit or a simulation: what would make the
output-error cost meaningless (a fitted output that never varies, two fitted outputs that are
the same record, fewer samples than parameters, a delay as long as a record) is named with the
channel and the cause instead of surfacing as a diverging, singular or all-zero result; so
are records no rotorcraft gives (a sample interval of seconds, a record shorter than 1 s or
longer than 1000 s, attitudes beyond 90°, rates beyond 1000 °/s, specific forces beyond 30 g),
whose usual cause is a unit or a scale error."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import DataError
from rotorid.model.structure import ModelStructure
from rotorid.units import unit_system

#: An output whose standard deviation over all maneuvers is below this fraction of its
#: largest magnitude (or exactly zero) carries no information.
CONSTANT_FRACTION = 1e-9
#: Longest sample interval that still resolves rotorcraft dynamics, s.
MAX_SAMPLE_INTERVAL = 0.5
#: Shortest record that shows a rotorcraft's response, s: its slowest body modes (the
#: speed and heave subsidences, phugoid) need seconds, its fastest (roll subsidence, about
#: 0.1–0.3 s) several time constants. Shorter records (a few samples, or time in minutes)
#: leave the derivatives undetermined.
MIN_RECORD_SECONDS = 1.0
#: Longest record an identification maneuver has, s (multisteps last 5–30 s, sweeps up to
#: about 120 s): a record of thousands of seconds is a time in ms.
MAX_RECORD_SECONDS = 1000.0
#: Largest attitude perturbation from trim a small-perturbation model describes, deg.
MAX_ATTITUDE_DEG = 90.0
#: Largest angular rate and specific force a rotorcraft record can hold, deg/s and g.
MAX_RATE_DEG_S = 1000.0
MAX_ACCELERATION_G = 30.0


def is_constant(record: np.ndarray) -> bool:
    """Whether the samples ``record`` (any shape) never vary (see :data:`CONSTANT_FRACTION`);
    a record without samples (no channel) does not."""
    return bool(np.size(record) == 0
                or np.std(record) <= CONSTANT_FRACTION * np.max(np.abs(record)))


def check_fit_data(maneuvers: ManeuverSet, outputs: Sequence[str] | None,
                   model: ModelStructure) -> None:
    """Raise :class:`DataError` naming the channel and the fix when ``maneuvers`` cannot
    inform a fit of ``model`` (from its initial values) on ``outputs`` (``None``: all of the
    model's)."""
    _check_plausible(maneuvers)
    check_delays(model, maneuvers)
    unknown = [n for n in outputs or () if n not in model.outputs]
    if unknown:
        raise DataError(f"unknown output(s) {', '.join(map(repr, unknown))} to fit; choose from "
                        f"{', '.join(model.outputs)}")
    n_parameters = model.n_parameters
    names = tuple(outputs or model.outputs)
    for maneuver in maneuvers:
        block = maneuver.columns(names)
        if np.all(np.ptp(block, axis=0) == 0.0):
            raise DataError(f"maneuver {maneuver.name}: every fitted output is constant (a "
                            f"record without response, or a file of zeros); remove it from "
                            f"the data")
    records = np.concatenate([m.columns(names) for m in maneuvers])
    for name, record in zip(names, records.T):
        if is_constant(record):
            raise DataError(f"output {name!r} is constant in every maneuver (value "
                            f"{record[0]:.6g}): it carries no information and makes the noise "
                            f"covariance singular; check the recording or leave it out with "
                            f"--outputs")
    for i, first in enumerate(names):
        for j in range(i + 1, len(names)):
            if np.array_equal(records[:, i], records[:, j]):
                raise DataError(f"outputs {first!r} and {names[j]!r} hold the same record in "
                                f"every maneuver (a channel recorded twice?); leave one out "
                                f"with --outputs")
    if records.size < n_parameters:
        raise DataError(f"{records.size} output samples cannot determine {n_parameters} "
                        f"parameters; give longer or more maneuvers or fewer parameters")


def check_delays(model: ModelStructure, maneuvers: ManeuverSet, values=None) -> None:
    """Raise :class:`DataError` when a delay of ``model`` (at ``values``, a vector or mapping
    of its free parameters; default its initial values) is not shorter than the shortest
    record of ``maneuvers``: the delayed term would never act."""
    delays = {d.delay_name: d.delay.initial for d in model.derivatives if d.delay is not None}
    if values is not None:
        delays.update({n: v for n, v in model.as_mapping(values).items() if n in delays})
    shortest = min(maneuvers, key=lambda m: m.time[-1] - m.time[0])
    duration = float(shortest.time[-1] - shortest.time[0])
    for name, tau in delays.items():
        if tau >= duration:
            raise DataError(f"delay {name} = {tau:g} s is not shorter than the record "
                            f"{shortest.name} ({duration:g} s): the delayed term would never "
                            f"act; check its unit (s) or give longer records")


def _check_plausible(maneuvers: ManeuverSet) -> None:
    """Sample interval and output magnitudes a rotorcraft record can have; the usual cause of
    others is a unit (time in ms, angles in deg declared as rad) or a scale error."""
    for maneuver in maneuvers:
        if maneuver.dt > MAX_SAMPLE_INTERVAL:
            raise DataError(f"maneuver {maneuver.name}: sample interval {maneuver.dt:g} s is "
                            f"longer than {MAX_SAMPLE_INTERVAL:g} s; is the time in ms? give "
                            f"it in s")
        duration = float(maneuver.time[-1] - maneuver.time[0])
        if duration > MAX_RECORD_SECONDS:
            raise DataError(f"maneuver {maneuver.name}: the record lasts {duration:.4g} s "
                            f"({maneuver.n_samples} samples), longer than any identification "
                            f"maneuver ({MAX_RECORD_SECONDS:g} s); is the time in ms? give it "
                            f"in s")
        if duration < MIN_RECORD_SECONDS:
            raise DataError(f"maneuver {maneuver.name}: the record lasts {duration:.4g} s "
                            f"({maneuver.n_samples} samples), shorter than the "
                            f"{MIN_RECORD_SECONDS:g} s a rotorcraft response needs; give "
                            f"longer records (or the time in s, if it is in minutes)")
        units = unit_system(maneuver.units)
        degrees = math.degrees(units.radian_per_angle)
        for names, scale, limit, unit, guess in (
                (("theta", "phi"), degrees, MAX_ATTITUDE_DEG, "°",
                 "angles in deg declared as rad"),
                (("p", "q", "r"), degrees, MAX_RATE_DEG_S, "°/s",
                 "rates in deg/s declared as rad/s"),
                (("ax", "ay", "az"), 1 / units.g, MAX_ACCELERATION_G, " g",
                 "m/s² or ft/s² declared as g")):
            for name in (n for n in names if n in maneuver.output_names):
                largest = float(np.max(np.abs(maneuver.channel(name)))) * scale
                if largest > limit:
                    raise DataError(f"maneuver {maneuver.name}: output {name!r} reaches "
                                    f"{largest:.4g}{unit} from trim, beyond {limit:g}{unit}; "
                                    f"check the unit and scale of that channel in the data "
                                    f"file ({guess}?)")
