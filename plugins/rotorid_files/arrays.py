"""NumPy ``.npz`` and MATLAB ``.mat`` maneuver files.

Both hold one numeric vector per channel (``time``, ``long`` … ``r``) and a text variable
``header``: the flat header (name, units, initial_state, channel_units, metadata) as one JSON
object. In ``.npz`` the header is a 0-d string array; in ``.mat`` a char array. Two other
layouts are read too: a **column matrix**, ``data`` (N × k, one channel per column) with
``channels`` (its k names: a cell array or char rows in MATLAB, a string array in NumPy); and,
in ``.mat`` files, a **struct** as the only variable, whose fields are the variables of either
layout (``s.time``, ``s.q`` …, or ``s.data`` and ``s.channels``; ``s.header`` optional). Files
without a header are read as flight-test data named after the file. ``.npz`` files are opened
without pickle support, so they cannot run code; MATLAB files must be level 5 (``save -v7``),
not v7.3.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
from rotorid.errors import DataFileError
from rotorid.ingestion import Ingestion

from .records import assemble, columns_of, encode_value, header_of, vector

HEADER_KEY = "header"


def _header(path: Path, value) -> dict:
    value = np.asarray(value)
    if value.dtype.kind != "U" or value.size != 1:
        raise DataFileError(f"{path}: variable {HEADER_KEY!r} must be one JSON string, got "
                            f"{value.dtype} of shape {value.shape}")
    try:
        header = json.loads(str(value.reshape(-1)[0]))
    except ValueError as error:
        raise DataFileError(f"{path}: variable {HEADER_KEY!r} is not valid JSON ({error})"
                            ) from None
    if not isinstance(header, dict):
        raise DataFileError(f"{path}: variable {HEADER_KEY!r} must hold a JSON object")
    return header


#: Variable names of the column-matrix layout.
MATRIX_KEY, NAMES_KEY = "data", "channels"


def _struct_fields(variables: dict) -> dict:
    """The fields of a file's only variable when it is a struct, else ``variables``."""
    if len(variables) != 1:
        return variables
    value = np.asarray(next(iter(variables.values())))
    if value.dtype.names is None or value.size != 1:
        return variables
    record = value.reshape(-1)[0]
    return {name: record[name] for name in value.dtype.names}


def _names(path: Path, value) -> list[str]:
    value = np.asarray(value)
    if value.dtype.kind == "O":
        return [str(np.asarray(item).reshape(-1)[0]).strip() if np.asarray(item).size else ""
                for item in value.reshape(-1)]
    if value.dtype.kind != "U":
        raise DataFileError(f"{path}: variable {NAMES_KEY!r} must hold the channel names as "
                            f"text (a cell array or char rows), got {value.dtype}")
    return [str(item).strip() for item in value.reshape(-1)]


def _matrix_columns(path: Path, variables: dict) -> dict:
    """The column-matrix layout split into one variable per channel (other layouts pass)."""
    if MATRIX_KEY not in variables or NAMES_KEY not in variables:
        return variables
    names = _names(path, variables.pop(NAMES_KEY))
    matrix = np.asarray(variables.pop(MATRIX_KEY))
    if matrix.ndim != 2 or matrix.dtype.kind not in "fiu":
        raise DataFileError(f"{path}: variable {MATRIX_KEY!r} must be a numeric matrix, one "
                            f"channel per column; got {matrix.dtype} of shape {matrix.shape}")
    if matrix.shape[1] != len(names) and matrix.shape[0] == len(names):
        matrix = matrix.T
    if matrix.shape[1] != len(names):
        raise DataFileError(f"{path}: {MATRIX_KEY!r} has {matrix.shape[1]} columns but "
                            f"{NAMES_KEY!r} names {len(names)} channels; give one name per "
                            f"column")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise DataFileError(f"{path}: {NAMES_KEY!r} names channel(s) {', '.join(twice)} twice")
    return {**variables, **{name: matrix[:, i] for i, name in enumerate(names)}}


def _split(path: Path, variables: dict, ingestion: Ingestion):
    variables = _matrix_columns(path, _struct_fields(variables))
    header = _header(path, variables.pop(HEADER_KEY)) if HEADER_KEY in variables else {}
    columns = {name: vector(path, name, value) for name, value in variables.items()}
    return assemble(path, columns, header, ingestion)


def _encoded_header(maneuver) -> np.ndarray:
    where = f"maneuver {maneuver.name!r}"
    return np.array(encode_value(header_of(maneuver, where), where))


def read_npz(path: Path, ingestion: Ingestion):
    """The maneuver stored in the NumPy archive ``path``, prepared as ``ingestion`` says."""
    try:
        archive = np.load(path, allow_pickle=False)
        if not isinstance(archive, np.lib.npyio.NpzFile):
            raise DataFileError(f"{path}: a .npy array, not a .npz archive of channels")
        with archive:
            names = archive.files
            twice = sorted({n for n in names if names.count(n) > 1})
            if twice:
                raise DataFileError(f"{path}: channel(s) {', '.join(twice)} stored twice")
            variables = {name: archive[name] for name in names}
    except (ValueError, OSError, zipfile.BadZipFile, EOFError) as error:
        raise DataFileError(f"{path}: cannot read as a NumPy .npz archive of plain arrays "
                            f"(pickled objects are refused): {error}") from None
    return _split(path, variables, ingestion)


def write_npz(maneuver, handle) -> None:
    """Write ``maneuver`` as an uncompressed ``.npz`` archive into ``handle``."""
    np.savez(handle, **columns_of(maneuver), **{HEADER_KEY: _encoded_header(maneuver)})


def read_mat(path: Path, ingestion: Ingestion):
    """The maneuver stored in the MATLAB file ``path``, prepared as ``ingestion`` says."""
    import scipy.io

    try:
        variables = scipy.io.loadmat(path, squeeze_me=False, chars_as_strings=True)
    except NotImplementedError as error:
        raise DataFileError(f"{path}: {error}; save it from MATLAB with -v7") from None
    except (scipy.io.matlab.MatReadError, ValueError, TypeError, OSError) as error:
        raise DataFileError(f"{path}: cannot read as a MATLAB .mat file: {error}") from None
    return _split(path, {k: v for k, v in variables.items() if not k.startswith("__")},
                  ingestion)


def write_mat(maneuver, handle) -> None:
    """Write ``maneuver`` as a compressed MATLAB level-5 file into ``handle``."""
    import scipy.io

    scipy.io.savemat(handle, {**columns_of(maneuver), HEADER_KEY: _encoded_header(maneuver)},
                     do_compression=True, oned_as="column")
