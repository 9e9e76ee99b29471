"""The output-error estimator: recovery, statistics, bounds, convergence reporting, options."""

import json
import warnings

import numpy as np
import pytest
import rotorid
from hover_reference import closed_loop_maneuvers, true_structure
from rotorid import Derivative, FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.errors import EstimationError, IdentifiabilityWarning
from rotorid.simulation.simulator import simulate

HOVER = FlightCondition.from_airspeed(0.0)
SMALL_TRUTH = {"X_u": -0.02, "X_q": 0.6, "X_long": -0.1, "Z_w": -0.32, "Z_coll": -1.2,
               "M_u": 0.1, "M_q": -3.7, "M_long": 0.9, "L_v": -0.4, "L_p": -14.0, "L_lat": 3.0,
               "Y_v": -0.04, "Y_lat": 0.05, "N_r": -0.3, "N_ped": 1.5, "N_p": -2.4}


def estimator(**options):
    return rotorid.create("estimators", "output-error", **options)


def doublet_maneuvers(n=600, dt=0.02, amplitude=5.0):
    t = np.arange(n) * dt
    maneuvers = []
    for i, axis in enumerate(rotorid.CONTROLS):
        for direction in (1, -1):
            u = np.zeros((n, 4))
            u[50:100, i] = amplitude * direction
            u[100:150, i] = -amplitude * direction
            u[200:230, (i + 1) % 4] = 0.6 * amplitude * direction
            maneuvers.append(Maneuver(f"{axis}{direction:+d}", t, u, np.zeros((n, 8))))
    return ManeuverSet(maneuvers)


def with_outputs(structure, values, maneuvers, noise=None, seed=0):
    rng = np.random.default_rng(seed)
    outputs = simulate(structure, values, maneuvers)
    if noise is not None:
        outputs = [y + rng.normal(size=y.shape) * noise for y in outputs]
    return ManeuverSet([m.with_outputs(y) for m, y in zip(maneuvers, outputs)])


def small_structure(delays=("L_lat", "M_long")):
    return ModelStructure(HOVER, [Derivative(n) for n in SMALL_TRUTH]).with_delays(delays)


def test_noise_free_data_are_recovered_to_1e_6():
    structure = small_structure()
    truth = structure.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.07, "tau_M_long": 0.05})
    data = with_outputs(structure, truth, doublet_maneuvers())
    result = estimator().estimate(structure, data)
    assert result.converged, result.stop_reason
    assert np.max(np.abs(result.values - truth) / np.abs(truth)) < 1e-6


def test_bo105_hover_from_zero_start_reaches_noise_floor():
    """All 60 derivatives free from zero plus two delays, 16 closed-loop maneuvers, noise."""
    structure, truth = true_structure()
    data = closed_loop_maneuvers(structure, truth, seed=3)
    outputs = simulate(structure, truth, data)
    residuals = np.concatenate([m.outputs - y for m, y in zip(data, outputs)])
    cost_at_truth = np.linalg.det(residuals.T @ residuals / len(residuals))
    start = structure.with_initial({n: 0.0 for n in structure.parameter_names})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator().estimate(start, data)
    assert result.converged, result.stop_reason
    assert abs(result.cost / cost_at_truth - 1.0) < 0.05
    significant = np.abs(truth) > 3 * result.cramer_rao
    assert significant.sum() >= 30
    within = np.abs(result.values - truth) <= 3 * result.cramer_rao
    missed = [n for n, s, w in zip(structure.parameter_names, significant, within) if s and not w]
    assert not missed


def test_monte_carlo_spread_matches_cramer_rao_bounds():
    structure = ModelStructure(HOVER, [Derivative(n) for n in
                                       ("M_u", "M_q", "M_long", "X_u", "X_long", "L_p", "L_lat")])
    truth = structure.as_vector({n: SMALL_TRUTH[n] for n in structure.parameter_names})
    clean = with_outputs(structure, truth, doublet_maneuvers(n=400))
    noise = np.array([0.2, 0.2, 0.3, 0.1, 0.2, 0.3, 0.1, 0.2])
    fit = estimator(horizons=())
    estimates, bounds = [], []
    for seed in range(60):
        rng = np.random.default_rng(seed)
        noisy = ManeuverSet([m.with_outputs(m.outputs + rng.normal(size=m.outputs.shape) * noise)
                             for m in clean])
        result = fit.estimate(structure, noisy, start=truth)
        estimates.append(result.values)
        bounds.append(result.cramer_rao)
    estimates, bounds = np.array(estimates), np.array(bounds)
    spread = estimates.std(axis=0, ddof=1)
    mean_bound = bounds.mean(axis=0)
    assert np.all(np.abs(spread / mean_bound - 1.0) < 0.25), spread / mean_bound
    coverage = np.mean(np.abs(estimates - truth) <= 2 * bounds)
    assert 0.90 <= coverage <= 0.99


