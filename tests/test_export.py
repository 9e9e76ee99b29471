"""A user's longitudinal flight data through identify, verify and export.

The data are made here: a 4-state longitudinal hover model with a 60 ms delay on M_long, one
record per file (CSV, and one MAT file), doublets for identification and long/coll sweeps for
verification. The lateral channels carry sensor noise only, as they would in flight.
"""

import csv
import json
import math
import runpy
import sys
from pathlib import Path

import numpy as np
import pytest
import rotorid
from rotorid.cli.main import main
from rotorid.errors import ExitStatus, StructureError, UsageError
from rotorid.estimation.result_file import load_result, to_statespace
from rotorid.model.modelfile import load_model
from rotorid.model.statespace import pade_realisation, state_space
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import Study
from rotorid.verification.producible import producible_pairs
from rotorid_files.formats import write_maneuver
from scipy.io import loadmat

sys.path.insert(0, str(Path(__file__).parent))
from sweeps import log_sweep  # noqa: E402

MODEL = """
units = "flight-test"
[condition]
airspeed_kt = 0.0
[structure]
populate = "none"
[derivatives.X_u]
[derivatives.X_q]
[derivatives.X_long]
[derivatives.Z_w]
[derivatives.Z_coll]
[derivatives.M_u]
[derivatives.M_q]
[derivatives.M_long]
delay = 0.0
"""
TRUTH = {"X_u": -0.03, "X_q": 0.6, "X_long": -0.12, "Z_w": -0.35, "Z_coll": -1.1,
         "M_u": 0.08, "M_q": -2.0, "M_long": 0.8, "tau_M_long": 0.06}
NOISE = np.array([0.05, 0.05, 0.1, 0.05, 0.05, 0.1, 0.05, 0.1])   # ax az q θ ay p φ r
DT = 0.02
OMEGA = np.geomspace(0.1, 10.0, 40)
TINY = Path(__file__).parent / "cases" / "tiny.toml"


def _maneuver(name, signal, axis, kind):
    inputs = np.zeros((signal.size, 4))
    inputs[:, rotorid.CONTROLS.index(axis)] = signal
    return rotorid.Maneuver(name, np.arange(signal.size) * DT, inputs,
                            np.zeros((signal.size, 8)), metadata={"kind": kind, "axis": axis})


def _doublet(amplitude, n=500):
    signal = np.zeros(n)
    signal[25:75], signal[75:125] = amplitude, -amplitude
    return signal


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    """Model file, identification and sweep directories, and the identify result."""
    root = tmp_path_factory.mktemp("flight")
    model = root / "model.toml"
    model.write_text(MODEL, encoding="utf-8")
    structure = load_model(model)
    rng = np.random.default_rng(1)
    sweep = 2.0 * log_sweep(40.0, 0.5, 12.0)
    sets = {"ident": ([_maneuver("doublet_long", _doublet(4.0), "long", "doublet"),
                       _maneuver("doublet_coll", _doublet(3.0), "coll", "doublet")], "csv"),
            "sweeps": ([_maneuver("sweep_long", sweep, "long", "sweep"),
                        _maneuver("sweep_coll", sweep, "coll", "sweep")], "mat")}
    for folder, (maneuvers, last_format) in sets.items():
        (root / folder).mkdir()
        outputs = rotorid.simulate(structure, structure.as_vector(TRUTH),
                                   rotorid.ManeuverSet(maneuvers))
        for i, (m, y) in enumerate(zip(maneuvers, outputs)):
            suffix = last_format if i == len(maneuvers) - 1 else "csv"
            write_maneuver(m.with_outputs(y + rng.normal(size=y.shape) * NOISE),
                           root / folder / f"{m.name}.{suffix}")
    result = root / "result.json"
    assert main(["identify", str(model), str(root / "ident"), "--outputs", "ax,az,q,theta",
                 "--out", str(result), "--quiet"]) == ExitStatus.OK
    return root, result


def _reference(structure, values, names, omega=OMEGA):
    """rotorid's analytic response restricted to the system's outputs × inputs, (F, p, m)."""
    full = rotorid.frequency_response(structure, values, omega)
    rows = [rotorid.OUTPUTS.index(o) for o in names.outputs]
    columns = [rotorid.CONTROLS.index(i) for i in names.inputs]
    return full[:, rows][:, :, columns]


