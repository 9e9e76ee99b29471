"""The paper's claims measured on constructed results: verdicts, evidence, the truth model's
value beside each sign; on a user's own data the guidelines instead; the models' RMSE as
the summaries give it."""

import types

import numpy as np
from rotorid.study.claims import (
    case_claims,
    claims_tally,
    claims_title,
    paper_claims,
    phase_claim,
    sign_claim,
)
from rotorid.verification.band import DEFAULT_BAND


def _estimate(values: dict, bounds: dict, rmse: float = 0.3):
    names = tuple(values)
    return types.SimpleNamespace(
        units="si", rmse=rmse, parameter_names=names, values=np.array(list(values.values())),
        cramer_rao=np.array([bounds[n] for n in names]), index=names.index,
        value=lambda name: values[name])


def _result(source="helisim", airspeed_kt=70.0, truth=None, simulated_rmse=None,
            kept_delays=("L_lat",), **estimates):
    """A case result of ``estimates``; each model's simulation RMSE is its estimate's unless
    ``simulated_rmse`` gives it (an estimator whose RMSE is not a simulation's). Without
    ``kept_delays`` it shows its model with delays alone, as the "identified model"."""
    case = types.SimpleNamespace(data_source=source, band=DEFAULT_BAND)
    metrics = {label: types.SimpleNamespace(
        rmse=estimate.rmse if simulated_rmse is None else simulated_rmse)
        for label, estimate in estimates.items()}
    return types.SimpleNamespace(
        case=case, condition=types.SimpleNamespace(airspeed_kt=airspeed_kt),
        estimates=estimates, time_metrics=metrics, verification={}, truth_derivatives=truth,
        kept_delays=kept_delays, models=tuple(estimates) if kept_delays else ("with delays",),
        model_name=lambda label: label if kept_delays else "identified model",
        final_model_name="model with delays" if kept_delays else "identified model")


def test_sign_claims_carry_the_truth_models_value_and_their_verdicts():
    model = _estimate({"M_w": 0.09, "L_v": -0.4, "N_v": 0.001}, {"M_w": 0.01, "L_v": 0.01,
                                                                 "N_v": 0.01})
    result = _result(truth={"M_w": 0.34}, **{"no delays": model, "with delays": model})
    m_w = sign_claim(result, "M_w", -1)
    assert m_w.claim == "M_w < 0" and m_w.verdict == "does not hold"
    assert m_w.evidence == ("identified +0.09 ± 0.01 rad/s² per m/s; "
                            "truth model +0.34 rad/s² per m/s")
    assert sign_claim(result, "L_v", -1).verdict == "holds"
    undetermined = sign_claim(result, "N_v", +1)           # |value| < 2 Cramér-Rao bounds
    assert undetermined.verdict == "not checked" and "Cramér-Rao" in undetermined.reason
    removed = sign_claim(result, "Z_w", -1)
    assert removed.verdict == "not checked" and removed.evidence.startswith("removed")
    # The paper's hover statement: M_w about zero, removed.
    assert sign_claim(result, "M_w", 0).verdict == "does not hold"


def _verified(**passed):
    """The model with delays verified on the pairs ``passed`` names (MUAD passed or not)."""
    items = [types.SimpleNamespace(pair=pair.replace("_", "/"), checks={
        "muad": types.SimpleNamespace(passed=ok, n_inside=10 if ok else 7, n_used=10,
                                      worst_margin_db=0.5 if ok else -1.0,
                                      worst_margin_deg=3.0, status="checked",
                                      outside_text=lambda ok=ok: "" if ok else
                                      "; outside at 2–4 rad/s")})
        for pair, ok in passed.items()]
    by_pair = {item.pair: item for item in items}
    return {"with delays": types.SimpleNamespace(pairs=items, get=by_pair.get)}


