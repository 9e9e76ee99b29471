"""Registers the built-in input signals (cheap to import; the signal classes load on use)."""

from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl


def _multistep(kind):
    def factory(**options):
        from .signals import Multistep

        return Multistep(kind, **options)

    factory.__name__ = f"make_{kind}"
    factory.__doc__ = (f"A {kind} multistep; options: amplitude (%), step_width (s), start, "
                       f"trailing (s), sample_time (s).")
    return factory


def _sweep(**options):
    from .signals import Sweep

    return Sweep(**options)


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
                         "logarithmic frequency sweep with 2 cycles at omega_min, trim at both ends"),
    ]