def _response(a, b, c, d, omega=OMEGA):
    """C (jωI − A)⁻¹ B + D from plain matrices, (F, p, m)."""
    eye = np.eye(a.shape[0])
    return np.array([c @ np.linalg.solve(1j * w * eye - a, b) + d for w in omega])


def _strict_json(path):
    def refuse(constant):
        raise AssertionError(f"{path} holds {constant}")

    return json.loads(Path(path).read_text(encoding="utf-8"), parse_constant=refuse)


# ----------------------------------------------------------------- verify
def test_verify_skips_the_pairs_a_decoupled_model_cannot_produce(flight, capsys):
    root, result = flight
    out = root / "verification"
    status = main(["verify", str(result), str(root / "sweeps"), "--out", str(out),
                   "--no-figures"])
    captured = capsys.readouterr()
    assert status == ExitStatus.OK, captured.err
    assert "Traceback" not in captured.err
    summary = _strict_json(out / "verification.json")
    assert [p["pair"] for p in summary["pairs"]] == ["q/long", "az/coll"]
    skipped = {s["pair"]: s["reason"] for s in summary["skipped_pairs"]}
    assert set(skipped) == {"p/long", "r/coll"}
    assert "does not respond to long" in skipped["p/long"]
    assert "skipped r/coll: the model's r does not respond to coll" in captured.out
    assert summary["average_cost"] is not None
    assert "q/long compared [##########          ] 1/2, about " in captured.err
    assert "az/coll compared [####################] 2/2, about 0 s left" in captured.err


def test_verify_of_only_pairs_a_decoupled_model_cannot_produce_is_one_line(flight, capsys):
    root, result = flight
    out = root / "verification-none"
    status = main(["verify", str(result), str(root / "sweeps"), "--pairs", "p/long",
                   "--out", str(out), "--no-figures"])
    lines = capsys.readouterr().err.splitlines()
    assert status == ExitStatus.ERROR
    assert lines == ["rotorid verify: error: no pair can be verified: p/long: the model's p "
                     "does not respond to long (no derivative couples them): its response is "
                     "identically zero"]
    assert not (out / "verification.json").exists()


def test_verification_json_carries_the_responses_it_judged(flight):
    root, result = flight
    out = root / "verification-arrays"
    assert main(["verify", str(result), str(root / "sweeps"), "--pairs", "q/long",
                 "--out", str(out), "--no-figures"]) == ExitStatus.OK
    pair = _strict_json(out / "verification.json")["pairs"][0]
    arrays = pair["frequency_response"]
    omega = np.array(arrays["omega_rad_s"])
    assert omega.size > 50 and np.all(np.diff(omega) > 0)
    assert len(arrays["coherence"]) == omega.size
    measured = np.array(arrays["measured"]["magnitude_db"], dtype=float)
    model = np.array(arrays["model"]["magnitude_db"], dtype=float)
    error = np.array(arrays["error"]["magnitude_db"], dtype=float)
    covered = np.isfinite(measured)
    assert covered.sum() > 50
    assert np.allclose(error[covered], model[covered] - measured[covered], atol=1e-9)
    # the analytic model response is the identified model's exact one
    identified = load_result(result)
    exact = rotorid.simulation.transfer.pair_response(identified.structure, identified.values,
                                                      omega, "q", "long")
    assert np.allclose(arrays["analytic"]["model"]["magnitude_db"],
                       20 * np.log10(np.abs(exact)), atol=1e-9)
    coherent = np.array(arrays["coherence"], dtype=float) >= 0.8
    assert pair["checks"]["muad"]["points_used"] == int((coherent & covered).sum())


def test_verify_skips_a_pair_no_sweep_excites_and_fails_cleanly_without_any(flight, capsys):
    root, result = flight
    out = root / "verification-lat"
    assert main(["verify", str(result), str(root / "sweeps"), "--pairs", "q/long,q/lat",
                 "--out", str(out), "--no-figures"]) == ExitStatus.OK
    skipped = _strict_json(out / "verification.json")["skipped_pairs"]
    assert skipped == [{"pair": "q/lat", "reason": "no sweep excites 'lat' (the sweeps excite "
                                                   "coll, long)"}]
    capsys.readouterr()
    assert main(["verify", str(result), str(root / "sweeps"), "--pairs", "p/long,r/ped",
                 "--out", str(out), "--no-figures", "--force"]) == ExitStatus.ERROR
    err = capsys.readouterr().err
    assert err.startswith("rotorid verify: error: no pair can be verified: p/long: the model's")
    assert len(err.strip().splitlines()) == 1


