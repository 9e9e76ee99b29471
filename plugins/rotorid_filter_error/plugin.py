"""Registers the ``filter-error`` estimator (cheap to import; the estimator loads on use)."""

from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl


def _make_estimator(**options):
    from .estimator import FilterErrorEstimator

    return FilterErrorEstimator(**options)


@hookimpl
def rotorid_estimators():
    return [PluginDescriptor(
        "filter-error", _make_estimator,
        "maximum likelihood with process noise: steady-state Kalman filter, process-noise "
        "and measurement-noise estimation, Cramér-Rao bounds (linear structures)")]
