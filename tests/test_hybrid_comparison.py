"""``[compare] hybrid``: the hybrid model beside the case's two, on data simulated with the
70 kt hybrid reference (tests/test_hybrid_model.py), and its report tables."""

import types
import warnings

import numpy as np
import pytest
import rotorid
from hybrid_reference import NOISE, hybrid_reference, open_loop_maneuvers, six_dof_of
from rotorid import Maneuver, ManeuverSet
from rotorid.errors import DataFileError, IdentifiabilityWarning
from rotorid.model.hybrid import REQUIRED, hybrid_from_six_dof
from rotorid.report.figures import hybrid_figures
from rotorid.report.html import (
    hybrid_derivative_rows,
    hybrid_html,
    hybrid_model_rows,
    hybrid_muad_rows,
    hybrid_term_rows,
)
from rotorid.simulation.simulator import simulate
from rotorid.study.case import FlightCase
from rotorid.study.hybrid_comparison import FLAP_SHAPED, HYBRID_MODELS, compare_hybrid
from rotorid.model.residualisation import derivatives_of, residualise
from rotorid.verification.simulation_fit import simulation_fit
from rotorid.verification.band import DEFAULT_BAND
from rotorid.verification.verify import verify_model

PAIRS = ("q/long", "p/lat")


def _sweeps(structure, values, seed) -> ManeuverSet:
    """One log sweep 0.5–20 rad/s per cyclic axis (1 % of travel, 40 s at 50 Hz), outputs with
    a fifth of the identification data's white noise."""
    time = np.arange(2001) * 0.02
    phase = 0.5 * 40.0 / np.log(40.0) * (np.exp(np.log(40.0) * time / 40.0) - 1.0)
    sweeps = []
    for axis in (0, 1):
        inputs = np.zeros((time.size, 4))
        inputs[:, axis] = np.sin(phase)
        sweeps.append(Maneuver(f"sweep_{structure.controls[axis]}", time, inputs,
                               np.zeros((time.size, 8))))
    clean = ManeuverSet(sweeps)
    rng = np.random.default_rng(seed)
    return ManeuverSet([m.with_outputs(y + rng.normal(size=y.shape) * NOISE / 5)
                        for m, y in zip(clean, simulate(structure, values, clean))])


@pytest.fixture(scope="module")
def inputs(truth_model, trim_70kt):
    """The arguments of :func:`compare_hybrid` on data of the 70 kt hybrid reference."""
    condition, a, b = hybrid_reference(truth_model, trim_70kt)
    six_dof, six_values = six_dof_of(condition, a, b)
    truth = hybrid_from_six_dof(six_dof, six_values)
    reference = derivatives_of(truth, a, b)
    values = truth.as_vector({**{n: reference[n] for n in truth.parameter_names
                                 if n in reference},
                              **{n: 0.03 for n in truth.parameter_names
                                 if n.startswith("tau_")}})
    ident = open_loop_maneuvers(truth, values, seed=4)
    estimator = rotorid.create("estimators", "output-error")
    delayed = six_dof.with_delays()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        plain = estimator.estimate(six_dof, ident)
        with_delays = estimator.estimate(delayed, ident, start=plain.as_mapping())
    structures = {"no delays": six_dof, "with delays": delayed}
    estimates = {"no delays": plain, "with delays": with_delays}
    simulations = {label: simulation_fit(structures[label], estimates[label].values, ident)
                   for label in structures}
    sweeps = _sweeps(truth, values, seed=5)
    verification = {label: verify_model(structures[label], estimates[label].values, sweeps,
                                        PAIRS) for label in structures}

    def reference(structure):
        """The truth's derivatives of ``structure``: the hybrid's own, or a six-dof
        structure's, those of the simulated hybrid with its flap tilts residualised."""
        if structure.states == truth.states:
            return derivatives_of(structure, a, b)
        simulated_a, simulated_b, _, _ = truth.matrices(values)
        return derivatives_of(structure, *residualise(simulated_a, simulated_b, truth.states,
                                                      structure.states))

    return dict(structures=structures, estimates=estimates, simulations=simulations,
                verification=verification, sweeps=sweeps, estimator=estimator,
                reference=reference)


@pytest.fixture(scope="module")
def comparison(inputs):
    return compare_hybrid(**inputs)


def test_the_case_models_responses_are_checked_again_in_the_comparisons_band(inputs,
                                                                              comparison):
    """J of the case's two models over the hybrid band, from their verification's responses,
    is J of a verification made in that band."""
    for label, structure in inputs["structures"].items():
        fresh = verify_model(structure, inputs["estimates"][label].values, inputs["sweeps"],
                             PAIRS, ["mismatch-cost"], band=comparison.band)
        assert comparison.costs[label] == {p.pair: p.checks["mismatch-cost"].cost
                                           for p in fresh.pairs}
        assert all(p.band == comparison.band for p in comparison.verification[label].pairs)


def test_the_hybrid_model_of_hybrid_data_beats_both_six_dof_models(comparison):
    simulation, costs = comparison.simulation, comparison.costs
    assert set(simulation) == set(costs) == set(HYBRID_MODELS)
    assert simulation["hybrid"].det_r < simulation["with delays"].det_r
    assert simulation["with delays"].det_r < simulation["no delays"].det_r
    for pair in PAIRS:
        assert costs["hybrid"][pair] < costs["with delays"][pair]
    for name, (tau, bound) in comparison.flap_time_constants().items():
        truth = -1.0 / comparison.reference[name]
        assert abs(tau - truth) < 3.0 * bound
    assert comparison.parameters["hybrid"] == comparison.structure.n_parameters