def test_a_measured_output_that_never_moves_is_skipped(flight):
    root, result = flight
    identified = load_result(result)
    sweeps = rotorid.create("data-sources", "files").load(root / "sweeps")
    padded = [m.with_outputs(np.where(np.arange(8) == rotorid.OUTPUTS.index("q"), 0.0,
                                      m.outputs)) for m in sweeps]
    selection = producible_pairs(identified.structure, identified.values,
                                 rotorid.ManeuverSet(padded), ["q/long", "az/coll"])
    assert selection.pairs == ("az/coll",)
    assert "the measured q never moves on the long sweeps (sweep_long)" in selection.skipped[
        "q/long"]


# ----------------------------------------------------------------- state space
def test_the_state_space_has_only_the_states_the_controls_reach(flight):
    identified = load_result(flight[1])
    system = identified.state_space()
    assert system.states == ("u", "w", "q", "theta")
    assert system.inputs == ("long", "coll")
    assert system.outputs == ("ax", "az", "q", "theta")
    poles = np.linalg.eigvals(system.a)
    assert poles.size == 4 and np.all(np.abs(poles) > 1e-3)      # no spurious integrators
    assert system.units["q"] == "deg/s" and system.units["ax"] == "ft/s²"
    assert [(t.derivative, t.equation, t.source) for t in system.delays] == [
        ("M_long", "q", "long")]
    assert system.delays[0].seconds == pytest.approx(0.06, abs=0.01)


