"""The study scripts of docs/examples run, in their quick modes, and give sensible models.

study_hover.py and study_forward.py run the built-in cases' quick variants: by default on
from the reduction steps of the session's shared quick study (``quick_study`` in conftest.py),
from scratch in the slow suite (about 20 s each); own_flight_data.py identifies from CSV files
it writes itself, custom_estimator.py registers an equation-error estimator plugin and runs a
case with it; turbulence_montecarlo.py repeats both estimators in turbulence (reduced, and
slow), and turbulence_hover.py (slow) checks the hover key-derivative criterion in turbulence.
"""

import json
import shutil
import sys

import matplotlib
import numpy as np
import pytest
import rotorid
from docs_examples import EXAMPLES, load_example
from rotorid import Delay, Derivative, FlightCondition, ModelStructure
from rotorid.estimation.estimate import Estimate
from rotorid.study.case import FlightCase
from test_output_error import doublet_maneuvers, with_outputs

matplotlib.use("Agg")

ON_AXIS = ("q/long", "p/lat", "az/coll", "r/ped")


def _load(name):
    return load_example(name)


def _assert_on_axis_pairs_verify(result, heave: float = 0.9):
    """The paper's verification claim, with room for the estimation noise of a quick run:
    with delays, at least 90 % of the coherent points (γ² ≥ 0.8) of every on-axis pair lie
    inside MUAD (quick runs reach 100 %, with worst margins between 0.1 and 1.2 dB), az/coll
    at least the fraction ``heave``, and the delays bring more pitch and roll points inside
    than the model without them (quick runs: 66–94 % without)."""
    for pair in ON_AXIS:
        check = result.verification["with delays"][pair].checks["muad"]
        needed = heave if pair == "az/coll" else 0.9
        assert check.n_used > 100 and check.fraction_inside >= needed, pair
    for pair in ("q/long", "p/lat"):
        checks = {m: result.verification[m][pair].checks["muad"] for m in ("no delays",
                                                                         "with delays")}
        assert checks["with delays"].n_inside > checks["no delays"].n_inside, pair


def _check_study_result(result, out_dir, out, heave: float = 0.9):
    """What every quick study run must show, whatever the case."""
    directory = out_dir / result.name
    record = json.loads((directory / "result.json").read_text())
    path = result.path
    assert record["selected_structure"] == list(result.structures["no delays"].names)
    assert record["reduction"]["removed"] == list(path.removed)
    assert len(list((directory / "steps").glob("step_*.json"))) == len(path.steps)
    assert path.steps[0].n_parameters == 60
    assert len(path.removed) >= 5 and path.selected.n_parameters == 60 - len(path.removed)
    # Delays are positive, below their bound, and improve the fit (the paper's two steps).
    delayed = result.estimates["with delays"]
    taus = delayed.values[delayed.is_delay]
    assert taus.size >= 3 and np.all((taus > 0.0) & (taus < 0.3)), taus
    assert not delayed.at_bound
    rmse = {label: m.rmse for label, m in result.time_metrics.items()}
    assert rmse["with delays"] < 0.9 * rmse["no delays"] <= 2.0
    _assert_on_axis_pairs_verify(result, heave)
    # The printout shows every section with these numbers.
    assert f"{path.selected_index:>6}  {path.selected.removal.parameter}" in out
    assert "◀ selected" in out and f"RMSE with delays {rmse['with delays']:.3f}" in out
    for pair in result.case.pairs:
        assert f"\n  {pair:<9}" in out
    for name in ("Reduction path", "Selected structure", "Time delays", "Key derivatives",
                 "Verification"):
        assert name in out
    return {name: row["identified"] for name, row in result.key_derivatives().items()}, {
        name: row["truth_linearisation"] for name, row in result.key_derivatives().items()}


def _run_example(name, out_dir, argv, resume_from=None):
    """Run a study example into ``out_dir``; with ``resume_from`` (a case directory of the
    shared quick study), on from a copy of its finished reduction steps and delays."""
    if resume_from is not None:
        shutil.copytree(resume_from, out_dir / resume_from.name)
        argv = [*argv, "--resume"]
    return _load(name).main([str(out_dir), *argv])


