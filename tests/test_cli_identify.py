"""``rotorid identify``: estimates from maneuver files against the truth; one-line errors."""

import json
import os
from pathlib import Path

import numpy as np
import pytest
import rotorid
from rotorid.cli import main as cli
from rotorid.errors import ExitStatus
from rotorid.model.modelfile import load_model
from rotorid.progress import counted
from rotorid_files.formats import read_maneuver, write_maneuver

MODEL = """
units = "flight-test"

[condition]
airspeed_kt = 0.0

[structure]
populate = "none"

[derivatives.X_u]
[derivatives.X_long]
[derivatives.M_u]
[derivatives.M_q]
sign = "negative"
[derivatives.M_long]
[derivatives.L_p]
[derivatives.L_v]
[derivatives.L_lat]
delay = 0.0
[derivatives.Z_w]
[derivatives.Z_coll]
[derivatives.N_r]
[derivatives.N_ped]
"""
TRUTH = {"X_u": -0.03, "X_long": -0.12, "M_u": 0.08, "M_q": -3.0, "M_long": 0.8, "L_p": -9.0,
         "L_v": -0.3, "L_lat": 2.5, "Z_w": -0.35, "Z_coll": -1.1, "N_r": -0.4, "N_ped": 1.4,
         "tau_L_lat": 0.06}
NOISE = np.array([0.05, 0.05, 0.1, 0.05, 0.05, 0.1, 0.05, 0.1])   # ax az q θ ay p φ r


def _doublets(n=400, dt=0.02):
    t = np.arange(n) * dt
    maneuvers = []
    for i, axis in enumerate(rotorid.CONTROLS):
        u = np.zeros((n, 4))
        u[25:75, i], u[75:125, i] = 4.0, -4.0
        maneuvers.append(rotorid.Maneuver(f"doublet_{axis}", t, u, np.zeros((n, 8))))
    return rotorid.ManeuverSet(maneuvers)


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    """Model file, a directory of noisy CSV maneuvers simulated from TRUTH, the structure."""
    root = tmp_path_factory.mktemp("identify")
    model = root / "model.toml"
    model.write_text(MODEL, encoding="utf-8")
    structure = load_model(model)
    blank = _doublets()
    rng = np.random.default_rng(11)
    outputs = rotorid.simulate(structure, structure.as_vector(TRUTH), blank)
    data = root / "data"
    data.mkdir()
    for m, y in zip(blank, outputs):
        write_maneuver(m.with_outputs(y + rng.normal(size=y.shape) * NOISE),
                       data / f"{m.name}.csv")
    return model, data, structure


