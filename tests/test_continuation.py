"""Refits that continue an earlier fit (warm-started reduction steps, the delayed fit, delay
profiles) start from its derivatives and from the estimator's own parameters."""

import numpy as np
import pytest
from rotorid.estimation.continuation import continued_start
from rotorid.estimation.profiles import delay_profile
from rotorid.estimation.reduction import ReductionStep, reduce
from rotorid.plugin.contracts import Removal
from rotorid.study.case import FlightCase
from rotorid.study.delays import with_delays
from rotorid_filter_error.estimator import VARIANCE_FLOOR, FilterErrorProblem
from rotorid_filter_error.starts import measurement_noise_start
from rotorid_output_error.levenberg_marquardt import Settings
from test_filter_error import PROCESS, estimator, noisy_data, structure

NOISE = tuple(f"F_{s}" for s in PROCESS)
pytestmark = pytest.mark.filterwarnings("ignore::rotorid.errors.IdentifiabilityWarning")


@pytest.fixture(scope="module")
def fitted():
    """A filter-error fit of the small hover model, with an output bias per record."""
    model, data = structure(), noisy_data(PROCESS)
    fitter = estimator(process_noise=tuple(PROCESS), output_biases=True)
    return model, data, fitter, fitter.estimate(model, data)


class RemoveOnce:
    """A reduction criterion that proposes ``name`` while the estimate has it."""

    def __init__(self, name):
        self.name = name

    def propose(self, estimate):
        if self.name in estimate.parameter_names:
            return Removal(self.name, "test", 1.0, 0.0, "test")
        return None


def test_a_continued_start_carries_the_shared_derivatives_and_the_noise_not_the_records(
        fitted):
    model, _, _, fit = fitted
    reduced = model.without("Y_lat")
    start = continued_start(fit, model, reduced)
    derivatives = set(reduced.parameter_names)
    noise = {n for n in fit.parameter_names if n.startswith(("F_", "R_"))}
    assert set(start) == derivatives | noise
    assert {f"F_{s}" for s in PROCESS} | {f"R_{o}" for o in model.outputs} == noise
    assert all(start[n] == fit[n].value for n in start)
    assert any(n.startswith("bias_") for n in fit.parameter_names)


def test_a_filter_error_refit_from_its_continued_start_stays_at_its_optimum(fitted):
    model, data, fitter, fit = fitted
    refit = fitter.estimate(model, data, start=continued_start(fit, model, model))
    assert refit.cost == pytest.approx(fit.cost, rel=1e-6)
    assert refit.iterations <= 2
    moved = np.abs(refit.values - fit.values)[:model.n_parameters]
    assert np.all(moved < 0.05 * fit.cramer_rao[:model.n_parameters])


def test_the_delayed_fit_without_delays_continues_the_selected_filter_error_fit(fitted,
                                                                                tmp_path):
    model, data, fitter, fit = fitted
    case = FlightCase.from_mapping({"name": "t", "data": {"source": "files"},
                                    "delays": {"derivatives": []}})
    delayed, estimate, dropped = with_delays(case, ReductionStep(0, None, fit, model), data,
                                             fitter, tmp_path)
    assert not delayed.free_delays and dropped == ()
    assert estimate.cost == pytest.approx(fit.cost, rel=1e-6)
    for name in NOISE:
        assert estimate[name].start == fit[name].value


def test_a_warm_started_reduction_step_starts_from_the_previous_noise_model(fitted):
    model, data, fitter, fit = fitted
    path = reduce(model, data, fitter, [RemoveOnce("Y_lat")], warm_start=True,
                  finished=[ReductionStep(0, None, fit, model)])
    step = path.steps[1].estimate
    assert "Y_lat" not in step.parameter_names
    for name in NOISE + ("M_q",):
        assert step[name].start == fit[name].value


def test_a_filter_error_delay_profile_at_the_free_delay_is_the_free_fit():
    model = structure(delays=("M_long",)).with_delays(["M_long"], upper=0.3)
    data = noisy_data(PROCESS)
    fitter = estimator(process_noise=tuple(PROCESS))
    free = fitter.estimate(model, data)
    profile = delay_profile(model, free, data, fitter, "tau_M_long",
                            [free["tau_M_long"].value])
    assert profile.cost[0] == pytest.approx(free.cost, rel=1e-5)


def test_a_measurement_noise_start_far_below_the_sensors_keeps_the_datas_floor(fitted):
    """R's lower bound is 10⁻⁴ of its start, but not below 10⁻⁴ of the first differences'
    variance: a fit continued from one whose R sat at its floor gets no floor 10⁻⁴ lower."""
    model, data, fitter, fit = fitted
    problem = FilterErrorProblem(model, data, tuple(PROCESS), Settings())
    data_floor = VARIANCE_FLOOR * measurement_noise_start(problem.records)
    r = slice(problem.n_global - model.n_outputs, problem.n_global)
    values = fit.values[:problem.n_global].copy()
    values[r] = 1e-4 * fit.values[r]                  # an R at its floor of the earlier fit
    lower, _ = fitter._bounds(problem, values)
    np.testing.assert_allclose(lower[r], np.maximum(VARIANCE_FLOOR * values[r], data_floor))
    assert np.all(lower[r] >= data_floor) and np.any(lower[r] > VARIANCE_FLOOR * values[r])
    values[r] = 10.0 * data_floor / VARIANCE_FLOOR            # a start above the data's
    lower, _ = fitter._bounds(problem, values)
    np.testing.assert_allclose(lower[r], VARIANCE_FLOOR * values[r])
