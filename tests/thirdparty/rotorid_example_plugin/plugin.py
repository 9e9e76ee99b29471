"""The hooks (cheap to import: the components load when a factory runs)."""

from rotorid import PluginDescriptor, hookimpl


def _component(name: str):
    def factory(**options):
        from . import components

        return getattr(components, name)(**options)
    return factory


@hookimpl
def rotorid_data_sources():
    return [PluginDescriptor("example-simulated", _component("SimulatedSource"),
                             "doublets and chirps of a small pitch/roll model, with noise")]


@hookimpl
def rotorid_validation_envelopes():
    return [PluginDescriptor("example-flat", _component("FlatEnvelope"),
                             "±6 dB, ±45° on the verification error"),
            PluginDescriptor("example-gain-cost", _component("GainCost"),
                             "mean squared magnitude error (dB²) over the coherent points")]


@hookimpl
def rotorid_reduction_criteria():
    return [PluginDescriptor("example-largest-bound", _component("LargestBound"),
                             "removes the derivative of largest normalised Cramér-Rao bound")]


@hookimpl
def rotorid_estimators():
    return [PluginDescriptor("example-output-error", _component("WrappedOutputError"),
                             "the built-in output error under another name")]
