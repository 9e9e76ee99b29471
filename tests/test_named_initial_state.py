"""A record's initial state is named (``Maneuver.state_names``, default the six-dof states):
a model starts each of its own states from the value of that name, or from trim, so a
six-dof record starts a longitudinal model, and files keep and convert named states."""

import numpy as np
import pytest
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.errors import DataError
from rotorid.simulation.simulator import simulate
from rotorid_files.formats import convert_units, read_maneuver, write_maneuver

CONDITION = FlightCondition(u0=18.0, w0=1.0, theta0=np.radians(4.0))
#: u w q θ v p φ r (flight-test units)
SIX_DOF_STATE = np.array([2.0, -1.0, 3.0, 1.5, 0.5, -2.0, 1.0, 0.7])


def _record(initial_state, state_names=None, **names) -> Maneuver:
    time = np.arange(200) * 0.02
    inputs = np.zeros((time.size, len(names.get("input_names", "1234"))))
    outputs = np.zeros((time.size, len(names.get("output_names", "12345678"))))
    return Maneuver("free", time, inputs, outputs, initial_state=initial_state,
                    state_names=state_names, **names)


def test_a_longitudinal_model_starts_from_the_named_states_of_a_six_dof_record():
    longitudinal = ModelStructure.populated(CONDITION, "longitudinal").with_initial(
        {"X_u": -0.03, "Z_w": -0.6, "M_q": -1.5, "M_w": 0.006})
    from_six_dof = simulate(longitudinal, None, ManeuverSet([_record(SIX_DOF_STATE)]))[0]
    own = _record(SIX_DOF_STATE[:4], ("u", "w", "q", "theta"), input_names=("long", "coll"),
                  output_names=("ax", "az", "q", "theta"))
    expected = simulate(longitudinal, None, ManeuverSet([own]))[0]
    np.testing.assert_array_equal(from_six_dof, expected)
    # q and θ are states and outputs: the free response starts at the named values.
    np.testing.assert_allclose(expected[0, 2:], SIX_DOF_STATE[2:4])


def test_states_a_record_does_not_name_start_at_trim():
    record = _record(np.array([3.0]), ("q",))
    np.testing.assert_array_equal(record.initial_values(("u", "q", "beta1c")), [0.0, 3.0, 0.0])
    np.testing.assert_array_equal(_record(None).initial_values(("u", "q")), [0.0, 0.0])


def test_initial_state_and_state_names_must_agree():
    with pytest.raises(DataError, match=r"initial_state has 3 values for the 2 states q theta; "
                                        r"give one value per state and name them"):
        _record(np.ones(3), ("q", "theta"))
    with pytest.raises(DataError, match="state_names q q repeat a name"):
        _record(np.ones(2), ("q", "q"))


@pytest.mark.parametrize("suffix", [".csv", ".npz", ".mat"])
def test_files_keep_and_convert_named_initial_states(tmp_path, suffix):
    record = _record(np.array([10.0, 2.0]), ("u", "theta"), units="si")
    path = write_maneuver(record, tmp_path / f"free{suffix}")
    back = read_maneuver(path)
    assert back.state_names == ("u", "theta")
    np.testing.assert_array_equal(back.initial_state, [10.0, 2.0])
    flight_test = convert_units(back, "flight-test")
    np.testing.assert_allclose(flight_test.initial_state, [10.0 / 0.3048, np.degrees(2.0)])
    assert read_maneuver(write_maneuver(_record(SIX_DOF_STATE), tmp_path / f"six{suffix}")
                         ).state_names == ("u", "w", "q", "theta", "v", "p", "phi", "r")


LONGITUDINAL_CASE = """name = "tinylon"
description = "Short hover pitch and heave multisteps, longitudinal template"

[data]
source = "helisim"
condition = "tiny"
airspeed_kt = 0.0
seed = 0
duration_scale = 0.3
identification = ["3211"]
verification = []
axes = ["long", "coll"]
directions = [1]

[structure]
template = "longitudinal"

[reduction]
continue_to_zero = false

[delays]
derivatives = ["M_long"]
"""


def test_montecarlo_of_a_longitudinal_case_on_generated_six_dof_records(tmp_path, capsys):
    """The truth model's records carry the six-dof initial state; the longitudinal model
    starts from its own states of it."""
    import json

    from rotorid.cli.main import main

    case = tmp_path / "tinylon.toml"
    case.write_text(LONGITUDINAL_CASE, encoding="utf-8")
    status = main(["montecarlo", str(case), "--runs", "2", "--executor", "serial", "--out",
                   str(tmp_path / "mc")])
    assert status == 0, capsys.readouterr().err
    record = json.loads((tmp_path / "mc" / "tinylon" / "montecarlo.json").read_text())
    assert "M_q" in record["parameter_names"] and "L_p" not in record["parameter_names"]
    assert len(record["estimates"]) == 2
