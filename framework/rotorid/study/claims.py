"""The paper's claims as it states them, measured on a study case.

Each :class:`Claim` carries its evidence and one verdict of :data:`VERDICTS`; a claim that
cannot be decided says why. The claims (paper sections "Hover" and "Forward flight"):

* the selected model meets the time-domain guideline RMSE ≤ 1.0 to 2.0 (checked against 2.0)
  on its simulation of the identification maneuvers;
* the signs of the key stability derivatives: L_v < 0, N_v > 0 and Z_w < 0 in hover and at
  70 kt, M_w < 0 at 70 kt (horizontal tail), and M_w removed in hover (about zero, high
  insensitivity); each sign claim shows the truth model's own linearised value beside the
  identified one, so a claim the truth model itself does not meet reads as such;
* with delays, the on-axis pairs (q/long, p/lat, r/ped, az/coll) are inside the MUAD bounds
  where γ² ≥ 0.8 (checked in the case's verification band), the off-axis cyclic pairs (p/long, q/lat) too, and the delays reduce the
  off-axis phase error.

The derivative claims are the paper's statements about its helicopter at hover and 70 kt: they
are checked only on cases whose data come from the truth model (data source ``helisim``) at
those conditions.

A case about one's own aircraft (no truth model: measured data) is held against no paper.
What its user needs is whether the model meets the accepted guidelines: :func:`case_claims`
gives it :func:`guideline_claims`, the RMSE guideline of the models shown and the MUAD bounds
on every pair the model with delays (or the one model) was verified on (the case's own pairs,
not the paper's).
"""

from __future__ import annotations

import math

import attrs
import numpy as np

from rotorid.study.expectations import SIGNIFICANCE, derivative_unit, regime_of
from rotorid.verification.envelopes import error_db_deg

#: The three verdicts of a claim.
VERDICTS = ("holds", "does not hold", "not checked")
#: The upper end of the paper's time-domain guideline RMSE ≤ 1.0 to 2.0 (its ref. 16).
RMSE_GUIDELINE = 2.0
#: The on-axis pairs the paper shows inside the MUAD bounds with delays.
ON_AXIS_PAIRS = ("q/long", "p/lat", "r/ped", "az/coll")
#: The off-axis cyclic pairs the delays bring inside the bounds (hover) and whose phase error
#: they reduce.
OFF_AXIS_PAIRS = ("p/long", "q/lat")
#: The paper's sign claims by regime: derivative → expected sign (0: removed, about zero).
SIGN_CLAIMS = {"hover": {"M_w": 0, "L_v": -1, "N_v": +1, "Z_w": -1},
               "forward": {"M_w": -1, "L_v": -1, "N_v": +1, "Z_w": -1}}
#: Data sources whose data are the paper's kind of helicopter (the derivative claims apply).
PAPER_SOURCES = ("helisim",)


@attrs.frozen
class Claim:
    """One of the paper's claims measured on a case.

    ``verdict`` is one of :data:`VERDICTS`; ``reason`` says why a claim is not checked.
    """

    claim: str
    evidence: str
    verdict: str = attrs.field(validator=attrs.validators.in_(VERDICTS))
    reason: str = ""

    def as_dict(self) -> dict:
        return attrs.asdict(self)


def _decided(claim: str, evidence: str, holds: bool) -> Claim:
    return Claim(claim, evidence, "holds" if holds else "does not hold")


def mean_phase_error(item) -> float | None:
    """Mean |∠ε| in deg (principal values) over the points of the pair's verification band;
    None without such points."""
    _, phase = error_db_deg(item.error)
    used = item.checked & np.isfinite(phase)
    return float(np.mean(np.abs(phase[used]))) if used.any() else None


def _band_text(result) -> str:
    """The case's verification band, e.g. "γ² ≥ 0.8 over 0.1–10 rad/s"."""
    return result.case.band.describe()


def _verified(result, label: str, pair: str):
    verification = result.verification.get(label)
    return None if verification is None else verification.get(pair)


def rmse_claims(result) -> list[Claim]:
    """The time-domain guideline on the models shown (both, or the one model of a case that
    kept no delay: ``CaseResult.models``), each simulated on the identification maneuvers
    (``result.time_metrics``): the model's own response to the recorded inputs, not an
    estimator's one-step predictions (filter error's innovation RMSE stays small in
    turbulence whatever the simulation does). Not checked where the RMSE is not given: it
    would mix units."""
    claims = []
    for label in result.models:
        rmse = result.time_metrics[label].rmse
        claim = (f"time-domain RMSE ≤ 1.0 to 2.0 ({result.model_name(label)}; checked against "
                 f"{RMSE_GUIDELINE:g})")
        claims.append(
            _decided(claim, f"RMSE {rmse:.3f}", rmse <= RMSE_GUIDELINE)
            if math.isfinite(rmse) else
            Claim(claim, "", "not checked", "no RMSE: an output has no reference unit, so it "
                                            "would mix units"))
    return claims