def _check_hover_example(result, out_dir, out, figures: bool = True):
    assert result.case.is_quick and result.name == "hover"
    identified, truth = _check_study_result(result, out_dir, out)
    if figures:     # the example's default
        assert f"Report: {out_dir / 'report.html'}" in out
        assert (out_dir / "report.html").stat().st_size > 1000
        assert (out_dir / "hover" / "figures" / "rmse.png").stat().st_size > 10_000
    else:
        assert "Report:" not in out and not (out_dir / "report.html").exists()
    for name in ("M_w", "M_u", "Z_w", "L_v"):      # hover signs (truth-model.md)
        assert np.sign(identified[name]) == np.sign(truth[name]), name
    assert identified["Z_w"] == pytest.approx(truth["Z_w"], rel=0.15)
    assert identified["M_w"] == pytest.approx(truth["M_w"], rel=0.3)


def test_hover_study_example_resumed_from_the_shared_quick_study(quick_study, tmp_path, capsys):
    """Without figures: the shared quick study drew the same report (tests/test_report.py)."""
    result = _run_example("study_hover", tmp_path, ["--quick", "--no-figures"],
                          quick_study.out / "hover")
    assert result.resumed_steps == len(result.path.steps)
    _check_hover_example(result, tmp_path, capsys.readouterr().out, figures=False)


@pytest.mark.slow
def test_hover_study_example(tmp_path, capsys):
    _check_hover_example(_run_example("study_hover", tmp_path, ["--quick"]), tmp_path,
                         capsys.readouterr().out)


def _check_forward_example(result, out_dir, out):
    """The quick 70 kt run. Its delayed fit ends in one of two minima by the machine's
    round-off (tests/test_quick_study_numbers.py): with M_lat's delay 0.185 s every on-axis
    pair is inside MUAD; where the starts miss that minimum (M_lat's delay dropped at 0,
    det R 27 % higher) az/coll keeps 73 % of its points inside."""
    assert result.case.is_quick and result.condition.airspeed_kt == pytest.approx(70.0)
    identified, truth = _check_study_result(result, out_dir, out, heave=0.7)
    for name in ("N_v", "M_u", "Z_w", "L_v", "Y_v"):   # 70 kt: N_v > 0 (fin)
        assert np.sign(identified[name]) == np.sign(truth[name]), name
    assert identified["N_v"] > 0 and identified["Z_w"] == pytest.approx(truth["Z_w"], rel=0.2)
    # With delays, the off-axis pitch response to lateral stick verifies better.
    checks = {m: result.verification[m]["q/lat"].checks["muad"] for m in ("no delays",
                                                                         "with delays")}
    assert checks["with delays"].n_inside > checks["no delays"].n_inside


def test_forward_study_example_resumed_from_the_shared_quick_study(quick_study, tmp_path,
                                                                   capsys, monkeypatch):
    monkeypatch.setenv("ROTORID_QUICK", "1")
    result = _run_example("study_forward", tmp_path, ["--no-figures"],
                          quick_study.out / "forward")
    assert result.resumed_steps == len(result.path.steps)
    # Resuming gives the uninterrupted run's result file, apart from its timing.
    records = [json.loads((out / "forward" / "result.json").read_text())
               for out in (quick_study.out, tmp_path)]
    assert [r.pop("timing")["resumed_steps"] for r in records] == [0, len(result.path.steps)]
    assert records[0] == records[1]
    _check_forward_example(result, tmp_path, capsys.readouterr().out)


@pytest.mark.slow
def test_forward_study_example_follows_the_quick_environment_variable(tmp_path, capsys,
                                                                      monkeypatch):
    monkeypatch.setenv("ROTORID_QUICK", "1")
    _check_forward_example(_run_example("study_forward", tmp_path, ["--no-figures"]),
                           tmp_path, capsys.readouterr().out)


