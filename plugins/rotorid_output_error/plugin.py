"""Registers the ``output-error`` estimator (cheap to import; the estimator loads on use)."""

from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl


def _make_estimator(**options):
    from .estimator import OutputErrorEstimator

    return OutputErrorEstimator(**options)


@hookimpl
def rotorid_estimators():
    return [PluginDescriptor(
        "output-error", _make_estimator,
        "maximum-likelihood output error (det R), Levenberg-Marquardt, Cramér-Rao bounds")]
