"""Argument types of the ``rotorid`` command line, checked by argparse before any work starts.

Each converter raises :class:`argparse.ArgumentTypeError` with the rule and the value given;
argparse names the option and the command exits with status 2 (docs/conventions.md).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path


def seed(text: str) -> int:
    """A noise seed: a whole number ≥ 0."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"a seed is a whole number ≥ 0, got {text!r}")
    return value


def output_directory(text: str) -> str:
    """A directory to write into (returned as given): an existing writable directory, or a new
    one whose nearest existing parent is a writable directory."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} exists and is not a directory; give a "
                                         f"directory")
    _check_writable(path)
    return text


def output_file(text: str) -> str:
    """A file to write (returned as given): not a directory or device, in a writable directory
    or one that can be created in a writable directory."""
    path = Path(text)
    if path.exists() and not path.is_file():
        raise argparse.ArgumentTypeError(f"{text} exists and is not a regular file; give a "
                                         f"file name")
    _check_writable(path.absolute().parent)
    return text


def _check_writable(path: Path) -> None:
    existing = next(p for p in (path, *path.absolute().parents) if p.exists())
    if not existing.is_dir() or not os.access(existing, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"cannot write into {existing}; give a directory you "
                                         f"may write to")
