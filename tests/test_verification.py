"""Sweep verification: a missing 0.08 s delay fails the MUAD phase envelope, the delay passes."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
import rotorid_envelopes.plugin as envelope_plugin  # noqa: E402
from rotorid.data import Maneuver, ManeuverSet  # noqa: E402
from rotorid.errors import ExitStatus, VerificationError  # noqa: E402
from rotorid.plugin.manager import create, new_plugin_manager  # noqa: E402
from rotorid.report.plots.frequency import plot_bode, plot_error  # noqa: E402
from rotorid.verification.band import VerificationBand  # noqa: E402
from rotorid.verification.compare import compare_sweeps, envelopes_by_name  # noqa: E402
from rotorid.verification.pairs import parse_pair  # noqa: E402
from rotorid.verification.frequency import log_grid, moving_inputs  # noqa: E402
from sweeps import DT, analytic, log_sweep, respond  # noqa: E402

OMEGA = log_grid(0.3, 15.0, 100)
PITCH = ([30.0], [1.0, 3.0])      # q/long
COUPLING = ([-6.0], [1.0, 5.0])   # p/long
DELAY = 0.08
Q, P = 2, 5                       # output columns


@pytest.fixture(scope="module")
def envelopes():
    manager = new_plugin_manager([envelope_plugin], load_entry_points=False)
    return envelopes_by_name(("muad", "aee", "mismatch-cost"), manager)


def _outputs(x, delay):
    out = np.zeros((x.size, 8))
    out[:, Q] = respond(*PITCH, x, delay=delay)
    out[:, P] = respond(*COUPLING, x, delay=delay)
    return out


@pytest.fixture(scope="module")
def case():
    """Two longitudinal sweeps of a truth with a 0.08 s control delay, noisy sensors, and a
    lateral input moved by a 'stabilising loop'; model outputs without and with the delay."""
    rng = np.random.default_rng(7)
    u = log_sweep(duration=60.0, omega_max=18.0)
    time = np.arange(u.size) * DT
    maneuvers, without, with_delay = [], [], []
    for k in range(2):
        inputs = np.zeros((u.size, 4))
        inputs[:, 0] = (-1) ** k * 5.0 * u
        inputs[:, 1] = 0.5 * rng.standard_normal(u.size)
        truth = _outputs(inputs[:, 0], DELAY)
        noise = 0.05 * truth.std(axis=0) * rng.standard_normal(truth.shape)
        maneuvers.append(Maneuver(f"long-sweep-{k}", time, inputs, truth + noise,
                                  {"kind": "sweep", "axis": "long"}))
        without.append(_outputs(inputs[:, 0], 0.0))
        with_delay.append(_outputs(inputs[:, 0], DELAY))
    return ManeuverSet(maneuvers), without, with_delay


def _analytic(delay):
    def response(omega):
        full = np.zeros((len(omega), 8, 4), dtype=complex)
        full[:, Q, 0] = analytic(*PITCH, omega, delay=delay)
        full[:, P, 0] = analytic(*COUPLING, omega, delay=delay)
        return full
    return response


def test_missing_delay_fails_phase_envelope_and_delay_passes(case, envelopes):
    sweeps, without, with_delay = case
    pairs = ["q/long", "p/long"]
    no_delay = compare_sweeps(sweeps, without, pairs, envelopes, omega=OMEGA,
                              analytic=_analytic(0.0))
    delayed = compare_sweeps(sweeps, with_delay, pairs, envelopes, omega=OMEGA,
                             analytic=_analytic(DELAY))
    for pair in pairs:
        bad, good = no_delay[pair], delayed[pair]
        assert bad.truth.conditioned_on == () and bad.conditioned.conditioned_on == ("lat",)
        for checks in (bad.checks, bad.analytic_checks):
            muad = checks["muad"]
            assert muad.passed is False
            outside = muad.omega[muad.used & ~muad.inside]
            assert outside.min() > 3.0            # the failure is at high frequency …
            assert muad.worst_margin_deg < 0      # … and in phase,
            assert muad.worst_margin_db > 0       # not in magnitude
            assert checks["mismatch-cost"].cost > 100
        for checks in (good.checks, good.analytic_checks):
            assert checks["muad"].passed is True and checks["muad"].n_used >= 60
            assert checks["mismatch-cost"].cost < 50   # "nearly indistinguishable"
            assert checks["aee"].status == "not available"
    assert delayed.average_cost() < 50 < 100 < no_delay.average_cost()
    summary = delayed.summary()
    assert summary["pairs"][0]["checks"]["muad"]["passed"] is True
    assert summary["time_domain"]["rmse"] < no_delay.summary()["time_domain"]["rmse"]
    assert "q/long" in delayed.report() and "MUAD: pass" in delayed.report()


def test_every_check_counts_the_points_of_one_band(case):
    """MUAD, AEE, J and the analytic checks use only the band's points: in its frequency range
    and at or above its coherence, and nothing else."""
    sweeps, _, with_delay = case
    band = VerificationBand(coherence=0.9, omega_min=0.5, omega_max=6.0)
    result = compare_sweeps(sweeps, with_delay, ["q/long"], omega=OMEGA,
                            analytic=_analytic(DELAY), band=band)
    item = result["q/long"]
    expected = (OMEGA >= 0.5) & (OMEGA <= 6.0) & (item.coherence >= 0.9)
    assert 0 < expected.sum() < OMEGA.size
    np.testing.assert_array_equal(item.checked, expected)
    assert np.array_equal(item.checks["muad"].used, expected)
    cost = item.checks["mismatch-cost"]
    assert cost.threshold == 0.9 and cost.n_used > 0
    assert cost.omega.min() >= OMEGA[expected].min() and cost.omega.max() <= 6.0
    analytic = item.analytic_checks["muad"]
    assert not np.any(analytic.used & ~band.in_range(OMEGA))
    assert not np.any(analytic.used & ~(item.analytic_coherence >= 0.9))
    assert result.summary()["band"] == {"coherence": 0.9, "omega_min": 0.5, "omega_max": 6.0}
    assert "verification band (every check): γ² ≥ 0.9 over 0.5–6 rad/s" in result.report()


def test_an_envelope_with_another_threshold_is_refused(case):
    from rotorid_envelopes.cost import MismatchCost

    sweeps, _, with_delay = case
    with pytest.raises(VerificationError, match=r"'mismatch-cost' counts points with γ² ≥ "
                                                r"0.6 but the verification band is γ² ≥ 0.8 "
                                                r"over 0.1–10 rad/s: build it with "
                                                r"threshold=0.8"):
        compare_sweeps(sweeps, with_delay, ["q/long"], {"mismatch-cost": MismatchCost()},
                       omega=OMEGA)


def test_a_band_needs_a_coherence_and_an_increasing_positive_range():
    with pytest.raises(VerificationError, match=r"coherence must be a γ² in \(0, 1\]"):
        VerificationBand(coherence=0.0)
    with pytest.raises(VerificationError, match=r"needs 0 < omega_min < omega_max"):
        VerificationBand(omega_min=10.0, omega_max=1.0)


def test_pairs_and_sweeps_are_matched_with_clear_errors(case, envelopes):
    sweeps, without, _ = case
    assert parse_pair("az/coll") == ("az", "coll")
    with pytest.raises(VerificationError, match="unknown response pair 'q-long'"):
        compare_sweeps(sweeps, without, ["q-long"], envelopes)
    with pytest.raises(VerificationError, match="no sweep excites 'ped'"):
        compare_sweeps(sweeps, without, ["r/ped"], envelopes)
    with pytest.raises(VerificationError, match="simulate every sweep"):
        compare_sweeps(sweeps, without[:1], ["q/long"], envelopes)
    result = compare_sweeps(sweeps, without, ["q/long"], envelopes, omega=OMEGA,
                            analytic=_analytic(0.0), conditioning="none")
    assert result["q/long"].conditioned is result["q/long"].truth
    assert compare_sweeps(sweeps, without, ["q/long"], envelopes,
                          omega=OMEGA)["q/long"].conditioned is None
    with pytest.raises(VerificationError, match="was not verified"):
        result["p/lat"]


def test_figures_are_built_and_saved(case, envelopes, tmp_path):
    sweeps, without, with_delay = case
    pairs = ["p/long"]
    a = compare_sweeps(sweeps, without, pairs, envelopes, omega=OMEGA,
                       analytic=_analytic(0.0))["p/long"]
    b = compare_sweeps(sweeps, with_delay, pairs, envelopes, omega=OMEGA,
                       analytic=_analytic(DELAY))["p/long"]
    figure = plot_error({"no delays": a, "with delays": b},
                        [envelopes["muad"], envelopes["aee"]])
    mag, phase, coherence = figure.axes
    assert "p/long" in figure.get_suptitle()
    assert mag.get_ylabel() == "|ε| [dB]" and coherence.get_xlabel() == "frequency ω [rad/s]"
    labels = [t.get_text() for t in figure.legends[0].get_texts()]
    assert labels[:2] == ["MUAD bounds", "MUAD extrapolated (not checked)"]
    assert not any(label.startswith("AEE") for label in labels)      # no data: left out
    assert any(label.startswith("no delays: MUAD ") for label in labels)
    figure.savefig(tmp_path / "error.png")
    bode = plot_bode(b, "deg/s")
    assert len(bode.axes) == 3 and "magnitude" in bode.axes[0].get_ylabel()
    bode.savefig(tmp_path / "bode.png")
    assert (tmp_path / "error.png").stat().st_size > 0 and (tmp_path / "bode.png").exists()
    analytic_figure = plot_error(b, [envelopes["muad"]], analytic=True)
    assert "analytic" in analytic_figure.get_suptitle()


def test_documented_example_runs():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "verification.md").read_text(
        encoding="utf-8")
    (example,) = [block.split("```", 1)[0] for block in text.split("```python\n")[1:]]
    exec(compile(example, "docs/verification.md", "exec"), {})


# ----------------------------------------------------------------- with the simulation engine
def _pitch_structures():
    """A truth with 0.08 s delays on the pitch and roll control derivatives, and the same
    model without them (flight-test units, hover)."""
    from rotorid.model.derivatives import Delay, Derivative
    from rotorid.model.structure import FlightCondition, ModelStructure

    def build(delay):
        delayed = None if delay is None else Delay(delay, fixed=True)
        return ModelStructure(FlightCondition(), [
            Derivative("M_q", -3.0), Derivative("M_long", 30.0, delay=delayed),
            Derivative("L_p", -5.0), Derivative("L_long", -6.0, delay=delayed)])

    return build(DELAY), build(None)


@pytest.fixture(scope="module")
def simulated_sweeps():
    from rotorid.simulation.simulator import simulate

    truth, _ = _pitch_structures()
    rng = np.random.default_rng(12)
    u = log_sweep(duration=60.0, omega_max=18.0)
    time = np.arange(u.size) * DT
    maneuvers = []
    for k in range(2):
        inputs = np.zeros((u.size, 4))
        inputs[:, 0] = (-1) ** k * 2.0 * u
        inputs[:, 1] = 0.3 * rng.standard_normal(u.size)
        maneuvers.append(Maneuver(f"long-sweep-{k}", time, inputs, np.zeros((u.size, 8)),
                                  {"kind": "sweep", "axis": "long"}))
    sweeps = ManeuverSet(maneuvers)
    outputs = simulate(truth, None, sweeps)
    return ManeuverSet([m.with_outputs(y + 0.05 * y.std(axis=0) * rng.standard_normal(y.shape))
                        for m, y in zip(sweeps, outputs)])


def test_verify_model_with_and_without_delays(simulated_sweeps, envelopes):
    from rotorid.verification.verify import verify_model

    truth, no_delay = _pitch_structures()
    pairs = ["q/long", "p/long"]
    bad = verify_model(no_delay, None, simulated_sweeps, pairs, envelopes, omega=OMEGA)
    good = verify_model(truth, None, simulated_sweeps, pairs, envelopes, omega=OMEGA)
    for pair in pairs:
        for checks in (bad[pair].checks, bad[pair].analytic_checks):
            assert checks["muad"].passed is False and checks["muad"].worst_margin_deg < 0
        for checks in (good[pair].checks, good[pair].analytic_checks):
            assert checks["muad"].passed is True
    assert good.average_cost() < 50 < 100 < bad.average_cost()
    assert good.time_metrics.rmse < bad.time_metrics.rmse
    assert good.notes == () and good["q/long"].output_rms_ratio == pytest.approx(1.0, abs=0.05)


def test_unstable_or_drifting_models_are_flagged(simulated_sweeps, envelopes, case):
    from rotorid.verification.verify import verify_model

    truth, _ = _pitch_structures()
    unstable = truth.fixing("M_q", 0.05)  # pitch divergence, e-folding in 20 s
    result = verify_model(unstable, None, simulated_sweeps, ["q/long"], envelopes, omega=OMEGA)
    assert "unstable (eigenvalues 0.05+0j 1/s" in result.notes[0]
    assert "note: the model is unstable" in result.report()
    sweeps, without, _ = case
    drifting = compare_sweeps(sweeps, [100.0 * y for y in without], ["q/long"], envelopes,
                              omega=OMEGA)
    assert drifting["q/long"].output_rms_ratio == pytest.approx(100.0, rel=0.05)
    assert drifting.notes and "drifts" in drifting.notes[0]
    assert drifting.summary()["notes"] == list(drifting.notes)


def _write_result(path, delays):
    import json

    result = {
        "estimator": "output-error",
        "parameters": {"M_q": {"value": -3.0}, "M_long": {"value": 30.0},
                       "L_p": {"value": -5.0}, "L_long": {"value": -6.0},
                       "bias_3211-long_q": {"value": 0.4}},   # identification record bias
        "delays": {name: {"value": DELAY} for name in delays},
        "fixed": {},
        "units": "flight-test",
        "structure": "model.toml",
    }
    path.write_text(json.dumps(result), encoding="utf-8")
    return path


def test_verify_command_writes_checks_and_figures(simulated_sweeps, tmp_path, capsys):
    import json

    from rotorid.cli.main import main
    from rotorid.model.modelfile import save_model

    _, no_delay = _pitch_structures()
    save_model(no_delay.without("L_long"), tmp_path / "model.toml")  # reduced away, re-added
    save_model(no_delay, tmp_path / "full.toml")
    create("data-sources", "files").save(simulated_sweeps, tmp_path / "sweeps", "npz")
    with_delays = _write_result(tmp_path / "delays.json", ["M_long", "L_long"])
    status = main(["verify", str(tmp_path / "full.toml"), str(with_delays),
                   str(tmp_path / "sweeps"), "--pairs", "p/long", "--out", str(tmp_path / "out")])
    assert status == 0
    summary = json.loads((tmp_path / "out" / "verification.json").read_text())
    assert [p["pair"] for p in summary["pairs"]] == ["p/long"]
    assert summary["pairs"][0]["checks"]["muad"]["passed"] is True
    assert summary["pairs"][0]["checks"]["aee"]["status"] == "not available"
    assert summary["pairs"][0]["input_coherence"] < 0.3  # lat moved independently
    for name in ("error_p_long.png", "bode_p_long.png"):
        assert (tmp_path / "out" / name).stat().st_size > 1000
    assert "MUAD: pass" in capsys.readouterr().out
    # the model from the result's own structure, without delays, fails under --strict
    missing = _write_result(tmp_path / "nodelays.json", [])
    missing.write_text(missing.read_text().replace("model.toml", "full.toml"))
    assert main(["verify", str(missing), str(tmp_path / "sweeps"), "--pairs",
                 "q/long,p/long", "--out", str(tmp_path / "out2"), "--strict",
                 "--no-figures"]) == 1
    failed = json.loads((tmp_path / "out2" / "verification.json").read_text())
    assert [p["checks"]["muad"]["passed"] for p in failed["pairs"]] == [False, False]
    assert not list((tmp_path / "out2").glob("*.png"))
    assert main(["verify", str(missing), "--out", str(tmp_path / "out3")]) == ExitStatus.USAGE
    assert "RESULT.json SWEEPS" in capsys.readouterr().err


@pytest.mark.slow
def test_paper_story_on_the_truth_model(envelopes):
    """Hover data from the nonlinear truth model (quick records): the model identified with
    the paper's delays verifies better on the sweeps than the one without (paper figs. 4–5)."""
    from rotorid.model.structure import FlightCondition, ModelStructure
    from rotorid.verification.verify import verify_model

    data = create("data-sources", "helisim").generate({"condition": "hover", "quick": True})
    identification = data.select(lambda m: m.metadata.get("kind") != "sweep")
    sweeps = data.select(kind="sweep")
    estimator = create("estimators", "output-error")
    plain = ModelStructure.six_dof(FlightCondition.from_airspeed(0.0))
    first = estimator.estimate(plain, identification)
    delayed = plain.with_delays()
    second = estimator.estimate(delayed, identification, start=first.as_mapping())
    pairs = ["q/long", "p/long", "q/lat", "p/lat"]
    without = verify_model(plain, first.as_mapping(), sweeps, pairs, envelopes)
    with_delays = verify_model(delayed, second.as_mapping(), sweeps, pairs, envelopes)
    assert with_delays.average_cost() < 0.5 * without.average_cost()
    assert without["q/long"].checks["muad"].passed is False
    assert with_delays["q/long"].checks["muad"].passed is True


