"""The ``rotorid`` command.

Subcommands live one per module in :mod:`rotorid.commands`; each module defines ``NAME``,
``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``. Errors that rotorid raises on
purpose are printed as one line on stderr with exit status 2; they never show a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys

from . import __version__, commands
from .errors import RotoridError


def _command_modules():
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda i: i.name):
        if not info.name.startswith("_"):
            yield importlib.import_module(f"{commands.__name__}.{info.name}")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand of :mod:`rotorid.commands`."""
    parser = argparse.ArgumentParser(
        prog="rotorid",
        description="Time-domain system identification of helicopter flight dynamics.")
    parser.add_argument("--version", action="version", version=f"rotorid {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in _command_modules():
        command = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(command)
        command.set_defaults(run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 1
    try:
        return int(args.run(args) or 0)
    except (RotoridError, OSError) as error:
        print(f"rotorid {args.command}: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"rotorid {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