def test_the_hybrids_quasi_steady_derivatives_recover_the_residualised_truth(inputs,
                                                                            comparison):
    """The hybrid fitted to its own model's data: its flap tilts residualised, the roll and
    pitch derivatives are the truth's residualised ones within 3 propagated bounds, and the
    six-dof models' entries are their own estimates."""
    truth = comparison.six_dof_reference
    for name in FLAP_SHAPED:
        value, bound = comparison.flap_shaped_derivatives["hybrid"][name]
        assert 0.0 < bound < np.inf
        assert abs(value - truth[name]) < 3.0 * bound, name
    for label in ("no delays", "with delays"):
        estimate = inputs["estimates"][label]
        assert comparison.flap_shaped_derivatives[label]["M_q"] == (
            estimate.value("M_q"), estimate["M_q"].cramer_rao)


def _result(comparison):
    """What the report reads of a case result: the comparison, and the case's band."""
    return types.SimpleNamespace(hybrid_comparison=comparison,
                                 case=types.SimpleNamespace(band=DEFAULT_BAND))


def test_report_tables_of_the_three_models(comparison):
    result = _result(comparison)
    models = hybrid_model_rows(result)
    assert [row[0] for row in models[1:]] == list(HYBRID_MODELS)
    assert models[0][4:6] == ["J q/long [-]", "J p/lat [-]"]
    muad = hybrid_muad_rows(result)
    assert muad[0] == ["model", "MUAD q/long [inside/counted]", "MUAD p/lat [inside/counted]"]
    inside, counted = map(int, muad[3][1].split("/"))
    assert 0 < counted and inside == comparison.muad["hybrid"]["q/long"][0]
    derivatives = {row[0]: row for row in hybrid_derivative_rows(result)[1:]}
    assert list(derivatives) == list(FLAP_SHAPED)
    assert derivatives["L_p"][1] == "1/s" and float(derivatives["L_p"][-1]) == pytest.approx(
        1.0, abs=0.1)
    terms = {row[0]: row for row in hybrid_term_rows(result)[1:]}
    assert terms["M_beta1c"][1] == "1/s²"
    assert float(terms["τ_f = −1/Bc_beta1c"][5]) == pytest.approx(1.0, abs=0.05)
    assert "tau_Bs_lat" in terms
    assert 'id="hybrid"' in hybrid_html(result)


def test_report_figures_of_the_three_models(comparison, tmp_path):
    result = _result(comparison)
    figures = hybrid_figures(result, tmp_path, "70 kt", comparison.structure.signals)
    assert [f.file for f in figures] == ["hybrid_error_q_long.png", "hybrid_error_p_lat.png"]
    assert all((tmp_path / f.file).stat().st_size > 0 for f in figures)
    assert "hybrid_error_q_long.png" in hybrid_html(result, figures)
    assert hybrid_html(types.SimpleNamespace(hybrid_comparison=None)) == ""


def test_case_option():
    mapping = {"name": "h", "data": {"source": "helisim", "condition": "hover"}}
    plain = FlightCase.from_mapping(mapping)
    assert not plain.compare_hybrid and "compare_hybrid" not in plain.as_dict()
    hybrid = FlightCase.from_mapping({**mapping, "compare": {"hybrid": True,
                                                             "hybrid_band_max": 14.0}})
    assert hybrid.compare_hybrid and hybrid.as_dict()["compare_hybrid"] is True
    assert hybrid.as_dict()["compare_hybrid_band_max"] == 14.0
    assert "compare_hybrid_reduction" not in hybrid.as_dict()
    reduced = FlightCase.from_mapping({**mapping, "compare": {"hybrid": True,
                                                              "hybrid_reduction": True}})
    assert reduced.as_dict()["compare_hybrid_reduction"] is True
    for extra in ({"hybrid_band_max": 14.0}, {"hybrid_reduction": True}):
        with pytest.raises(DataFileError, match="hybrid comparison only"):
            FlightCase.from_mapping({**mapping, "compare": extra})
    with pytest.raises(DataFileError, match="top frequency"):
        FlightCase.from_mapping({**mapping, "compare": {"hybrid": True, "hybrid_band_max": 0.5}})


def test_the_hybrid_reduced_before_its_fit(inputs, comparison):
    """A reduction before the fit (insensitivity above 100 %: X_long, 0.011 in the truth,
    goes) takes its terms out of the hybrid and the report says which; the flap damping and
    hub moments stay."""
    criteria = [rotorid.create("reduction-criteria", "insensitivity", threshold=100.0)]
    reduced = compare_hybrid(**inputs, criteria=criteria)
    assert comparison.removed is None and comparison.summary()["removed"] is None
    assert reduced.removed and reduced.summary()["removed"] == list(reduced.removed)
    assert set(reduced.structure.names) == set(comparison.structure.names) - set(reduced.removed)
    assert set(REQUIRED) <= set(reduced.structure.names)
    assert reduced.removed[-1] in hybrid_html(_result(reduced))