def _cramer_rao_at_truth(structure):
    """Cramér-Rao bounds from the true noise (diagonal NOISE²) and central-difference
    sensitivities at the truth: sqrt(diag F⁻¹), F = Σ Jᵀ diag(NOISE⁻²) J."""
    truth, blank = structure.as_vector(TRUTH), _doublets()
    columns = []
    for k in range(truth.size):
        step = np.zeros(truth.size)
        step[k] = 1e-6 * max(abs(truth[k]), 1e-2)
        up = np.concatenate(rotorid.simulate(structure, truth + step, blank))
        down = np.concatenate(rotorid.simulate(structure, truth - step, blank))
        columns.append(((up - down) / (2 * step[k])).ravel())
    jacobian = np.array(columns).T                                  # (N·8, P)
    weights = np.tile(NOISE**-2, jacobian.shape[0] // NOISE.size)
    information = jacobian.T @ (weights[:, None] * jacobian)
    return np.sqrt(np.diag(np.linalg.inv(information)))


def test_identify_recovers_the_truth_and_writes_the_json(case, tmp_path, capsys):
    model, data, structure = case
    out = tmp_path / "result.json"
    status = cli.main(["identify", str(model), str(data), "--out", str(out)])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    record = json.loads(out.read_text(encoding="utf-8"))
    assert record["estimator"] == "output-error"
    assert record["converged"] is True
    assert set(record["parameters"]) == set(structure.parameter_names) - {"tau_L_lat"}
    assert set(record["delays"]) == {"L_lat"}
    expected_bounds = dict(zip(structure.parameter_names, _cramer_rao_at_truth(structure)))
    for name, truth in TRUTH.items():
        entry = (record["delays"]["L_lat"] if name == "tau_L_lat"
                 else record["parameters"][name])
        assert abs(entry["value"] - truth) <= 4 * entry["cramer_rao"], (name, entry, truth)
        assert entry["cramer_rao"] == pytest.approx(expected_bounds[name], rel=0.2), name
        assert entry["cramer_rao_pct"] == pytest.approx(
            100 * entry["cramer_rao"] / abs(entry["value"]))
    assert record["parameters"]["M_q"]["sign"] == "negative"
    noise = np.sqrt(np.diag(record["noise_covariance"]))
    assert np.allclose(noise, NOISE, rtol=0.1)
    assert (out.parent / record["structure"]).resolve() == model.resolve()
    assert "[[Parameters]]" in captured.out and "M_long" in captured.out
    assert "[[Modes]] (A with delays set to zero, slowest first)" in captured.out
    assert record["data_warnings"] == []
    assert "Data checks before the fit: no warning" in captured.out
    assert f"estimate written to {out}" in captured.out
    assert "[full] iteration" in captured.err and "RMSE" in captured.err
    assert not list(tmp_path.glob(".*.tmp"))


def test_options_reach_the_estimator(case, tmp_path, capsys):
    model, data, _ = case
    out = tmp_path / "biases.json"
    status = cli.main(["identify", str(model), str(data / "doublet_*.csv"), "--out", str(out),
                       "--outputs", "q,theta,p,phi,r,ax,ay,az", "--noise", "diagonal",
                       "--output-biases", "--initial-states", "--enforce-signs",
                       "--max-iterations", "30",
                       "--quiet"])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    assert "] iteration" not in captured.err                  # --quiet: no progress lines
    record = json.loads(out.read_text(encoding="utf-8"))
    limit = (f"iteration limit reached after {counted(record['iterations'], 'iteration')}; "
             f"--max-iterations raises it")
    reason = limit if record["stop_reason"] == "iteration limit reached" else record["stop_reason"]
    assert captured.err == ("" if record["converged"] else
                            f"rotorid identify: warning: the fit did not converge "
                            f"({reason}); --strict makes this an error\n")
    assert record["outputs"] == ["q", "theta", "p", "phi", "r", "ax", "ay", "az"]
    covariance = np.array(record["noise_covariance"])
    assert np.array_equal(covariance, np.diag(np.diag(covariance)))
    assert "bias_doublet_long_q" in record["parameters"]
    assert abs(record["parameters"]["bias_doublet_long_q"]["value"]) < 0.05
    assert "x0_doublet_lat_p" in record["parameters"]
    assert record["parameters"]["M_q"]["value"] <= 0.0


def test_coloured_residuals_widen_the_bounds_and_need_output_error(case, tmp_path, capsys):
    model, data, _ = case
    plain, coloured = tmp_path / "plain.json", tmp_path / "coloured.json"
    for out, extra in ((plain, []), (coloured, ["--coloured-residuals"])):
        assert cli.main(["identify", str(model), str(data), "--out", str(out), "--quiet",
                         *extra]) == 0, capsys.readouterr().err
    first, second = (json.loads(p.read_text(encoding="utf-8")) for p in (plain, coloured))
    assert second["estimator_options"] == {"coloured_residuals": True}
    assert second["parameters"]["M_q"]["value"] == first["parameters"]["M_q"]["value"]
    assert second["parameters"]["M_q"]["cramer_rao"] != first["parameters"]["M_q"]["cramer_rao"]
    assert any("Morelli & Klein" in note for note in second["notes"])
    assert cli.main(["identify", str(model), str(data), "--out", str(tmp_path / "fe.json"),
                     "--estimator", "filter-error", "--coloured-residuals"]) == 2
    assert "--coloured-residuals widens output error's bounds" in capsys.readouterr().err


def test_a_misspelt_estimator_is_named_before_its_options_are_judged(case, tmp_path, capsys):
    model, data, _ = case
    assert cli.main(["identify", str(model), str(data), "--out", str(tmp_path / "x.json"),
                     "--estimator", "filter_error", "--disturbances", "q"]) == 2
    assert ("argument --estimator: no estimator named 'filter_error'; available: "
            "filter-error, frequency-response, output-error") in capsys.readouterr().err
    # a noise-model state the model lacks is a usage error, found before the data are read
    assert cli.main(["identify", str(model), str(tmp_path / "no-such-data"), "--out",
                     str(tmp_path / "x.json"), "--estimator", "filter-error",
                     "--disturbances", "q,beta0"]) == 2
    assert "error: --disturbances names beta0, not states of the structure" in (
        capsys.readouterr().err)


def test_max_iterations_limits_the_final_run(case, tmp_path, capsys):
    model, data, _ = case
    out = tmp_path / "short.json"
    status = cli.main(["identify", str(model), str(data), "--out", str(out), "--quiet",
                       "--max-iterations", "1"])
    assert status == 0, capsys.readouterr().err
    assert json.loads(out.read_text(encoding="utf-8"))["iterations"] <= 1


def test_a_fit_that_does_not_converge_warns_and_strict_makes_it_an_error(case, tmp_path,
                                                                         capsys):
    model, data, _ = case
    out = tmp_path / "stopped.json"
    argv = ["identify", str(model), str(data), "--out", str(out), "--quiet",
            "--max-iterations", "1", "--noise", "diagonal"]
    assert cli.main(argv) == ExitStatus.OK
    assert json.loads(out.read_text(encoding="utf-8"))["converged"] is False
    assert ("warning: the fit did not converge (iteration limit reached after 1 iteration; "
            "--max-iterations raises it)") in capsys.readouterr().err
    assert cli.main([*argv, "--strict", "--force"]) == ExitStatus.NOT_CONVERGED
    err = capsys.readouterr().err
    assert err.startswith("rotorid identify: error: the fit did not converge (")
    assert out.is_file()


def test_warnings_are_one_line_each(case, tmp_path, capsys):
    model, data, _ = case
    out = tmp_path / "long_only.json"
    status = cli.main(["identify", str(model), str(data / "doublet_long.csv"), "--out", str(out),
                       "--quiet"])
    captured = capsys.readouterr()
    err = captured.err
    assert status == 0, err
    lines = err.strip().splitlines()
    assert lines and all(line.startswith("rotorid identify: warning: ") for line in lines)
    # the data checks' warnings (printed before the fit's own) are recorded and end the
    # report, word for word
    recorded = json.loads(out.read_text(encoding="utf-8"))["data_warnings"]
    assert sum("never moves" in m for m in recorded) == 3
    assert lines[:len(recorded)] == [f"rotorid identify: warning: {m}" for m in recorded]
    report = captured.out.split("Data checks before the fit: ")[1].splitlines()
    assert report[0] == f"{len(recorded)} warning(s)"
    assert report[1:1 + len(recorded)] == [f"    {m}" for m in recorded]
    # only long moves: the derivatives of the other inputs are dropped before the fit
    for control, dropped in (("lat", "L_lat"), ("coll", "Z_coll"), ("ped", "N_ped")):
        assert any(line.startswith(
            f"rotorid identify: warning: input {control!r} never moves (constant 0 in every "
            f"maneuver): its derivatives cannot be estimated, so the structure drops "
            f"{dropped} before the first fit") for line in lines)
    parameters = json.loads(out.read_text(encoding="utf-8"))["parameters"]
    assert {"L_lat", "Z_coll", "N_ped"}.isdisjoint(parameters) and "M_long" in parameters


def _error_line(argv, capsys, status=ExitStatus.ERROR):
    assert cli.main(argv) == status
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    return err


def test_bad_inputs_give_one_line_errors(case, tmp_path, capsys):
    model, data, _ = case
    out = str(tmp_path / "r.json")
    assert "does not exist" in _error_line(
        ["identify", str(tmp_path / "nope.toml"), str(data), "--out", out], capsys)
    assert "no such file" in _error_line(
        ["identify", str(model), str(tmp_path / "missing.csv"), "--out", out], capsys)
    assert "no estimator named 'least-squares'" in _error_line(
        ["identify", str(model), str(data), "--estimator", "least-squares", "--out", out],
        capsys, ExitStatus.USAGE)
    assert "argument --outputs: 'vz' is no output of" in _error_line(
        ["identify", str(model), str(data), "--outputs", "q,vz", "--out", out, "--quiet"],
        capsys, ExitStatus.USAGE)
    assert "must be at least 1" in _error_line(
        ["identify", str(model), str(data), "--max-iterations", "0", "--out", out], capsys,
        ExitStatus.USAGE)
    assert "directory" in _error_line(
        ["identify", str(model), str(data), "--out", str(tmp_path / "no" / "r.json")], capsys)
    lines = (data / "doublet_long.csv").read_text(encoding="utf-8").splitlines()
    first = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    row = lines[first + 5].split(",")
    row[lines[first].split(",").index("q")] = "nan"
    lines[first + 5] = ",".join(row)
    broken = tmp_path / "broken.csv"
    broken.write_text("\n".join(lines) + "\n", encoding="utf-8")
    message = _error_line(["identify", str(model), str(broken), "--out", out], capsys)
    assert "NaN" in message and "'q'" in message
    assert not (tmp_path / "r.json").exists()


def test_trim_removal_before_the_fit(case, tmp_path, capsys):
    """Absolute pitch attitudes (trim 5°) draw the offset warning; --trim theta=5 removes the
    trim and the fit matches the one on perturbation data."""
    model, data, _ = case
    absolute = tmp_path / "absolute"
    absolute.mkdir()
    for path in sorted(data.glob("doublet_*.csv")):
        m = read_maneuver(path)
        outputs = m.outputs.copy()
        outputs[:, rotorid.OUTPUTS.index("theta")] += 5.0
        write_maneuver(m.with_outputs(outputs), absolute / path.name)
    runs = {}
    for label, extra in (("as recorded", []), ("trimmed", ["--trim", "theta=5.0"]),
                         ("perturbations", [])):
        out = tmp_path / f"{label}.json"
        source = data if label == "perturbations" else absolute
        status = cli.main(["identify", str(model), str(source), "--out", str(out), "--quiet",
                           *extra])
        runs[label] = (capsys.readouterr().err, json.loads(out.read_text(encoding="utf-8")))
        assert status == 0, runs[label][0]
    assert "warning: output 'theta' starts away from zero in 4 of 4 maneuvers (an absolute " \
           "attitude?): 5" in runs["as recorded"][0]
    assert "starts away" not in runs["trimmed"][0]
    trimmed, reference = runs["trimmed"][1], runs["perturbations"][1]
    for name, entry in reference["parameters"].items():
        assert trimmed["parameters"][name]["value"] == pytest.approx(entry["value"], rel=1e-6,
                                                                     abs=1e-9), name


def test_a_known_actuator_lag_takes_its_share_of_the_delay(case, tmp_path, capsys):
    """The records carry a 0.06 s delay on L_lat; with the lateral stick through a known
    0.02 s actuator lag the fitted delay is what is left of it, and the result records the
    lag for rotorid verify (rotorid.estimation.result_file.load_result)."""
    from rotorid.estimation.result_file import load_result

    model, data, _ = case
    out = tmp_path / "lagged.json"
    status = cli.main(["identify", str(model), str(data), "--out", str(out), "--quiet",
                       "--actuator-lag", "0.02", "--actuator-inputs", "lat"])
    capsys.readouterr()
    assert status == 0
    record = json.loads(out.read_text(encoding="utf-8"))
    assert (record["actuator_lag_s"], record["actuator_inputs"]) == (0.02, ["lat"])
    assert record["delays"]["L_lat"]["value"] == pytest.approx(0.04, abs=0.01)
    identified = load_result(out)
    assert (identified.actuator_lag_s, identified.actuator_inputs) == (0.02, ("lat",))
    assert cli.main(["identify", str(model), str(data), "--out", str(tmp_path / "x.json"),
                     "--actuator-inputs", "lat"]) == ExitStatus.USAGE
    assert "--actuator-inputs needs --actuator-lag" in capsys.readouterr().err


def test_filter_error_noise_model_options(case, tmp_path, capsys):
    """--estimator filter-error with --process-noise none --gusts w --disturbances r: the
    estimate holds the w gust's and the r disturbance's parameters and no F; the w gust's fit
    from equation error shows its gust-free first fit in the progress lines; the derivatives
    of these noise-free data stay within 4 CR of the truth. --states writes each maneuver's
    state estimates as a maneuver file (the states, then d_r and g_w, in their units) and a
    figure."""
    model, data, _ = case
    out, states = tmp_path / "fe.json", tmp_path / "states"
    status = cli.main(["identify", str(model), str(data), "--out", str(out),
                       "--estimator", "filter-error", "--process-noise", "none",
                       "--gusts", "w", "--disturbances", "r", "--update-every", "1",
                       "--longest-correlation", "Tg_w=100,T_r=50", "--states", str(states)])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    written = sorted(p.name for p in states.iterdir())
    recorded = sorted(p.stem for p in Path(data).iterdir())
    assert written == sorted([f"{n}.csv" for n in recorded] + [f"{n}.png" for n in recorded])
    estimates = read_maneuver(states / f"{recorded[0]}.csv")
    assert estimates.metadata["content"] == "state estimates"
    assert np.all(np.isfinite(estimates.channel("g_w")))
    assert list(estimates.metadata["state_units"])[-2:] == ["d_r", "g_w"]
    assert estimates.metadata["state_units"]["g_w"] == "ft/s"
    assert estimates.metadata["state_units"]["d_r"] == "deg/s²"
    assert estimates.metadata["standard_deviation"]["g_w"] > 0.0
    assert f"written to {states}" in captured.out
    record = json.loads(out.read_text(encoding="utf-8"))
    names = set(record["parameters"])
    assert {"G_w", "Tg_w", "D_r", "T_r"} <= names
    assert {k: record["estimator_options"][k] for k in ("gusts", "disturbances",
                                                        "longest_correlation")} == {
        "gusts": ["w"], "disturbances": ["r"], "longest_correlation": {"Tg_w": 100, "T_r": 50}}
    assert record["parameters"]["Tg_w"]["value"] <= 100 and record["parameters"]["T_r"][
        "value"] <= 50
    assert not any(n.startswith("F_") for n in names)
    assert "[gust-free start] iteration" in captured.err
    for name in ("M_q", "L_p", "Z_w", "Z_coll", "N_r"):
        entry = record["parameters"][name]
        assert abs(entry["value"] - TRUTH[name]) <= 4 * entry["cramer_rao"], (name, entry)


def test_filter_error_options_are_checked(case, tmp_path, capsys):
    model, data, _ = case
    out = str(tmp_path / "r.json")
    base = ["identify", str(model), str(data), "--out", out, "--quiet"]
    assert _error_line(base + ["--states", str(tmp_path / "s")], capsys,
                       ExitStatus.USAGE).endswith(
        "--states: estimator 'output-error' gives no state estimates; use --estimator "
        "filter-error")
    assert not (tmp_path / "s").exists()
    before = {p: p.read_bytes() for p in Path(data).iterdir()}
    refused = _error_line(base + ["--estimator", "filter-error", "--states", str(data)], capsys)
    assert refused.startswith(f"rotorid identify: error: {data}{os.sep}doublet_")
    assert refused.endswith(".csv exists already; give --force to overwrite it")
    assert {p: p.read_bytes() for p in Path(data).iterdir()} == before
    assert _error_line(base + ["--gusts", "w"], capsys, ExitStatus.USAGE).endswith(
        "--gusts: filter error's noise model; add --estimator filter-error (the output-error "
        "estimator has no process noise)")
    assert "gusts must name distinct states" in _error_line(
        base + ["--estimator", "filter-error", "--gusts", "w,w"], capsys)
    assert "names no state" in _error_line(
        base + ["--estimator", "filter-error", "--gusts", ","], capsys, ExitStatus.USAGE)
    assert "give --resample decimate or --update-every, not both" in _error_line(
        base + ["--estimator", "filter-error", "--update-every", "3", "--resample", "decimate",
                "--sample-time", "0.1"], capsys, ExitStatus.USAGE)
    assert "--update-every must be at least 1" in _error_line(
        base + ["--estimator", "filter-error", "--update-every", "0"], capsys,
        ExitStatus.USAGE)
    assert "vz" in _error_line(
        base + ["--estimator", "filter-error", "--disturbances", "vz"], capsys,
        ExitStatus.USAGE)
    assert _error_line(base + ["--estimator", "filter-error", "--gusts", "w",
                               "--longest-correlation", "T_w=3"], capsys,
                       ExitStatus.USAGE).endswith(
        "--longest-correlation names T_w, not a correlation time of this noise model; its "
        "correlation times are Tg_w")
    with pytest.raises(SystemExit) as stopped:
        cli.main(base + ["--estimator", "filter-error", "--longest-correlation", "T_w"])
    assert stopped.value.code == ExitStatus.USAGE
    assert capsys.readouterr().err.strip() == (
        "rotorid identify: error: argument --longest-correlation: NAME=SECONDS pairs of "
        "correlation times such as T_w=3,Tg_u=10; got 'T_w'; see rotorid identify --help")
    assert _error_line(base + ["--longest-correlation", "T_w=3"], capsys,
                       ExitStatus.USAGE).endswith(
        "--longest-correlation: filter error's noise model; add --estimator filter-error (the "
        "output-error estimator has no process noise)")
    assert not (tmp_path / "r.json").exists()