def test_own_flight_data_example_writes_csv_files_and_identifies_from_them(tmp_path, capsys):
    example = _load("own_flight_data")
    result = example.main([str(tmp_path), "--quick", "--no-figures"])
    out = capsys.readouterr().out
    assert not (tmp_path / "report.html").exists()
    multisteps = sorted((tmp_path / "flight-data" / "multisteps").glob("*.csv"))
    sweeps = sorted((tmp_path / "flight-data" / "sweeps").glob("*.csv"))
    assert len(multisteps) == 8 and len(sweeps) == 4
    lines = multisteps[0].read_text().splitlines()
    assert lines[:4] == ["# name: hover_2311_coll_pos", '# kind: "2311"', '# axis: "coll"',
                         "# direction: 1"]
    assert lines[4] == "time,long,lat,coll,ped,ax,az,q,theta,ay,p,phi,r"
    loaded = rotorid.create("data-sources", "files").load(sweeps[0])[0]
    assert loaded.metadata == {"kind": "sweep", "axis": "coll", "direction": 1}

    case = FlightCase.load(tmp_path / "my-hover.toml")
    assert case.data["source"] == "files" and not case.continue_to_zero
    assert case.condition["theta0_deg"] == pytest.approx(2.1, abs=0.05)
    assert result.case == case and result.truth_derivatives is None
    assert len(result.identification) == 8 and len(result.verification_data) == 4
    assert (tmp_path / "my-hover" / "result.json").is_file()
    assert "[data]\nsource = \"files\"" in out and "hover_sweep_ped" in out
    rmse = {label: m.rmse for label, m in result.time_metrics.items()}
    assert rmse["with delays"] < rmse["no delays"] <= 2.0
    _assert_on_axis_pairs_verify(result)
    estimate = result.estimates["with delays"]
    assert estimate.value("M_u") > 0 and estimate.value("Z_w") < 0 and estimate.value("L_p") < 0
    assert np.all(np.isfinite(estimate.values)) and np.all(np.isfinite(estimate.cramer_rao))


def test_own_flight_data_csv_writer_round_trips(tmp_path):
    example = _load("own_flight_data")
    rng = np.random.default_rng(1)
    time = np.arange(200) * 0.02
    maneuver = rotorid.Maneuver("f42_run7_long_3211", time, rng.normal(size=(200, 4)) * 5,
                                rng.normal(size=(200, 8)) * 3)
    path = example.write_csv(tmp_path / "run7.csv", maneuver,
                             {"kind": "3211", "axis": "long", "pilot": "A. N. Other"})
    loaded = rotorid.create("data-sources", "files").load(path)[0]
    assert loaded.name == maneuver.name and loaded.units == "flight-test"
    assert loaded.metadata == {"kind": "3211", "axis": "long", "pilot": "A. N. Other"}
    assert np.allclose(loaded.outputs, maneuver.outputs, rtol=1e-6, atol=0)
    assert np.allclose(loaded.inputs, maneuver.inputs, rtol=1e-6, atol=0)
    assert np.allclose(loaded.time, time, rtol=0, atol=1e-12)


def test_own_flight_data_case_file_takes_user_paths(tmp_path):
    example = _load("own_flight_data")
    text = example.case_text("/data/f42/ms/*.csv", None,
                             {"airspeed_kt": 60.0, "theta0_deg": -1.5, "phi0_deg": 0.5},
                             quick=False)
    case = example.write_case_file(tmp_path / "f42.toml", text)
    assert case.data == {"source": "files", "identification": "/data/f42/ms/*.csv"}
    assert case.continue_to_zero and not case.warm_start
    assert FlightCondition.from_mapping(case.condition).airspeed_kt == pytest.approx(60.0)
    with pytest.raises(rotorid.MissingFileError, match="no file matches"):
        example.inventory(str(tmp_path / "none" / "*.csv"))


# ----------------------------------------------------------------- custom estimator
HOVER = FlightCondition.from_airspeed(0.0)
TRUE = {"M_u": 0.5, "M_q": -3.7, "M_long": 0.9, "L_v": -0.4, "L_p": -8.0, "L_lat": 2.0,
        "X_u": -0.3, "X_long": -0.1}


