"""The output-error fit goes through the horizon continuation only where it helps: a zero
start, an unstable start model or a start whose simulation diverges. A stable aeroplane started
at its equation-error values goes straight to the full records and costs no more iterations
than a fit told to skip the horizons; initial values that diverge restart from the
equation-error start.

The aeroplane and its records are those of docs/examples/full_vs_diagonal_noise.py
(uncorrelated noise here)."""

import warnings

import attrs
import numpy as np
import pytest
import rotorid
from rotorid.errors import IdentifiabilityWarning, SimulationDivergedError
from rotorid.estimation.models import LinearModel
from rotorid_output_error.levenberg_marquardt import Problem
from test_docs_full_vs_diagonal_noise import _example

#: The start of output error's note on the horizons it fitted first.
HORIZONS_NOTE = ("horizons 3 s, 6 s first (fitted on each record's first seconds before the "
                 "whole records, so that the simulation stays near the data): ")


def _counting_evaluations(monkeypatch) -> list:
    """Patch the output-error cost evaluation to record the values of every call."""
    calls = []
    evaluate = Problem.evaluate

    def counted(problem, values):
        calls.append(np.array(values))
        return evaluate(problem, values)

    monkeypatch.setattr(Problem, "evaluate", counted)
    return calls


def test_a_stable_well_started_fit_skips_the_horizons_and_costs_no_iterations(monkeypatch):
    example = _example()
    structure = example.aeroplane()
    truth = structure.as_vector(example.TRUTH)
    assert LinearModel(structure).growth_rate(truth) < 0.0
    data = example.flight_records(structure, seed=4)
    calls = _counting_evaluations(monkeypatch)
    default = rotorid.create("estimators", "output-error").estimate(structure, data)
    default_calls, calls[:] = list(calls), []
    plain = rotorid.create("estimators", "output-error", horizons=()).estimate(structure, data)
    assert default.notes == ("start values from equation error",)
    assert default.converged and plain.converged
    assert default.iterations <= plain.iterations
    # deciding to skip the horizons simulates the start once, and the fit reuses it
    assert len(default_calls) == len(calls)
    assert sum(np.array_equal(v, default_calls[0]) for v in default_calls) == 1
    np.testing.assert_array_equal(default.values, plain.values)
    within = np.abs(default.values - truth) <= 4 * default.cramer_rao
    assert within.all(), dict(zip(structure.parameter_names, within))


def test_zero_and_unstable_starts_go_through_the_horizons():
    example = _example()
    structure = example.aeroplane()
    data = example.flight_records(structure, seed=4)
    fit = rotorid.create("estimators", "output-error", start="initial")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        zero = fit.estimate(structure, data)
    assert zero.notes[0] == HORIZONS_NOTE + "zero start"
    unstable = structure.as_vector(example.TRUTH)
    unstable[structure.parameter_names.index("M_w")] = 0.2      # statically unstable
    started = fit.estimate(structure, data, start=unstable)
    assert started.notes[0] == (HORIZONS_NOTE + "the start model is unstable "
                                "(growth rate 0.961 1/s)")
    assert started.converged
    well_started = rotorid.create("estimators", "output-error").estimate(structure, data)
    # the same minimum, to a small fraction of the Cramér-Rao bounds
    assert np.all(np.abs(started.values - well_started.values)
                  <= 0.01 * well_started.cramer_rao)


def test_a_continuation_ending_above_its_start_gives_way_to_the_full_fit_from_it(monkeypatch):
    """Constructed: the horizon stages end where the full records fit worse than the start
    (the true model with its control derivatives times −3) and the full-record stage cannot
    leave that point, as happened to a reduced hybrid model at 70 kt (0 iterations on the full
    records, RMSE 5.75 against 0.23 fitted from its start). The fit is then the full records'
    fit straight from the start values, as without horizons."""
    example = _example()
    structure = example.aeroplane()
    data = example.flight_records(structure, seed=4)
    astray = structure.as_vector(example.TRUTH)
    controls = [structure.is_control(d) for d in structure.free_derivatives]
    astray[controls] *= -3.0
    estimator = rotorid.create("estimators", "output-error", start="initial")
    fit = type(estimator)._run

    def led_astray(self, model, maneuvers, columns, weights, start, settings, stage,
                   final_information=True, start_evaluation=None):
        if stage != "full" or np.array_equal(start, astray):
            start, settings = astray, attrs.evolve(settings, max_iterations=0)
            start_evaluation = None
        return fit(self, model, maneuvers, columns, weights, start, settings, stage,
                   final_information, start_evaluation)

    direct = rotorid.create("estimators", "output-error", start="initial", horizons=())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        expected = direct.estimate(structure, data)
        monkeypatch.setattr(type(estimator), "_run", led_astray)
        estimate = estimator.estimate(structure, data)
    assert estimate.notes[0] == HORIZONS_NOTE + "zero start"
    assert ("the horizons ended above the start values' cost on the full records; refitted "
            "the full records from the start values") in estimate.notes
    np.testing.assert_array_equal(estimate.values, expected.values)


def test_initial_values_that_diverge_restart_from_the_equation_error_start():
    example = _example()
    structure = example.aeroplane()
    data = example.flight_records(structure, seed=4)
    diverging = dict(example.TRUTH, M_w=40.0)                 # doubles in a few ms
    started = structure.with_initial(diverging)
    estimate = rotorid.create("estimators", "output-error").estimate(started, data)
    assert estimate.notes == (
        HORIZONS_NOTE + "the start model is unstable (growth rate 42.5 1/s)",
        "the start values gave no finite cost; restarted from the equation-error start")
    assert estimate.converged
    well_started = rotorid.create("estimators", "output-error").estimate(structure, data)
    assert np.all(np.abs(estimate.values - well_started.values)
                  <= 0.01 * well_started.cramer_rao)
    plain = rotorid.create("estimators", "output-error", start="initial")
    with pytest.raises(SimulationDivergedError, match="the start values give no finite cost"):
        plain.estimate(started, data)
