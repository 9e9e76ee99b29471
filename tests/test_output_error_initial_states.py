"""Output error with per-maneuver initial states as parameters (``initial_states=True``)."""

import warnings

import numpy as np
import pytest
from rotorid import ManeuverSet
from rotorid.errors import EstimationError, IdentifiabilityWarning
from rotorid.estimation.models import LinearModel, finite_difference_sensitivities
from rotorid.simulation.simulator import simulate
from rotorid_output_error.augment import WithInitialStates
from test_output_error import (
    SMALL_TRUTH,
    Pendulum,
    doublet_maneuvers,
    estimator,
    small_structure,
)

#: initial perturbation states u w q θ v p φ r (ft/s, deg/s, deg) scaled per maneuver
X0_PATTERN = np.array([4.0, -1.5, 2.0, 1.5, -3.0, 3.0, 2.0, -1.0])


def _initial_states(n_maneuvers, seed=2):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.0, 1.0, size=(n_maneuvers, 1)) * X0_PATTERN


def test_initial_state_sensitivities_match_finite_differences():
    structure = small_structure()
    truth = structure.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.07, "tau_M_long": 0.05})
    maneuvers = ManeuverSet(doublet_maneuvers(n=200)[:3])
    model = WithInitialStates(LinearModel(structure), maneuvers.names)
    values = np.concatenate([truth, _initial_states(3).ravel()])
    outputs, sens = model.sensitivities(values, maneuvers)
    reference_outputs, reference = finite_difference_sensitivities(model, values, maneuvers)
    for y, yr in zip(outputs, reference_outputs):
        assert np.allclose(y, yr, rtol=0, atol=1e-12)
    for s, sr in zip(sens, reference):
        assert s.shape == (200, len(model.parameter_names), 8)
        assert np.max(np.abs(s - sr)) <= 1e-5 * np.max(np.abs(sr))
    # the x0 block of maneuver 1 moves only maneuver 1's outputs
    block = slice(len(truth) + 8, len(truth) + 16)
    assert np.any(sens[1][:, block] != 0.0)
    assert not np.any(sens[0][:, block]) and not np.any(sens[2][:, block])


def test_initial_states_are_estimated_and_remove_the_start_bias():
    structure = small_structure(delays=())
    truth = structure.as_vector(SMALL_TRUTH)
    blank = doublet_maneuvers(n=400)
    x0 = _initial_states(len(blank))
    rng = np.random.default_rng(5)
    outputs = simulate(structure, truth, blank, initial_states=x0)
    data = ManeuverSet([m.with_outputs(y + rng.normal(size=y.shape) * 0.05)
                        for m, y in zip(blank, outputs)])
    result = estimator(initial_states=True).estimate(structure, data)
    assert result.converged, result.stop_reason
    n = len(truth)
    assert result.parameter_names[n] == f"x0_{data.names[0]}_u"
    assert np.all(np.abs(result.values[:n] - truth) <= 4 * result.cramer_rao[:n])
    estimated_x0 = result.values[n:].reshape(x0.shape)
    bounds = result.cramer_rao[n:].reshape(x0.shape)
    assert np.all(np.abs(estimated_x0 - x0) <= 4 * bounds)
    without = estimator().estimate(structure, data)
    assert without.rmse > 1.5 * result.rmse
    assert np.max(np.abs(without.values - truth) / without.cramer_rao) > 4


def test_initial_states_combine_with_output_biases_and_need_a_structure():
    structure = small_structure(delays=())
    truth = structure.as_vector(SMALL_TRUTH)
    blank = ManeuverSet(doublet_maneuvers(n=300)[:6])   # ped: off-axis of coll
    data = ManeuverSet([m.with_outputs(y) for m, y in
                        zip(blank, simulate(structure, truth, blank,
                                            initial_states=_initial_states(6, seed=9)))])
    with warnings.catch_warnings():
        warnings.simplefilter("error", IdentifiabilityWarning)
        result = estimator(initial_states=True, output_biases=True).estimate(structure, data)
    n_states, n_biases = 8 * 6, 8 * 6
    assert len(result.parameter_names) == len(truth) + n_states + n_biases
    assert result.parameter_names[-1].startswith("bias_")
    assert result.parameter_names[len(truth)].startswith("x0_")
    with pytest.raises(EstimationError, match="needs a model structure"):
        estimator(initial_states=True).estimate(Pendulum(), data)
