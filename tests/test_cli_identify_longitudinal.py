"""A longitudinal-only helicopter data set (no lat, ped, v, p, φ, r or ay columns) identifies
with the ``longitudinal`` structure template through ``rotorid identify``, also when the files
name and scale their columns as a test range does and the model file's ``[channels]`` table
maps them.

The data are the test's own: the longitudinal structure simulated at known derivatives from
3211 and doublet inputs on long and coll, with white measurement noise, written as CSV files
holding only time, long, coll, ax, az, q and theta.
"""

import json
import re

import numpy as np
import pytest
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.cli.main import main
from rotorid.simulation.simulator import simulate

CONDITION = FlightCondition(u0=60.0 * 0.3048, w0=4.0 * 0.3048, theta0=np.radians(4.0))
TRUTH = {"X_u": -0.03, "X_w": 0.02, "X_q": 0.5, "X_long": -0.3, "Z_u": -0.05, "Z_w": -0.6,
         "Z_q": 0.3, "Z_coll": -2.0, "M_u": 0.004, "M_w": 0.006, "M_q": -1.5, "M_long": 0.8,
         "M_coll": 0.1}
COLUMNS = ("time", "long", "coll", "ax", "az", "q", "theta")
#: Noise standard deviations of ax az q θ (ft/s², ft/s², deg/s, deg).
NOISE = np.array([0.05, 0.05, 0.05, 0.02])
MODEL = """units = "flight-test"

[condition]
u0_fps = 60.0
w0_fps = 4.0
theta0_deg = 4.0

[structure]
template = "longitudinal"
remove = ["X_coll", "Z_long"]
"""


def _multistep(time: np.ndarray, start: float, step: float, pattern) -> np.ndarray:
    """A multistep of unit amplitude: ``pattern`` holds the sign and length (in steps) of each
    pulse, starting at ``start`` s, ``step`` s per unit length."""
    signal = np.zeros_like(time)
    t = start
    for sign, length in pattern:
        signal[(time >= t) & (time < t + length * step)] = sign
        t += length * step
    return signal


def _data(tmp_path, columns=COLUMNS, transform=lambda table: table):
    structure = ModelStructure.populated(CONDITION, "longitudinal").with_initial(TRUTH)
    time = np.arange(0.0, 12.0, 0.02)
    three_two_one_one = [(1, 3), (-1, 2), (1, 1), (-1, 1)]
    doublet = [(1, 1), (-1, 1)]
    records = {
        "long3211": (_multistep(time, 1.0, 0.5, three_two_one_one), 0.0 * time),
        "coll3211": (0.0 * time, _multistep(time, 1.0, 0.7, three_two_one_one)),
        "mixed": (_multistep(time, 0.5, 1.0, doublet), -_multistep(time, 3.0, 0.8, doublet)),
    }
    maneuvers = ManeuverSet([
        Maneuver(name, time, np.column_stack([2.0 * long, 3.0 * coll]),
                 np.zeros((time.size, 4)), input_names=("long", "coll"),
                 output_names=("ax", "az", "q", "theta"))
        for name, (long, coll) in records.items()])
    outputs = simulate(structure, None, maneuvers)
    rng = np.random.default_rng(7)
    paths = []
    for m, y in zip(maneuvers, outputs):
        noisy = y + rng.standard_normal(y.shape) * NOISE
        table = transform(np.column_stack([m.time, m.inputs, noisy]))
        path = tmp_path / f"{m.name}.csv"
        lines = [",".join(columns)] + [",".join(f"{v:.10g}" for v in row) for row in table]
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        paths.append(str(path))
    return paths


