"""Model reduction (criteria, loop, selection rules, hooks) and the Study pipeline on files."""

import json

import numpy as np
import pytest
import rotorid
from rotorid import Derivative, FlightCondition, ModelStructure
from rotorid.estimation.reduction import ReductionPath, reduce
from rotorid.plugin.hookspecs import hookimpl
from rotorid.plugin.manager import get_plugin_manager
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import load_data, run_case
from test_output_error import doublet_maneuvers, with_outputs

HOVER = FlightCondition.from_airspeed(0.0)
#: A roll/pitch model whose structure also carries four derivatives that are truly zero.
TRUE = {"M_u": 0.5, "M_q": -3.7, "M_long": 0.9, "L_v": -0.4, "L_p": -8.0, "L_lat": 2.0,
        "X_u": -0.3, "X_long": -0.1}
SPURIOUS = ("M_v", "L_u", "X_lat", "L_long")


def criteria():
    return [rotorid.create("reduction-criteria", "insensitivity"),
            rotorid.create("reduction-criteria", "cramer-rao")]


@pytest.fixture(scope="module")
def data():
    truth_structure = ModelStructure(HOVER, [Derivative(n) for n in TRUE]).with_delays(["L_lat"])
    return with_outputs(truth_structure, truth_structure.as_vector({**TRUE, "tau_L_lat": 0.06}),
                        doublet_maneuvers(n=300), noise=0.05, seed=2)


def full_structure():
    return ModelStructure(HOVER, [Derivative(n) for n in (*TRUE, *SPURIOUS)])


def test_criteria_rank_and_threshold(data):
    estimate = rotorid.create("estimators", "output-error").estimate(full_structure(), data)
    insensitivity = rotorid.create("reduction-criteria", "insensitivity", threshold=10.0)
    worst = insensitivity.rank(estimate)
    assert worst.metric == pytest.approx(np.max(estimate.insensitivity_pct))
    loose = rotorid.create("reduction-criteria", "insensitivity", threshold=1e9)
    assert loose.propose(estimate) is None
    assert loose.rank(estimate).parameter == worst.parameter
    cramer_rao = rotorid.create("reduction-criteria", "cramer-rao")
    assert cramer_rao.rank(estimate).metric == pytest.approx(np.max(estimate.cramer_rao_pct))
    with pytest.raises(rotorid.EstimationError, match="positive percentage"):
        rotorid.create("reduction-criteria", "cramer-rao", threshold=-1)


def test_reduction_removes_the_spurious_derivatives_and_keeps_the_true_ones(data):
    seen = []

    class Observer:
        @hookimpl
        def rotorid_reduction_step(self, case, step):
            seen.append((case, step.index))

    name = rotorid.register_plugin(Observer())
    try:
        path = reduce(full_structure(), data, rotorid.create("estimators", "output-error"),
                      criteria(), continue_to_zero=True, case="test")
    finally:
        get_plugin_manager().unregister(name=name)
    assert seen == [("test", i) for i in range(len(path.steps))]
    assert len(path.steps) == len(TRUE) + len(SPURIOUS) + 1
    assert path.steps[-1].n_parameters == 0
    assert set(path.steps[len(SPURIOUS)].structure.names) == set(TRUE)
    # Removing a truly zero derivative moves the RMSE by noise only: the lowest RMSE (the
    # paper's rule) is among the steps that keep every true derivative, and the most reduced
    # structure within the tolerance is exactly the true one.
    assert path.selected_index <= len(SPURIOUS)
    assert set(ReductionPath(path.steps, rule="parsimonious").removed) == set(SPURIOUS)
    removed_order = [s.removal.parameter for s in path.steps[1:]]
    assert set(removed_order[: len(SPURIOUS)]) == set(SPURIOUS)
    counts, rmse = path.rmse_curve()
    assert counts.tolist() == list(range(len(path.steps)))
    assert rmse[len(SPURIOUS) + 1] > (1 + path.rmse_tolerance) * rmse[len(SPURIOUS)]
    first_rise = ReductionPath(path.steps, rule="first-rise")
    assert first_rise.selected_index == len(SPURIOUS)


def test_reduction_stops_with_the_criteria_and_warm_start_agrees(data):
    estimator = rotorid.create("estimators", "output-error")
    cold = reduce(full_structure(), data, estimator, criteria())
    warm = reduce(full_structure(), data, estimator, criteria(), warm_start=True)
    assert cold.steps[-1].structure.names == warm.steps[-1].structure.names
    assert np.allclose(cold.steps[-1].estimate.values, warm.steps[-1].estimate.values,
                       rtol=1e-4, atol=1e-6)
    assert set(cold.steps[-1].structure.names) == set(TRUE)   # where the criteria stop


