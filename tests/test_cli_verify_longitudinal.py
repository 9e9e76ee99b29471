"""``rotorid verify`` and ``rotorid simulate`` of a ``longitudinal`` template model on
longitudinal-only records (time, long, coll, ax, az, q, theta: no lateral columns).

The sweeps are the test's own: the longitudinal structure at known derivatives driven by an
exponential sweep on long, then on coll, with white measurement noise.
"""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from rotorid import Maneuver, ManeuverSet, ModelStructure
from rotorid.cli.main import main
from rotorid.errors import ExitStatus
from rotorid.simulation.simulator import simulate
from rotorid_files.formats import read_maneuver
from sweeps import log_sweep
from test_cli_identify_longitudinal import COLUMNS, CONDITION, MODEL, NOISE, TRUTH, _data


def _write(maneuver: Maneuver, outputs: np.ndarray, path) -> str:
    table = np.column_stack([maneuver.time, maneuver.inputs, outputs])
    lines = [",".join(COLUMNS)] + [",".join(f"{v:.10g}" for v in row) for row in table]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return str(path)


def _sweeps(folder) -> list[str]:
    """Noisy sweeps of the true longitudinal model on long and on coll, as CSV files."""
    structure = ModelStructure.populated(CONDITION, "longitudinal").with_initial(TRUTH)
    sweep = log_sweep(duration=60.0, omega_min=0.5, omega_max=12.0)
    time = np.arange(sweep.size) * 0.02
    zero = np.zeros_like(sweep)
    maneuvers = ManeuverSet([
        Maneuver(name, time, np.column_stack(inputs), np.zeros((time.size, 4)),
                 metadata={"axis": axis}, input_names=("long", "coll"),
                 output_names=("ax", "az", "q", "theta"))
        for name, axis, inputs in (("sweep_long", "long", (6.0 * sweep, zero)),
                                   ("sweep_coll", "coll", (zero, 6.0 * sweep)))])
    rng = np.random.default_rng(3)
    folder.mkdir()
    return [_write(m, y + rng.standard_normal(y.shape) * NOISE, folder / f"{m.name}.csv")
            for m, y in zip(maneuvers, simulate(structure, None, maneuvers))]


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    """The model file, the estimate of ``rotorid identify`` and the sweep files."""
    folder = tmp_path_factory.mktemp("longitudinal")
    model = folder / "model.toml"
    model.write_text(MODEL, encoding="utf-8")
    result = folder / "result.json"
    assert main(["identify", str(model), *_data(folder), "--out", str(result),
                 "--quiet"]) == 0
    return model, result, _sweeps(folder / "sweeps")


def test_verify_checks_the_structures_own_pairs_on_longitudinal_sweeps(identified, tmp_path,
                                                                      capsys):
    model, result, sweeps = identified
    out = tmp_path / "verification"
    status = main(["verify", str(result), *sweeps, "--out", str(out)])
    printed = capsys.readouterr()
    assert status == 0, printed.err
    summary = json.loads((out / "verification.json").read_text(encoding="utf-8"))
    verified = [p["pair"] for p in summary["pairs"]]
    assert verified == ["q/long", "az/coll"]
    assert summary["skipped_pairs"] == []
    for pair in summary["pairs"]:
        assert pair["checks"]["muad"]["passed"], pair
    assert set(summary["time_domain"]["rmse_per_output"]) == {"ax", "az", "q", "theta"}
    assert {f.name for f in out.glob("*.png")} == {"error_q_long.png", "bode_q_long.png",
                                                   "error_az_coll.png", "bode_az_coll.png"}


def test_verify_refuses_a_pair_the_model_lacks_in_one_line(identified, tmp_path, capsys):
    model, result, sweeps = identified
    status = main(["verify", str(result), *sweeps, "--pairs", "p/lat", "--no-figures",
                   "--out", str(tmp_path / "v")])
    error = capsys.readouterr().err.strip()
    assert status != 0
    assert "\n" not in error and "unknown response pair 'p/lat'" in error
    assert "OUTPUT one of ax, az, q, theta and INPUT one of long, coll" in error


