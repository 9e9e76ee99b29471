"""Registers the ``muad``, ``aee`` and ``mismatch-cost`` envelopes (cheap to import)."""

from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl


def _muad(**options):
    from .muad import MuadEnvelope

    return MuadEnvelope.packaged(**options)


def _aee(path=None, **options):
    from .table import TableEnvelope

    if path is None:
        return TableEnvelope.packaged_aee(**options)
    return TableEnvelope.from_file(path, **options)


def _mismatch_cost(**options):
    from .cost import MismatchCost

    return MismatchCost(**options)


@hookimpl
def rotorid_validation_envelopes():
    return [
        PluginDescriptor("muad", _muad, "Maximum Unnoticeable Added Dynamics bounds on "
                         "H_model/H_truth (MIL-STD-1797A), 0.1–10 rad/s"),
        PluginDescriptor("aee", _aee, "allowable error envelopes from a data table "
                         "(packaged table unverified; path=... loads your own)"),
        PluginDescriptor("mismatch-cost", _mismatch_cost, "Tischler's frequency-response "
                         "mismatch cost J over 20 coherent points (J ≤ 100)"),
    ]