def test_equation_error_plugin_recovers_a_known_linear_model():
    example = _load("custom_estimator")
    structure = ModelStructure(HOVER, [Derivative(n) for n in TRUE])
    data = with_outputs(structure, structure.as_vector(TRUE), doublet_maneuvers())
    estimate = example.EquationErrorEstimator().estimate(structure, data)
    assert isinstance(estimate, Estimate) and estimate.converged
    assert estimate.output_units == ("ft/s²",) * 3 + ("deg/s²",) * 3   # the equations' own
    assert estimate.rmse_basis.startswith("dimensionless")
    truth = structure.as_vector(TRUE)
    # Written per sample interval, the equations hold exactly for held controls: only the
    # trapezoid means of the states differ from the true interval means.
    assert np.max(np.abs(estimate.values - truth) / np.abs(truth)) < 0.005
    # With sensor noise: finite Cramér-Rao bounds; the moment derivatives, whose regressors
    # are measured rates and controls, within a few bounds of the truth.
    noisy = with_outputs(structure, truth, doublet_maneuvers(), noise=0.02, seed=4)
    estimate = example.EquationErrorEstimator().estimate(structure, noisy)
    assert np.all(np.isfinite(estimate.cramer_rao)) and np.all(estimate.cramer_rao > 0)
    assert np.all(np.abs(estimate.values - truth) < 0.1 * np.abs(truth))
    moments = np.array([n[0] in "LM" for n in estimate.parameter_names])
    assert np.all(np.abs(estimate.values - truth)[moments] < 3 * estimate.cramer_rao[moments])
    assert estimate.information.shape == (8, 8) and estimate.information[0, -1] == 0.0


def test_equation_error_plugin_handles_fixed_values_and_refuses_free_delays():
    example = _load("custom_estimator")
    structure = ModelStructure(HOVER, [Derivative(n) for n in TRUE])
    data = with_outputs(structure, structure.as_vector(TRUE), doublet_maneuvers())
    fixed = structure.fixing("L_p", TRUE["L_p"])
    estimate = example.EquationErrorEstimator().estimate(fixed, data)
    assert "L_p" not in estimate.parameter_names and estimate.fixed == {"L_p": -8.0}
    assert estimate.value("L_v") == pytest.approx(TRUE["L_v"], rel=0.03)
    with pytest.raises(rotorid.EstimationError, match="cannot estimate delays.*output-error"):
        example.EquationErrorEstimator().estimate(structure.with_delays(["L_lat"]), data)
    known_delay = structure.replacing(
        Derivative("L_lat", delay=Delay(0.06, fixed=True)))
    assert known_delay.parameter_names == structure.parameter_names
    example.EquationErrorEstimator().estimate(known_delay, data)


def test_custom_estimator_example_registers_the_plugin_and_runs_a_case(tmp_path, capsys):
    example = _load("custom_estimator")
    estimates, result = example.main([str(tmp_path)])
    out = capsys.readouterr().out
    listed = next(line for line in out.splitlines() if line.startswith("estimators: "))
    assert {"ls-equation-error", "output-error"} <= set(listed[len("estimators: "):].split(", "))
    assert example.NAME not in rotorid.registry("estimators")      # unregistered afterwards
    ee, oe = estimates[example.NAME], estimates["output-error"]
    assert ee.estimator == example.NAME and ee.parameter_names == oe.parameter_names
    assert np.all(np.isfinite(ee.values)) and np.all(np.isfinite(ee.cramer_rao))
    for name in ("M_w", "Z_w", "M_u", "L_p", "M_q", "N_r"):   # hover signs, both estimators
        assert np.sign(ee.value(name)) == np.sign(oe.value(name)), name
    assert ee.value("Z_w") < 0 and ee.value("M_w") < 0 and ee.value("M_u") > 0
    # The Study ran the reduction with the plugin at every step.
    assert {s.estimate.estimator for s in result.path.steps} == {example.NAME}
    assert result.path.selected.n_parameters < 40
    assert not any(n.startswith("tau_") for n in result.estimates["with delays"].parameter_names)
    record = json.loads((tmp_path / "hover-equation-error" / "result.json").read_text())
    assert record["case"]["estimator"] == example.NAME
    assert result.time_metrics["no delays"].rmse < 2.0
    assert f"selected step {result.path.selected_index}" in out