def test_a_case_on_a_users_own_data_is_checked_on_the_guidelines():
    """No truth model: no paper claims (no derivative signs, none of the paper's pairs), but
    the RMSE guideline of both models and MUAD on every pair the case verified."""
    model = _estimate({"M_w": -0.2, "L_v": -0.4}, {"M_w": 0.01, "L_v": 0.01}, rmse=2.5)
    models = {"no delays": model, "with delays": model}
    own = _result(source="files", **models)
    own.verification = _verified(alpha_elevator=True, q_elevator=False)
    assert claims_title(own) == "The guidelines"
    claims = case_claims(own)
    assert [c.claim.split(" (")[0].split(" with")[0] for c in claims] == [
        "time-domain RMSE ≤ 1.0 to 2.0"] * 2 + ["alpha/elevator", "q/elevator"]
    decided, failed = claims_tally(claims)
    assert len(decided) == 4
    assert [c.claim.split(" ")[0] for c in failed] == ["time-domain", "time-domain",
                                                        "q/elevator"]
    assert failed[-1].evidence.endswith("worst margin -1.00 dB / +3.0°; outside at 2–4 rad/s")
    truth_data = _result(truth={"M_w": -0.1}, **models)
    assert claims_title(truth_data) == "The paper's claims"
    assert case_claims(truth_data) == paper_claims(truth_data)
    assert [c.claim for c in case_claims(truth_data) if c.claim.startswith("M_w")] == [
        "M_w < 0"]


def test_a_case_without_delays_is_checked_once_on_its_one_model():
    model = _estimate({"M_w": -0.2}, {"M_w": 0.01}, rmse=1.5)
    own = _result(source="files", kept_delays=(), **{"no delays": model, "with delays": model})
    own.verification = _verified(alpha_elevator=True)
    assert [c.claim.split(" where")[0] for c in case_claims(own)] == [
        "time-domain RMSE ≤ 1.0 to 2.0 (identified model; checked against 2)",
        "alpha/elevator of the identified model inside MUAD"]
    phase = phase_claim(own, "p/long")
    assert phase.verdict == "not checked" and phase.reason == "the model kept no delay"


def test_an_rmse_that_would_mix_units_is_not_checked():
    model = _estimate({"M_w": -0.2}, {"M_w": 0.01}, rmse=float("nan"))
    claims = case_claims(_result(source="files", **{"no delays": model, "with delays": model}))
    assert [c.verdict for c in claims] == ["not checked"] * 2
    assert "reference unit" in claims[0].reason


def test_the_rmse_guideline_is_checked_on_the_models_simulation():
    """Filter error's own RMSE is that of its one-step predictions (0.56 on a turbulent case
    whose simulation RMSE is 11.3): the guideline judges the simulation."""
    model = _estimate({"M_w": -0.2}, {"M_w": 0.01}, rmse=0.56)
    models = {"no delays": model, "with delays": model}
    claims = case_claims(_result(source="files", simulated_rmse=11.3, **models))
    assert [(c.evidence, c.verdict) for c in claims] == [("RMSE 11.300", "does not hold")] * 2
    claims = case_claims(_result(source="files", simulated_rmse=1.2, **models))
    assert [(c.evidence, c.verdict) for c in claims] == [("RMSE 1.200", "holds")] * 2


def test_a_models_rmse_shows_its_simulations_where_the_estimators_own_differs():
    """The study's summary lines: filter error's one-step RMSE with the simulation's beside
    it; output error's, which is the simulation's, alone."""
    from rotorid.study.result import CaseResult

    model = _estimate({"M_w": -0.2}, {"M_w": 0.01}, rmse=0.5566)
    models = {"no delays": model, "with delays": model}
    filtered = _result(source="files", simulated_rmse=11.3451, **models)
    assert CaseResult.rmse_text(filtered, "no delays") == "0.5566 (simulated 11.3451)"
    assert CaseResult.rmse_text(_result(source="files", **models), "with delays") == "0.5566"
