"""The Table-1 data sets: maneuver list, metadata, files, CLI, and the flight envelope and
sweep coherence on the nonlinear truth model."""

import math

import numpy as np
import pytest
from rotorid.cli.main import main
from rotorid.errors import DataError
from rotorid.units import KNOT
from rotorid_files.formats import read_maneuver
from rotorid_helisim import source as source_module
from rotorid_helisim.datasets import (
    AMPLITUDE,
    STEP_WIDTH,
    DataSetConfig,
    Job,
    fly_jobs,
    maneuver_specs,
)
from rotorid_helisim.linear_plant import LinearHoverPlant
from rotorid_helisim.sensors import SensorNoise
from rotorid_helisim.source import HelisimSource, resolve_case
from rotorid_signals.signals import Multistep, Sweep
from scipy.signal import coherence

AXES = ("long", "lat", "coll", "ped")
#: On-axis response of each control: output column in [ax az q θ ay p φ r] (angular rates;
#: the vertical specific force for the collective, which has no on-axis rate).
ON_AXIS = {"long": 2, "lat": 5, "coll": 1, "ped": 7}


def _stand_in_source(**options):
    return HelisimSource(LinearHoverPlant(), trimmer=lambda plant, kt: plant.trim, **options)


def test_table_1_maneuver_list():
    specs = maneuver_specs(DataSetConfig.for_condition("forward"))
    assert len(specs) == 20
    names = [s.name for s in specs]
    assert len(set(names)) == 20
    for kind in ("3211", "2311"):
        chosen = [s for s in specs if s.kind == kind]
        assert sorted((s.axis, s.direction) for s in chosen) == sorted(
            (a, d) for a in AXES for d in (1, -1))
        for spec in chosen:
            direction = "pos" if spec.direction > 0 else "neg"
            assert spec.name == f"forward_{kind}_{spec.axis}_{direction}"
            assert isinstance(spec.signal, Multistep) and spec.signal.kind == kind
            assert spec.signal.amplitude == spec.direction * AMPLITUDE[spec.axis]
            assert spec.signal.step_width == pytest.approx(STEP_WIDTH[spec.axis])
            assert spec.signal.duration == pytest.approx(15.0)
    sweeps = [s for s in specs if s.kind == "sweep"]
    assert [s.name for s in sweeps] == [f"forward_sweep_{a}" for a in AXES]
    for spec in sweeps:
        assert isinstance(spec.signal, Sweep)
        assert 60.0 <= spec.signal.duration <= 90.0
        assert spec.signal.omega_min < 0.5 and spec.signal.omega_max > 10.0


def test_selection_and_settings_are_checked():
    config = resolve_case({"condition": "hover", "kinds": "sweep", "axes": ["ped", "long"],
                           "quick": True, "seed": 4})
    assert [s.name for s in maneuver_specs(config)] == ["hover_sweep_long", "hover_sweep_ped"]
    assert config.duration_scale == 0.3 and config.seed == 4
    assert resolve_case("forward").airspeed_kt == 70.0
    with pytest.raises(DataError, match="unknown or empty selection"):
        resolve_case({"kinds": ["3212"]})
    with pytest.raises(DataError, match="unknown data-set setting"):
        resolve_case({"airspeed": 70})
    with pytest.raises(DataError, match="unknown flight condition"):
        resolve_case("cruise")
    with pytest.raises(DataError, match="duration_scale"):
        DataSetConfig(duration_scale=1.5)


def test_step_widths_snap_to_the_sample_grid():
    config = DataSetConfig(sample_rate=64.0, kinds=["3211"], axes=["lat"])
    signal = maneuver_specs(config)[0].signal
    assert signal.sample_time == 1 / 64
    assert signal.step_width == pytest.approx(19 / 64)  # 0.3 s → nearest whole sample


