"""Registers the ``helisim`` data source and the ``generate``, ``trim`` and ``linearize``
commands (cheap to import; the truth model loads on use)."""

import importlib

from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl


def _make_source(**options):
    from .source import HelisimSource

    return HelisimSource(**options)


@hookimpl
def rotorid_data_sources():
    return [PluginDescriptor("helisim", _make_source,
                             "nonlinear Bo-105-class truth model flown through the paper's "
                             "3211/2311/sweep maneuvers (hover, 70 kt)")]


def _command(name: str):
    return lambda: importlib.import_module(f"{__package__}.commands.{name}")


@hookimpl
def rotorid_commands():
    return [PluginDescriptor("generate", _command("generate"),
                             "generate a condition's data set (16 multisteps, 4 sweeps) with "
                             "the helisim truth model and write it as .npz maneuver files"),
            PluginDescriptor("trim", _command("trim"),
                             "trim the Bo-105 truth model (hover, forward = 70 kt, or "
                             "--airspeed-kt V)"),
            PluginDescriptor("linearize", _command("linearize"),
                             "linearise the Bo-105 truth model (hover, forward = 70 kt, or "
                             "--airspeed-kt V): residualised 6-DoF model, or the full model "
                             "with --full")]
