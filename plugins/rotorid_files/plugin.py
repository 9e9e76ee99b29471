"""Registers the ``files`` data source (cheap to import; the readers load on use)."""

from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl


def _make_source(**options):
    from .formats import FileSource

    return FileSource(**options)


@hookimpl
def rotorid_data_sources():
    return [PluginDescriptor("files", _make_source,
                             "maneuver files: CSV (header row), NumPy .npz, MATLAB .mat")]