def test_longitudinal_only_files_identify_with_the_longitudinal_template(tmp_path, capsys):
    files = _data(tmp_path)
    assert open(files[0], encoding="utf-8").readline().strip() == ",".join(COLUMNS)
    model = tmp_path / "model.toml"
    model.write_text(MODEL, encoding="utf-8")
    out = tmp_path / "result.json"
    status = main(["identify", str(model), *files, "--out", str(out), "--quiet"])
    printed = capsys.readouterr().out
    assert status == 0, printed
    result = json.loads(out.read_text(encoding="utf-8"))
    assert result["outputs"] == ["ax", "az", "q", "theta"]
    estimated = {name: p["value"] for name, p in result["parameters"].items()}
    assert set(estimated) == set(TRUTH)
    for name, truth in TRUTH.items():
        bound = result["parameters"][name]["cramer_rao"]
        assert estimated[name] == pytest.approx(truth, abs=max(5 * bound, 1e-3)), name


def test_a_channel_the_model_uses_but_the_files_lack_is_named(tmp_path, capsys):
    files = _data(tmp_path)
    model = tmp_path / "model.toml"
    model.write_text(MODEL.replace('template = "longitudinal"\nremove = ["X_coll", "Z_long"]',
                                   'populate = "all"'), encoding="utf-8")
    status = main(["identify", str(model), *files, "--out", str(tmp_path / "r.json")])
    error = capsys.readouterr().err
    assert status != 0
    assert "has no channel" in error and "structure template" in error
    assert len(error.strip().splitlines()) == 1


#: The test range's names and units: stick in % with the opposite sign, accelerations in g,
#: rate and attitude in rad.
RANGE_COLUMNS = ("time", "DELE", "DCOL", "NX_g", "NZ_g", "Q_radps", "THETA_rad")
CHANNELS = """
[channels]
DELE = { signal = "long", unit = "%", scale = -1.0 }
DCOL = { signal = "coll", unit = "%" }
NX_g = { signal = "ax", unit = "g" }
NZ_g = { signal = "az", unit = "g" }
Q_radps = { signal = "q", unit = "rad/s" }
THETA_rad = { signal = "theta", unit = "rad" }
"""


def _range_units(table: np.ndarray) -> np.ndarray:
    g_ft = 9.80665 / 0.3048
    return table * np.array([1.0, -1.0, 1.0, 1 / g_ft, 1 / g_ft, np.pi / 180, np.pi / 180])


def test_a_channel_map_reads_the_test_range_names_and_units(tmp_path, capsys):
    plain, mapped = tmp_path / "plain", tmp_path / "mapped"
    plain.mkdir()
    mapped.mkdir()
    results = []
    for folder, columns, transform, text in (
            (plain, COLUMNS, lambda table: table, MODEL),
            (mapped, RANGE_COLUMNS, _range_units, MODEL + CHANNELS)):
        files = _data(folder, columns, transform)
        model = folder / "model.toml"
        model.write_text(text, encoding="utf-8")
        out = folder / "result.json"
        assert main(["identify", str(model), *files, "--out", str(out), "--quiet"]) == 0
        results.append(json.loads(out.read_text(encoding="utf-8"))["parameters"])
    assert RANGE_COLUMNS[1] in open(files[0], encoding="utf-8").readline()
    for name, parameter in results[0].items():
        assert results[1][name]["value"] == pytest.approx(parameter["value"], rel=1e-5,
                                                          abs=1e-7), name


