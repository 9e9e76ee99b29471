"""docs/examples/fixed_wing_nonlinear.py: a nonlinear aeroplane model in a Python file
(states V α θ q; inputs elevator and thrust; outputs V α θ q q̇ ax az; 11 coefficients)
identifies through ``rotorid identify FILE.py:AEROPLANE`` from CSV records with the test
range's own column names and SI units.

The records are flown by ``scipy.integrate.solve_ivp`` (the example's ``write_records``), not
by rotorid's integrator, from level trim, with seeded sensor noise.
"""

import json
import re
import shutil

import numpy as np
import pytest
from docs_examples import EXAMPLES, load_example
from rotorid import Maneuver, ManeuverSet
from rotorid.cli.main import main
from rotorid.estimation.integrated import InitialConditions, IntegratedModel

EXAMPLE = EXAMPLES / "fixed_wing_nonlinear.py"


@pytest.fixture(scope="module")
def example():
    return load_example("fixed_wing_nonlinear")


def test_identify_fits_the_aeroplane_from_its_own_columns(example, tmp_path, capsys):
    model = tmp_path / "models" / "fixed_wing_nonlinear.py"
    model.parent.mkdir()
    shutil.copy(EXAMPLE, model)
    records = example.write_records(tmp_path / "records")
    header = records[0].read_text(encoding="utf-8").splitlines()[0].split(",")
    assert header == ["time", "VTAS_mps", "AOA_rad", "PITCH_rad", "Q_radps", "QDOT_radps2",
                      "AX_mps2", "AZ_mps2", "DELE_rad", "THRUST_N"]
    out = tmp_path / "result.json"
    status = main(["identify", f"{model}:AEROPLANE", str(tmp_path / "records"), "--out",
                   str(out), "--quiet"])
    printed = capsys.readouterr()
    assert status == 0, printed.err
    assert "error" not in printed.err and "Traceback" not in printed.err
    result = json.loads(out.read_text(encoding="utf-8"))
    assert result["model"] == "models/fixed_wing_nonlinear.py:AEROPLANE"
    assert result["outputs"] == ["V", "alpha", "theta", "q", "q_dot", "ax", "az"]
    assert result["converged"] is True
    started_outside = []
    for (name, value), factor in zip(example.TRUTH.items(), example.START_FACTORS):
        entry = result["parameters"][name]
        assert abs(entry["value"] - value) <= 3 * entry["cramer_rao"], (name, entry)
        if abs(value * factor - value) > 3 * entry["cramer_rao"]:
            started_outside.append(name)
    assert len(started_outside) >= 9, started_outside         # the fit had to move them
    initial = [n for n in result["parameters"] if n.startswith("x0_")]
    assert len(initial) == 2 * 4                # one estimated state vector per record


def test_rotorids_integration_of_the_records_matches_the_independent_solver(example):
    """RK4 at the records' 0.02 s under zero-order hold against solve_ivp at 1e-10: the
    records the test fits are the model rotorid integrates, to well below the sensor noise."""
    alpha, elevator, thrust = example.trim()
    time = np.arange(301) * 0.02
    inputs = np.tile([elevator, thrust], (time.size, 1))
    inputs[(time >= 1.0) & (time < 1.6), 0] += 0.03
    inputs[(time >= 2.0) & (time < 3.0), 1] -= 500.0
    state = {"V": 50.0, "alpha": alpha, "theta": alpha, "q": 0.0}
    reference = example.fly(time, inputs, np.array(list(state.values())))
    record = Maneuver("step", time, np.zeros((time.size, 0)), np.zeros((time.size, 0)),
                      units="si", input_names=(), output_names=(),
                      extra_channels={"DELE_rad": inputs[:, 0], "THRUST_N": inputs[:, 1]})
    model = IntegratedModel(example.LongitudinalAeroplane(), channels=example.AEROPLANE.channels,
                            initial=InitialConditions(fixed=state))
    simulated = model.simulate(list(example.TRUTH.values()), ManeuverSet([record]))[0]
    noise = np.array(list(example.NOISE.values()))
    assert np.all(np.max(np.abs(simulated - reference), axis=0) <= 1e-3 * noise)


@pytest.mark.parametrize("edit, fragment", [
    (('"VTAS_mps": ("V", "m/s")', '"VTAS_kt": ("V", "kt")'),
     r"maneuver 'elevator_3211' has no column 'VTAS_kt' \(linked to signal 'V' in "
     r"fixed_wing_nonlinear.py\); columns: time, VTAS_mps, .*; correct the column name in "
     r"fixed_wing_nonlinear.py"),
    (('"AOA_rad": ("alpha", "rad")', '"AOA_rad": ("alpha", "m/s")'),
     r"fixed_wing_nonlinear.py: column 'AOA_rad' has unit m/s, which does not fit signal "
     r"'alpha' \(angle in rad\)"),
    (('"PITCH_rad": ("theta", "rad")', '"PITCH_rad": ("alpha", "rad")'),
     r"fixed_wing_nonlinear.py: signal 'alpha' is linked to several columns"),
])
def test_bad_channel_maps_of_the_model_file_are_one_line_errors(example, tmp_path, capsys,
                                                               edit, fragment):
    model = tmp_path / "fixed_wing_nonlinear.py"
    model.write_text(EXAMPLE.read_text(encoding="utf-8").replace(*edit), encoding="utf-8")
    records = tmp_path / "records"
    records.mkdir()
    for path in example.write_records(tmp_path / "all"):
        shutil.copy(path, records / path.name)
        break
    status = main(["identify", f"{model}:AEROPLANE", str(records), "--out",
                   str(tmp_path / "r.json")])
    error = capsys.readouterr().err.strip()
    assert status != 0
    assert len(error.splitlines()) == 1 and "Traceback" not in error, error
    assert re.search(fragment, error), error