def test_a_fit_that_cannot_move_never_reports_convergence():
    structure = small_structure(delays=())
    quiet = ManeuverSet([Maneuver("quiet", np.arange(200) * 0.02, np.zeros((200, 4)),
                                  np.random.default_rng(0).normal(size=(200, 8)))])
    result = estimator(start="initial", horizons=()).estimate(structure, quiet)
    assert not result.converged
    assert "start values" in result.stop_reason
    assert np.array_equal(result.values, result.start)


def test_a_start_outside_the_bounds_that_cannot_move_never_reports_convergence():
    structure = ModelStructure(HOVER, [Derivative("M_q", sign="negative"), Derivative("M_long")])
    quiet = ManeuverSet([Maneuver("quiet", np.arange(200) * 0.02, np.zeros((200, 4)),
                                  np.random.default_rng(0).normal(size=(200, 8)))])
    result = estimator(start="initial", horizons=(), enforce_signs=True).estimate(
        structure, quiet, start={"M_q": 1.0, "M_long": 0.5})
    assert result.value("M_q") == 0.0          # clipped onto its bound, then never moved
    assert not result.converged
    assert "start values" in result.stop_reason


def test_zero_start_moves_without_equation_error_start():
    structure = small_structure(delays=())
    truth = structure.as_vector(SMALL_TRUTH)
    data = with_outputs(structure, truth, doublet_maneuvers(), noise=0.05)
    result = estimator(start="initial", horizons=(2.0, 5.0)).estimate(structure, data)
    assert not np.array_equal(result.values, result.start)
    assert result.cost_history[-1] < result.cost_history[0]
    assert all(b <= a for a, b in zip(result.cost_history, result.cost_history[1:]))


def test_delays_stay_non_negative_and_signs_can_be_enforced():
    structure = ModelStructure(HOVER, [Derivative("L_p", sign="negative"), Derivative("L_lat"),
                                       Derivative("L_v", sign="positive")]).with_delays(["L_lat"])
    truth = structure.as_vector({"L_p": -8.0, "L_lat": 2.0, "L_v": -0.3, "tau_L_lat": 0.0})
    data = with_outputs(structure, truth, doublet_maneuvers(), noise=0.3, seed=4)
    free = estimator().estimate(structure, data)
    assert free.value("tau_L_lat") >= 0.0
    assert "L_v" in free.sign_violations
    bounded = estimator(enforce_signs=True).estimate(structure, data)
    assert bounded.value("L_v") == 0.0
    assert "L_v" in bounded.at_bound
    assert bounded.value("tau_L_lat") >= 0.0


def test_output_biases_are_estimated():
    structure = small_structure(delays=())
    truth = structure.as_vector(SMALL_TRUTH)
    data = with_outputs(structure, truth, doublet_maneuvers(n=400), noise=0.02)
    shifted = ManeuverSet([m.with_outputs(m.outputs + np.array([0.5, 0, 0, 0, 0, 0, 0, -0.3]))
                           for m in data])
    result = estimator(output_biases=True).estimate(structure, shifted)
    name = shifted.names[0]
    assert result.value(f"bias_{name}_ax") == pytest.approx(0.5, abs=0.02)
    assert result.value(f"bias_{name}_r") == pytest.approx(-0.3, abs=0.02)
    assert np.allclose(result.values[: len(truth)], truth, rtol=0.05, atol=0.02)


def test_excluded_outputs_and_diagonal_noise():
    structure = small_structure(delays=())
    truth = structure.as_vector(SMALL_TRUTH)
    data = with_outputs(structure, truth, doublet_maneuvers(n=400), noise=0.05)
    result = estimator(outputs=("q", "theta", "p", "phi", "r", "ax", "ay", "az"),
                       noise="diagonal").estimate(structure, data)
    assert result.noise_covariance.shape == (8, 8)
    assert np.count_nonzero(result.noise_covariance - np.diag(np.diag(
        result.noise_covariance))) == 0
    without_accels = estimator(outputs=("q", "theta", "p", "phi", "r")).estimate(structure, data)
    assert without_accels.output_names == ("q", "theta", "p", "phi", "r")


class Pendulum:
    """A nonlinear model of one's own: θ'' = −a·sin θ − b·θ' + c·δ, integrated by RK4."""

    parameter_names = ("a", "b", "c")
    output_names = ("theta", "q")

    def initial_values(self):
        return np.array([1.0, 0.1, 1.0])

    def bounds(self):
        return np.full(3, -np.inf), np.full(3, np.inf)

    def simulate(self, values, maneuvers):
        a, b, c = values
        results = []
        for m in maneuvers:
            x, out = np.zeros(2), []
            u = m.inputs[:, 0]
            for k in range(m.n_samples):
                out.append(x.copy())
                f = lambda s: np.array([s[1], -a * np.sin(s[0]) - b * s[1] + c * u[k]])  # noqa
                k1 = f(x)
                k2 = f(x + 0.5 * m.dt * k1)
                k3 = f(x + 0.5 * m.dt * k2)
                k4 = f(x + m.dt * k3)
                x = x + m.dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            results.append(np.array(out))
        return results


