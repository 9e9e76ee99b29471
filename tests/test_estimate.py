"""Estimate: the builder from a fit, per-name access and the JSON record."""

import json
import math

import numpy as np
import pytest
from rotorid import Derivative, Estimate, FlightCondition, ModelStructure
from rotorid.errors import EstimationError

#: Three derivatives: one with a negative sign prior, one fixed, one delayed (so four parameters).
STRUCTURE = ModelStructure(FlightCondition.from_airspeed(0.0), [
    Derivative("L_p", sign="negative"),
    Derivative("M_q", initial=-1.5),
    Derivative("M_u", initial=0.02, fixed=True),
    Derivative("L_lat", initial=0.3, delay=0.05),
])
#: Residuals of two maneuvers with hand-computable statistics: outputs 0 and 1 only, others 0.
RESIDUALS = [np.zeros((2, 8)), np.zeros((2, 8))]
RESIDUALS[0][:, 0] = [1.0, -1.0]
RESIDUALS[1][:, 0] = [3.0, -3.0]
RESIDUALS[0][:, 1] = [2.0, 2.0]
RESIDUALS[1][:, 1] = [0.0, 0.0]


def fitted(**fields) -> Estimate:
    information = np.diag([4.0, 1.0, 16.0, 100.0])
    return Estimate.from_fit(STRUCTURE, [0.5, -2.0, 0.25, 0.04], information, RESIDUALS,
                             estimator="hand", **fields)


def test_from_fit_derives_the_statistics_the_noise_and_the_structure_facts():
    estimate = fitted()
    assert estimate.parameter_names == ("L_p", "M_q", "L_lat", "tau_L_lat")
    # R = Σ eᵀe / N over N = 4 samples: R00 = (1 + 1 + 9 + 9)/4 = 5, R11 = (4 + 4)/4 = 2,
    # R01 = (1·2 − 1·2 + 0 + 0)/4 = 0; the six other outputs are zero, so det R = 0.
    assert estimate.noise_covariance[0, 0] == 5.0 and estimate.noise_covariance[1, 1] == 2.0
    assert estimate.noise_covariance[0, 1] == 0.0
    assert estimate.cost == 0.0
    # RMSE (eq. 18) = sqrt((20 + 8) / (4 · 8)).
    assert estimate.rmse == pytest.approx(math.sqrt(28 / 32))
    assert estimate.n_samples == 4
    # Diagonal F: CR = 1/sqrt(F_ii) = I, correlation the identity.
    np.testing.assert_allclose(estimate.cramer_rao, [0.5, 1.0, 0.25, 0.1])
    np.testing.assert_allclose(estimate.insensitivity, [0.5, 1.0, 0.25, 0.1])
    np.testing.assert_allclose(estimate.correlation, np.eye(4), atol=1e-15)
    assert estimate.sign_violations == ("L_p",)          # positive against a negative prior
    assert estimate.signs["L_p"] == "negative" and estimate.fixed == {"M_u": 0.02}
    assert estimate.units == "flight-test" and estimate.output_names == STRUCTURE.outputs
    assert estimate.start.tolist() == [0.0, -1.5, 0.3, 0.05]
    assert (estimate.iterations, estimate.converged, estimate.stop_reason) == (0, True,
                                                                               "converged")
    assert estimate.cost_history == (0.0,) and estimate.rmse_history == (estimate.rmse,)


def test_fields_given_to_from_fit_override_the_derived_ones():
    estimate = fitted(cost=2.5, iterations=7, stop_reason="cost tolerance",
                      cost_history=(9.0, 2.5), sign_violations=())
    assert estimate.cost == 2.5 and estimate.cost_history == (9.0, 2.5)
    assert estimate.iterations == 7 and estimate.sign_violations == ()


def test_from_fit_without_residuals_names_what_it_needs():
    with pytest.raises(EstimationError, match="needs the residuals, or noise_covariance, cost, "
                                              "rmse, n_samples given explicitly"):
        Estimate.from_fit(STRUCTURE, np.zeros(4), np.eye(4), estimator="hand")


def test_one_parameter_by_name():
    estimate = fitted()
    l_p = estimate["L_p"]
    assert (l_p.value, l_p.start, l_p.cramer_rao, l_p.sign) == (0.5, 0.0, 0.5, "negative")
    assert l_p.cramer_rao_pct == pytest.approx(100.0)            # |0.5 / 0.5|·100
    assert estimate["tau_L_lat"].insensitivity_pct == pytest.approx(250.0)   # 0.1/0.04
    assert "M_q" in estimate and "M_u" not in estimate
    assert [p.name for p in estimate] == list(estimate.parameter_names)
    with pytest.raises(EstimationError, match="no estimated parameter 'M_w'"):
        estimate["M_w"]


