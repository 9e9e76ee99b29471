"""Filter error's state estimates x̂(n|n) against the true states of a simulation whose noise
model is the filter's own: their errors have the spread the filter states."""

import types

import numpy as np
import pytest
import rotorid
from rotorid.errors import EstimationError
from rotorid.estimation.state_estimates import StateEstimates
from rotorid.report.plots.states import drawing_order, plot_state_estimates, recorded_states
from rotorid_filter_error.estimator import FilterErrorProblem
from rotorid_output_error.levenberg_marquardt import Settings
from test_filter_error import PROCESS, SMALL_TRUTH, VARIANCE, noisy_outputs, structure

#: A pitch disturbance (σ deg/s², τ s) and a lateral gust (σ ft/s, τ s) besides PROCESS.
DISTURBANCE = {"q": (2.0, 0.8)}
GUST = {"v": (4.0, 1.0)}
#: Samples left out at each record's start, where the filter's error has not yet the
#: stationary spread its steady-state covariance states (the filter starts at the known trim).
SETTLING = 500


@pytest.fixture(scope="module")
def flight():
    """One 300 s record of the small hover model (random steps on every control) with white
    process noise, the disturbance and the gust; the record and its true states (N, 8 + 2)."""
    model = structure()
    dt, n = 0.02, 15000
    rng = np.random.default_rng(5)
    inputs = np.repeat(rng.normal(size=(n // 50, 4)), 50, axis=0)
    trace = []
    outputs, = noisy_outputs(model, SMALL_TRUTH, [inputs], dt, PROCESS, VARIANCE, rng,
                             DISTURBANCE, GUST, trace=trace)
    data = rotorid.ManeuverSet([rotorid.Maneuver(
        "steps", np.arange(n) * dt, inputs, outputs, input_names=model.controls,
        output_names=model.outputs)])
    truth_names = list(model.states) + [f"g_{s}" for s in GUST] + [f"d_{s}" for s in DISTURBANCE]
    return model, data, dict(zip(truth_names, trace[0].T))


def _true_values(model):
    """The filter-error parameter vector of the simulation's own model and noise."""
    return np.concatenate([model.as_vector(SMALL_TRUTH), list(PROCESS.values()),
                           [DISTURBANCE["q"][0], GUST["v"][0], DISTURBANCE["q"][1],
                            GUST["v"][1]], VARIANCE])


def _problem(model, data, every=1):
    return FilterErrorProblem(model, data, tuple(PROCESS), Settings(10, 1e-7, 1e-9),
                              tuple(DISTURBANCE), tuple(GUST), update_every=every)


@pytest.mark.parametrize("every", [1, 2])
def test_filtered_states_err_by_the_spread_the_filter_states(flight, every):
    """At the true parameters, each estimated state's error against the simulation's state
    (a matrix exponential with its own noise draws, not the filter's recursion) has the
    standard deviation of the filter's steady-state covariance P − K B Kᵀ within 10 %, the
    gust and the disturbance included; u, whose error mode settles over tens of seconds, is
    left out. The measured rates are estimated better than their sensors read them, and the
    gust, which no output measures, correlates with the true one as the orthogonality of a
    Kalman estimate and its error says."""
    model, data, truth = flight
    estimates = _problem(model, data, every).state_estimates(_true_values(model))
    assert estimates.names == (*model.states, "d_q", "g_v")
    assert estimates.units[-2:] == ("deg/s²", "ft/s")
    assert estimates.time[0] == pytest.approx(data[0].time[::every])
    assert estimates.method == ("Kalman filter x̂(n|n), steady-state gain"
                                + (", updated at every 2nd sample" if every == 2 else ""))
    settle = SETTLING // every
    for name, sigma in zip(estimates.names, estimates.standard_deviation):
        if name == "u":
            continue
        error = estimates.of(name)[settle:] - truth[name][::every][settle:]
        assert np.std(error) == pytest.approx(sigma, rel=0.1), name
    sensors = dict(zip(model.outputs, np.sqrt(VARIANCE)))
    for rate in ("q", "p", "r"):
        assert estimates.standard_deviation[estimates.names.index(rate)] < sensors[rate]
    # the estimate is orthogonal to its error, so it correlates with the truth as
    # sqrt(1 − σ_e²/σ_g²): here about 0.87
    gust, true_gust = estimates.of("g_v")[settle:], truth["g_v"][::every][settle:]
    sigma = estimates.standard_deviation[estimates.names.index("g_v")]
    assert np.corrcoef(gust, true_gust)[0, 1] == pytest.approx(
        np.sqrt(1.0 - sigma**2 / np.var(true_gust)), abs=0.03)


def test_state_estimates_from_the_estimator_need_its_own_fit(flight):
    """The estimator's state_estimates gives the problem's at the estimate's values, and
    refuses an estimate of other parameters (another noise model, another estimator), of
    other records, or something that is no estimate, naming the difference and the fix."""
    model, data, _ = flight
    head = rotorid.ManeuverSet([data[0].head(20.0)])
    options = {"process_noise": tuple(PROCESS), "disturbances": tuple(DISTURBANCE),
               "gusts": tuple(GUST), "max_iterations": 3}
    estimator = rotorid.create("estimators", "filter-error", **options)
    estimate = estimator.estimate(model, head, start=dict(zip(
        _problem(model, head).parameter_names, _true_values(model))))
    estimates = estimator.state_estimates(model, head, estimate)
    direct = _problem(model, head).state_estimates(estimate.values)
    np.testing.assert_allclose(estimates.values[0], direct.values[0])
    other = rotorid.create("estimators", "filter-error", process_noise=tuple(PROCESS))
    with pytest.raises(EstimationError, match=r"the estimate has D_q, G_v, T_q, Tg_v besides:"
                                              r" .*same noise model"):
        other.state_estimates(model, head, estimate)
    with pytest.raises(EstimationError, match=r"the estimate lacks F_w, .*same noise model"):
        estimator.state_estimates(model, head, rotorid.create(
            "estimators", "output-error", max_iterations=2).estimate(model, head))
    longer = rotorid.ManeuverSet([data[0].head(30.0)])
    with pytest.raises(EstimationError, match=r"fitted to 1001 innovations, these maneuvers "
                                              r"give 1501: give the records as fitted"):
        estimator.state_estimates(model, longer, estimate)
    with pytest.raises(EstimationError, match="need the Estimate of a filter-error fit, got "
                                              "dict"):
        estimator.state_estimates(model, head, {"parameters": {}})


def test_state_estimates_as_maneuver_files_and_their_figure(flight):
    """As maneuver files: the record's inputs at the estimated instants, the estimates as
    channels, the units and error spreads in the header; the figure draws the noise model's
    states first, one panel per state with its ±2σ band, and a known history behind (a true
    gust so labelled; a measured output less its estimated bias)."""
    model, data, truth = flight
    estimates = _problem(model, data, 2).state_estimates(_true_values(model))
    written = estimates.as_maneuvers(data)[0]
    assert written.n_samples == estimates.time[0].size
    np.testing.assert_array_equal(written.inputs, data[0].inputs[::2])
    np.testing.assert_array_equal(written.channel("g_v"), estimates.of("g_v"))
    assert written.metadata["state_units"]["d_q"] == "deg/s²"
    assert drawing_order(estimates.names)[:2] == [8, 9]
    figure = plot_state_estimates(estimates, "steps",
                                  known={"g_v": (data[0].time, truth["g_v"])})
    panels = [axis for axis in figure.axes if axis.get_visible()]
    assert len(panels) == len(estimates.names)
    assert panels[0].get_ylabel() == "disturbance q [deg/s²]"
    assert panels[1].get_ylabel() == "gust v [ft/s]"
    assert [line.get_label() for line in panels[1].lines] == ["true (recorded)", "estimate"]
    biased = types.SimpleNamespace(parameter_names=("bias_steps_q", "bias_other_q"),
                                   values=np.array([2.0, 5.0]))
    behind = recorded_states(data[0], estimates.names, biased)
    assert set(behind) == {"q", "theta", "p", "phi", "r"}     # the outputs named like states
    np.testing.assert_array_equal(behind["q"][1], data[0].channel("q") - 2.0)
    np.testing.assert_array_equal(behind["p"][1], data[0].channel("p"))
    with pytest.raises(EstimationError, match="no such maneuver"):
        estimates.as_maneuvers(rotorid.ManeuverSet([data[0].with_outputs(
            data[0].outputs, name="other")]))


def test_state_estimate_files_of_low_passed_records_say_so(flight, tmp_path):
    """Estimates along records low-passed for the filter (rotorid.resampling.low_passed)
    carry the filtering in their files' header."""
    from rotorid.resampling import low_passed
    from rotorid_files.formats import read_maneuver

    model, data, _ = flight
    estimates = _problem(model, data, 2).state_estimates(_true_values(model))
    rotorid.create("data-sources", "files").save(
        estimates.as_maneuvers(low_passed(data, 5.0)), tmp_path)
    written = read_maneuver(tmp_path / "steps.csv")
    assert written.metadata["low_passed"] == "zero-phase low-pass at 5 Hz"
    assert written.metadata["content"] == "state estimates"


def test_state_estimates_check_their_shapes():
    with pytest.raises(EstimationError, match=r"values of shape \(3, 1\), expected \(4, 1\)"):
        StateEstimates(["w"], ["ft/s"], ["m"], [np.arange(4.0)], [np.zeros((3, 1))], [0.1])
    with pytest.raises(EstimationError, match="1 names need as many units"):
        StateEstimates(["w"], [], ["m"], [np.arange(4.0)], [np.zeros((4, 1))], [0.1])


def test_a_study_asks_the_estimator_for_state_estimates_only_where_it_gives_them(flight):
    """The study's step: none from an estimator without the method; a progress line naming
    the states from one with it; a progress line with the reason, and none, where it cannot;
    a PluginError naming the call where it returns something else."""
    from rotorid.errors import PluginError
    from rotorid.study.case import FlightCase
    from rotorid.study.pipeline import _state_estimates

    model, data, _ = flight
    case = FlightCase.from_mapping({"name": "own", "estimator": {"name": "filter-error"},
                                    "data": {"source": "files", "identification": "f/*.csv"}})
    given = _problem(model, data).state_estimates(_true_values(model))

    class Giving:
        def state_estimates(self, structure, maneuvers, estimate):
            return given

    class Failing:
        def state_estimates(self, structure, maneuvers, estimate):
            raise EstimationError("not for this model")

    class Wrong:
        def state_estimates(self, structure, maneuvers, estimate):
            return {}

    heard = []

    def report(name, message):
        heard.append(message)

    assert _state_estimates(case, object(), model, data, None, report) is None
    assert _state_estimates(case, Giving(), model, data, None, report) is given
    assert _state_estimates(case, Failing(), model, data, None, report) is None
    assert heard == ["state estimates of u, w, q, theta, v, p, phi, r, d_q, g_v along 1 "
                     "maneuver", "no state estimates: not for this model"]
    with pytest.raises(PluginError, match="state_estimates"):
        _state_estimates(case, Wrong(), model, data, None, report)
