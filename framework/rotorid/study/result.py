"""What one flight case produced: :class:`CaseResult` and its ``result.json`` record."""

from __future__ import annotations

from collections.abc import Mapping

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.estimation.estimate import Estimate
from rotorid.estimation.profiles import DelayProfile
from rotorid.estimation.reduction import ReductionPath
from rotorid.estimation.state_estimates import StateEstimates
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.notebook import case_result_html, case_result_summary
from rotorid.study.case import FlightCase
from rotorid.study.comparison import FrequencyComparison
from rotorid.study.estimator_comparison import EstimatorComparison
from rotorid.study.hybrid_comparison import HybridComparison
from rotorid.study.claims import case_claims, claims_title
from rotorid.study.reference import ReferenceComparison, compare_with_reference
from rotorid.verification.compare import VerificationResult
from rotorid.verification.equivalent_delays import EquivalentDelays
from rotorid.verification.handling_qualities import HandlingQualities
from rotorid.verification.metrics import TimeDomainMetrics
from rotorid.verification.simulation_fit import SimulationFit

#: The two identified models of a case: the selected structure, and it with delays.
MODELS = ("no delays", "with delays")
#: What tables, legends and sentences call the one model of a case that kept no delay.
ONE_MODEL = "identified model"
#: Derivatives the paper checks for sign and magnitude (truth-model.md §8).
KEY_DERIVATIVES = ("M_w", "L_v", "N_v", "Z_w", "M_u", "X_u", "X_v", "Y_u", "Y_v")


