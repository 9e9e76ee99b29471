"""Three models side by side (``[compare] hybrid``): no delays, with delays, and hybrid.

The hybrid rotor-body model (docs/hybrid.md) is built on the selected 6-DoF model
(:func:`rotorid.model.hybrid.hybrid_from_six_dof`: the disc tilt instead of the direct rate
terms of X, Y, L, M, N and the direct roll and pitch terms of the cyclic and the velocities, the
flap equations, delays on the cyclic into flapping) and fitted with the case's estimator to the
identification maneuvers, starting where the 6-DoF fit ended; optionally it is first reduced,
without its delays, by the case's criteria (its flap damping and hub moments kept). Every model
is judged on the same terms: its parameters, the RMSE and det R of its simulation of the
identification maneuvers, and per verification pair the mismatch cost J over γ² ≥ 0.8 from
1 rad/s to the sweeps' top frequency, at most 20 rad/s (:func:`hybrid_band`: the band where the
rotor's lag shows), and whether its error stays inside MUAD there. The key roll and pitch
derivatives of all three are set side by side, the hybrid's with its flap tilts residualised
(its quasi-steady 6-DoF form). With a truth model, those are set beside the truth's 6-DoF
linearisation (rotor and inflow residualised), and the hybrid's rotor terms beside the truth's
flap-coupled reference (its full linearisation with the flap rates, coning and inflow
residualised).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping, Sequence

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import IdentifiabilityWarning
from rotorid.estimation.estimate import Estimate
from rotorid.estimation.reduction import reduce
from rotorid.model.hybrid import (
    REQUIRED,
    hybrid_from_six_dof,
    quasi_steady_derivatives,
    with_flap_delays,
)
from rotorid.model.structure import ModelStructure
from rotorid.verification.band import VerificationBand
from rotorid.verification.compare import VerificationResult, envelopes_by_name
from rotorid.verification.simulation_fit import SimulationFit, fit_unless_diverging
from rotorid.verification.verify import verify_model

#: The models compared, in table order.
HYBRID_MODELS = ("no delays", "with delays", "hybrid")
#: Highest frequency of the comparison's J, rad/s, unless the sweeps stop lower.
HYBRID_OMEGA_MAX = 20.0
#: The hybrid's rotor terms set beside the truth's reference: flap damping (−1/τ_f), hub
#: moments per disc tilt, cyclic into flapping.
ROTOR_TERMS = ("Bc_beta1c", "Bs_beta1s", "M_beta1c", "L_beta1s", "Bc_long", "Bs_lat")
#: The flap equations' own damping terms, each giving a flap time constant τ_f = −1/value.
FLAP_DAMPING = ("Bc_beta1c", "Bs_beta1s")
#: The 6-DoF derivatives the rotor's flapping shapes: roll and pitch damping, cross rates,
#: control powers and speed stability; compared across the three models.
FLAP_SHAPED = ("L_p", "L_q", "L_v", "L_lat", "L_long", "M_q", "M_p", "M_u", "M_long", "M_lat")
#: The envelopes every model is held against in the comparison's band.
HYBRID_ENVELOPES = ("muad", "mismatch-cost")


def hybrid_band(omega_max: float = HYBRID_OMEGA_MAX) -> VerificationBand:
    """Where J is taken: γ² ≥ 0.8 from 1 rad/s to ``omega_max``, the sweeps' top frequency.

    Points past the top frequency are artefacts whatever their coherence: on the built-in
    hover sweeps (0.45–14 rad/s) the p/lat estimate at 17.5 rad/s has γ² = 0.84 and every
    model errs there by 28–29 dB, which alone sets J to about 700; at Tischler's γ² ≥ 0.6 the
    q/long point at 15.6 rad/s (γ² 0.64, 25 dB off) did the same."""
    return VerificationBand(coherence=0.8, omega_min=1.0, omega_max=omega_max)


@attrs.frozen(eq=False)
class HybridComparison:
    """The three models of one case on common terms (module docstring).

    Attributes:
        structure, estimate: the hybrid model and its fit.
        parameters: number of estimated parameters by model label (:data:`HYBRID_MODELS`).
        simulation: each model's simulation of the identification maneuvers.
        verification: by model label, the sweeps' verification in ``band`` with J (empty
            without sweeps).
        band: where J is taken (:func:`hybrid_band`).
        reference: the truth's flap-coupled values of the hybrid's derivatives by name, or
            None without a truth model.
        flap_shaped_derivatives: by model label, each of :data:`FLAP_SHAPED` as (value,
            Cramér-Rao bound): the six-dof models' own (0 and None where the reduction removed
            it), the hybrid's quasi-steady form with bounds propagated from its fit (infinite
            where a parameter it depends on has an infinite bound).
        six_dof_reference: the truth's 6-DoF linearisation (rotor and inflow residualised)
            by name, or None without a truth model.
        seconds: wall time of the hybrid fit (and its reduction), s.
        removed: what the reduction removed from the hybrid, in order; None without one.
    """

    structure: ModelStructure
    estimate: Estimate
    parameters: Mapping[str, int]
    simulation: Mapping[str, SimulationFit | None]
    verification: Mapping[str, VerificationResult]
    reference: Mapping[str, float] | None
    seconds: float
    band: VerificationBand
    flap_shaped_derivatives: Mapping[str, Mapping[str, tuple[float, float | None]]]
    six_dof_reference: Mapping[str, float] | None = None
    removed: tuple[str, ...] | None = None

    @property
    def costs(self) -> dict[str, dict[str, float | None]]:
        """J by model label and pair over :attr:`band` (None where no point)."""
        return {label: {pair.pair: pair.checks["mismatch-cost"].cost for pair in result.pairs}
                for label, result in self.verification.items()}

    @property
    def values(self) -> np.ndarray:
        """The hybrid's own parameter vector (an estimator's noise parameters left out)."""
        return self.estimate.restricted(self.structure.parameter_names).values

    @property
    def muad(self) -> dict[str, dict[str, tuple[int, int]]]:
        """(points inside MUAD, points counted) by model label and pair over :attr:`band` and
        MUAD's own range."""
        return {label: {pair.pair: (pair.checks["muad"].n_inside, pair.checks["muad"].n_used)
                        for pair in result.pairs}
                for label, result in self.verification.items()}

    def flap_time_constants(self) -> dict[str, tuple[float, float]]:
        """τ_f = −1/value of each flap damping term with its Cramér-Rao bound, s."""
        result = {}
        for name in FLAP_DAMPING:
            value, bound = self.estimate.value(name), self.estimate[name].cramer_rao
            result[name] = (-1.0 / value, bound / value**2)
        return result

    def rotor_terms(self) -> dict[str, dict]:
        """Each of :data:`ROTOR_TERMS`: identified value, Cramér-Rao bound, reference."""
        return {name: {"identified": self.estimate.value(name),
                       "cramer_rao": self.estimate[name].cramer_rao,
                       "reference": None if self.reference is None
                       else self.reference.get(name)}
                for name in ROTOR_TERMS if name in self.estimate.parameter_names}

    def summary(self) -> dict:
        """The ``result.json`` record (the fit's wall time goes to the record's
        ``timing``)."""
        return {"band": attrs.asdict(self.band),
                "models": {label: {"parameters": self.parameters[label],
                                   "simulation": (None if self.simulation[label] is None
                                                  else self.simulation[label].summary()),
                                   "mismatch_cost": dict(self.costs.get(label, {})),
                                   "muad_points_inside": {
                                       pair: {"inside": inside, "counted": counted}
                                       for pair, (inside, counted)
                                       in self.muad.get(label, {}).items()},
                                   "flap_shaped_derivatives": {
                                       name: {"value": value, "cramer_rao": bound}
                                       for name, (value, bound)
                                       in self.flap_shaped_derivatives[label].items()}}
                           for label in HYBRID_MODELS},
                "six_dof_reference": (None if self.six_dof_reference is None
                                      else {n: self.six_dof_reference[n]
                                            for n in FLAP_SHAPED}),
                "flap_time_constants_s": {n: {"identified": t, "cramer_rao": s}
                                          for n, (t, s) in self.flap_time_constants().items()},
                "rotor_terms": self.rotor_terms(),
                "estimate": self.estimate.as_dict(),
                "removed": None if self.removed is None else list(self.removed)}