def test_reduction_rejects_bad_setups(data):
    estimator = rotorid.create("estimators", "output-error")
    with pytest.raises(rotorid.EstimationError, match="delays are added"):
        reduce(full_structure().with_delays(["L_lat"]), data, estimator, criteria())
    with pytest.raises(rotorid.EstimationError, match="selection rule"):
        reduce(full_structure(), data, estimator, criteria(), rule="best")
    with pytest.raises(rotorid.EstimationError, match="at least one criterion"):
        reduce(full_structure(), data, estimator, [])


def files_case(tmp_path, data) -> FlightCase:
    directory = tmp_path / "flight"
    rotorid.create("data-sources", "files").save(data, directory, format="csv")
    structure = {"populate": "none"}
    derivatives = {n: {} for n in (*TRUE, *SPURIOUS)}
    return FlightCase(name="own", data={"source": "files", "identification": str(directory)},
                      condition={"airspeed_kt": 0.0},
                      structure=structure, derivatives=derivatives,
                      delay_derivatives=("L_lat", "M_long"), continue_to_zero=False,
                      # noise alone orders the RMSE of the structures that keep every true
                      # derivative; the tolerance rule selects the true structure itself
                      rule="parsimonious")


def test_study_on_flight_data_files_writes_results_and_resumes(tmp_path, data):
    case = files_case(tmp_path, data)
    messages = []
    first = run_case(case, tmp_path / "out", progress=lambda c, m: messages.append(m))
    record = json.loads((tmp_path / "out" / "own" / "result.json").read_text())
    assert record["reduction"]["removed"] == list(first.path.removed)
    assert set(record["selected_structure"]) == set(TRUE)
    # The data carry a 0.06 s delay on L_lat and none on M_long: the first is estimated, the
    # second is dropped as undetermined (it sits at its lower bound).
    delays = record["estimates"]["with delays"]["delays"]
    assert set(delays) == {"L_lat"}
    assert delays["L_lat"]["value"] == pytest.approx(0.06, abs=0.01)
    assert record["dropped_delays"] == ["M_long"]
    assert first.time_metrics["with delays"].rmse <= first.time_metrics["no delays"].rmse * 1.01

    again = []
    second = run_case(case, tmp_path / "out", progress=lambda c, m: again.append(m))
    assert any("resuming after" in m for m in again)
    assert first.resumed_steps == 0 and second.resumed_steps == len(first.path.steps)
    assert not any(m.startswith("reduction step") for m in again)
    assert np.array_equal(second.estimates["with delays"].values,
                          first.estimates["with delays"].values)


def test_an_interrupted_study_resumes_from_its_finished_steps(tmp_path, data):
    case = files_case(tmp_path, data)

    def interrupt_at_third_step(case_name, message):
        if message.startswith("reduction step 2"):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_case(case, tmp_path / "out", progress=interrupt_at_third_step)
    resumed = []
    result = run_case(case, tmp_path / "out", progress=lambda c, m: resumed.append(m))
    assert any("resuming after 3 finished" in m for m in resumed)
    assert set(result.path.selected.structure.names) == set(TRUE)


def test_builtin_cases_load_and_quick_variant():
    hover = FlightCase.load("hover")
    assert hover.data["source"] == "helisim" and hover.continue_to_zero
    quick = hover.quick()
    assert quick.is_quick and not quick.continue_to_zero
    assert quick.data["duration_scale"] < 1.0
    assert FlightCase.load("forward").data["airspeed_kt"] == 70.0
    assert hover.with_seed(7).data["seed"] == 7
    files = FlightCase.from_mapping({"name": "own", "data": {"source": "files",
                                                             "identification": "f.csv"}})
    assert files.quick() is files and not files.quick().is_quick      # no [quick] table
    with pytest.raises(rotorid.MissingFileError, match="built-in cases"):
        FlightCase.load("cruise")
    with pytest.raises(rotorid.DataFileError, match="unknown key"):
        FlightCase.from_mapping({"name": "x", "data": {"source": "files"}, "colour": 1})


def test_data_paths_in_a_case_file_are_relative_to_the_file(tmp_path, data, monkeypatch):
    rotorid.create("data-sources", "files").save(data, tmp_path / "cases" / "flight",
                                                 format="csv")
    (tmp_path / "cases" / "own.toml").write_text(
        'name = "own"\n[data]\nsource = "files"\nidentification = "flight"\n'
        '[condition]\nairspeed_kt = 0.0\n')
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    case = FlightCase.load(tmp_path / "cases" / "own.toml")
    assert case.data["identification"] == str(tmp_path / "cases" / "flight")
    data_of_case, condition = load_data(case, tmp_path / "out")
    assert len(data_of_case.identification) == len(data) and data_of_case.verification is None
    assert data_of_case.truth is None and condition == FlightCondition.from_airspeed(0.0)
