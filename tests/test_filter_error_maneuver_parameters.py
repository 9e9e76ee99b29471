"""The filter-error estimator's per-maneuver parameters: initial filter states and output
biases (plugins/rotorid_filter_error/maneuver_parameters.py)."""

import numpy as np
import pytest
from rotorid.errors import EstimationError
from rotorid_filter_error.estimator import FilterErrorProblem
from rotorid_output_error.levenberg_marquardt import Settings
from test_filter_error import GUSTS, PROCESS, SMALL_TRUTH, VARIANCE, estimator, noisy_data, structure

#: The recovery test's records start off trim in these states, uniformly within ± these sizes
#: (ft/s, deg/s, deg), and their outputs (ax az q θ ay p φ r) carry constant offsets within
#: ± BIAS_SIZES.
START_STATES = ("w", "q", "theta", "p", "phi", "r")
START_SIZES = np.array([3.0, 3.0, 2.0, 5.0, 3.0, 3.0])
BIAS_SIZES = np.array([0.3, 0.3, 0.5, 0.4, 0.3, 0.5, 0.4, 0.5])


def _problem(**options):
    model = structure()
    data = noisy_data({}, disturbances={"r": (2.0, 0.8)}, gusts=GUSTS)
    problem = FilterErrorProblem(model, data, (), Settings(), ("r",), tuple(GUSTS), **options)
    truth = np.concatenate([model.as_vector(SMALL_TRUTH), [2.0, 3.0, 4.0, 0.8, 1.0, 1.0],
                            VARIANCE])
    extra = len(problem.parameter_names) - truth.size
    return problem, np.concatenate(
        [truth, 0.5 * np.random.default_rng(0).standard_normal(extra)])


def _negative_log_likelihood(problem, values) -> float:
    innovations, b = problem.innovations(values)
    quadratic = np.einsum("nmi,ij,nmj->", innovations, np.linalg.inv(b), innovations)
    return 0.5 * quadratic + 0.5 * problem.n_samples * np.linalg.slogdet(b)[1]


def _whitened_difference(problem, values, k, whiten, step=1e-6) -> np.ndarray:
    up, down = values.copy(), values.copy()
    up[k] += step
    down[k] -= step
    return (problem.innovations(up)[0] - problem.innovations(down)[0]) @ whiten / (2 * step)


@pytest.mark.parametrize("every", [1, 3])
def test_gradient_and_information_of_the_maneuvers_parameters_match_finite_differences(every):
    """The exact gradient of L against central differences of L, and the information's
    cross terms of a derivative with each maneuver parameter against products of the
    whitened innovations' central differences, for an initial velocity, rate and gust and
    two biases; also with a measurement update at every third sample only."""
    problem, values = _problem(initial_states=True, output_biases=True, update_every=every)
    assert problem.parameter_names[problem.n_global:problem.n_global + 12] == tuple(
        f"x0_long+1_{s}" for s in ("u", "w", "q", "theta", "v", "p", "phi", "r", "d_r",
                                   "g_w", "g_v")) + ("bias_long+1_ax",)
    cost, b, residuals, _ = problem.evaluate(values)
    information, gradient = problem.gauss_newton(values, b, residuals)
    whiten = np.linalg.cholesky(np.linalg.inv(b))
    m_q = problem.parameter_names.index("M_q")
    d_m_q = _whitened_difference(problem, values, m_q, whiten)
    for name in ("x0_long+1_u", "x0_lat-1_p", "x0_coll+1_g_w", "bias_long+1_az",
                 "bias_ped-1_r"):
        k = problem.parameter_names.index(name)
        step = 1e-5
        up, down = values.copy(), values.copy()
        up[k] += step
        down[k] -= step
        expected = (_negative_log_likelihood(problem, up)
                    - _negative_log_likelihood(problem, down)) / (2 * step)
        assert gradient[k] == pytest.approx(expected, rel=1e-5, abs=1e-4), name
        d_k = _whitened_difference(problem, values, k, whiten)
        assert information[m_q, k] == pytest.approx(np.sum(d_m_q * d_k), rel=1e-5), name
        assert information[k, k] == pytest.approx(np.sum(d_k * d_k), rel=1e-5), name


@pytest.mark.parametrize("seed", [3, 7])
def test_recovers_initial_states_and_output_biases(seed):
    """Records started off trim with biased sensors and white process noise: with the initial
    states and the biases estimated every derivative, F and R is within 4 CR (the largest of
    38 over four seeds was 3.6) and the 112 initial states and biases scatter like their
    bounds (RMS of their errors in CR within 1.3; four seeds gave 1.02–1.22); without them
    some derivative is more than 5 CR off."""
    rng = np.random.default_rng(seed)
    model = structure()
    count = 8
    x0 = np.zeros((count, model.n_states))
    columns = [model.states.index(s) for s in START_STATES]
    x0[:, columns] = rng.uniform(-1.0, 1.0, (count, len(columns))) * START_SIZES
    biases = rng.uniform(-1.0, 1.0, (count, model.n_outputs)) * BIAS_SIZES
    data = noisy_data(PROCESS, seed=seed + 10, initial_states=x0, biases=biases)
    assert len(data) == count
    result = estimator(process_noise=tuple(PROCESS), initial_states=START_STATES,
                       output_biases=True).estimate(model, data)
    assert result.converged, result.stop_reason
    shared = np.concatenate([model.as_vector(SMALL_TRUTH), list(PROCESS.values()), VARIANCE])
    own = np.concatenate([x0[:, columns], biases], axis=1).ravel()
    error = (result.values - np.concatenate([shared, own])) / result.cramer_rao
    assert np.all(np.abs(error[:shared.size]) < 4.0), dict(zip(result.parameter_names,
                                                                error.round(2)))
    assert np.sqrt(np.mean(error[shared.size:]**2)) < 1.3
    plain = estimator(process_noise=tuple(PROCESS)).estimate(model, data)
    derivatives = slice(0, model.n_parameters)
    assert np.max(np.abs(plain.values[derivatives] - shared[derivatives])
                  / plain.cramer_rao[derivatives]) > 5.0


def test_initial_state_names_are_checked():
    with pytest.raises(EstimationError, match=r"initial_states names g_u: the filter's states "
                                              r"are u, w, q, theta, v, p, phi, r, d_r, g_w, g_v"):
        _problem(initial_states=("g_u",))