def test_a_nonlinear_model_of_ones_own_is_identified_with_finite_differences():
    model = Pendulum()
    truth = np.array([4.0, 0.6, 2.0])
    t = np.arange(500) * 0.02
    u = np.zeros((500, 4))
    u[25:75, 0], u[75:125, 0] = 1.0, -1.0
    blank = ManeuverSet([Maneuver("swing", t, u, np.zeros((500, 8)))])
    y = model.simulate(truth, blank)[0]
    outputs = np.zeros((500, 8))
    outputs[:, [3, 2]] = y + np.random.default_rng(0).normal(size=y.shape) * 0.002
    data = ManeuverSet([blank[0].with_outputs(outputs)])
    result = estimator(horizons=()).estimate(model, data)
    assert result.converged
    assert np.allclose(result.values, truth, rtol=0.02)


def test_estimate_report_json_and_bad_options():
    structure = small_structure(delays=("L_lat",))
    truth = structure.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.05})
    data = with_outputs(structure, truth, doublet_maneuvers(n=300), noise=0.05)
    result = estimator().estimate(structure, data)
    text = result.report()
    for section in ("[[Fit statistics]]", "[[Parameters]]", "[[Correlations]]"):
        assert section in text
    record = json.loads(result.to_json())
    assert record["estimator"] == "output-error"
    assert set(record["delays"]) == {"L_lat"}
    assert record["parameters"]["L_p"]["value"] == pytest.approx(result.value("L_p"))
    assert result.cramer_rao_pct[result.index("L_p")] == pytest.approx(
        100 * result.cramer_rao[result.index("L_p")] / abs(result.value("L_p")))
    with pytest.raises(EstimationError, match="unknown output"):
        estimator(outputs=("nope",)).estimate(structure, data)
    with pytest.raises(EstimationError, match="noise must be one of"):
        estimator(noise="banded")
    with pytest.raises(EstimationError, match="start has shape"):
        estimator().estimate(structure, data, start=np.zeros(2))


def test_diverging_start_values_fall_back_to_the_initial_values():
    structure = small_structure(delays=())
    truth = structure.as_vector(SMALL_TRUTH)
    data = with_outputs(structure, truth, doublet_maneuvers(n=400), noise=0.05)
    unstable = truth.copy()
    unstable[structure.parameter_names.index("L_p")] = 60.0   # roll divergence
    result = estimator().estimate(structure, data, start=unstable)
    assert any("the start values gave no finite cost" in note for note in result.notes)
    assert result.converged
    assert result.value("L_p") == pytest.approx(SMALL_TRUTH["L_p"], rel=0.05)


def test_predicted_cost_change_matches_the_observed_one_near_the_minimum():
    """The convergence test's Gauss-Newton prediction −(2GᵀΔ + ΔᵀFΔ)/N of the relative
    change of det R agrees with the change a simulated step actually gives."""
    from rotorid.estimation.models import LinearModel
    from rotorid.estimation.steps import bounded_step
    from rotorid_output_error.levenberg_marquardt import Problem, Settings, predicted_change

    structure = small_structure()
    truth = structure.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.07, "tau_M_long": 0.05})
    data = with_outputs(structure, truth, doublet_maneuvers(), noise=0.01, seed=2)
    model = LinearModel(structure)
    problem = Problem(model, data, [m.outputs for m in data], np.ones(8), Settings())
    bounds = model.bounds()
    values = truth * (1 + 3e-4 * np.random.default_rng(1).normal(size=truth.size))
    cost, r, residuals, _ = problem.evaluate(values)
    f, g = problem.gauss_newton(values, r, residuals)
    predicted = predicted_change(f, g, values, bounds, problem.n_samples)
    stepped = problem.evaluate(values + bounded_step(f, g, 0.0, values, *bounds))[0]
    observed = (cost - stepped) / cost
    assert 1e-4 < predicted < 1e-1, predicted
    assert abs(predicted / observed - 1) < 0.01


def test_a_converged_fit_reports_the_information_at_its_final_values():
    structure = small_structure()
    truth = structure.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.07, "tau_M_long": 0.05})
    data = with_outputs(structure, truth, doublet_maneuvers(), noise=0.01, seed=2)
    result = estimator().estimate(structure.with_initial(dict(zip(
        structure.parameter_names, truth * 0.8))), data)
    assert result.converged, result.stop_reason
    outputs = simulate(structure, result.values, data)
    residuals = [m.outputs - y for m, y in zip(data, outputs)]
    q = np.linalg.inv(sum(e.T @ e for e in residuals) / sum(len(e) for e in residuals))
    from rotorid.estimation.models import LinearModel

    fresh, _ = LinearModel(structure).gauss_newton(result.values, data, residuals, q)
    assert np.allclose(result.information, fresh, rtol=1e-6)