def test_examples_are_listed_in_the_documentation_index():
    index = (EXAMPLES.parent / "index.md").read_text()
    for script in ("study_hover.py", "study_forward.py", "own_flight_data.py",
                   "custom_estimator.py"):
        assert f"examples/{script}" in index


@pytest.fixture(autouse=True)
def _forget_example_modules():
    """study_forward and own_flight_data import study_hover by name from their folder; keep
    the tests independent of each other and of the rest of the suite."""
    path = list(sys.path)
    yield
    sys.path[:] = path
    sys.modules.pop("study_hover", None)


def _median_derivative_ratios(directory) -> dict[str, float]:
    """Median std/CR over the longitudinal derivatives with finite bounds, per estimator."""
    ratios = {}
    for name in ("output-error", "filter-error"):
        record = json.loads((directory / f"{name}.json").read_text())
        derivatives = [n for n in record["parameter_names"] if n[0] in "XZM" and n[1] == "_"]
        rows = [record["parameters"][n] for n in derivatives]
        # runs that diverge leave infinite bounds (None in the record): no ratio there
        ratios[name] = float(np.median([r["ratio"] for r in rows
                                        if r["mean_cramer_rao"] is not None]))
    return ratios


@pytest.mark.slow
def test_output_error_bounds_underestimate_the_spread_in_turbulence(tmp_path):
    """docs/examples/turbulence_montecarlo.py reduced (docs/estimation.md has its 30 runs):
    eight runs on half-length records. On the linearised truth's longitudinal part, which the
    structure represents exactly, filter error's median std/CR over the derivatives is within
    30 % of 1; on both truths output error's is above 2 and filter error's below it."""
    _load("turbulence_montecarlo").main(["--runs", "8", "--duration-scale", "0.5",
                                         "--truth", "linear-longitudinal", "nonlinear",
                                         "--out", str(tmp_path)])
    assert (tmp_path / "turbulence_montecarlo.png").is_file()
    for truth in ("linear-longitudinal", "nonlinear"):
        ratios = _median_derivative_ratios(tmp_path / truth)
        assert ratios["output-error"] > 2.0, (truth, ratios)
        assert ratios["filter-error"] < ratios["output-error"], (truth, ratios)
    linear = _median_derivative_ratios(tmp_path / "linear-longitudinal")
    assert 0.7 <= linear["filter-error"] <= 1.3, linear


@pytest.mark.slow
def test_on_decimated_records_filter_errors_bounds_describe_the_nonlinear_truths_spread(
        tmp_path):
    """The same example on the nonlinear truth's records low-passed at 3 Hz and kept at every
    8th sample, the sensor noise left white (docs/estimation.md: 100 runs, all 15 derivatives
    within 30 %), eight full-length runs (about 30 s): filter error's median std/CR over the
    derivatives is within 30 % of 1 (undecimated it was 1.21 over 30 runs), output error's
    above 2."""
    _load("turbulence_montecarlo").main(["--runs", "8", "--truth", "nonlinear", "--cutoff", "3",
                                         "--out", str(tmp_path)])
    ratios = _median_derivative_ratios(tmp_path / "nonlinear")
    assert 0.7 <= ratios["filter-error"] <= 1.3, ratios
    assert ratios["output-error"] > 2.0, ratios


def test_filter_error_is_unbiased_in_turbulence_where_output_error_is_not(tmp_path):
    """The same example, four runs on 30 % records of the linearised truth's longitudinal
    part: filter error's key derivatives average within 3 of their bounds of the truth,
    output error's M_long more than 10 bounds off."""
    table = _load("turbulence_montecarlo").main(
        ["--runs", "4", "--duration-scale", "0.3", "--truth", "linear-longitudinal",
         "--out", str(tmp_path)])
    for key in ("M_q", "M_long", "Z_w", "Z_coll"):
        row = table[("linear-longitudinal", "filter-error", key)]
        assert abs(row["mean"] - row["truth"]) <= 3 * row["mean_cr"], (key, row)
    row = table[("linear-longitudinal", "output-error", "M_long")]
    assert abs(row["mean"] - row["truth"]) > 10 * row["mean_cr"], row