def test_without_pade_the_matrices_are_the_model_with_zero_delays(flight):
    identified = load_result(flight[1])
    system = identified.state_space()
    undelayed = {**identified.values, "tau_M_long": 0.0}
    reference = _reference(identified.structure, undelayed, system)
    assert np.allclose(_response(system.a, system.b, system.c, system.d), reference,
                       rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("order, tolerance", [(2, 1e-3), (4, 1e-8)])
def test_the_pade_realisation_reproduces_the_delayed_response(flight, order, tolerance):
    identified = load_result(flight[1])
    system = identified.state_space(order)
    assert len(system.states) == 4 + order
    reference = _reference(identified.structure, identified.values, system)
    response = _response(system.a, system.b, system.c, system.d)
    assert np.max(np.abs(response - reference) / np.abs(reference).max()) < tolerance


def test_pade_realisation_of_a_pure_delay():
    a, b, c, d = pade_realisation(0.1, 3)
    omega = np.array([0.5, 2.0, 8.0])
    response = _response(a, b, c, d, omega)[:, 0, 0]
    assert np.allclose(np.abs(response), 1.0, atol=1e-12)      # an all-pass filter
    assert np.allclose(response, np.exp(-0.1j * omega), atol=1e-5)
    with pytest.raises(StructureError, match="order ≥ 1"):
        pade_realisation(0.1, 0)


def test_an_estimate_gives_a_scipy_state_space(flight):
    identified = load_result(flight[1])
    scipy_system = to_statespace(identified.estimate, identified.structure)
    assert np.array_equal(scipy_system.A, identified.state_space().a)
    assert np.array_equal(identified.to_statespace(2).A, identified.state_space(2).a)


def test_a_model_without_control_derivatives_has_no_state_space():
    structure = rotorid.ModelStructure(rotorid.FlightCondition(), [rotorid.Derivative("M_q")])
    with pytest.raises(StructureError, match="no control drives a state or an output"):
        state_space(structure, {"M_q": -1.0})


# ----------------------------------------------------------------- export
def test_a_mat_export_read_back_with_scipy_reproduces_the_response(flight, capsys):
    root, result = flight
    path = root / "model.mat"
    assert main(["export", str(result), "--format", "mat", "--out", str(path),
                 "--pade", "4"]) == ExitStatus.OK
    assert f"written to {path}" in capsys.readouterr().out
    content = loadmat(path)
    names = [[str(x[0]) for x in content[key][0]] for key in
             ("StateName", "InputName", "OutputName", "OutputUnit")]
    assert names[0][:4] == ["u", "w", "q", "theta"] and len(names[0]) == 8
    assert names[1:] == [["long", "coll"], ["ax", "az", "q", "theta"],
                         ["ft/s²", "ft/s²", "deg/s", "deg"]]
    assert str(content["DelayDerivative"][0, 0][0]) == "M_long"
    assert content["PadeOrder"][0, 0] == 4
    identified = load_result(result)
    response = _response(*(content[k] for k in "ABCD"))
    reference = _reference(identified.structure, identified.values, identified.state_space())
    assert np.max(np.abs(response - reference) / np.abs(reference).max()) < 1e-8


def test_python_control_reads_the_exported_model_with_names(flight):
    control = pytest.importorskip("control")
    root, result = flight
    path = root / "model.py"
    assert main(["export", str(result), "--format", "python-control", "--out", str(path),
                 "--pade", "4"]) == ExitStatus.OK
    system = runpy.run_path(str(path))["system"]()
    assert isinstance(system, control.StateSpace)
    assert system.input_labels == ["long", "coll"]
    assert system.output_labels == ["ax", "az", "q", "theta"]
    assert system.state_labels[:4] == ["u", "w", "q", "theta"]
    identified = load_result(result)
    reference = _reference(identified.structure, identified.values, identified.state_space())
    response = np.moveaxis(system(1j * OMEGA), -1, 0)
    assert np.max(np.abs(response - reference) / np.abs(reference).max()) < 1e-8
    undelayed = runpy.run_path(str(_export(root, result, "python-control", "plain.py")))
    assert np.all(np.abs(undelayed["system"]().poles()) > 1e-3)
    assert len(undelayed["STATES"]) == 4


def _export(root, result, file_format, name, *extra):
    path = root / name
    assert main(["export", str(result), "--format", file_format, "--out", str(path),
                 *extra]) == ExitStatus.OK
    return path


def test_json_and_csv_exports_carry_names_units_and_delays(flight):
    root, result = flight
    record = _strict_json(_export(root, result, "json", "model.json"))
    assert [s["name"] for s in record["states"]] == ["u", "w", "q", "theta"]
    assert {s["name"]: s["unit"] for s in record["inputs"]} == {"long": "%", "coll": "%"}
    assert record["delays"][0]["derivative"] == "M_long" and record["pade_order"] == 0
    assert np.array_equal(record["A"], load_result(result).state_space().a)
    folder = _export(root, result, "csv", "model-csv")
    rows = (folder / "A.csv").read_text(encoding="utf-8").splitlines()
    assert rows[0] == ",u,w,q,theta" and rows[3].startswith("q,")
    assert np.allclose([float(x) for x in rows[3].split(",")[1:]],
                       load_result(result).state_space().a[2])
    assert "output,az,ft/s²" in (folder / "signals.csv").read_text(encoding="utf-8")
    assert (folder / "delays.csv").read_text(encoding="utf-8").splitlines()[1].startswith(
        "M_long,q,long,0.0")


def test_export_never_overwrites_without_force(flight, capsys):
    root, result = flight
    path = _export(root, result, "json", "once.json")
    before = path.read_text(encoding="utf-8")
    capsys.readouterr()
    argv = ["export", str(result), "--format", "json", "--out", str(path), "--pade", "2"]
    assert main(argv) == ExitStatus.ERROR
    assert capsys.readouterr().err.strip() == (f"rotorid export: error: {path} exists already; "
                                               f"give --force to overwrite it")
    assert path.read_text(encoding="utf-8") == before
    assert main([*argv, "--force"]) == ExitStatus.OK
    assert _strict_json(path)["pade_order"] == 2


def test_export_usage_errors(flight, capsys):
    root, result = flight
    assert main(["export", str(result), "--format", "json", "--out", str(root / "x.json"),
                 "--model", "no delays"]) == ExitStatus.USAGE
    assert "holding one model" in capsys.readouterr().err
    assert main(["export", str(result), "--format", "json", "--out", str(root / "x.json"),
                 "--pade", "-1"]) == ExitStatus.USAGE
    assert not (root / "x.json").exists()
    with pytest.raises(UsageError, match="holding one model"):
        load_result(result, "with delays")


# ----------------------------------------------------------------- study results
@pytest.fixture(scope="module")
def tiny_study(tmp_path_factory):
    out = tmp_path_factory.mktemp("tiny-study")
    results = Study([FlightCase.load(TINY)], out, progress=None).run()
    return out / "tiny" / "result.json", results["tiny"]


@pytest.mark.parametrize("model", ["with delays", "no delays"])
def test_a_study_result_gives_each_of_its_models(tiny_study, model):
    path, case = tiny_study
    identified = load_result(path, model)
    assert identified.model == model
    expected = state_space(case.structures[model], case.estimates[model].values, pade_order=3)
    loaded = identified.state_space(3)
    assert loaded.states == expected.states and loaded.outputs == expected.outputs
    assert np.allclose(loaded.a, expected.a, rtol=1e-12, atol=0)
    assert np.allclose(loaded.b, expected.b, rtol=1e-12, atol=0)
    assert identified.estimate.rmse == case.estimates[model].rmse
    assert len(loaded.delays) == len(case.structures[model].free_delays)


def test_the_default_model_of_a_study_result_has_the_delays(tiny_study, tmp_path):
    path, case = tiny_study
    assert load_result(path).model == "with delays"
    assert main(["export", str(path), "--format", "mat", "--model", "no delays",
                 "--out", str(tmp_path / "m.mat")]) == ExitStatus.OK
    assert loadmat(tmp_path / "m.mat")["DelaySeconds"].size == 0


def test_a_study_of_the_longitudinal_files_skips_the_pairs_it_cannot_verify(flight, capsys):
    root, _ = flight
    case = root / "my-hover.toml"
    case.write_text('name = "my-hover"\n[data]\nsource = "files"\nidentification = "ident"\n'
                    'verification = "sweeps"\n[condition]\nairspeed_kt = 0.0\n'
                    '[structure]\npopulate = "none"\n'
                    '[derivatives]\n' + "".join(f"{n} = {{}}\n" for n in TRUTH if "tau" not in n)
                    + '[delays]\nderivatives = ["M_long"]\n', encoding="utf-8")
    assert main(["study", str(case), "--out", str(root / "study")]) == ExitStatus.OK
    printed = capsys.readouterr()
    err = printed.err
    assert "[my-hover] q/lat not verified: no sweep excites 'lat'" in err
    assert "Traceback" not in err
    # the reports speak about this aircraft only: no paper, truth model or Bo-105
    for page in (root / "study" / "report.html", root / "study" / "my-hover" / "report.html"):
        text = page.read_text(encoding="utf-8")
        for word in ("paper's claims", "Bo-105", "Helisim", "Padfield", "truth"):
            assert word not in text, (page, word)
    assert "measured" in (root / "study" / "my-hover" / "report.html").read_text()
    drawn = sorted(p.name for p in (root / "study" / "my-hover" / "figures").glob("time_*.png"))
    assert drawn == ["time_doublet_coll.png", "time_doublet_long.png"]
    record = _strict_json(root / "study" / "my-hover" / "result.json")
    verified = record["frequency_verification"]["with delays"]
    assert [p["pair"] for p in verified["pairs"]] == ["q/long", "az/coll"]
    # result.json, report and terminal give the same claims: the guidelines
    claims = [c["claim"] for c in record["claims"]]
    assert record["claims_title"] == "The guidelines" and len(claims) == 4
    assert claims[2:] == [f"{pair} with delays inside MUAD where γ² ≥ 0.8 over 0.1–10 rad/s"
                          for pair in ("q/long", "az/coll")]
    with open(root / "study" / "my-hover" / "tables" / "checks.csv", encoding="utf-8") as rows:
        assert [row[0] for row in list(csv.reader(rows))[1:]] == claims
    decided = sum(c["verdict"] != "not checked" for c in record["claims"])
    assert f"  guidelines: {sum(c['verdict'] == 'holds' for c in record['claims'])}/{decided} " \
           f"hold" in printed.out
    assert sum("not verified" in note for note in verified["notes"]) == 6
    exported = load_result(root / "study" / "my-hover" / "result.json").state_space()
    assert exported.states == ("u", "w", "q", "theta")
    assert main(["verify", str(root / "study" / "my-hover" / "result.json"), str(root / "sweeps"),
                 "--model", "no delays", "--out", str(root / "study-verification"),
                 "--no-figures"]) == ExitStatus.OK
    summary = _strict_json(root / "study-verification" / "verification.json")
    assert summary["pairs"][0]["checks"] == record["frequency_verification"]["no delays"][
        "pairs"][0]["checks"]


def test_exports_say_how_each_signal_is_read_from_the_recorded_columns(flight):
    """A model file whose channel map reads the stick in inches (25.4 % per inch), q in rad/s
    and az in g with its sign flipped and 1 g taken out: every format carries
    signal = factor · column + offset in the exported units."""
    root, result = flight
    model = root / "geared.toml"
    model.write_text(MODEL + '[channels]\nSTICK_IN = { signal = "long", unit = "%", '
                             'scale = 25.4 }\nQ_RAD = { signal = "q", unit = "rad/s" }\n'
                             'NZ = { signal = "az", unit = "g", scale = -1.0, offset = 1.0 }\n',
                     encoding="utf-8")
    record = json.loads(result.read_text(encoding="utf-8"))
    record["structure"] = model.name
    geared = root / "geared.json"
    geared.write_text(json.dumps(record), encoding="utf-8")
    g = 9.80665 / 0.3048
    expected = {"long": (25.4, 0.0), "q": (math.degrees(1.0), 0.0), "az": (-g, g)}
    exported = _strict_json(_export(root, geared, "json", "geared_model.json"))
    channels = {c["signal"]: (c["factor"], c["offset"]) for c in exported["channels"]}
    assert channels.keys() == expected.keys()
    for name, (factor, offset) in expected.items():
        assert channels[name] == pytest.approx((factor, offset), rel=1e-12), name
    content = loadmat(_export(root, geared, "mat", "geared_model.mat"))
    assert [str(x[0]) for x in content["ChannelColumn"][0]] == [
        next(c["column"] for c in exported["channels"] if c["signal"] == s)
        for s in [str(x[0]) for x in content["ChannelSignal"][0]]]
    assert content["ChannelFactor"][0] == pytest.approx([c["factor"]
                                                         for c in exported["channels"]])
    script = runpy.run_path(str(_export(root, geared, "python-control", "geared_model.py")))
    assert script["CHANNELS"]["long"] == {"column": "STICK_IN", "factor": 25.4, "offset": 0.0}
    assert "channels.csv" in {p.name for p in _export(root, geared, "csv", "geared_csv").iterdir()}


def test_a_stated_trim_is_taken_off_the_exported_offsets(flight, capsys):
    """Identified with stated trim values (in the model's units), the export's channels give
    the model's perturbations: az read from g with the sign flipped and 1 g out, then the
    stated az trim off; theta, which no link reads, from its own column less its trim."""
    root, result = flight
    model = root / "trimmed.toml"
    model.write_text(MODEL + '[channels]\nNZ = { signal = "az", unit = "g", scale = -1.0, '
                             'offset = 1.0 }\n', encoding="utf-8")
    record = json.loads(result.read_text(encoding="utf-8"))
    record["structure"] = model.name
    record["ingestion"] = {"trim": {"az": -2.5, "theta": 4.0}}
    trimmed = root / "trimmed.json"
    trimmed.write_text(json.dumps(record), encoding="utf-8")
    exported = _strict_json(_export(root, trimmed, "json", "trimmed_model.json"))
    channels = {c["signal"]: (c["column"], c["factor"], c["offset"])
                for c in exported["channels"]}
    g = 9.80665 / 0.3048
    assert channels["az"] == ("NZ", pytest.approx(-g), pytest.approx(g + 2.5))
    assert channels["theta"] == ("theta", 1.0, -4.0)
    assert "offsets take off the identification's stated trim (az=-2.5, theta=4)" in \
        capsys.readouterr().out
    # a column of 1.1 g reads az = −1.1·g + g + 2.5, the perturbation from the −2.5 trim
    _, factor, offset = channels["az"]
    assert factor * 1.1 + offset == pytest.approx(-0.1 * g + 2.5)
