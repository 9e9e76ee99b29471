"""NumPy ``.npz`` and MATLAB ``.mat`` maneuver files.

Both hold one numeric vector per channel (``time``, ``long`` … ``r``) and a text variable
``header``: the flat header (name, units, initial_state, metadata) as one JSON object. In
``.npz`` the header is a 0-d string array; in ``.mat`` a char array. Files without a header
are read as flight-test data named after the file. ``.npz`` files are opened without pickle
support, so they cannot run code; MATLAB files must be level 5 (``save -v7``), not v7.3.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
from rotorid.errors import DataFileError

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


def _split(path: Path, variables: dict):
    header = _header(path, variables.pop(HEADER_KEY)) if HEADER_KEY in variables else {}
    columns = {name: vector(path, name, value) for name, value in variables.items()}
    return assemble(path, columns, header)


def _encoded_header(maneuver) -> np.ndarray:
    where = f"maneuver {maneuver.name!r}"
    return np.array(encode_value(header_of(maneuver, where), where))


def read_npz(path: Path):
    """The maneuver stored in the NumPy archive ``path``."""
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
    return _split(path, variables)


def write_npz(maneuver, handle) -> None:
    """Write ``maneuver`` as an uncompressed ``.npz`` archive into ``handle``."""
    np.savez(handle, **columns_of(maneuver), **{HEADER_KEY: _encoded_header(maneuver)})


def read_mat(path: Path):
    """The maneuver stored in the MATLAB file ``path``."""
    import scipy.io

    try:
        variables = scipy.io.loadmat(path, squeeze_me=False, chars_as_strings=True)
    except NotImplementedError as error:
        raise DataFileError(f"{path}: {error}; save it from MATLAB with -v7") from None
    except (scipy.io.matlab.MatReadError, ValueError, TypeError, OSError) as error:
        raise DataFileError(f"{path}: cannot read as a MATLAB .mat file: {error}") from None
    return _split(path, {k: v for k, v in variables.items() if not k.startswith("__")})


def write_mat(maneuver, handle) -> None:
    """Write ``maneuver`` as a compressed MATLAB level-5 file into ``handle``."""
    import scipy.io

    scipy.io.savemat(handle, {**columns_of(maneuver), HEADER_KEY: _encoded_header(maneuver)},
                     do_compression=True, oned_as="column")
