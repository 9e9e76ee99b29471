"""The ``rotorid`` command.

Built-in subcommands live one per module in :mod:`rotorid.cli.commands`; each module defines
``NAME``, ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``. Plugins add their own
through the ``rotorid_commands`` hook. Errors that rotorid raises on purpose are printed as one
line on stderr, never with a traceback; the exit status tells usage errors (2) from data and
model errors (3) (:class:`rotorid.errors.ExitStatus`, docs/conventions.md).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import pkgutil
import sys

from rotorid import __version__
from rotorid.cli import commands
from rotorid.errors import ExitStatus, PluginError, RotoridError, UsageError
from rotorid.plugin.manager import create, registry

#: Characters of an error message printed before the rest is cut (and counted).
MESSAGE_LIMIT = 400


def _command_modules():
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda i: i.name):
        if not info.name.startswith("_"):
            yield importlib.import_module(f"{commands.__name__}.{info.name}")


def _subcommands():
    """(name, help, command) of every built-in and plugin subcommand, sorted by name."""
    found = {module.NAME: (module.HELP, module) for module in _command_modules()}
    for name, registered in registry("commands").items():
        if name in found:
            raise PluginError(f"plugin {registered.provider!r} registers the command {name!r}, "
                              f"which rotorid itself provides; rename the plugin's command")
        found[name] = (registered.summary, create("commands", name))
    return [(name, *found[name]) for name in sorted(found)]


class _Parser(argparse.ArgumentParser):
    """argparse with its errors on one line: ``rotorid COMMAND: error: …; see … --help``."""

    def error(self, message: str):
        self.exit(ExitStatus.USAGE, f"{self.prog}: error: {message}; see {self.prog} --help\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand (built-in and registered by plugins)."""
    parser = _Parser(
        prog="rotorid",
        description="System identification of aircraft flight dynamics, helicopters first: "
                    "time and frequency domain, reduction, delays, verification.")
    parser.add_argument("--version", action="version", version=f"rotorid {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, summary, implementation in _subcommands():
        command = sub.add_parser(name, help=summary, description=summary)
        implementation.add_arguments(command)
        command.set_defaults(run=implementation.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status."""
    try:
        parser = build_parser()
    except RotoridError as error:              # an installed plugin that cannot be loaded
        print(f"rotorid: error: {one_line(str(error))}", file=sys.stderr)
        return ExitStatus.ERROR
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return ExitStatus.USAGE
    try:
        with _progress_on_stderr():
            return int(args.run(args) or ExitStatus.OK)
    except (RotoridError, OSError) as error:
        print(f"rotorid {args.command}: error: {one_line(str(error))}", file=sys.stderr)
        return ExitStatus.USAGE if isinstance(error, UsageError) else ExitStatus.ERROR
    except KeyboardInterrupt:
        print(f"rotorid {args.command}: interrupted", file=sys.stderr)
        return ExitStatus.INTERRUPTED


def one_line(message: str, limit: int = MESSAGE_LIMIT) -> str:
    """``message`` on one line and at most about ``limit`` characters. A longer one loses
    its middle, counted where it was cut: a message names the problem first and the fix
    last, and a long list between them (a range file's columns) is what goes."""
    text = " ".join(message.split())
    if len(text) <= limit:
        return text
    tail = limit // 3
    return (f"{text[:limit - tail]} … ({len(text) - limit} characters left out) … "
            f"{text[-tail:]}")


@contextlib.contextmanager
def _progress_on_stderr():
    """While a command runs, the ``rotorid`` logger's INFO messages (progress) go to stderr,
    one line each."""
    logger = logging.getLogger("rotorid")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(message)s"))
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)


if __name__ == "__main__":
    sys.exit(main())