def compare_hybrid(structures: Mapping[str, ModelStructure], estimates: Mapping[str, Estimate],
                   simulations: Mapping[str, SimulationFit],
                   verification: Mapping[str, VerificationResult], sweeps: ManeuverSet | None,
                   estimator, reference=None, omega_max: float = HYBRID_OMEGA_MAX,
                   criteria: Sequence = (), rule: str = "lowest-rmse",
                   rmse_tolerance: float = 0.01) -> HybridComparison:
    """Build and fit the hybrid model on ``structures["no delays"]`` and compare it with the
    case's two models.

    Args:
        structures, estimates: the case's models by label (``no delays``, ``with delays``).
        simulations: their simulations of the identification maneuvers, by label (reused).
        verification: their verification on the ``sweeps``, by label (empty: no J); its
            responses are checked again in the comparison's band, and the hybrid is
            verified on the same pairs.
        sweeps: the verification maneuvers; estimator: the case's estimator.
        reference: ``reference(structure) -> {name: value}`` of the truth, or None.
        omega_max: the sweeps' top frequency, rad/s (J's band, :func:`hybrid_band`).
        criteria: reduction criteria; with any, the hybrid without delays is reduced first
            (:func:`~rotorid.estimation.reduction.reduce`, stopped when the criteria are
            satisfied, :data:`~rotorid.model.hybrid.REQUIRED` kept) and the step ``rule``
            selects (with ``rmse_tolerance``) is fitted with its delays from its start values.
    """
    band = hybrid_band(omega_max)
    ident = simulations["no delays"].maneuvers
    hybrid = hybrid_from_six_dof(structures["no delays"], estimates["no delays"].values,
                                 delay_upper=None)
    clock = time.perf_counter()
    removed = None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        if criteria:
            path = reduce(hybrid, ident, estimator, criteria, rule=rule,
                          rmse_tolerance=rmse_tolerance, keep=REQUIRED)
            hybrid, removed = path.selected.structure, path.removed
        hybrid = with_flap_delays(hybrid)
        estimate = estimator.estimate(hybrid, ident)        # the disc starts at trim
    seconds = time.perf_counter() - clock
    values = estimate.restricted(hybrid.parameter_names).values
    if verification:
        envelopes = envelopes_by_name(HYBRID_ENVELOPES, band=band)
        pairs = [p.pair for p in verification["with delays"].pairs]
        verification = {**{label: result.checked_in(band, envelopes)
                           for label, result in verification.items()},
                        "hybrid": verify_model(hybrid, values, sweeps, pairs, envelopes,
                                               band=band)}
    parameters = {**{label: s.n_parameters for label, s in structures.items()},
                  "hybrid": hybrid.n_parameters}
    six_dof = structures["no delays"]
    quasi_steady, bounds = estimate.propagated(
        lambda vector: quasi_steady_derivatives(hybrid, vector, six_dof, FLAP_SHAPED))
    flap_shaped = {**{label: _six_dof_flap_shaped(estimates[label]) for label in structures},
                   "hybrid": {name: (float(value), float(bound)) for name, value, bound
                              in zip(FLAP_SHAPED, quasi_steady, bounds)}}
    return HybridComparison(
        hybrid, estimate, parameters,
        {**simulations, "hybrid": fit_unless_diverging(hybrid, values, ident)},
        verification, None if reference is None else reference(hybrid), seconds, band,
        flap_shaped, None if reference is None else reference(six_dof), removed)


def _six_dof_flap_shaped(estimate: Estimate) -> dict[str, tuple[float, float | None]]:
    """Each of :data:`FLAP_SHAPED` of a six-dof estimate: (value, Cramér-Rao bound);
    a fixed derivative has no bound, one its structure does not hold is (0, None)."""
    def pair(name):
        if name in estimate:
            return estimate.value(name), estimate[name].cramer_rao
        return float(estimate.fixed.get(name, 0.0)), None
    return {name: pair(name) for name in FLAP_SHAPED}


def mean_cost(costs: Mapping[str, float | None]) -> float | None:
    """Mean J over the pairs that have one, or None."""
    values = [c for c in costs.values() if c is not None]
    return float(np.mean(values)) if values else None
