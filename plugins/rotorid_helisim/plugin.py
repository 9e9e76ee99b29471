"""Registers the ``helisim`` data source (cheap to import; the truth model loads on use)."""

from rotorid.hookspecs import PluginDescriptor, hookimpl


def _make_source(**options):
    from .source import HelisimSource

    return HelisimSource(**options)


@hookimpl
def rotorid_data_sources():
    return [PluginDescriptor("helisim", _make_source,
                             "nonlinear Bo-105-class truth model flown through the paper's "
                             "3211/2311/sweep maneuvers (hover, 70 kt)")]