def test_the_analytic_comparison_leaves_out_points_with_correlated_inputs():
    from rotorid.verification.compare import INPUT_COHERENCE_LIMIT, _reliable
    from rotorid.verification.frequency import FrequencyResponse

    omega = np.array([1.0, 2.0, 3.0, 4.0])
    conditioned = FrequencyResponse(
        "ped", "r", omega, np.ones(4), coherence=[0.9, 0.9, 0.95, 0.85],
        random_error=np.zeros(4), conditioned_on=("lat",),
        input_coherence=[0.2, INPUT_COHERENCE_LIMIT, 0.93, np.nan])
    # Inputs more than 0.5 coherent (or of unknown coherence) with the conditioning ones.
    assert _reliable(conditioned).coherence.tolist() == [0.9, 0.9, 0.0, 0.0]
    single = FrequencyResponse("ped", "r", omega, np.ones(4), coherence=np.full(4, 0.9),
                               random_error=np.zeros(4))
    assert _reliable(single) is single


def test_a_small_input_that_drives_the_output_is_conditioned_out(envelopes):
    """A 'roll loop' moves the lateral stick by 2 % of the longitudinal sweep's RMS, too
    little for the RMS rule, but the stick drives p 33 times harder than the sweep does: the
    single-input p/long is then not the model's analytic p/long, and ``auto`` must condition
    on the stick (the model says it matters) for the analytic comparison to pass."""
    coupling, roll, loop = ([-6.0], [1.0, 5.0]), ([200.0], [1.0, 5.0]), ([1.0], [1.0, 1.0])
    rng = np.random.default_rng(7)
    u = log_sweep(duration=60.0, omega_max=18.0)
    maneuvers, outputs = [], []
    for k in range(2):
        inputs = np.zeros((u.size, 4))
        inputs[:, 0] = (-1) ** k * 5.0 * u
        coupled = respond(*coupling, inputs[:, 0])
        inputs[:, 1] = 0.02 * respond(*loop, coupled) + 0.02 * rng.standard_normal(u.size)
        y = np.zeros((u.size, 8))
        y[:, P] = coupled + respond(*roll, inputs[:, 1])
        noise = 0.05 * y.std(axis=0) * rng.standard_normal(y.shape)
        maneuvers.append(Maneuver(f"long-{k}", np.arange(u.size) * DT, inputs, y + noise,
                                  {"kind": "sweep", "axis": "long"}))
        outputs.append(y)
    sweeps = ManeuverSet(maneuvers)
    assert moving_inputs(sweeps, "long") == ()

    def response(omega):
        full = np.zeros((len(omega), 8, 4), dtype=complex)
        full[:, P, 0] = analytic(*coupling, omega)
        full[:, P, 1] = analytic(*roll, omega)
        return full

    def verified(conditioning):
        return compare_sweeps(sweeps, outputs, ["p/long"], envelopes, omega=OMEGA,
                              analytic=response, conditioning=conditioning)["p/long"]

    plain, auto = verified("none"), verified("auto")
    assert plain.analytic_checks["muad"].status == "fail"
    assert auto.conditioned.conditioned_on == ("lat",)
    muad = auto.analytic_checks["muad"]
    assert muad.status == "pass" and muad.used.sum() >= 10