#: turbulence_hover.py's key derivatives: roll, pitch and yaw first, then heave.
KEY_DERIVATIVES = ("L_p", "M_q", "L_lat", "M_long", "N_r", "N_ped", "Z_w", "Z_coll")


def _assert_meets_the_criterion(table, column, keys):
    """Each of ``keys`` in ``column`` of a turbulence_hover.py table within 3 CR or 10 % of
    the truth, whichever is larger."""
    for key in keys:
        row = table[(column, key)]
        assert abs(row["percent"]) <= 10.0 or abs(row["cr_off"]) <= 3.0, (key, row)


@pytest.mark.slow
def test_filter_error_meets_the_key_derivative_criterion_in_turbulence(capsys):
    """docs/examples/turbulence_hover.py on 60 % records (docs/estimation.md has the full
    ones): in moderate turbulence filter error with gust states gets the hybrid structure's
    residualised roll, pitch and yaw key derivatives within 3 CR or 10 % of the truth
    linearisation, whichever is larger, and output error is measurably biased (Z_coll many
    CR off, the roll damping lost). The heave pair is not met (its model error)."""
    table = _load("turbulence_hover").main(["--quick"])
    capsys.readouterr()
    _assert_meets_the_criterion(table, "FE moderate", KEY_DERIVATIVES[:6])
    assert abs(table[("OE moderate", "Z_coll")]["cr_off"]) > 10.0
    assert abs(table[("OE moderate", "L_p")]["percent"]) > 100.0


@pytest.mark.slow
@pytest.mark.parametrize("heave", [[], ["--heave-disturbance"]],
                         ids=["w-gust", "heave-disturbance"])
def test_filter_error_meets_the_criterion_where_the_structure_is_exact(capsys, heave):
    """docs/examples/turbulence_hover.py --truth linear --structure six-dof [--heave-
    disturbance] on 60 % records: the maneuvers flown in moderate turbulence by the truth's
    residualised linearisation, which the six-dof structure represents exactly; filter error
    (the w gust, started from its gust-free fit as equation error starts it, or a heave
    acceleration in its place) gets all eight key derivatives within 3 CR or 10 % of the
    truth, output error misses Z_coll by more than 10 CR."""
    table = _load("turbulence_hover").main(["--quick", "--truth", "linear", "--structure",
                                            "six-dof", *heave])
    capsys.readouterr()
    _assert_meets_the_criterion(table, "FE moderate", KEY_DERIVATIVES)
    assert abs(table[("OE moderate", "Z_coll")]["cr_off"]) > 10.0


def test_filter_error_meets_the_criterion_on_a_hybrid_truth(capsys):
    """docs/examples/turbulence_hover.py --truth hybrid --cutoff 4 --update-every on 60 %
    records: the maneuvers flown in moderate turbulence by the hybrid that output error fits to
    the rotor-kept linearisation's still air (the structure exact, the loops, gusts and sensors
    the truth model's); filter error gets all eight key derivatives within 3 CR or 10 % of
    that hybrid's, output error misses Z_coll by more than 10 CR."""
    table = _load("turbulence_hover").main(["--quick", "--truth", "hybrid", "--cutoff", "4",
                                            "--update-every", "--turbulent-only"])
    capsys.readouterr()
    _assert_meets_the_criterion(table, "FE moderate", KEY_DERIVATIVES)
    assert abs(table[("OE moderate", "Z_coll")]["cr_off"]) > 10.0


