"""load_result sorts a record's parameters by role: the model's, the records', an estimator's
noise parameters; a parameter of none of these (a derivative of another structure) is refused."""

import json

import pytest
from rotorid.errors import DataFileError
from rotorid.estimation.result_file import load_result
from test_simulation_fit import hover_model

MODEL = hover_model(derivatives=("M_q", "M_long", "Z_w"))


def _write(tmp_path, parameters):
    path = tmp_path / "estimate.json"
    record = {"structure": MODEL, "units": "flight-test",
              "parameters": {name: {"value": value} for name, value in parameters.items()},
              "delays": {"M_long": {"value": 0.05}}}
    path.write_text(json.dumps(record), encoding="utf-8")
    return path


def test_noise_parameters_are_kept_apart_from_the_model(tmp_path):
    path = _write(tmp_path, {"M_q": -2.0, "M_long": 0.8, "F_q": 0.3, "D_w": 0.1, "T_w": 1.5,
                             "G_u": 2.0, "Tg_u": 5.0, "R_theta": 0.01, "bias_m1_q": 0.2,
                             "x0_m1_w": 1.5,
                             "x0_m1_d_q": 0.02})
    identified = load_result(path)
    assert identified.values == {"M_q": -2.0, "M_long": 0.8, "tau_M_long": 0.05}
    assert identified.noise == {"F_q": 0.3, "D_w": 0.1, "T_w": 1.5, "G_u": 2.0, "Tg_u": 5.0,
                                "R_theta": 0.01}
    assert identified.structure.names == ("M_q", "M_long")      # Z_w not estimated: removed


def test_a_derivative_the_structure_cannot_hold_names_the_model_file(tmp_path):
    path = _write(tmp_path, {"M_q": -2.0, "M_long": 0.8, "Bc_beta1c": -20.0, "R_q": 0.01})
    with pytest.raises(DataFileError, match=r"parameter\(s\) Bc_beta1c are neither "
                                            r"derivatives.*another model file"):
        load_result(path)
