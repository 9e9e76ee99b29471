"""``rotorid identify`` with a model of one's own named by reference (file or module)."""

import json
import textwrap

import numpy as np
import pytest
from rotorid.cli import main as cli
from rotorid.errors import ExitStatus, MissingFileError, StructureError
from rotorid.model.reference import is_model_reference, load_model_reference
from rotorid_files.formats import write_maneuver
from test_integrated_model import PENDULUM_TRUTH, pendulum_data

MODEL_FILE = textwrap.dedent('''
    """The damped pendulum of the tests, driven by the stick in the maneuvers' long column."""
    from rotorid.estimation.integrated import InitialConditions, IntegratedModel
    from test_integrated_model import STICK_IN_LONG, Pendulum


    def pendulum():
        return IntegratedModel(Pendulum(), channels=STICK_IN_LONG,
                               initial=InitialConditions(fixed={"theta": 0.0, "q": 0.0}))


    PENDULUM = pendulum()
''')


@pytest.fixture
def flight(tmp_path):
    """The model file and a directory of the pendulum's noisy records (flight-test units)."""
    (tmp_path / "models").mkdir()
    model = tmp_path / "models" / "pendulum_model.py"
    model.write_text(MODEL_FILE, encoding="utf-8")
    data = tmp_path / "data"
    data.mkdir()
    for maneuver in pendulum_data(seed=11)[1]:
        write_maneuver(maneuver, data / f"{maneuver.name}.csv")
    return model, data


@pytest.mark.parametrize("name", ["pendulum", "PENDULUM"])
def test_identify_fits_a_model_in_a_python_file(flight, tmp_path, capsys, name):
    model, data = flight
    out = tmp_path / "result.json"
    status = cli.main(["identify", f"{model}:{name}", str(data), "--out", str(out), "--quiet"])
    assert status == ExitStatus.OK, capsys.readouterr().err
    record = json.loads(out.read_text())
    assert record["model"] == f"models/pendulum_model.py:{name}"
    assert "structure" not in record
    values = np.array([record["parameters"][n]["value"] for n in ("omega2", "damping", "gain")])
    bounds = np.array([record["parameters"][n]["cramer_rao"]
                       for n in ("omega2", "damping", "gain")])
    assert np.all(np.abs(values - PENDULUM_TRUTH) <= 3 * bounds)
    assert "estimate written to" in capsys.readouterr().out


def test_identify_fits_a_model_in_an_importable_module(flight, tmp_path, monkeypatch, capsys):
    model, data = flight
    monkeypatch.syspath_prepend(str(model.parent))
    out = tmp_path / "module.json"
    status = cli.main(["identify", "pendulum_model:pendulum", str(data), "--out", str(out),
                       "--quiet"])
    assert status == ExitStatus.OK, capsys.readouterr().err
    assert json.loads(out.read_text())["model"] == "pendulum_model:pendulum"


def test_references_are_told_apart_from_model_files():
    assert is_model_reference("pkg.models:Aircraft")
    assert is_model_reference("models/aircraft.py:build")
    assert not is_model_reference("model.toml")
    assert not is_model_reference("C:/models/model.toml")
    assert not is_model_reference("pkg.models:not-a-name")


def test_bad_references_are_one_line_errors(flight, tmp_path, capsys):
    model, data = flight
    broken = tmp_path / "broken.py"
    broken.write_text("import numpy as np\nraise RuntimeError('no licence')\n")
    failing = tmp_path / "failing.py"
    failing.write_text("def model():\n    return 1 / 0\n")
    cases = [
        (f"{tmp_path / 'missing.py'}:Model", MissingFileError, "does not exist"),
        (f"{model}:Aircraft", StructureError, r"has no 'Aircraft'; it defines .*Pendulum"),
        ("no_such_package_xyz.models:Model", StructureError,
         "cannot import module 'no_such_package_xyz.models'"),
        (f"{broken}:Model", StructureError, r"importing it failed \(RuntimeError: no licence\)"),
        (f"{failing}:model", StructureError, r"calling model\(\) failed \(ZeroDivisionError"),
    ]
    for reference, error, message in cases:
        with pytest.raises(error, match=message):
            load_model_reference(reference)
        assert cli.main(["identify", reference, str(data), "--out",
                         str(tmp_path / "r.json")]) == ExitStatus.ERROR
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and "Traceback" not in err
    assert not (tmp_path / "r.json").exists()
