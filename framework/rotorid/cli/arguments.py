"""Argument types of the ``rotorid`` command line, checked by argparse before any work starts.

Each converter raises :class:`argparse.ArgumentTypeError` with the rule and the value given;
argparse names the option and the command exits with status 2 (docs/conventions.md).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from rotorid.io import parse_number


def _number(text: str, convert, accepted, rule: str):
    """``convert(text)`` when it reads and ``accepted`` holds for it; else the ``rule``."""
    try:
        value = convert(text)
    except ValueError:
        value = None
    if value is None or not accepted(value):
        raise argparse.ArgumentTypeError(f"{rule}, got {text!r}")
    return value


def seed(text: str) -> int:
    """A noise seed: a whole number ≥ 0."""
    return _number(text, int, lambda value: value >= 0, "a seed is a whole number ≥ 0")


def run_count(text: str) -> int:
    """The number of Monte Carlo runs: a whole number ≥ 2 (one run has no spread)."""
    return _number(text, int, lambda value: value >= 2,
                   "a Monte Carlo needs a whole number ≥ 2 of runs to estimate a spread")


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


def trim(text: str) -> str | dict[str, float]:
    """Trim to remove: ``first-second`` or stated values ``CHANNEL=VALUE,…`` (plain decimals,
    in the data's units)."""
    if text == "first-second":
        return text
    return _named_numbers(text, "trim is 'first-second' or CHANNEL=VALUE pairs such as "
                                "theta=5.0,az=-32.17")


def correlation_limits(text: str) -> dict[str, float]:
    """Filter error's longest correlation times: ``NAME=SECONDS,…`` (``T_w=3,Tg_u=10``)."""
    return _named_numbers(text, "NAME=SECONDS pairs of correlation times such as "
                                "T_w=3,Tg_u=10")


def _named_numbers(text: str, rule: str) -> dict[str, float]:
    """``NAME=VALUE,…`` as a mapping (plain decimals); ``rule`` says the form in the error."""
    values = {}
    for item in text.split(","):
        name, equals, value = item.partition("=")
        try:
            values[name.strip()] = parse_number(value)
        except ValueError:
            equals = ""
        if not equals or not name.strip():
            raise argparse.ArgumentTypeError(f"{rule}; got {item!r}")
    return values


def names(text: str) -> list[str]:
    """The names of a comma-separated option (``q,theta,p``), blanks dropped, in order."""
    return [name.strip() for name in text.split(",") if name.strip()]


def seconds(text: str) -> float:
    """A positive time in s."""
    return _number(text, parse_number, lambda value: value > 0,
                   "a time in s is a positive number")


def add_ingestion_arguments(parser, what: str = "file") -> None:
    """``--trim``, ``--resample`` and ``--sample-time``: how every ``what`` is read
    (:mod:`rotorid.ingestion`); :func:`ingestion_settings` turns them into settings."""
    parser.add_argument("--trim", type=trim, default=None,
                        metavar="first-second|CH=VALUE,...",
                        help=f"remove the trim from every {what}: each channel's mean over the "
                             "first second, or stated values by the model's channel names in "
                             "its unit system, e.g. az=-32.17 (ft/s², flight-test) or "
                             "az=-9.81,rudder=2.1 (SI)")
    parser.add_argument("--resample", choices=("linear", "decimate"), default=None,
                        help="resample non-uniform time onto a uniform grid: linear "
                             "interpolation, or anti-aliased decimation to --sample-time")
    parser.add_argument("--sample-time", type=seconds, default=None, metavar="S",
                        help="the grid's interval in s for --resample (default: the median "
                             "step)")


def ingestion_settings(args) -> dict:
    """The settings :func:`add_ingestion_arguments` read, those given only (a usage error for
    a --sample-time without --resample)."""
    from rotorid.errors import UsageError

    if args.sample_time is not None and args.resample is None:
        raise UsageError("--sample-time needs --resample linear or --resample decimate")
    settings = {"trim": args.trim, "resample": args.resample, "sample_time": args.sample_time}
    return {k: v for k, v in settings.items() if v is not None}


def trim_text(removed) -> str:
    """``first-second``, or the stated trim values as ``theta=3.1, az=-32.1``."""
    if isinstance(removed, str):
        return removed
    return ", ".join(f"{name}={value:g}" for name, value in removed.items())


def ingestion_text(settings) -> str:
    """Ingestion settings in words: ``trim first-second, resample linear, sample_time 0.02``."""
    return ", ".join(f"{key} {trim_text(value) if key == 'trim' else value}"
                     for key, value in settings.items())
