"""Registers the built-in input signals: the multisteps (a kind of :class:`Multistep` each) and
the sweep, their options those of the classes."""

import functools

from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl

from .signals import Multistep, Sweep


def _multistep(kind):
    """A factory of ``kind`` multisteps taking :class:`Multistep`'s other fields."""
    return functools.partial(Multistep, kind)


_sweep = Sweep


@hookimpl
def rotorid_input_signals():
    return [
        PluginDescriptor("2311", _multistep("2311"),
                         "2311 multistep (+2 −3 +1 −1 step widths): amplitude, step_width"),
        PluginDescriptor("3211", _multistep("3211"),
                         "3211 multistep (+3 −2 +1 −1 step widths): amplitude, step_width"),
        PluginDescriptor("doublet", _multistep("doublet"),
                         "doublet (+1 −1 step widths): amplitude, step_width"),
        PluginDescriptor("sweep", _sweep,
                         "logarithmic frequency sweep with 2 cycles at omega_min, trim at both ends: "
                         "amplitude, omega_min, omega_max, sweep_time"),
    ]