def muad_claim(result, pair: str) -> Claim:
    """``pair`` of the model with delays (the final model) inside the MUAD bounds in the
    verification band."""
    item = _verified(result, "with delays", pair)
    model = "with delays" if result.kept_delays else f"of the {result.final_model_name}"
    claim = f"{pair} {model} inside MUAD where {_band_text(result)}"
    check = None if item is None else item.checks.get("muad")
    if check is None or check.passed is None:
        return Claim(claim, "", "not checked",
                     "pair not verified" if check is None else check.status)
    return _decided(claim, f"{check.n_inside}/{check.n_used} coherent points inside, worst "
                           f"margin {check.worst_margin_db:+.2f} dB / "
                           f"{check.worst_margin_deg:+.1f}°{check.outside_text()}",
                    bool(check.passed))


def phase_claim(result, pair: str) -> Claim:
    """The delays reduce the mean phase error of off-axis ``pair``."""
    claim = f"{pair}: delays reduce the phase error (mean |∠ε| where {_band_text(result)})"
    if not result.kept_delays:
        return Claim(claim, "", "not checked", "the model kept no delay")
    items = {label: _verified(result, label, pair) for label in ("no delays", "with delays")}
    phases = {label: None if item is None else mean_phase_error(item)
              for label, item in items.items()}
    if None in phases.values():
        return Claim(claim, "", "not checked", "pair not verified or no coherent points")
    without, with_ = phases["no delays"], phases["with delays"]
    return _decided(claim, f"{without:.1f}° without delays, {with_:.1f}° with", with_ < without)


def sign_claim(result, name: str, sign: int) -> Claim:
    """The paper's sign of derivative ``name`` (``sign`` 0: removed, about zero) on the model
    with delays, with the truth model's linearised value beside it."""
    estimate = result.estimates["with delays"]
    unit = derivative_unit(name, estimate.units)
    truth = (result.truth_derivatives or {}).get(name)
    beside = "" if truth is None else f"; truth model {truth:+.4g} {unit}"
    if sign == 0:
        claim = f"{name} about zero, removed (high insensitivity)"
        if name not in estimate.parameter_names:
            return _decided(claim, f"removed{beside}", True)
        value = estimate.value(name)
        return _decided(claim, f"kept, identified {value:+.4g} {unit}{beside}", False)
    claim = f"{name} {'<' if sign < 0 else '>'} 0"
    if name not in estimate.parameter_names:
        return Claim(claim, f"removed by the reduction{beside}", "not checked",
                     "the selected structure has no such derivative")
    index = estimate.index(name)
    value, bound = float(estimate.values[index]), float(estimate.cramer_rao[index])
    evidence = f"identified {value:+.4g} ± {bound:.2g} {unit}{beside}"
    if abs(value) < SIGNIFICANCE * bound:
        return Claim(claim, evidence, "not checked",
                     f"|value| below {SIGNIFICANCE:g} Cramér-Rao bounds: the data do not fix "
                     f"the sign")
    return _decided(claim, evidence, math.copysign(1, value) == sign)


def paper_claims(result) -> list[Claim]:
    """The paper's claims for one case (see the module docstring), in the report's order."""
    claims = rmse_claims(result)
    regime = regime_of(result.condition.airspeed_kt)
    if result.case.data_source in PAPER_SOURCES and regime is not None:
        claims += [sign_claim(result, name, sign)
                   for name, sign in SIGN_CLAIMS[regime].items()]
    claims += [muad_claim(result, pair) for pair in ON_AXIS_PAIRS]
    claims += [muad_claim(result, pair) for pair in OFF_AXIS_PAIRS]
    claims += [phase_claim(result, pair) for pair in OFF_AXIS_PAIRS]
    return claims


def guideline_claims(result) -> list[Claim]:
    """The guidelines on a case about one's own aircraft: the RMSE guideline of the models
    shown and each pair the model with delays was verified on inside the MUAD bounds."""
    verified = result.verification.get("with delays")
    pairs = () if verified is None else [item.pair for item in verified.pairs]
    return rmse_claims(result) + [muad_claim(result, pair) for pair in pairs]


def holds_paper_claims(result) -> bool:
    """Whether a case is held against the paper: its data come from a truth model."""
    return result.truth_derivatives is not None


def case_claims(result) -> list[Claim]:
    """The claims a case is checked on: the paper's (:func:`paper_claims`) for a case whose
    data come from a truth model, else the guidelines (:func:`guideline_claims`)."""
    return paper_claims(result) if holds_paper_claims(result) else guideline_claims(result)


def claims_title(result) -> str:
    """What :func:`case_claims` of the case are: "The paper's claims" or "The guidelines"."""
    return "The paper's claims" if holds_paper_claims(result) else "The guidelines"


def claims_tally(claims) -> tuple[list[Claim], list[Claim]]:
    """(decided, failed): the claims with a verdict, and those that do not hold."""
    decided = [c for c in claims if c.verdict != "not checked"]
    return decided, [c for c in decided if c.verdict == "does not hold"]
