"""A case's ``[actuators]``: every record's inputs through the actuators' known lag before the
study's fits and verification, checked when the case is read, recorded only when set."""

import json

import attrs
import numpy as np
import pytest
from rotorid.actuators import lagged_inputs
from rotorid.errors import DataFileError
from rotorid.estimation.result_file import load_result
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import run_case
from test_reduction_study import data, files_case  # noqa: F401  (data: fixture)

CASE = {"name": "actuated", "data": {"source": "helisim", "condition": "hover"}}


def test_the_setting_is_read_applied_and_recorded_only_when_set(data):  # noqa: F811
    case = FlightCase.from_mapping({**CASE, "actuators": {"lag_s": 0.03,
                                                          "inputs": ["long", "lat"]}})
    assert (case.actuator_lag_s, case.actuator_inputs) == (0.03, ("long", "lat"))
    assert case.as_dict()["actuator_lag_s"] == 0.03
    expected = lagged_inputs(data, 0.03, ("long", "lat"))
    for records in (case.actuated(data), case.identification_records(data)):
        np.testing.assert_array_equal(records[0].inputs, expected[0].inputs)
    assert case.actuated(None) is None
    plain = FlightCase.from_mapping(CASE)
    assert not {"actuator_lag_s", "actuator_inputs"} & set(plain.as_dict())
    assert plain.actuated(data) is data


@pytest.mark.parametrize("table, message", [
    ({"lag_s": 0.0}, r"\[actuators\] lag_s must be the actuators' first-order time constant "
                     r"in s \(> 0\), got 0.0"),
    ({"inputs": ["lat"]}, r"\[actuators\] inputs needs lag_s"),
    ({"lag_s": 0.03, "inputs": ["aileron"]}, r"\[actuators\] inputs names aileron, not an "
                                             r"input of the structure \(long, lat, coll, ped\)"),
    ({"lag": 0.03}, r"\[actuators\] unknown key\(s\) \['lag'\]"),
])
def test_bad_settings_are_refused_when_the_case_is_read(table, message):
    with pytest.raises(DataFileError, match=message):
        FlightCase.from_mapping({**CASE, "actuators": table}, "case.toml")


def test_the_study_fits_the_actuated_records(tmp_path, data):  # noqa: F811
    """The files' records carry a 0.06 s delay on L_lat; with a 0.02 s lag on the lateral
    stick given as known, the fitted delay is what is left of it (a first-order lag acts as
    its time constant of delay at low frequency)."""
    case = attrs.evolve(files_case(tmp_path, data), actuator_lag_s=0.02,
                        actuator_inputs=("lat",))
    messages = []
    result = run_case(case, tmp_path / "out", progress=lambda c, m: messages.append(m))
    assert "lat through the actuators' 0.02 s first-order lag" in messages
    expected = {m.name: m.inputs for m in lagged_inputs(data, 0.02, ("lat",))}
    for maneuver in result.identification:
        np.testing.assert_allclose(maneuver.inputs, expected[maneuver.name], rtol=1e-6,
                                   atol=1e-9)
    record = json.loads((tmp_path / "out" / "own" / "result.json").read_text())
    assert record["case"]["actuator_lag_s"] == 0.02
    delays = record["estimates"]["with delays"]["delays"]
    assert delays["L_lat"]["value"] == pytest.approx(0.04, abs=0.01)
    identified = load_result(tmp_path / "out" / "own" / "result.json")
    assert (identified.actuator_lag_s, identified.actuator_inputs) == (0.02, ("lat",))