def test_the_known_actuator_lag_puts_the_hover_roll_axis_within_its_bounds(capsys):
    """docs/examples/turbulence_hover.py --cutoff 4 --update-every --heave-disturbance on 60 %
    records of the truth model in moderate turbulence: with the inputs through the truth's
    0.03 s actuator lag (--actuator-lag 0.03) filter error gets the roll, pitch and yaw key
    derivatives within 3 CR or 10 %; on the sticks as recorded, L_p misses by more than 3 CR
    and 10 % (the hybrid's delays stand in for the lag, docs/estimation.md)."""
    example = _load("turbulence_hover")
    options = ["--quick", "--cutoff", "4", "--update-every", "--heave-disturbance",
               "--turbulent-only"]
    lagged = example.main(options + ["--actuator-lag", "0.03"])
    recorded = example.main(options)
    capsys.readouterr()
    _assert_meets_the_criterion(lagged, "FE moderate", KEY_DERIVATIVES[:6])
    miss = recorded[("FE moderate", "L_p")]
    assert abs(miss["percent"]) > 10.0 and abs(miss["cr_off"]) > 3.0, miss


#: The documented setting of the hover criterion in moderate turbulence (docs/estimation.md,
#: "Where it stands"): the actuators' lag, a heave disturbance held to a fifth of the 15 s
#: records, 0-3 Hz with an update at every 8th sample, multisteps sized for the turbulence.
CRITERION_SETTING = ["--actuator-lag", "0.03", "--heave-disturbance", "--cutoff", "3",
                     "--update-every", "--amplitude", "long=10", "lat=6", "coll=18", "ped=12",
                     "--turbulent-only", "--longest-correlation", "T_w=3"]


@pytest.mark.slow
def test_filter_error_meets_all_eight_key_derivatives_on_the_hover_case(capsys):
    """docs/examples/turbulence_hover.py with :data:`CRITERION_SETTING` on the hover case's
    full records (seed 0) in moderate turbulence: filter error gets all eight key derivatives
    within 3 CR or 10 % of the truth linearisation, output error loses the roll axis (L_lat
    many CR off, of the wrong sign) and misses Z_coll by more than 5 CR."""
    table = _load("turbulence_hover").main(CRITERION_SETTING)
    capsys.readouterr()
    _assert_meets_the_criterion(table, "FE moderate", KEY_DERIVATIVES)
    assert table[("OE moderate", "L_lat")]["value"] < 0.0
    assert abs(table[("OE moderate", "L_lat")]["cr_off"]) > 10.0
    assert abs(table[("OE moderate", "Z_coll")]["cr_off"]) > 5.0


def test_turbulence_example_flies_the_multisteps_at_the_amplitudes_given(capsys):
    """turbulence_hover.py --amplitude: the named axes' multisteps are flown at those
    amplitudes (% of travel), the others at the built-in ones; a malformed item is a usage
    error that names the form."""
    from rotorid_helisim.datasets import AMPLITUDE, DataSetConfig, maneuver_specs

    example = _load("turbulence_hover")
    specs = maneuver_specs(DataSetConfig.from_mapping(example._settings(0, True,
                                                                        {"coll": 12.0})))
    peaks = {}
    for spec in specs:
        peaks.setdefault(spec.axis, set()).add(float(np.max(np.abs(spec.signal(
            np.arange(0.0, 15.0, 0.02))))))
    assert peaks["coll"] == {12.0}
    assert peaks["lat"] == {AMPLITUDE["lat"]}
    with pytest.raises(SystemExit) as exit_info:
        example.main(["--amplitude", "coll12"])
    assert exit_info.value.code == 2
    assert "AXIS=PERCENT" in capsys.readouterr().err


@pytest.mark.slow
def test_filter_error_on_decimated_records_reduces_to_the_truth_in_still_air(capsys):
    """docs/examples/turbulence_hover.py --decimate 4 --cutoff 4 on 60 % records: in still air
    filter error with gust states meets the key-derivative criterion for all eight, the heave
    pair included (on the raw records its heave noise states follow the coning, inflow and
    actuator band the hybrid lacks, docs/estimation.md)."""
    table = _load("turbulence_hover").main(["--quick", "--decimate", "4", "--cutoff", "4"])
    capsys.readouterr()
    _assert_meets_the_criterion(table, "FE still", KEY_DERIVATIVES)