def test_flown_set_metadata_and_excursions():
    plant = LinearHoverPlant()
    config = DataSetConfig(kinds=["2311", "sweep"], axes=["lat", "coll"], duration_scale=0.3,
                           noise={c: 0.0 for c in ("ax", "az", "q", "theta", "ay", "p",
                                                   "phi", "r")})
    [flown], record, names = fly_jobs(plant, [Job(plant.trim.state, plant.trim.stick, config)],
                                      with_record=True)
    assert flown.names == tuple(names) and len(flown) == 6
    for row, maneuver in enumerate(flown):
        meta = maneuver.metadata
        assert meta["condition"] == "hover" and meta["axis"] in ("lat", "coll")
        assert meta["role"] == ("verification" if meta["kind"] == "sweep" else "identification")
        assert meta["sample_rate_hz"] == 50.0 and maneuver.dt == pytest.approx(0.02)
        assert meta["trim_theta_deg"] == pytest.approx(2.2)
        # Starts in trim: zero inputs and (noise-free) zero outputs at t = 0.
        assert np.abs(maneuver.inputs[0]).max() < 1e-9
        assert np.abs(maneuver.outputs[0]).max() < 1e-9
        states = record.states[row, :maneuver.n_samples]
        theta = plant.state_names.index("theta")
        assert meta["excursion"]["theta_deg"] == pytest.approx(
            np.degrees(np.abs(states[:, theta] - plant.trim.state[theta]).max()))
        v = plant.state_names.index("v")
        assert meta["excursion"]["v_kt"] == pytest.approx(np.abs(states[:, v]).max() / KNOT)
        # Outputs are the truth model's measurements, as perturbations in flight-test units.
        q = record.measurements[row, :maneuver.n_samples, 2]
        np.testing.assert_allclose(maneuver.channel("q"), np.degrees(q), atol=1e-9)


