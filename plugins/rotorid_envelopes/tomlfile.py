"""Reading envelope definition files (TOML or JSON) with clear errors."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

from rotorid.errors import VerificationError
from rotorid.io import require_file

PACKAGE_DIR = Path(__file__).resolve().parent


def load_definition(path) -> dict:
    """The table in ``path`` (``.toml`` or ``.json``) as a dict."""
    path = require_file(path, "envelope file")
    try:
        if path.suffix.lower() == ".json":
            return json.loads(path.read_text(encoding="utf-8"))
        with path.open("rb") as handle:
            return tomllib.load(handle)
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, UnicodeDecodeError) as error:
        raise VerificationError(f"envelope file {path} cannot be parsed: {error}") from None


def require(definition: dict, key: str, kind, where: str):
    """``definition[key]``, which must exist and be of ``kind``."""
    if key not in definition:
        raise VerificationError(f"{where}: field {key!r} is missing")
    value = definition[key]
    if not isinstance(value, kind) or (kind is str and not value.strip()):
        raise VerificationError(f"{where}: field {key!r} must be a non-empty "
                                f"{getattr(kind, '__name__', kind)}, got {value!r}")
    return value


def omega_range(definition: dict, where: str) -> tuple[float, float]:
    """The validity range ``[low, high]`` in rad/s."""
    value = require(definition, "omega_range", list, where)
    if len(value) != 2 or not 0 < float(value[0]) < float(value[1]):
        raise VerificationError(f"{where}: omega_range must be [low, high] with "
                                f"0 < low < high rad/s, got {value!r}")
    return float(value[0]), float(value[1])