@attrs.frozen(eq=False)
class CaseResult:
    """Everything one flight case produced (immutable)."""

    case: FlightCase
    condition: FlightCondition
    identification: ManeuverSet
    verification_data: ManeuverSet | None
    path: ReductionPath
    structures: Mapping[str, ModelStructure]      # by model label (MODELS)
    estimates: Mapping[str, Estimate]
    # by model label: its simulation of the identification data, simulated once for all uses
    simulations: Mapping[str, SimulationFit]
    verification: Mapping[str, VerificationResult]
    truth_derivatives: Mapping[str, float] | None
    seconds: Mapping[str, float]
    dropped_delays: tuple[str, ...] = ()
    resumed_steps: int = 0           # finished reduction steps reused from an earlier run
    truth_delays: EquivalentDelays | None = None   # the truth model's equivalent delays
    # by model label, with [compare] frequency: the frequency-domain fit beside the model's
    frequency_comparison: Mapping[str, FrequencyComparison] = attrs.field(factory=dict)
    delay_profiles: tuple[DelayProfile, ...] = ()  # of each kept delay (estimation.profiles)
    # with [compare] estimators: the model with delays fitted by each listed estimator
    estimator_comparison: EstimatorComparison | None = None
    # what the sanity checks of the identification data warned about (estimation.sanity)
    data_warnings: tuple[str, ...] = ()
    # with [compare] hybrid: the hybrid rotor-body model beside the two models
    hybrid_comparison: HybridComparison | None = None
    # ADS-33 bandwidth and phase delay by source: each model's and the measured (sweeps)
    handling_qualities: Mapping[str, tuple[HandlingQualities, ...]] = attrs.field(
        factory=dict)
    # the estimator's state estimates of the model with delays along the identification data
    # (filter error's gusts and disturbances; None from an estimator that gives none)
    state_estimates: StateEstimates | None = None

    @property
    def name(self) -> str:
        return self.case.name

    def __repr__(self) -> str:
        return case_result_summary(self)

    def _repr_html_(self) -> str:
        return case_result_html(self)

    @property
    def time_metrics(self) -> dict[str, TimeDomainMetrics]:
        """Each model's time-domain metrics on the identification data, by model label."""
        return {label: fit.metrics for label, fit in self.simulations.items()}

    @property
    def kept_delays(self) -> tuple[str, ...]:
        """The derivatives whose delays the model with delays kept (none where the case
        declares none, or the data determined none)."""
        return tuple(d.name for d in self.structures["with delays"].derivatives
                     if d.delay is not None)

    @property
    def models(self) -> tuple[str, ...]:
        """The labels of the models the case shows: :data:`MODELS`, or ``"with delays"``
        alone where it kept no delay (the two are then one model)."""
        return MODELS if self.kept_delays else MODELS[1:]

    def model_name(self, label: str) -> str:
        """How the report names model ``label``: the label itself, or :data:`ONE_MODEL`
        where the case shows one model."""
        return label if self.kept_delays else ONE_MODEL

    @property
    def final_model_name(self) -> str:
        """The model verified and checked, in words: "model with delays", or
        :data:`ONE_MODEL` where the case shows one model."""
        return "model with delays" if self.kept_delays else ONE_MODEL

    def rmse_summary(self) -> str:
        """The RMSE of the models shown: "RMSE 0.2763 without delays, 0.2350 with delays",
        or "RMSE 0.2427" for one model (:meth:`rmse_text`)."""
        if not self.kept_delays:
            return f"RMSE {self.rmse_text('with delays')}"
        return (f"RMSE {self.rmse_text('no delays')} without delays, "
                f"{self.rmse_text('with delays')} with delays")

    def rmse_text(self, model: str) -> str:
        """The RMSE of ``model`` ("no delays", "with delays") as its estimator gives it, four
        decimals, with the RMSE of its simulation of the identification maneuvers beside it
        where the two differ by more than 0.1 % (filter error's is that of its one-step
        predictions; biases and initial states estimated per record are not simulated)."""
        own, simulated = self.estimates[model].rmse, self.time_metrics[model].rmse
        text = f"{own:.4f}"
        if np.isfinite(simulated) and not np.isclose(own, simulated, rtol=1e-3, atol=0.0):
            text += f" (simulated {simulated:.4f})"
        return text

    def simulated(self, model: str) -> tuple[np.ndarray, ...]:
        """Outputs of one identified model on the identification data, one (N_i, n_o) array
        per maneuver (the simulation the metrics were taken from)."""
        return self.simulations[model].outputs

    def key_derivative_names(self) -> tuple[str, ...]:
        """The key derivatives (:data:`KEY_DERIVATIVES`) the case's structure can hold (an
        aeroplane's declared structure in β, say, holds none of them)."""
        possible = set(self.structures["with delays"].template.derivative_names())
        return tuple(name for name in KEY_DERIVATIVES if name in possible)

    def key_derivatives(self) -> dict:
        """Identified key derivatives of the delayed model, and the truth's linearisation
        (those of :meth:`key_derivative_names`)."""
        estimate = self.estimates["with delays"]
        table = {}
        for name in self.key_derivative_names():
            identified = (estimate.value(name) if name in estimate.parameter_names else None)
            truth = None if self.truth_derivatives is None else self.truth_derivatives.get(name)
            table[name] = {"identified": identified, "truth_linearisation": truth}
        return table

    def reference_comparison(self) -> list[ReferenceComparison]:
        """The model with delays beside the case's ``[reference]`` values (empty without)."""
        return compare_with_reference(self.estimates["with delays"], self.case.reference)

    def _comparison_seconds(self) -> dict:
        """Wall time of each comparison's fits, s: the frequency-domain fit per model, each
        estimator's fit, the hybrid's fit (those the case ran)."""
        seconds = {}
        if self.frequency_comparison:
            seconds["frequency"] = {label: c.seconds
                                    for label, c in self.frequency_comparison.items()}
        if self.estimator_comparison is not None:
            seconds["estimators"] = dict(self.estimator_comparison.seconds)
        if self.hybrid_comparison is not None:
            seconds["hybrid"] = self.hybrid_comparison.seconds
        return seconds

    def as_dict(self) -> dict:
        """The ``result.json`` record (``estimator_comparison`` and ``hybrid_comparison`` only
        when the case ran them)."""
        path = self.path
        comparison = ({} if self.estimator_comparison is None
                      else {"estimator_comparison": self.estimator_comparison.summary()})
        if self.hybrid_comparison is not None:
            comparison["hybrid_comparison"] = self.hybrid_comparison.summary()
        return {
            "case": self.case.as_dict(),
            "condition": attrs.asdict(self.condition),
            "reduction": {"rule": path.rule, "rmse_tolerance": path.rmse_tolerance,
                          "selected_step": path.selected_index,
                          # the step each selection rule picks on this path
                          "selections": path.selections(),
                          "removed": list(path.removed),
                          "stopped": path.stopped,
                          "steps": [s.summary() for s in path.steps]},
            "selected_structure": list(self.structures["no delays"].names),
            "estimates": {label: e.as_dict() for label, e in self.estimates.items()},
            "time_metrics": {label: m.summary() for label, m in self.time_metrics.items()},
            "frequency_verification": {label: v.summary()
                                       for label, v in self.verification.items()},
            "key_derivatives": self.key_derivatives(),
            # the paper's claims, or the guidelines for a case without a truth model
            "claims_title": claims_title(self),
            "claims": [claim.as_dict() for claim in case_claims(self)],
            "data_warnings": list(self.data_warnings),
            "reference_comparison": [row.as_dict() for row in self.reference_comparison()],
            "dropped_delays": list(self.dropped_delays),
            "frequency_comparison": {label: c.summary()
                                     for label, c in self.frequency_comparison.items()},
            "delay_profiles": [p.as_dict() for p in self.delay_profiles],
            "truth_equivalent_delays": (None if self.truth_delays is None
                                        else self.truth_delays.as_dict()),
            "handling_qualities": {source: [item.as_dict() for item in items]
                                   for source, items in self.handling_qualities.items()},
            "state_estimates": (None if self.state_estimates is None
                                else self.state_estimates.summary()),
            **comparison,
            # What differs between an uninterrupted and a resumed run of the same case, and
            # nothing else: compare result files without this key.
            "timing": {"seconds": dict(self.seconds), "resumed_steps": self.resumed_steps,
                       "comparison_seconds": self._comparison_seconds()},
        }
