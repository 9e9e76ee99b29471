"""The paper's reduction criteria (eqs. 14 and 16).

Only derivatives are candidates: delays and nuisance parameters (output biases) are never
proposed. A parameter estimated at exactly zero has an infinite normalised measure and goes
first.
"""

from __future__ import annotations

import math

import attrs
import numpy as np
from rotorid.errors import DerivativeError, EstimationError
from rotorid.estimation.estimate import Estimate
from rotorid.plugin.contracts import Removal
from rotorid.model.derivatives import parse_name


def _is_derivative(name: str) -> bool:
    try:
        parse_name(name)
    except DerivativeError:
        return False
    return True


def _positive(instance, attribute, value):
    if not (math.isfinite(value) and value > 0):
        raise EstimationError(f"{attribute.name} must be a positive percentage, got {value!r}")


@attrs.frozen
class _NormalisedMeasureCriterion:
    threshold: float = attrs.field(converter=float, validator=_positive)

    name = ""
    label = ""

    def _measure(self, estimate: Estimate) -> np.ndarray:
        raise NotImplementedError

    def rank(self, estimate: Estimate) -> Removal | None:
        """The derivative with the largest normalised measure, threshold ignored."""
        candidates = [i for i, n in enumerate(estimate.parameter_names) if _is_derivative(n)]
        if not candidates:
            return None
        measure = self._measure(estimate)
        worst = max(candidates, key=lambda i: measure[i])
        name, value = estimate.parameter_names[worst], float(measure[worst])
        verdict = "above" if value > self.threshold else "within"
        return Removal(name, self.name, value, self.threshold,
                       f"largest normalised {self.label}: {value:.1f} % ({verdict} the "
                       f"{self.threshold:g} % threshold)")

    def propose(self, estimate: Estimate) -> Removal | None:
        """Remove the worst derivative while its normalised measure exceeds the threshold."""
        removal = self.rank(estimate)
        if removal is None or removal.metric <= self.threshold:
            return None
        return removal


@attrs.frozen
class InsensitivityCriterion(_NormalisedMeasureCriterion):
    """Remove the parameter with the largest normalised insensitivity Ī = |I/Θ|·100."""

    threshold: float = attrs.field(default=10.0, converter=float, validator=_positive)
    name = "insensitivity"
    label = "insensitivity"

    def _measure(self, estimate: Estimate) -> np.ndarray:
        return estimate.insensitivity_pct


@attrs.frozen
class CramerRaoCriterion(_NormalisedMeasureCriterion):
    """Remove the parameter with the largest normalised Cramér-Rao bound |CR/Θ|·100."""

    threshold: float = attrs.field(default=20.0, converter=float, validator=_positive)
    name = "cramer-rao"
    label = "Cramér-Rao bound"

    def _measure(self, estimate: Estimate) -> np.ndarray:
        return estimate.cramer_rao_pct
