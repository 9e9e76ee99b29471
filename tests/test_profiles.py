"""Delay profiles on a constructed roll/pitch problem with a known 0.06 s delay."""

import numpy as np
import pytest
import rotorid
from rotorid import Derivative, FlightCondition, ModelStructure
from rotorid.estimation.profiles import delay_profile, fixing_delay
from test_output_error import doublet_maneuvers, with_outputs

HOVER = FlightCondition.from_airspeed(0.0)
TRUE = {"M_u": 0.5, "M_q": -3.7, "M_long": 0.9, "L_v": -0.4, "L_p": -8.0, "L_lat": 2.0}
TAU = 0.06


@pytest.fixture(scope="module")
def fitted():
    structure = ModelStructure(HOVER, [Derivative(n) for n in TRUE]).with_delays(["L_lat"])
    data = with_outputs(structure, structure.as_vector({**TRUE, "tau_L_lat": TAU}),
                        doublet_maneuvers(n=300), noise=0.02, seed=3)
    estimator = rotorid.create("estimators", "output-error")
    free = structure.with_delays(["L_lat"], upper=0.3)
    return free, estimator.estimate(free, data, start=TRUE), data, estimator


def test_the_profile_has_its_minimum_at_the_true_delay_and_meets_the_free_fit(fitted):
    structure, estimate, data, estimator = fitted
    grid = [0.0, 0.03, TAU, 0.09, 0.12]
    profile = delay_profile(structure, estimate, data, estimator, "tau_L_lat", grid)
    assert profile.grid.tolist() == grid and profile.converged.all()
    assert int(np.argmin(profile.cost)) == grid.index(TAU)
    assert profile.free_value == pytest.approx(TAU, abs=0.005)
    # Fixing the delay can only cost: no grid point beats the free fit.
    assert np.all(profile.cost >= profile.free_cost * (1 - 1e-9))
    assert np.all(profile.relative_rmse > -1e-6)
    # At the free fit's own delay the profile is the free fit.
    at_free = delay_profile(structure, estimate, data, estimator, "tau_L_lat",
                            [profile.free_value])
    assert at_free.cost[0] == pytest.approx(estimate.cost, rel=1e-5)
    record = profile.as_dict()
    assert record["grid_s"] == grid and record["free_rmse"] == pytest.approx(estimate.rmse)


def test_only_a_delay_of_the_structure_can_be_fixed(fitted):
    structure = fitted[0]
    fixed = fixing_delay(structure, "tau_L_lat", 0.1)
    assert "tau_L_lat" not in fixed.parameter_names
    assert fixed.derivative("L_lat").delay.initial == 0.1
    with pytest.raises(rotorid.EstimationError, match="tau_M_q is not a delay.*tau_L_lat"):
        fixing_delay(structure, "tau_M_q", 0.1)


def test_the_profile_figure_draws_one_line_and_one_marker_per_delay(fitted):
    from rotorid.report.plots.profiles import plot_delay_profiles

    structure, estimate, data, estimator = fitted
    profile = delay_profile(structure, estimate, data, estimator, "tau_L_lat", [0.0, 0.06, 0.12])
    figure = plot_delay_profiles([profile], title="test")
    axis = figure.axes[0]
    line, marker = axis.get_lines()
    assert line.get_xdata().tolist() == [0.0, 0.06, 0.12]
    assert line.get_ydata() == pytest.approx(100 * profile.relative_rmse)
    assert marker.get_xdata().tolist() == [profile.free_value]
    assert "[s]" in axis.get_xlabel() and "[%]" in axis.get_ylabel()
    assert axis.get_yscale() == "symlog"          # shallow and steep profiles both read
    legend = axis.get_legend()
    assert legend.get_bbox_to_anchor().x0 > axis.get_window_extent().x1 - 1   # outside the axes


def test_a_refit_that_did_not_converge_is_a_cross_off_the_line():
    from rotorid.estimation.profiles import DelayProfile
    from rotorid.report.plots.profiles import plot_delay_profiles

    profile = DelayProfile("tau_L_p", [0.0, 0.1, 0.2], [2.0, 1.0, 9.0], [1.02, 1.0, 1.7],
                           [True, True, False], 0.1, 1.0, 1.0)
    axis = plot_delay_profiles([profile]).axes[0]
    line, star, cross, proxy = axis.get_lines()
    assert np.isnan(line.get_ydata()[2]) and line.get_ydata()[:2] == pytest.approx([2.0, 0.0])
    assert cross.get_marker() == "x" and cross.get_xdata().tolist() == [0.2]
    assert cross.get_ydata() == pytest.approx([70.0])
    assert "did not converge" in proxy.get_label()


def test_the_progress_line_says_whether_a_grid_point_beats_the_free_fit():
    from rotorid.estimation.profiles import DelayProfile
    from rotorid.study.pipeline import _profile_line

    def profile(cost):
        return DelayProfile("tau_L_p", [0.0, 0.15, 0.3], cost, [1.02, 1.01, 1.05],
                            [True] * 3, 0.09, 1.0, 1.0)

    deeper = _profile_line(profile([1.05, 0.98, 1.2]))
    assert "fixed at 0.150 s its det R is 2.0% below the free fit's" in deeper
    assert "local optimum" in deeper and "fixed at 0 s the RMSE is +2.00%" in deeper
    assert "no grid point fits better" in _profile_line(profile([1.05, 1.01, 1.2]))
