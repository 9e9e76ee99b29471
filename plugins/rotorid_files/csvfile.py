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
one sample. An empty field is a dropout, read as NaN (interpolated across when the data are
resampled, refused otherwise). A field of the form ``DDD:HH:MM:SS.sss`` or ``HH:MM:SS.sss``
(an IRIG or clock time, as test ranges write their time column) is read as seconds
(days · 86400 + hours · 3600 + minutes · 60 + seconds).
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

#: A field that starts like a number (a units row has none).
_PLAIN_NUMBER_LIKE = re.compile(r"[+-]?\.?\d")
_HEADER_LINE = re.compile(rf"#\s*({KEY_PATTERN.pattern})\s*:\s*(.*?)\s*")
#: An IRIG (day of year first) or clock time: ``312:14:02:31.250``, ``14:02:31.250``.
_CLOCK_TIME = re.compile(r"(?:(\d{1,3}):)?(\d{1,2}):(\d{2}):(\d{2}(?:\.\d*)?)", re.ASCII)


def _field_value(field: str) -> float:
    """A CSV field's number: empty is NaN (a dropout), a clock time its seconds."""
    text = field.strip()
    if not text:
        return float("nan")
    clock = _CLOCK_TIME.fullmatch(text)
    if clock:
        day, hours, minutes, seconds = clock.groups()
        return (int(day or 0) * 86400.0 + int(hours) * 3600.0 + int(minutes) * 60.0
                + float(seconds))
    return parse_number(text)


def _format_hint(line: str) -> str:
    """What a data line that does not split into the header's channels suggests."""
    if ";" in line or "\t" in line:
        return ("; the file looks separated by semicolons or tabs: rotorid reads comma-"
                "separated values with a decimal point (export the log as such)")
    return ""


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
                                f"(one per channel of the header row), got {len(fields)}"
                                f"{_format_hint(line)}")
        row = []
        for name, field in zip(names, fields):
            try:
                row.append(_field_value(field))
            except ValueError:
                units_row = not values and not any(_PLAIN_NUMBER_LIKE.match(f.strip())
                                                   for f in fields)
                hint = ("; it looks like a row of units under the header row: delete it and "
                        "give the units in the model's channel map" if units_row
                        else _format_hint(line))
                raise DataFileError(f"{path}, line {number} (row {len(values)}), channel "
                                    f"{name!r}: {field.strip()!r} is not a number"
                                    f"{hint}") from None
        bad = [n for n, v in zip(names, row)
               if not np.isfinite(v) and not (ingestion.resample and np.isnan(v))]
        if bad:
            raise DataFileError(f"{path}, line {number} (row {len(values)}), channel "
                                f"{bad[0]!r}: value is empty, NaN or infinite; a dropout "
                                f"(empty or NaN) is interpolated across when the data are "
                                f"resampled (--resample linear)")
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
