"""Atomic file writing, shared by every writer in rotorid, JSON-ready values, JSON reading and
strict number parsing.

A reader never sees a half-written file: the content goes to a temporary file in the target's
directory, is flushed to disk, and only then replaces the target with :func:`os.replace`.
"""

from __future__ import annotations

import json
import math
import os
import re
import stat
import uuid
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import BinaryIO

from rotorid.errors import DataFileError, MissingFileError
from rotorid.lease import check_owner_alive


def atomic_write(path: str | os.PathLike, content: bytes | str | Callable[[BinaryIO], object]
                 ) -> Path:
    """Write ``content`` to ``path`` atomically and return the path.

    Args:
        path: target file; its directory must exist.
        content: ``bytes``, ``str`` (written as UTF-8) or a callable that receives a binary
            file object opened for writing and writes into it (e.g. ``lambda f: np.savez(f, **a)``).

    The new file gets the permissions of the file it replaces, or the usual permissions for a
    new file (0o666 less the umask). On any error the target is left untouched and the
    temporary file is removed. In a task whose run has ended nothing is written
    (:class:`~rotorid.errors.OrphanedRunError`, :mod:`rotorid.lease`).
    """
    target = Path(path)
    check_owner_alive(target)
    if not target.parent.is_dir():
        raise MissingFileError(f"cannot write {target}: directory {target.parent} does not exist")
    temporary = target.with_name(f".{target.name}.{uuid.uuid4().hex}.tmp")
    descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(descriptor, "wb") as handle:
            if callable(content):
                content(handle)
            else:
                handle.write(content.encode("utf-8") if isinstance(content, str) else content)
            handle.flush()
            os.fsync(handle.fileno())
        if target.exists():
            os.chmod(temporary, stat.S_IMODE(target.stat().st_mode))
        check_owner_alive(target)
        os.replace(temporary, target)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    return target


def jsonable(value):
    """``value`` with every non-finite float replaced by ``None`` (JSON has no inf or NaN),
    through nested mappings, lists and tuples."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Mapping):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    return value


def require_file(path: str | os.PathLike, what: str) -> Path:
    """``path`` as a Path when it is a regular file; otherwise :class:`MissingFileError`
    (nothing there) or :class:`DataFileError` (a directory, device or pipe), naming
    ``what`` (e.g. ``"model file"``)."""
    path = Path(path)
    if path.is_file():
        return path
    if path.exists():
        raise DataFileError(f"{what} {path} is not a regular file (a directory, device or "
                            f"pipe); name a {what}")
    raise MissingFileError(f"{what} {path} does not exist")


def read_json_object(path: str | os.PathLike, what: str, content: str = "") -> dict:
    """The JSON object stored in ``path``; errors name ``what`` (e.g. ``"result file"``), the
    path and, when given, the expected ``content`` (e.g. ``"name → value"``)."""
    path = require_file(path, what)
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise DataFileError(f"{what} {path} is not valid JSON: {error}") from None
    if not isinstance(record, Mapping):
        raise DataFileError(f"{what} {path} must hold a JSON object"
                            + (f" ({content})" if content else ""))
    return dict(record)


def read_toml(path: str | os.PathLike, what: str) -> dict:
    """The table stored in the TOML file ``path``; errors name ``what`` (e.g. ``"model
    file"``), the path and the parser's line."""
    import tomllib

    path = require_file(path, what)
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise DataFileError(f"{path}: not a valid TOML file: {error}") from None


#: A number as rotorid reads it from text: sign, decimal digits with an optional point, and an
#: optional exponent; or the words nan and inf, which the readers then refuse by name. Python's
#: other float syntax (``1_000``, surrounding words) is not a number here.
_PLAIN_NUMBER = re.compile(r"[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|nan|inf(?:inity)?)",
                           re.IGNORECASE | re.ASCII)


def parse_number(text: str) -> float:
    """The number written in ``text`` (surrounding blanks allowed); ``ValueError`` for anything
    but a plain decimal or exponent form."""
    stripped = text.strip()
    if not _PLAIN_NUMBER.fullmatch(stripped):
        raise ValueError(f"{stripped!r} is not a plain decimal number")
    return float(stripped)
