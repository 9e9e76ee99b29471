"""Registers the ``insensitivity`` and ``cramer-rao`` reduction criteria (cheap to import)."""

from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl


def _insensitivity(**options):
    from .criteria import InsensitivityCriterion

    return InsensitivityCriterion(**options)


def _cramer_rao(**options):
    from .criteria import CramerRaoCriterion

    return CramerRaoCriterion(**options)


@hookimpl
def rotorid_reduction_criteria():
    return [
        PluginDescriptor("insensitivity", _insensitivity,
                         "remove the largest normalised insensitivity while any is > 10 %"),
        PluginDescriptor("cramer-rao", _cramer_rao,
                         "remove the largest normalised Cramér-Rao bound while any is > 20 %"),
    ]