@pytest.mark.parametrize("channels, fragment", [
    ('DELX = { signal = "long", unit = "%" }', "has no column 'DELX' .linked to 'long'"),
    ('Q_radps = { signal = "q", unit = "g" }', "unit g, which does not fit 'q' .rate."),
    ('Q_radps = { signal = "q" }', "channel 'Q_radps' needs a table with 'signal' and 'unit'"),
    ('Q_radps = { signal = "q", unit = "rad/s" }\nTHETA_rad = { signal = "q", unit = "rad" }',
     "signal 'q' is linked to several columns"),
    ('Q_radps = { signal = "qq", unit = "rad/s" }',
     "model.toml: column 'Q_radps' is linked to 'qq', which is no signal of the model; its "
     "signals are .*; correct the signal name"),
    ('time = { signal = "time", unit = "deg" }', "unit deg, which does not fit 'time'"),
])
def test_bad_channel_maps_are_one_line_errors_naming_the_file(tmp_path, capsys, channels,
                                                             fragment):
    files = _data(tmp_path, RANGE_COLUMNS, _range_units)
    model = tmp_path / "model.toml"
    model.write_text(MODEL + CHANNELS.split("[channels]")[0] + "[channels]\n" + channels
                     + "\n", encoding="utf-8")
    status = main(["identify", str(model), *files, "--out", str(tmp_path / "r.json")])
    error = capsys.readouterr().err
    assert status != 0
    assert len(error.strip().splitlines()) == 1, error
    assert re.search(fragment, error), error
    assert "model.toml" in error or ".csv" in error
    assert error.count("model.toml:") <= 1, error


def test_time_in_ms_and_unused_columns_read_through_the_channel_map(tmp_path, capsys):
    """A test range's files with the time in ms under their own name and a column the model
    does not use (altitude) give the estimate of the same files with the time in s."""
    results = []
    for folder, time_column, time_scale, extra in (("s", "time", 1.0, ""),
                                                   ("ms", "TIME_ms", 1000.0, "ALT_ft")):
        directory = tmp_path / folder
        directory.mkdir()
        columns = (time_column,) + RANGE_COLUMNS[1:] + ((extra,) if extra else ())

        def transform(table, scale=time_scale, extra=extra):
            ranged = _range_units(table)
            ranged[:, 0] *= scale
            return np.column_stack([ranged, 500.0 + table[:, 0]]) if extra else ranged

        files = _data(directory, columns, transform)
        link = f'{time_column} = {{ signal = "time", unit = "ms" }}\n' if extra else ""
        model = directory / "model.toml"
        model.write_text(MODEL + CHANNELS + link, encoding="utf-8")
        out = directory / "result.json"
        status = main(["identify", str(model), *files, "--out", str(out), "--quiet"])
        assert status == 0, capsys.readouterr().err
        results.append(json.loads(out.read_text(encoding="utf-8"))["parameters"])
    assert "TIME_ms" in open(files[0], encoding="utf-8").readline()
    for name, parameter in results[0].items():
        assert results[1][name]["value"] == pytest.approx(parameter["value"], rel=1e-6), name


#: Constant sensor offsets of ax az q θ in every file of the bias test (flight-test units).
OFFSETS = np.array([0.4, -0.3, 0.5, -0.6])


def test_filter_error_estimates_each_files_sensor_offsets(tmp_path, capsys):
    """The same files with constant offsets on every output: ``--estimator filter-error
    --output-biases`` writes one bias per file and output, each within 3 bounds of the offset
    (every file has the same), and the derivatives within 5 bounds of the truth."""
    files = _data(tmp_path, transform=lambda table: table + np.r_[0.0, 0.0, 0.0, OFFSETS])
    model = tmp_path / "model.toml"
    model.write_text(MODEL, encoding="utf-8")
    out = tmp_path / "result.json"
    status = main(["identify", str(model), *files, "--out", str(out), "--quiet",
                   "--estimator", "filter-error", "--output-biases"])
    assert status == 0, capsys.readouterr()
    parameters = json.loads(out.read_text(encoding="utf-8"))["parameters"]
    for maneuver in ("long3211", "coll3211", "mixed"):
        for output, offset in zip(("ax", "az", "q", "theta"), OFFSETS):
            bias = parameters[f"bias_{maneuver}_{output}"]
            assert bias["value"] == pytest.approx(offset, abs=3 * bias["cramer_rao"]), (
                maneuver, output)
    for name, truth in TRUTH.items():
        bound = parameters[name]["cramer_rao"]
        assert parameters[name]["value"] == pytest.approx(truth, abs=max(5 * bound, 1e-3)), name