def test_simulate_writes_longitudinal_outputs_of_the_estimate(identified, tmp_path, capsys):
    model, result, sweeps = identified
    out = tmp_path / "simulated"
    assert main(["simulate", str(model), *sweeps, "--values", str(result), "--out",
                 str(out)]) == 0
    for path in sweeps:
        recorded = read_maneuver(path)
        simulated = read_maneuver(out / Path(path).name)
        assert simulated.channel_names == COLUMNS
        # The estimate is the truth within its bounds: the recorded ax, az and q differ from
        # its simulation by about their measurement noise; θ, the integral of q, drifts a
        # little further over the minute-long sweep.
        residual = np.array([np.std(recorded.channel(name) - simulated.channel(name))
                             for name in COLUMNS[3:]])
        assert np.allclose(residual[:3], NOISE[:3], rtol=0.2), residual
        assert residual[3] < 3 * NOISE[3], residual


def test_time_histories_are_labelled_with_the_models_signals(identified):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from rotorid.report.plots.case import plot_time_histories

    model, result, sweeps = identified
    structure = ModelStructure.populated(CONDITION, "longitudinal").with_initial(TRUTH)
    maneuver = read_maneuver(sweeps[0])
    simulated = simulate(structure, None, ManeuverSet([maneuver]))[0]
    figure = plot_time_histories(maneuver, {"truth": simulated}, signals=structure.signals)
    FigureCanvasAgg(figure).draw()
    labels = [axis.get_ylabel() for axis in figure.axes]
    assert labels[:4] == ["a_x [ft/s²]", "a_z [ft/s²]", "q [deg/s]", "θ [deg]"]
    assert labels[4:6] == ["input [%]", "input [%]"]
    assert [t.get_text() for t in figure.axes[4].get_legend().get_texts()] == ["δ_long [%]"]
    assert labels[6:] == ["q [deg/s]"]          # the zoom on the pitch response to long
    measured, model_line = figure.axes[2].get_lines()
    assert np.array_equal(measured.get_ydata(), maneuver.channel("q"))
    assert np.array_equal(model_line.get_ydata(), simulated[:, 2])


CASE = """name = "longitudinal"
description = "longitudinal-only records"

[data]
source = "files"
identification = "{ident}"
verification = "{sweeps}"
""" + MODEL.split("\n", 1)[1] + """
[reduction]
continue_to_zero = false

[delays]
derivatives = ["M_q"]
"""


def test_study_runs_a_longitudinal_case_on_longitudinal_only_files(identified, tmp_path,
                                                                  capsys):
    model, result, sweeps = identified
    case = tmp_path / "case.toml"
    case.write_text(CASE.format(ident=model.parent / "*.csv", sweeps=Path(sweeps[0]).parent),
                    encoding="utf-8")
    status = main(["study", str(case), "--out", str(tmp_path / "out")])
    printed = capsys.readouterr()
    assert status == 0, printed.err
    assert "not verified" not in printed.out + printed.err
    record = json.loads((tmp_path / "out" / "longitudinal" / "result.json").read_text())
    verified = record["frequency_verification"]["with delays"]["pairs"]
    assert [p["pair"] for p in verified] == ["q/long", "az/coll"]
    assert set(record["time_metrics"]["with delays"]["rmse_per_output"]) == {"ax", "az", "q",
                                                                             "theta"}
    figures = {f.name for f in (tmp_path / "out" / "longitudinal" / "figures").glob("*.png")}
    assert {"time_long3211.png", "bode_q_long.png", "error_az_coll.png"} <= figures


@pytest.mark.parametrize("channels, fragment", [
    ('DELX = { signal = "long", unit = "%" }\ntheta = { signal = "theta", unit = "deg" }',
     "has no column 'DELX' .linked to 'long'"),
    ('q = { signal = "q", unit = "g" }', "unit g, which does not fit 'q' .rate."),
    ('q = { signal = "q", unit = "deg/s" }\ntheta = { signal = "q", unit = "deg" }',
     "signal 'q' is linked to several columns"),
])
@pytest.mark.parametrize("command", ["verify", "simulate"])
def test_bad_channel_maps_stop_verify_and_simulate_in_one_line(identified, tmp_path, capsys,
                                                              command, channels, fragment):
    model, result, sweeps = identified
    bad = tmp_path / "bad.toml"
    bad.write_text(MODEL + "\n[channels]\n" + channels + "\n", encoding="utf-8")
    arguments = ([str(bad), str(result), *sweeps, "--no-figures"] if command == "verify"
                 else [str(bad), *sweeps, "--values", str(result)])
    status = main([command, *arguments, "--out", str(tmp_path / "out")])
    error = capsys.readouterr().err.strip()
    assert status != 0
    assert len(error.splitlines()) == 1 and "Traceback" not in error, error
    assert re.search(fragment, error), error
    assert "bad.toml" in error


