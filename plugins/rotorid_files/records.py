"""What every file format shares: the flat header and the checks that turn columns into a
:class:`~rotorid.data.Maneuver`.

A file holds one maneuver as named columns (``time``, controls, outputs and optionally the
body velocities ``u v w`` and the rotor angles ``beta0 beta1c beta1s``) plus a flat header: ``name``, ``units``, ``initial_state`` (and
``state_names``, the states it gives values for, when not ``u w q theta v p phi r``),
``channel_units`` (channel → the unit it was recorded in, when not its unit system's) and any
metadata key (``condition``, ``kind``, ``axis``, ``direction`` …). Header values are JSON
values.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from pathlib import Path

import attrs
import numpy as np
from rotorid.data import ALL_CHANNELS, GUST_CHANNELS, Maneuver
from rotorid.errors import DataError, DataFileError, RotoridError
from rotorid.ingestion import Ingestion
from rotorid.model.structure import STATES
from rotorid.units import unit_system

#: Optional body-velocity columns, kept as extra channels (the kinematic consistency check
#: integrates the accelerations against them, :mod:`rotorid.estimation.kinematics`).
VELOCITIES = ("u", "v", "w")
#: Optional rotor columns: coning and tip-path-plane tilts, kept as extra channels (a hybrid
#: model measuring its rotor states reads them, docs/hybrid.md).
ROTOR_ANGLES = ("beta0", "beta1c", "beta1s")
#: Columns beyond the fixed layout that a file may hold without a model naming them; the
#: gusts a generated record flew through (``rotorid generate --turbulence``) among them, which
#: filter error's gust estimates of the same names are drawn against (``rotorid identify
#: --states``).
OPTIONAL_COLUMNS = VELOCITIES + ROTOR_ANGLES + GUST_CHANNELS
#: Header keys that are not metadata.
RESERVED = ("name", "units", "initial_state", "state_names", "channel_units")
#: Allowed metadata keys (also the ``# key: value`` syntax of CSV files).
KEY_PATTERN = re.compile(r"[A-Za-z_][A-Za-z0-9_.-]*")


def _json_default(value):
    if isinstance(value, (np.generic, np.ndarray)):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not a JSON value")


def encode_value(value, where: str) -> str:
    """One header value as compact JSON text."""
    try:
        return json.dumps(value, default=_json_default, ensure_ascii=False, allow_nan=False)
    except (TypeError, ValueError) as error:
        raise DataFileError(f"{where}: cannot store {value!r} in a file header ({error}); "
                            f"use strings, numbers, booleans, lists or mappings") from None


def header_of(maneuver: Maneuver, where: str) -> dict:
    """The flat header of ``maneuver``: reserved keys first, then its metadata."""
    header = {"name": maneuver.name, "units": maneuver.units}
    if maneuver.initial_state is not None:
        header["initial_state"] = maneuver.initial_state.tolist()
        if maneuver.state_names != STATES:
            header["state_names"] = list(maneuver.state_names)
    for key, value in maneuver.metadata.items():
        if key in RESERVED or not isinstance(key, str) or not KEY_PATTERN.fullmatch(key):
            raise DataFileError(
                f"{where}: metadata key {key!r} cannot be stored; keys must match "
                f"{KEY_PATTERN.pattern} and not be one of {', '.join(RESERVED)}")
        header[key] = value
    return header


def columns_of(maneuver: Maneuver) -> dict[str, np.ndarray]:
    """Channel name → 1-D array: time, the inputs and the outputs the maneuver holds, and its
    body velocities and rotor angles if it has them."""
    optional = [c for c in OPTIONAL_COLUMNS if c in maneuver.extra_channels]
    return {name: maneuver.channel(name) for name in (*maneuver.channel_names, *optional)}


def vector(path: Path, channel: str, array) -> np.ndarray:
    """A numeric channel as a 1-D float array (row and column vectors are flattened)."""
    array = np.asarray(array)
    if array.dtype.kind not in "fiu":
        raise DataFileError(f"{path}: channel {channel!r} is not numeric (dtype {array.dtype})")
    if array.ndim > 1 and sum(n > 1 for n in array.shape) <= 1:
        array = array.reshape(-1)
    if array.ndim != 1:
        raise DataFileError(f"{path}: channel {channel!r} must be a vector, got shape "
                            f"{array.shape}")
    return array.astype(float)


def assemble(path: Path, columns: Mapping[str, np.ndarray], header: Mapping,
             ingestion: Ingestion, row_note: str = "") -> Maneuver:
    """Check columns and header read from ``path`` and build the maneuver.

    Args:
        columns: channel name → 1-D array, all of the same length: ``time`` and some of the
            channels of :data:`rotorid.data.ALL_CHANNELS` (at least one input and one
            output; a model names the ones it uses and lacks). Read for a model (``ingestion``
            with its signals, channel map or kept columns), any further columns are kept as
            unused extra channels; read plainly, they are refused as misspelt channels.
        header: flat header (see module docstring); ``name`` defaults to the file stem,
            ``units`` to ``"flight-test"``.
        ingestion: what to do to the columns first (:mod:`rotorid.ingestion`); the file's
            ``channel_units`` add to (and override) its ``channel_units``.
        row_note: appended to data errors, to say how rows map to lines of the file.
    """
    # read for a model (its signals, its channel map or the columns it reads itself): the
    # model says which columns matter, and a flight-test file's others travel unused as
    # extra channels
    for_model = bool(ingestion.signals is not None or ingestion.keep_columns
                     or ingestion.channels.links)
    if isinstance(header.get("axis"), str):                     # the column a sweep moves
        header = {**header, "axis": ingestion.channels.signal_of(header["axis"])}
    try:
        columns, ingestion = ingestion.mapped(columns, str(path))
    except DataError as error:
        raise DataFileError(str(error)) from None
    declared = () if ingestion.signals is None else ingestion.signals.all.names
    # a file of state estimates (rotorid identify --states) declares its states' units
    estimated = tuple(header.get("state_units") or ())
    known = tuple(dict.fromkeys(ALL_CHANNELS + OPTIONAL_COLUMNS + declared + estimated
                                + ingestion.keep_columns))
    unknown = [c for c in columns if c not in known]
    if unknown and not for_model:
        raise DataFileError(f"{path}: unknown channel(s) {', '.join(map(repr, unknown))}; "
                            f"channels are {','.join(known)}; link the file's own column "
                            f"names to them in the model's channel map (a model file's "
                            f"[channels] table; rotorid frequency reads through one with "
                            f"--model)")
    if "time" not in columns:
        link = ("; name the file's time column 'time' or link it in the model's channel map, "
                "e.g. Time = { signal = \"time\", unit = \"s\" } (or unit = \"ms\")"
                if for_model else "")
        channels = (ALL_CHANNELS[1:] if ingestion.signals is None
                    else ingestion.signals.all.names)
        raise DataFileError(f"{path}: missing channel(s) time; a maneuver file needs time, "
                            f"then any of {','.join(channels)}{link}")
    rows = columns["time"].size
    for channel in columns:
        if columns[channel].size != rows:
            raise DataFileError(f"{path}: channel {channel!r} has {columns[channel].size} "
                                f"samples but 'time' has {rows}; all channels need the same "
                                f"length")
    metadata = {k: v for k, v in header.items() if k not in RESERVED}
    name = header.get("name", path.stem)
    if not isinstance(name, str) or not name:
        raise DataFileError(f"{path}: header 'name' must be a non-empty string, got {name!r}")
    try:
        units = unit_system(header.get("units", "flight-test")).name
        declared = header.get("channel_units") or {}
        if not isinstance(declared, Mapping):
            raise DataError(f"'channel_units' must map channels to units, e.g. "
                            f'{{"q": "rad/s"}}, got {declared!r}')
        ingestion = attrs.evolve(ingestion, channel_units={**ingestion.channel_units,
                                                          **declared})
        return Maneuver.from_columns(name, columns, units=units, metadata=metadata,
                                     initial_state=header.get("initial_state"),
                                     state_names=header.get("state_names"),
                                     ingestion=ingestion)
    except DataError as error:
        raise DataFileError(f"{path}: {error}{row_note}") from None
    except (RotoridError, TypeError, ValueError) as error:
        raise DataFileError(f"{path}: bad header: {error}") from None
