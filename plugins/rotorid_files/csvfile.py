"""CSV maneuver files.

Layout (UTF-8)::

    # name: long_3211_pos
    # units: flight-test
    # condition: hover
    # direction: 1
    time,long,lat,coll,ped,ax,az,q,theta,ay,p,phi,r
    0.0,0.0,0.0,...

Leading ``# key: value`` lines form the header; a value is read as JSON when it parses as
JSON (``1``, ``true``, ``[0.1, 0.2]``, ``"1"``) and as plain text otherwise (``hover``).
``# units: si`` declares SI-rad data (m/s², rad/s, rad); the default is flight-test units
(ft/s², deg/s, deg, % of travel). Other leading comment lines and blank lines are ignored. The
first other line is the header row of channel names, in any order; every following line is
one sample.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
from rotorid.data import ALL_CHANNELS
from rotorid.errors import DataFileError
from rotorid.ingestion import Ingestion
from rotorid.io import parse_number

from .records import KEY_PATTERN, assemble, columns_of, encode_value, header_of

_HEADER_LINE = re.compile(rf"#\s*({KEY_PATTERN.pattern})\s*:\s*(.*?)\s*")


def _decode(text: str):
    try:
        return json.loads(text)
    except ValueError:
        return text


def _encode(value, where: str) -> str:
    """Plain text when it reads back as the same string, JSON otherwise."""
    if (isinstance(value, str) and value and value == value.strip() and "\n" not in value
            and _decode(value) is value):
        return value
    return encode_value(value, where)


def read(path: Path, ingestion: Ingestion):
    """The maneuver stored in the CSV file ``path``, prepared as ``ingestion`` says."""
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except UnicodeDecodeError as error:
        raise DataFileError(f"{path}: not a UTF-8 text file ({error})") from None
    header: dict = {}
    number = 0
    while number < len(lines) and (not lines[number].strip() or lines[number].startswith("#")):
        match = _HEADER_LINE.fullmatch(lines[number])
        if match:
            if match[1] in header:
                raise DataFileError(f"{path}, line {number + 1}: header key {match[1]!r} "
                                    f"is given twice")
            header[match[1]] = _decode(match[2])
        number += 1
    if number == len(lines):
        raise DataFileError(f"{path}: no header row; the first line after the '#' comments "
                            f"must name the channels: {','.join(ALL_CHANNELS)}")
    names = [n.strip() for n in lines[number].split(",")]
    for index, name in enumerate(names):
        if names.index(name) != index:
            raise DataFileError(f"{path}, line {number + 1}: channel {name!r} appears twice "
                                f"in the header row")
    first_data_line = number + 2
    values = []
    for number, line in enumerate(lines[first_data_line - 1:], start=first_data_line):
        if not line.strip():
            continue
        fields = line.split(",")
        if len(fields) != len(names):
            raise DataFileError(f"{path}, line {number}: expected {len(names)} values "
                                f"(one per channel of the header row), got {len(fields)}")
        row = []
        for name, field in zip(names, fields):
            try:
                row.append(parse_number(field))
            except ValueError:
                raise DataFileError(f"{path}, line {number} (row {len(values)}), channel "
                                    f"{name!r}: {field.strip()!r} is not a number") from None
        bad = [n for n, v in zip(names, row)
               if not np.isfinite(v) and not (ingestion.resample and np.isnan(v))]
        if bad:
            raise DataFileError(f"{path}, line {number} (row {len(values)}), channel "
                                f"{bad[0]!r}: value is NaN or infinite; a NaN gap is "
                                f"interpolated across when the data are resampled")
        values.append(row)
    table = np.array(values, dtype=float).reshape(len(values), len(names))
    columns = {name: table[:, i] for i, name in enumerate(names)}
    note = f" (rows count samples from 0; row 0 is line {first_data_line} of the file)"
    return assemble(path, columns, header, ingestion, row_note=note)


def write(maneuver, handle) -> None:
    """Write ``maneuver`` as CSV text into the binary file object ``handle``."""
    where = f"maneuver {maneuver.name!r}"
    lines = [f"# {key}: {_encode(value, where)}"
             for key, value in header_of(maneuver, where).items()]
    columns = columns_of(maneuver)
    lines.append(",".join(columns))
    table = np.column_stack(list(columns.values())).tolist()
    lines.extend(",".join(map(repr, row)) for row in table)
    handle.write(("\n".join(lines) + "\n").encode("utf-8"))
