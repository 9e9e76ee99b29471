"""``rotorid simulate``: written maneuvers equal rotorid.simulate for both value formats."""

import json

import numpy as np
import pytest
import rotorid
from rotorid.cli import main as cli
from rotorid.errors import ExitStatus
from rotorid.model.modelfile import load_model
from rotorid_files.formats import read_maneuver, write_maneuver

MODEL = """
units = "flight-test"

[condition]
airspeed_kt = 60.0
theta0_deg = 2.0

[structure]
populate = "all"

[derivatives.L_lat]
delay = 0.0
"""
VALUES = {"X_u": -0.05, "Z_w": -0.8, "M_q": -2.0, "L_p": -4.0, "N_r": -1.0, "Y_v": -0.2,
          "M_long": 0.5, "L_lat": 1.2, "Z_coll": -1.0, "N_ped": 0.8, "M_u": 0.01,
          "tau_L_lat": 0.037}


def _inputs(tmp_path, count=2, dt=0.02, n=300):
    directory = tmp_path / "inputs"
    directory.mkdir()
    t = np.arange(n) * dt
    for i in range(count):
        u = np.zeros((n, 4))
        u[(t > 0.5) & (t < 1.5), i] = 2.0
        u[(t >= 1.5) & (t < 2.5), i] = -2.0
        write_maneuver(rotorid.Maneuver(f"m{i}", t, u, np.ones((n, 8)),
                                        metadata={"axis": rotorid.CONTROLS[i]}),
                       directory / f"m{i}.csv")
    return directory


def _setup(tmp_path, values):
    model = tmp_path / "model.toml"
    model.write_text(MODEL, encoding="utf-8")
    values_path = tmp_path / "values.json"
    values_path.write_text(json.dumps(values), encoding="utf-8")
    return model, values_path, _inputs(tmp_path)


@pytest.mark.parametrize("fmt", ["csv", "npz", "mat"])
def test_flat_values_round_trip(tmp_path, fmt):
    model, values, inputs = _setup(tmp_path, VALUES)
    out = tmp_path / "out"
    assert cli.main(["simulate", str(model), str(inputs), "--values", str(values),
                     "--out", str(out), "--format", fmt]) == 0
    structure = load_model(model)
    source = rotorid.ManeuverSet([read_maneuver(inputs / f"m{i}.csv") for i in range(2)])
    expected = rotorid.simulate(structure, VALUES, source)
    for i, y in enumerate(expected):
        written = read_maneuver(out / f"m{i}.{fmt}")
        assert np.max(np.abs(written.outputs - y)) <= 1e-12 * np.max(np.abs(y))
        assert np.array_equal(written.inputs, source[i].inputs)
        assert written.metadata["axis"] == rotorid.CONTROLS[i]
    assert np.max(np.abs(expected[1])) > 0.1  # the lateral input moved the model


def test_identify_result_drops_removed_derivatives_and_adds_delays(tmp_path):
    kept = {n: v for n, v in VALUES.items() if not n.startswith("tau_") and n != "M_u"}
    result = {"parameters": {n: {"value": v} for n, v in kept.items()},
              "delays": {"L_lat": {"value": 0.037}, "M_long": {"value": 0.061}},
              "fixed": {"N_v": 0.02}}
    model, values, inputs = _setup(tmp_path, result)
    out = tmp_path / "out"
    assert cli.main(["simulate", str(model), str(inputs / "m0.csv"), str(inputs / "m1.csv"),
                     "--values", str(values), "--out", str(out)]) == 0
    loaded = load_model(model)
    removed = [d.name for d in loaded.free_derivatives if d.name not in kept]
    structure = (loaded.fixing("N_v", 0.02).without(*[n for n in removed if n != "N_v"])
                 .with_delays(["M_long"]))
    reference = {**kept, "tau_L_lat": 0.037, "tau_M_long": 0.061}
    source = rotorid.ManeuverSet([read_maneuver(inputs / f"m{i}.csv") for i in range(2)])
    expected = rotorid.simulate(structure, reference, source)
    full_model = rotorid.simulate(loaded, {**VALUES, "tau_L_lat": 0.037}, source)
    for i, y in enumerate(expected):
        written = read_maneuver(out / f"m{i}.csv").outputs
        assert np.max(np.abs(written - y)) <= 1e-12 * np.max(np.abs(y))
        assert np.max(np.abs(written - full_model[i])) > 1e-6  # M_u removed, M_long delayed


def test_divergence_is_one_line_error(tmp_path, capsys):
    model, values, inputs = _setup(tmp_path, {**VALUES, "L_p": 60.0})
    status = cli.main(["simulate", str(model), str(inputs), "--values", str(values),
                       "--out", str(tmp_path / "out")])
    error = capsys.readouterr().err
    assert status == ExitStatus.ERROR
    assert error.startswith("rotorid simulate: error: simulation diverged")
    assert len(error.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("content, message", [
    ('{"L_p": "fast"}', "L_p must be numbers"),
    ('{"X_x": 1.0}', "unknown or non-free"),
    ("[1, 2]", "must hold a JSON object"),
    ("{", "not valid JSON"),
])
def test_bad_values_files_are_named(tmp_path, capsys, content, message):
    model, values, inputs = _setup(tmp_path, {})
    values.write_text(content, encoding="utf-8")
    status = cli.main(["simulate", str(model), str(inputs), "--values", str(values),
                       "--out", str(tmp_path / "out")])
    assert status == ExitStatus.ERROR
    assert message in capsys.readouterr().err


def test_the_inputs_are_read_as_the_identification_records_were(tmp_path, capsys):
    """A result that records a first-second trim has its inputs read with it, so records
    carrying a 3 % stick trim simulate as the same records without it; --trim given on the
    command line takes the recorded trim's place."""
    result = {"parameters": {n: {"value": v} for n, v in VALUES.items()
                             if not n.startswith("tau_")},
              "delays": {"L_lat": {"value": 0.037}}, "ingestion": {"trim": "first-second"}}
    model, values, inputs = _setup(tmp_path, result)
    trimmed = tmp_path / "trimmed"
    trimmed.mkdir()
    for i in range(2):
        record = read_maneuver(inputs / f"m{i}.csv")
        write_maneuver(rotorid.Maneuver(record.name, record.time, record.inputs + 3.0,
                                        record.outputs, metadata=record.metadata),
                       trimmed / f"m{i}.csv")

    def simulated(records, name, *extra):
        out = tmp_path / name
        assert cli.main(["simulate", str(model), str(records), "--values", str(values),
                         "--out", str(out), *extra]) == 0
        return [read_maneuver(out / f"m{i}.csv").outputs for i in range(2)]

    recorded = simulated(trimmed, "recorded")
    assert "inputs read with trim first-second" in capsys.readouterr().out
    for a, b in zip(recorded, simulated(inputs, "original", "--trim", "first-second")):
        assert np.allclose(a, b, atol=1e-9)
    stated = simulated(trimmed, "stated", "--trim", "long=3,lat=3,coll=3,ped=3")
    for a, b in zip(stated, simulated(inputs, "untrimmed", "--trim", "long=0")):
        assert np.allclose(a, b, atol=1e-9)
    assert not np.allclose(recorded[0], stated[0])