def test_the_default_grid_starts_where_the_sweep_does_and_reaches_its_top():
    """Without metadata the grid starts at the input's slowest half cycle (a 0.5 rad/s sweep's
    0.5), not in the windows' leakage below it; a recorded omega_max above 20 rad/s, within a
    fifth of the Nyquist frequency, extends it."""
    from rotorid.verification.compare import default_omega
    from rotorid.verification.pairs import lowest_swept_frequency

    u = log_sweep(duration=60.0, omega_min=0.5, omega_max=30.0, dt=0.01)
    time = np.arange(u.size) * 0.01
    plain = Maneuver("sweep", time, np.column_stack([u, 0 * u, 0 * u, 0 * u]),
                     np.zeros((u.size, 8)), {"axis": "long"})
    assert lowest_swept_frequency(plain) == pytest.approx(0.5, rel=0.02)
    grid = default_omega(ManeuverSet([plain]))
    assert grid[0] == pytest.approx(0.5, rel=0.02) and grid[-1] == pytest.approx(20.0)
    topped = Maneuver("sweep", time, plain.inputs, plain.outputs,
                      {"axis": "long", "omega_max": 30.0})
    assert default_omega(ManeuverSet([topped]))[-1] == pytest.approx(30.0)
    doublet = Maneuver("doublet", time, np.column_stack([np.sign(np.sin(time)) * (time < 6.3),
                                                         0 * u, 0 * u, 0 * u]),
                       np.zeros((u.size, 8)))
    assert lowest_swept_frequency(doublet) is None


def test_an_envelope_available_on_no_pair_is_reported_once(case, envelopes):
    sweeps, _, with_delay = case
    report = compare_sweeps(sweeps, with_delay, ["q/long", "p/long"], envelopes,
                            omega=OMEGA).report()
    lines = report.splitlines()
    assert sum("AEE" in line for line in lines) == 1
    assert any(line.startswith("AEE: not available on any pair, no point checked")
               for line in lines)
    assert sum("MUAD" in line for line in lines) == 2
