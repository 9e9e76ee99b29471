"""Registers the ``frequency-response`` estimator (cheap to import; it loads on use)."""

from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl


def _make_estimator(**options):
    from .estimator import FrequencyResponseEstimator

    return FrequencyResponseEstimator(**options)


@hookimpl
def rotorid_estimators():
    return [PluginDescriptor(
        "frequency-response", _make_estimator,
        "state-space fit to sweep frequency responses: Tischler's cost J, Levenberg-Marquardt, "
        "Cramér-Rao bounds")]
