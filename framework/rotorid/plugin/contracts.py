"""What the core calls on a plugin component: one Protocol per family, and the values they pass.

This module is the only specification of the plugin families. The registration hooks
(:mod:`rotorid.plugin.hookspecs`) yield :class:`~rotorid.plugin.hookspecs.PluginDescriptor`
objects whose factory builds a component; :func:`rotorid.create` checks the component against
its family's Protocol here (:func:`violations`) and names what is wrong. The table in
``docs/plugins.md`` is tested against :data:`CONTRACTS`.

Units follow the model (flight-test by default: ft, ft/s, deg, deg/s, % of control travel);
frequencies are in rad/s, times and delays in s.
"""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal, Protocol, runtime_checkable

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import PluginError
from rotorid.estimation.estimate import Estimate
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.verification.envelopes import EnvelopeBounds, EnvelopeCheck

#: The kinds of validation envelope: ``"bounds"`` limits ε point by point (drawn on the error
#: plots); ``"cost"`` scores a whole pair (e.g. the mismatch cost J) and is left off the plots.
ENVELOPE_KINDS = ("bounds", "cost")


# ----------------------------------------------------------------- estimators
@runtime_checkable
class Estimator(Protocol):
    """Family ``estimators``: fits a structure's free parameters to maneuvers.

    Optionally, ``check_structure(structure)`` raises a rotorid error for options that cannot
    work with ``structure`` (a study calls it when reading a case, before any data exist), and
    ``state_estimates(structure, maneuvers, estimate)`` returns the
    :class:`~rotorid.estimation.state_estimates.StateEstimates` of the model's states along
    ``maneuvers`` at ``estimate`` (``rotorid identify --states``).
    """

    def estimate(self, structure: ModelStructure, maneuvers: ManeuverSet, *,
                 start: Mapping[str, float] | None = None) -> Estimate:
        """Estimate ``structure``'s free parameters from all ``maneuvers`` at once.

        ``start`` maps parameter names to start values (the structure's initial values where
        ``None`` or missing).
        """


# ----------------------------------------------------------------- reduction criteria
@attrs.frozen
class Removal:
    """A criterion's proposal: remove ``parameter`` because ``metric`` exceeds ``threshold``.

    ``criterion`` is the proposing criterion's name; ``metric`` and ``threshold`` are in the
    criterion's own measure, ``unit`` (``"%"`` for normalised Cramér-Rao bounds, ``""`` for a
    plain ratio); ``reason`` is one line.
    """

    parameter: str
    criterion: str
    metric: float
    threshold: float
    reason: str
    unit: str = "%"

    @property
    def metric_text(self) -> str:
        """The metric with its unit, e.g. ``"47.3 %"`` or ``"0.52"``."""
        return f"{self.metric:.3g}" + (f" {self.unit}" if self.unit else "")


@runtime_checkable
class ReductionCriterion(Protocol):
    """Family ``reduction-criteria``: picks the next parameter the reduction loop removes."""

    def propose(self, estimate: Estimate) -> Removal | None:
        """The parameter to remove next, or ``None`` when the criterion is satisfied."""

    def rank(self, estimate: Estimate) -> Removal | None:
        """The worst removable parameter by this criterion's metric, threshold ignored.

        The loop calls it on the last criterion when ``continue_to_zero`` is set;
        ``None`` when nothing can be removed.
        """


# ----------------------------------------------------------------- validation envelopes
@runtime_checkable
class ValidationEnvelope(Protocol):
    """Family ``validation-envelopes``: holds the verification error ε = H_model/H_truth.

    Attributes:
        name: the registered name, repeated in every check.
        kind: ``"bounds"`` or ``"cost"`` (:data:`ENVELOPE_KINDS`).
        provenance: where the envelope comes from (first sentence shown in reports).
        verified: whether the source was checked; an unverified envelope never reports a
            bare ``"pass"``.
        threshold: coherence γ² a point needs to count.
    """

    name: str
    kind: Literal["bounds", "cost"]
    provenance: str
    verified: bool
    threshold: float

    def bounds(self, omega: np.ndarray) -> EnvelopeBounds:
        """Magnitude (dB) and phase (deg) bounds on ε at ``omega`` (rad/s, shape (M,))."""

    def check(self, error: np.ndarray, coherence: np.ndarray, omega: np.ndarray
              ) -> EnvelopeCheck:
        """Hold ``error`` (complex ε, shape (M,)) with ``coherence`` (M,) against the envelope.

        A bounds-kind envelope can delegate to :func:`rotorid.check_bounds`.
        """


# ----------------------------------------------------------------- input signals
@runtime_checkable
class InputSignal(Protocol):
    """Family ``input-signals``: a control input shape (3211, doublet, sweep …)."""

    duration: float

    def __call__(self, time: np.ndarray) -> np.ndarray:
        """The input at ``time`` (s, shape (N,)), in % of control travel, shape (N,)."""