def test_a_time_column_of_the_ranges_own_name_is_linked_in_the_models_map(example, tmp_path,
                                                                        capsys):
    """The records' time column is ``IRIG_TIME`` (seconds of the day); the model file's
    channel map links it to time, as a linear model file's may."""
    model = tmp_path / "fixed_wing_nonlinear.py"
    model.write_text(EXAMPLE.read_text(encoding="utf-8").replace(
        '"VTAS_mps": ("V", "m/s")', '"IRIG_TIME": ("time", "s"), "VTAS_mps": ("V", "m/s")'),
        encoding="utf-8")
    records = tmp_path / "records"
    records.mkdir()
    for path in example.write_records(tmp_path / "all")[:1]:
        lines = path.read_text(encoding="utf-8").splitlines()
        first = next(i for i, line in enumerate(lines) if line.startswith("time,"))
        lines[first] = lines[first].replace("time,", "IRIG_TIME,", 1)
        (records / path.name).write_text("\n".join(lines) + "\n", encoding="utf-8")
    status = main(["identify", f"{model}:AEROPLANE", str(records), "--out",
                   str(tmp_path / "r.json"), "--quiet", "--max-iterations", "2"])
    printed = capsys.readouterr()
    assert status == 0, printed.err
    assert "rotorid identify: error" not in printed.err and "Traceback" not in printed.err


def test_verify_compares_the_models_simulation_with_its_sweeps(example, tmp_path, capsys):
    """A result of the model of one's own (here its true coefficients) verified on an
    elevator sweep flown by the independent solver, in the range's own columns: every pair
    of the swept elevator is compared through the model's simulation, q/elevator within
    MUAD."""
    shutil.copy(EXAMPLE, tmp_path / "fixed_wing_nonlinear.py")
    result = tmp_path / "result.json"
    result.write_text(json.dumps({
        "model": "fixed_wing_nonlinear.py:AEROPLANE",
        "parameters": {n: {"value": v} for n, v in example.TRUTH.items()}}), encoding="utf-8")
    alpha, elevator, thrust = example.trim()
    time = np.arange(0.0, 45.0, 0.02)
    frequency = 0.5 + (8.0 - 0.5) * time / time[-1]
    inputs = np.tile([elevator, thrust], (time.size, 1))
    inputs[:, 0] += 0.01 * np.sin(np.cumsum(frequency) * 0.02)
    outputs = example.fly(time, inputs, np.array([50.0, alpha, alpha, 0.0]))
    noisy = outputs + np.random.default_rng(2).normal(size=outputs.shape) * list(
        example.NOISE.values())
    sweeps = tmp_path / "sweeps"
    sweeps.mkdir()
    np.savetxt(sweeps / "elevator_sweep.csv", np.column_stack([time, noisy, inputs]),
               delimiter=",", comments="", fmt="%.10g",
               header="# axis: DELE_rad\n" + ",".join(["time", *example.NOISE, "DELE_rad",
                                                       "THRUST_N"]))
    out = tmp_path / "verification"
    status = main(["verify", str(result), str(sweeps), "--no-figures", "--out", str(out)])
    printed = capsys.readouterr()
    assert status == 0, printed.err
    assert "a model of one's own: compared through its simulation" in printed.out
    summary = json.loads((out / "verification.json").read_text(encoding="utf-8"))
    pairs = {p["pair"]: p for p in summary["pairs"]}
    assert set(pairs) == {f"{o}/elevator" for o in ("V", "alpha", "theta", "q", "q_dot", "ax",
                                                    "az")}
    assert pairs["q/elevator"]["checks"]["muad"]["passed"] is True


def test_export_of_a_model_of_ones_own_says_what_it_needs(tmp_path, capsys):
    result = tmp_path / "result.json"
    result.write_text(json.dumps({"model": "fixed_wing_nonlinear.py:AEROPLANE",
                                  "parameters": {"C_L0": {"value": 0.25}}}), encoding="utf-8")
    assert main(["export", str(result), "--format", "json", "--out",
                 str(tmp_path / "m.json")]) == 3
    error = capsys.readouterr().err
    assert "a model of one's own (fixed_wing_nonlinear.py:AEROPLANE), which has no linear " \
           "structure: rotorid verify compares its simulation" in error
