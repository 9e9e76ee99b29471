"""A study case run with the filter-error estimator on turbulent data, and the estimators
compared side by side ([compare] estimators): reduction, delays, verification and the report."""

import json
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest
from rotorid import load_result, simulate
from rotorid.errors import DataFileError
from rotorid.report.html import (StudyReport, estimator_fit_rows, estimator_rows,
                                 write_study_report)
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import run_case
from rotorid.study.result import MODELS
from rotorid.verification.metrics import rmse

TINY = Path(__file__).parent / "cases" / "tiny.toml"
COMPARED = ["output-error", "filter-error"]


def tiny_case(**tables) -> FlightCase:
    """The tiny case in light turbulence with ``tables`` added to (or replacing) its own."""
    mapping = tomllib.loads(TINY.read_text())
    mapping["data"]["turbulence"] = "light"
    mapping.update(tables)
    return FlightCase.from_mapping(mapping, "tiny in turbulence", TINY.parent)


@pytest.fixture(scope="module")
def filtered(tmp_path_factory):
    out = tmp_path_factory.mktemp("filter-error")
    case = tiny_case(estimator={"name": "filter-error"}, compare={"estimators": COMPARED})
    result = run_case(case, out, progress=None, report_writer=StudyReport())
    return result, out / case.name


def test_reduction_removes_derivatives_only(filtered):
    result, _ = filtered
    removed = [step.removal.parameter for step in result.path.steps[1:]]
    assert removed and set(removed) <= set(result.path.steps[0].structure.names)
    for step in result.path.steps:
        noise = [n for n in step.estimate.parameter_names if n[:2] in ("F_", "R_")]
        assert step.estimate.estimator == "filter-error"
        assert noise[-len(step.structure.outputs):] == [f"R_{o}" for o in
                                                        step.structure.outputs]


def test_delays_and_verification_use_the_structures_parameters(filtered):
    result, _ = filtered
    delayed = result.estimates["with delays"]
    assert "tau_M_long" in delayed.parameter_names and "F_q" in delayed.parameter_names
    for label in MODELS:
        structure = result.structures[label]
        values = [result.estimates[label].value(n) for n in structure.parameter_names]
        direct = rmse([m.outputs for m in result.identification],
                      simulate(structure, values, result.identification))
        assert result.time_metrics[label].rmse == pytest.approx(direct, rel=1e-12)


def test_the_result_file_gives_the_model_without_the_noise_parameters(filtered):
    """rotorid.load_result (behind verify, simulate and export) reads the filter-error model:
    its derivatives and delays, F and R kept apart as parameters of the estimation."""
    result, directory = filtered
    identified = load_result(directory / "result.json")
    structure = result.structures["with delays"]
    estimate = result.estimates["with delays"]
    assert identified.structure.parameter_names == structure.parameter_names
    assert identified.values == {n: estimate.value(n) for n in structure.parameter_names}
    noise = [n for n in estimate.parameter_names if n not in structure.parameter_names]
    assert noise and all(n[:2] in ("F_", "R_") for n in noise)
    assert identified.noise == {n: estimate.value(n) for n in noise}


def test_estimators_side_by_side_in_result_and_report(filtered):
    result, directory = filtered
    record = json.loads((directory / "result.json").read_text())
    assert record["case"]["compare_estimators"] == COMPARED
    compared = record["estimator_comparison"]
    assert list(compared) == ["filter-error", "output-error"]       # the case's own first
    comparison = result.estimator_comparison
    assert comparison.estimates["filter-error"] is result.estimates["with delays"]
    structure = result.structures["with delays"]
    output_error = comparison.estimates["output-error"]
    assert output_error.parameter_names == structure.parameter_names
    for name, estimate in comparison.estimates.items():
        # det R and RMSE of each fitted model's simulation, recomputed here
        values = [estimate.value(n) for n in structure.parameter_names]
        simulated = simulate(structure, values, result.identification)
        residuals = np.concatenate([m.outputs - y for m, y in zip(result.identification,
                                                                 simulated)])
        det_r = np.linalg.det(residuals.T @ residuals / len(residuals))
        assert compared[name]["simulation"]["det_r"] == pytest.approx(det_r, rel=1e-9)
        assert compared[name]["simulation"]["rmse"] == pytest.approx(
            np.sqrt(np.mean(residuals**2)), rel=1e-12)
    # output error minimises exactly that det R from the same start: it ends lowest
    assert compared["output-error"]["simulation"]["det_r"] <= \
        compared["filter-error"]["simulation"]["det_r"]
    rows = estimator_rows(result)
    assert rows[0][:6] == ["parameter", "unit", "filter-error: value", "filter-error: CR",
                           "output-error: value", "output-error: CR"]
    by_name = {row[0]: row for row in rows[1:]}
    assert by_name["R_q"][1] == "(deg/s)²" and by_name["F_q"][1] == "deg/s"
    assert by_name["R_q"][4:6] == ["", ""]             # output error has no R parameters
    assert [row[0] for row in estimator_fit_rows(result)[1:]] == ["filter-error",
                                                                   "output-error"]
    report = (directory / "report.html").read_text()
    assert '<h2 id="estimators">Estimators side by side</h2>' in report
    for target in re.findall(r'(?:src|href)="([^"]+)"', report):
        if target.startswith("#"):
            assert f'id="{target[1:]}"' in report, target
        else:
            assert (directory / target).is_file(), target
    assert "tables/estimators.csv" in report and "tables/estimator_fits.csv" in report
    # the overview gives filter error's own (innovation) RMSE with its simulation's beside it
    overview = write_study_report({result.name: result}, directory.parent)
    assert f"<td>{result.rmse_text('no delays')}</td>" in overview.read_text()
    assert "(simulated " in result.rmse_text("no delays")


def test_a_case_without_the_comparison_keeps_its_record():
    case = tiny_case()
    assert "compare_estimators" not in case.as_dict()


@pytest.mark.parametrize("estimators, message", [
    (["output-error", "output-error"], "names output-error twice"),
    (["output-error", "kalman"], "'kalman' is not registered"),
    (["output-error"], "names only the case's own estimator"),
    (["output-error", "frequency-response"], r"use \[compare\] frequency = true"),
    ("filter-error", "must be a list"),
])
def test_compared_estimators_are_checked(estimators, message):
    with pytest.raises(DataFileError, match=message):
        tiny_case(compare={"estimators": estimators})
