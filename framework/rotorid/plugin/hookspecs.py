"""The rotorid hook specifications (pluggy).

Two kinds of hooks:

* **Registration hooks** (plural nouns) return an iterable of :class:`PluginDescriptor`:
  small records naming a component, the factory that builds it and a one-line summary. What
  a factory must build is specified in :mod:`rotorid.plugin.contracts`.
  The host collects them, sorts them by name and rejects a name registered twice.
* **Lifecycle hooks** notify observers (loggers, exporters, live plots) of progress; their
  return values are ignored. They must not change the objects they receive (they are frozen).

Plugins implement hooks with :data:`hookimpl` and are registered through the ``rotorid``
entry-point group. Keep plugin modules cheap to import: do heavy imports inside the hook or
inside the factory.
"""

from __future__ import annotations

from collections.abc import Callable

import attrs
import pluggy

from rotorid.errors import PluginError

PROJECT = "rotorid"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@attrs.frozen
class PluginDescriptor:
    """What a registration hook yields.

    Attributes:
        name: the name users select the component by (e.g. ``"output-error"``).
        factory: callable building the component; keyword options are passed through.
        summary: one line shown by ``rotorid plugins``.
    """

    name: str = attrs.field()
    factory: Callable = attrs.field()
    summary: str = attrs.field()

    @name.validator
    def _check_name(self, attribute, value):
        if not isinstance(value, str) or not value.strip():
            raise PluginError(f"a plugin descriptor needs a non-empty name, got {value!r}")

    @factory.validator
    def _check_factory(self, attribute, value):
        if not callable(value):
            raise PluginError(f"plugin descriptor {self.name!r}: factory must be callable, "
                              f"got {value!r}")

    @summary.validator
    def _check_summary(self, attribute, value):
        if not isinstance(value, str):
            raise PluginError(f"plugin descriptor {self.name!r}: summary must be a string, "
                              f"got {value!r}")


# ----------------------------------------------------------------- registration hooks
@hookspec
def rotorid_estimators():
    """Register parameter estimators.

    Return an iterable of :class:`PluginDescriptor` whose factory builds a
    :class:`~rotorid.plugin.contracts.Estimator` (the contract is specified there only).
    """


@hookspec
def rotorid_reduction_criteria():
    """Register model-reduction criteria.

    Return an iterable of :class:`PluginDescriptor` whose factory builds a
    :class:`~rotorid.plugin.contracts.ReductionCriterion` (the contract is specified there only).
    """


@hookspec
def rotorid_validation_envelopes():
    """Register frequency-domain validation envelopes.

    Return an iterable of :class:`PluginDescriptor` whose factory builds a
    :class:`~rotorid.plugin.contracts.ValidationEnvelope` (the contract is specified there only).
    """


@hookspec
def rotorid_data_sources():
    """Register data sources.

    Return an iterable of :class:`PluginDescriptor` whose factory builds a
    :class:`~rotorid.plugin.contracts.DataSource` (the contract is specified there only).
    """


@hookspec
def rotorid_input_signals():
    """Register input signals (multisteps, sweeps …).

    Return an iterable of :class:`PluginDescriptor` whose factory builds a
    :class:`~rotorid.plugin.contracts.InputSignal` (the contract is specified there only).
    """


@hookspec
def rotorid_commands():
    """Register subcommands of the ``rotorid`` command line (the descriptor's name).

    Return an iterable of :class:`PluginDescriptor` whose factory builds a
    :class:`~rotorid.plugin.contracts.Command` (the contract is specified there only).
    """


# ----------------------------------------------------------------- lifecycle hooks
@hookspec
def rotorid_estimation_iteration(estimator, stage, iteration, cost, rmse, lm_lambda):
    """Called after every accepted iteration of an iterative estimator.

    Args:
        estimator: name of the estimator (``str``).
        stage: which run of the estimation (``str``, e.g. output error's ``"3 s"`` horizon or
            ``"full"``); ``""`` for an estimator with one run.
        iteration: 1-based iteration count within the stage (``int``).
        cost: current cost, for output error ``det R`` (``float``).
        rmse: current RMSE, the paper's eq. 18 (``float``).
        lm_lambda: current Levenberg-Marquardt parameter, or ``None``.
    """


@hookspec
def rotorid_case_started(case):
    """Called when a :class:`~rotorid.study.pipeline.FlightCase` starts running."""


@hookspec
def rotorid_reduction_step(case, step):
    """Called after every step of the model-reduction loop.

    Args:
        case: name of the flight case (``str``).
        step: the :class:`~rotorid.estimation.reduction.ReductionStep` just finished.
    """


@hookspec
def rotorid_case_finished(case, result):
    """Called when a flight case has finished: ``case`` the
    :class:`~rotorid.study.case.FlightCase`, ``result`` its immutable ``CaseResult``."""
