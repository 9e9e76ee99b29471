"""Command-line rules for the files a command writes."""

from __future__ import annotations

from pathlib import Path

from rotorid.errors import OverwriteError


def refuse_overwrite(path, force: bool) -> Path:
    """``path``, after checking that it does not exist yet unless ``force`` (``--force``)."""
    path = Path(path)
    if path.exists() and not force:
        raise OverwriteError(f"{path} exists already; give --force to overwrite it")
    return path