def test_restricted_keeps_the_full_fits_statistics_of_the_named_parameters():
    # F couples M_q with tau_L_lat.
    information = np.array([[4.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.5],
                            [0.0, 0.0, 16.0, 0.0], [0.0, 0.5, 0.0, 1.0]])
    estimate = Estimate.from_fit(STRUCTURE, [0.5, -2.0, 0.25, 0.04], information, RESIDUALS,
                                 estimator="hand")
    part = estimate.restricted(("M_q", "L_p"))
    assert part.parameter_names == ("M_q", "L_p")
    assert part.values.tolist() == [-2.0, 0.5] and part.start.tolist() == [-1.5, 0.0]
    # the M_q–tau block [[1, 0.5], [0.5, 1]] has inverse diagonal 1/0.75: the bound of the
    # fit with every parameter, not of the 2×2 block kept
    assert part.cramer_rao.tolist() == pytest.approx([math.sqrt(1 / 0.75), 0.5])
    assert part.insensitivity.tolist() == [1.0, 0.5]
    assert part.information.tolist() == [[1.0, 0.0], [0.0, 4.0]]
    assert part.sign_violations == ("L_p",) and part.cost == estimate.cost
    assert part.parameter_units == {"M_q": "1/s", "L_p": "1/s"}
    assert estimate.restricted(estimate.parameter_names) is estimate
    with pytest.raises(EstimationError, match="no estimated parameter 'F_q'"):
        estimate.restricted(("F_q",))


def test_propagated_bounds_of_a_linear_and_a_nonlinear_function_match_the_closed_form():
    """f = M·θ has the covariance M·C·Mᵀ; with a correlated information matrix C is its
    inverse. A product θ0·θ1 has the gradient (θ1, θ0) (delta method)."""
    information = np.array([[4.0, 1.0, 0.0, 0.0], [1.0, 2.0, 0.5, 0.0],
                            [0.0, 0.5, 16.0, 0.0], [0.0, 0.0, 0.0, 100.0]])
    estimate = Estimate.from_fit(STRUCTURE, [0.5, -2.0, 0.25, 0.04], information, RESIDUALS,
                                 estimator="hand")
    covariance = np.linalg.inv(information)
    weights = np.array([[1.0, -2.0, 0.0, 0.0], [0.0, 0.5, 3.0, 1.0]])
    values, bounds = estimate.propagated(lambda theta: weights @ theta)
    assert values == pytest.approx(weights @ estimate.values)
    assert bounds == pytest.approx(np.sqrt(np.diag(weights @ covariance @ weights.T)), rel=1e-7)
    _, (product,) = estimate.propagated(lambda theta: np.array([theta[0] * theta[1]]))
    gradient = np.array([-2.0, 0.5, 0.0, 0.0])
    assert product == pytest.approx(math.sqrt(gradient @ covariance @ gradient), rel=1e-6)


def test_a_quantity_of_a_parameter_with_an_infinite_bound_has_an_infinite_bound():
    singular = np.diag([4.0, 0.0, 16.0, 100.0])     # M_q unidentifiable
    with pytest.warns(Warning):
        estimate = Estimate.from_fit(STRUCTURE, [0.5, -2.0, 0.25, 0.04], singular, RESIDUALS,
                                     estimator="hand")
    assert not np.isfinite(estimate["M_q"].cramer_rao)
    _, bounds = estimate.propagated(lambda theta: np.array([theta[0] + theta[1], theta[2]]))
    assert bounds[0] == np.inf and bounds[1] == pytest.approx(0.25)


def test_the_record_round_trips_through_json():
    estimate = fitted(notes=("a note",), at_bound=("M_q",))
    record = json.loads(json.dumps(estimate.as_dict()))
    again = Estimate.from_dict(record)
    for field in ("parameter_names", "output_names", "cost", "rmse", "cost_history",
                  "rmse_history", "iterations", "converged", "stop_reason", "n_samples",
                  "sign_violations", "at_bound", "unidentifiable", "fixed", "signs", "units",
                  "notes", "estimator", "output_units", "parameter_units", "rmse_basis"):
        assert getattr(again, field) == getattr(estimate, field), field
    for field in ("values", "start", "cramer_rao", "insensitivity", "correlation",
                  "information", "noise_covariance", "residual_rms"):
        np.testing.assert_array_equal(getattr(again, field), getattr(estimate, field))


def test_the_record_layout():
    record = fitted().as_dict()
    assert set(record["parameters"]) == {"L_p", "M_q", "L_lat"}
    assert record["delays"]["L_lat"] == {"value": 0.04, "cramer_rao": 0.1,
                                         "cramer_rao_pct": pytest.approx(250.0),
                                         "insensitivity": 0.1,
                                         "insensitivity_pct": pytest.approx(250.0),
                                         "unit": "s"}
    assert record["parameters"]["L_p"]["sign"] == "negative"
    assert record["parameters"]["L_lat"]["unit"] == "deg/s² per %"
    assert record["outputs"] == list(STRUCTURE.outputs)
    assert "signs" not in record and "values" not in record


def test_an_estimate_of_no_parameter_round_trips():
    empty = Estimate.from_fit(STRUCTURE.without("L_p", "M_q", "L_lat"), [], np.zeros((0, 0)),
                              RESIDUALS, estimator="none")
    again = Estimate.from_dict(json.loads(json.dumps(empty.as_dict())))
    assert again.parameter_names == () and again.correlation.shape == (0, 0)


def test_an_incomplete_record_is_refused():
    record = fitted().as_dict()
    del record["outputs"]
    with pytest.raises(EstimationError, match="not a complete rotorid estimate record"):
        Estimate.from_dict(record)