def test_cli_writes_and_then_reuses_the_data_set(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(source_module, "_default_plant", LinearHoverPlant)
    monkeypatch.setattr(source_module, "_default_trim", lambda plant, kt: plant.trim)
    out = tmp_path / "hover"
    assert main(["generate", "hover", "--out", str(out), "--seed", "5", "--quick"]) == 0
    captured = capsys.readouterr()
    assert "20 maneuvers written" in captured.out and "100 %" in captured.err
    files = sorted(p.name for p in out.glob("*.npz"))
    assert len(files) == 20 and "hover_3211_long_pos.npz" in files
    stored = read_maneuver(out / "hover_sweep_ped.npz")
    assert stored.metadata["seed"] == 5 and stored.metadata["kind"] == "sweep"
    assert main(["generate", "hover", "--out", str(out), "--seed", "5", "--quick"]) == 0
    assert "unchanged, read from the cache" in capsys.readouterr().out
    assert main(["generate", "hover", "--out", str(out), "--seed", "6", "--quick"]) == 0
    assert "written" in capsys.readouterr().out
    assert read_maneuver(out / "hover_sweep_ped.npz").metadata["seed"] == 6


# --------------------------------------------------------------------------- truth model
def _within_envelope(maneuvers):
    for maneuver in maneuvers:
        excursion = maneuver.metadata["excursion"]
        assert excursion["theta_deg"] <= 10.0 and excursion["phi_deg"] <= 10.0, maneuver.name
        for speed in ("airspeed_kt", "u_kt", "v_kt", "w_kt"):
            assert excursion[speed] <= 10.0, (maneuver.name, speed, excursion)


#: (window length in samples, band in rad/s): 41 s Hann windows for 0.5–1 rad/s, 20 s above.
FULL_BANDS = ((2048, 0.5, 1.0), (1024, 1.0, 10.0))


def _check_sweep_coherence(sweep, bands=FULL_BANDS):
    """γ² ≥ 0.8 of the on-axis response over the bands (75 %-overlapped Hann windows),
    with scipy.signal.coherence."""
    axis = sweep.metadata["axis"]
    stick = sweep.channel(axis)
    rate = sweep.outputs[:, ON_AXIS[axis]]
    fs = 1.0 / sweep.dt
    for length, low, high in bands:
        frequency, gamma2 = coherence(stick, rate, fs=fs, nperseg=length,
                                      noverlap=3 * length // 4)
        omega = 2 * math.pi * frequency
        band = (omega >= low) & (omega <= high)
        assert gamma2[band].min() >= 0.8, (sweep.name, omega[band][np.argmin(gamma2[band])])


@pytest.fixture(scope="module")
def truth_source():
    return HelisimSource()


def test_truth_model_quick_maneuvers_stay_near_trim(truth_source):
    hover, forward = truth_source.generate_many([
        {"condition": "hover", "kinds": ["3211"], "axes": ["long", "ped"], "quick": True},
        {"condition": "forward", "kinds": ["2311"], "axes": ["lat", "coll"], "quick": True}])
    assert len(hover) == 4 and len(forward) == 4
    assert forward[0].metadata["airspeed_kt"] == 70.0
    _within_envelope(hover)
    _within_envelope(forward)
    # The on-axis response has the sign of the stick conventions: forward stick pitches the
    # nose down, right stick rolls right.
    for maneuver, rate, sign in ((hover["hover_3211_long_pos"], "q", -1),
                                 (forward["forward_2311_lat_pos"], "p", 1)):
        signal = maneuver.metadata["signal"]
        first = signal["start"] + signal["step_width"] * (3 if signal["kind"] == "3211" else 2)
        pulse = (maneuver.time > signal["start"]) & (maneuver.time <= first)
        assert sign * maneuver.channel(rate)[pulse].mean() > 1.0  # deg/s


def test_truth_model_quick_sweeps_are_coherent(truth_source):
    """Reduced version of the full check: the quick sweeps (ω_min = 1.5 rad/s, 28 s) over
    2–10 rad/s with 10 s windows."""
    sweeps = truth_source.generate({"condition": "hover", "kinds": ["sweep"], "quick": True})
    _within_envelope(sweeps)
    for sweep in sweeps:
        _check_sweep_coherence(sweep, bands=((512, 2.0, 10.0),))


@pytest.mark.slow
def test_full_data_sets_envelope_and_sweep_coherence(truth_source):
    sets = truth_source.generate_many(["hover", "forward"])
    assert [len(s) for s in sets] == [20, 20]
    for maneuvers in sets:
        _within_envelope(maneuvers)
        for sweep in maneuvers.select(kind="sweep"):
            _check_sweep_coherence(sweep)


def test_truth_model_integration_resolves_the_rotor_modes(truth_source):
    """RK4 at the default 0.01 s against 4× finer steps, noise-free: the outputs agree to
    a few hundredths of the sensor noise σ on every channel."""
    settings = {"condition": "hover", "kinds": ["3211"], "axes": ["lat"], "directions": [1],
                "quick": True, "noise": {c: 0.0 for c in SensorNoise().sigma}}
    [coarse] = truth_source.generate({**settings, "substeps": 2})
    [fine] = truth_source.generate({**settings, "substeps": 8})
    assert np.abs(fine.channel("p")).max() > 3.0  # a real roll response (deg/s)
    error = np.abs(coarse.outputs - fine.outputs).max(axis=0)
    assert np.all(error <= 0.05 * SensorNoise().vector), error


@pytest.mark.parametrize("condition", ["hover", "forward"])
def test_truth_model_loops_are_stable(truth_source, condition):
    """Closed-loop eigenvalues of the linearised truth model with each maneuver's loops."""
    from rotorid_helisim import loops

    plant = truth_source.plant
    point = truth_source.trim(resolve_case(condition).airspeed_kt)
    a, b = loops.jacobians(plant, point.state, point.stick)
    step = 1e-6
    feedback = np.array([
        (loops.feedback((point.state + step * e)[None], point.state, plant.state_names)
         - loops.feedback((point.state - step * e)[None], point.state, plant.state_names))[0]
        / (2 * step) for e in np.eye(plant.n_states)]).T
    model = loops.quasi_steady_model(plant, point.state, point.stick)
    theta0 = point.state[plant.state_names.index("theta")]
    for excited in (None, *AXES):
        gains = loops.design_loops(model, loops.LoopDesign(), excited, theta0).matrix
        assert np.linalg.eigvals(a - b @ gains @ feedback).real.max() < -0.02, excited


def test_cases_from_attrs_objects_and_physics_conveniences(truth_source):
    import attrs

    @attrs.frozen
    class Case:
        condition: str = "forward"
        airspeed_kt: float = 70.0
        seed: int = 9
        name: str = "ignored: not a data-set setting"

    config = resolve_case(Case())
    assert (config.condition, config.airspeed_kt, config.seed) == ("forward", 70.0, 9)
    point = truth_source.trim(70.0)
    assert point.state.shape == (truth_source.plant.n_states,) and point.stick.shape == (4,)
    linear = truth_source.linearize(0.0)
    assert linear.airspeed_kt == 0.0
    assert linear.eigenvalues.real.max() > 0.1  # the unstable hover phugoid
