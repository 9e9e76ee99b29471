"""Subcommands of the ``rotorid`` command, one module each (see :mod:`rotorid.cli.main`)."""