def test_frequency_estimates_the_on_axis_responses_of_longitudinal_sweeps(identified, tmp_path,
                                                                          capsys):
    model, result, sweeps = identified
    out = tmp_path / "responses.json"
    assert main(["frequency", *sweeps, "--out", str(out)]) == 0, capsys.readouterr().err
    responses = json.loads(out.read_text(encoding="utf-8"))
    assert [p["pair"] for p in responses["pairs"]] == ["q/long", "az/coll"]


def test_verify_leaves_out_sweeps_of_controls_the_model_lacks(identified, tmp_path, capsys):
    model, result, sweeps = identified
    lateral = tmp_path / "sweep_lat.csv"       # a lateral sweep read for this model: no
    table = np.loadtxt(sweeps[0], delimiter=",", skiprows=1)   # long or coll moves in it
    table[:, 1:3] = 0.0
    lateral.write_text(",".join(COLUMNS) + "\n" + "\n".join(
        ",".join(f"{v:.10g}" for v in row) for row in table) + "\n", encoding="utf-8")
    out = tmp_path / "v"
    status = main(["verify", str(result), *sweeps, str(lateral), "--no-figures",
                   "--out", str(out)])
    printed = capsys.readouterr()
    assert status == 0, printed.err
    assert "left out sweep_lat: none of the model's controls (long, coll) moves in it" \
        in printed.out
    summary = json.loads((out / "verification.json").read_text(encoding="utf-8"))
    assert summary["sweeps"] == ["sweep_long", "sweep_coll"]
    assert main(["verify", str(result), str(lateral), "--out", str(out),
                 "--force"]) == ExitStatus.ERROR
    assert "no sweep excites a control of the model: sweep_lat" in capsys.readouterr().err


def test_verify_lags_the_sweeps_as_the_identification_was(identified, tmp_path, capsys):
    """A result that records an actuator lag (``actuator_lag_s``) has the sweeps' inputs put
    through it: here a 0.1 s lag the data never had, so the model no longer matches."""
    model, result, sweeps = identified
    record = json.loads(Path(result).read_text(encoding="utf-8"))
    record["structure"] = str(model)
    record.update(actuator_lag_s=0.1, actuator_inputs=["long"])
    lagged = tmp_path / "lagged.json"
    lagged.write_text(json.dumps(record), encoding="utf-8")
    out = tmp_path / "verification"
    status = main(["verify", str(lagged), *sweeps, "--no-figures", "--out", str(out)])
    printed = capsys.readouterr()
    assert status == ExitStatus.OK, printed.err          # failed checks fail only with --strict
    assert "sweep inputs through the identification's 0.1 s actuator lag" in printed.out
    summary = json.loads((out / "verification.json").read_text(encoding="utf-8"))
    # the lag's phase costs q/long its mismatch cost (J 163 against 0.7 without the lag; the
    # MUAD envelope is wider than its phase at these frequencies)
    checks = {p["pair"]: p["checks"]["mismatch-cost"]["passed"] for p in summary["pairs"]}
    assert checks == {"q/long": False, "az/coll": True}


def test_verify_keeps_an_earlier_verification_unless_forced(identified, tmp_path, capsys):
    _, result, sweeps = identified
    out = tmp_path / "v"
    assert main(["verify", str(result), *sweeps, "--no-figures", "--out", str(out)]) == 0
    first = (out / "verification.json").read_bytes()
    assert main(["verify", str(result), *sweeps, "--no-figures", "--out", str(out)]) \
        == ExitStatus.ERROR
    assert "verification.json exists already; give --force" in capsys.readouterr().err
    assert (out / "verification.json").read_bytes() == first
    assert main(["verify", str(result), *sweeps, "--no-figures", "--out", str(out),
                 "--force"]) == 0