# ----------------------------------------------------------------- commands
@runtime_checkable
class Command(Protocol):
    """Family ``commands``: a ``rotorid`` subcommand named by its descriptor (a module will do)."""

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        """Declare the subcommand's arguments on ``parser``."""

    def run(self, args: argparse.Namespace) -> int:
        """Run with the parsed ``args``; return the exit status."""


# ----------------------------------------------------------------- data sources
@runtime_checkable
class LinearSystem(Protocol):
    """A truth model's linearisation: ``dx/dt = A x + B u``."""

    A: np.ndarray
    B: np.ndarray
    states: tuple[str, ...]
    controls: tuple[str, ...]


@runtime_checkable
class TruthModel(Protocol):
    """The model a simulating data source flew: linearised for truth derivatives and delays."""

    def linearize(self, airspeed_kt: float, *, full: bool = False,
                  units: str = "flight-test") -> LinearSystem:
        """Linear model about the trim at ``airspeed_kt`` (kt).

        ``full`` keeps the rotor (flap, inflow) states instead of residualising them;
        ``units`` is a unit-system name (:func:`rotorid.unit_system`).
        """


def _optional(kind: type, what: str):
    def check(instance, attribute, value):
        if value is not None and not isinstance(value, kind):
            raise PluginError(f"CaseData.{attribute.name} must be a {what} or None, got "
                              f"{type(value).__name__}; fix the data source's case_data")
    return check


def _truth(instance, attribute, value):
    if value is not None and not isinstance(value, TruthModel):
        raise PluginError(f"CaseData.truth must have linearize(airspeed_kt, *, full, units) "
                          f"or be None, got {type(value).__name__}; fix the data source's "
                          f"case_data")


@attrs.frozen
class CaseData:
    """What a data source gives a flight case.

    Attributes:
        identification: the maneuvers the parameters are estimated from.
        verification: the maneuvers (usually sweeps) the identified model is verified on,
            or ``None``.
        condition: the trim the data were flown at, or ``None`` (the case's
            ``[condition]`` table is used).
        truth: the model that produced the data, or ``None`` (no truth derivatives or
            equivalent delays then).
    """

    identification: ManeuverSet = attrs.field(validator=_optional(ManeuverSet, "ManeuverSet"))
    verification: ManeuverSet | None = attrs.field(
        default=None, validator=_optional(ManeuverSet, "ManeuverSet"))
    condition: FlightCondition | None = attrs.field(
        default=None, validator=_optional(FlightCondition, "FlightCondition"))
    truth: TruthModel | None = attrs.field(default=None, validator=_truth)

    @identification.validator
    def _check_identification(self, attribute, value):
        if value is None:
            raise PluginError("CaseData needs identification maneuvers; fix the data "
                              "source's case_data")


@runtime_checkable
class DataSource(Protocol):
    """Family ``data-sources``: the data of a flight case."""

    def case_data(self, settings: Mapping[str, Any], directory: Path) -> CaseData:
        """The case's data from its ``[data]`` settings (without ``source``).

        ``directory`` is the case's data directory, where a source may store what it produces
        (a simulator's flown set). Optional members the study uses when present:
        ``path_settings``, the names of settings that hold file paths (relative ones in a
        case file are resolved against its folder), and ``noise_realisations(settings,
        directory)``, a picklable ``data(seed) -> ManeuverSet`` of the identification
        maneuvers with that seed (its noise, and its gusts in turbulence; ``rotorid
        montecarlo``).
        """


#: Family name → the Protocol its components satisfy.
CONTRACTS: dict[str, type] = {
    "estimators": Estimator,
    "reduction-criteria": ReductionCriterion,
    "validation-envelopes": ValidationEnvelope,
    "data-sources": DataSource,
    "input-signals": InputSignal,
    "commands": Command,
}


def members(protocol: type) -> tuple[str, ...]:
    """The attributes and methods a component of ``protocol`` must have, in declaration order."""
    declared = [*vars(protocol).get("__annotations__", {}),
                *(name for name, value in vars(protocol).items()
                  if callable(value) and (not name.startswith("_") or name == "__call__"))]
    return tuple(dict.fromkeys(declared))


def violations(family: str, component: object) -> tuple[str, ...]:
    """How ``component`` breaks ``family``'s contract: missing members, methods that are not
    callable, an envelope kind outside :data:`ENVELOPE_KINDS`; empty when it conforms."""
    protocol = CONTRACTS[family]
    methods = {name for name, value in vars(protocol).items() if callable(value)}
    found = [f"missing {name}" if not hasattr(component, name) else f"{name} is not callable"
             for name in members(protocol)
             if not hasattr(component, name)
             or (name in methods and not callable(getattr(component, name)))]
    kind = getattr(component, "kind", ENVELOPE_KINDS[0])
    if protocol is ValidationEnvelope and kind not in ENVELOPE_KINDS:
        found.append(f"kind {kind!r} is not one of {', '.join(ENVELOPE_KINDS)}")
    return tuple(found)
