"""The flight harness on the linear stand-in plant: integration, loops, sensors, caching."""

import math

import numpy as np
import pytest
from rotorid.errors import DataError
from rotorid_helisim import loops
from rotorid_helisim.datasets import DataSetConfig
from rotorid_helisim.flight import fly
from rotorid_helisim.linear_plant import LinearHoverPlant
from rotorid_helisim.sensors import SensorNoise
from rotorid_helisim.source import HelisimSource
from rotorid_signals.signals import Multistep
from scipy.integrate import solve_ivp

DT = 0.02


@pytest.fixture(scope="module")
def plant():
    return LinearHoverPlant()


def _gains(plant, excited):
    model = loops.quasi_steady_model(plant, plant.trim.state, plant.trim.stick)
    theta0 = plant.trim.state[plant.state_names.index("theta")]
    return loops.design_loops(model, loops.LoopDesign(), excited, theta0)


def _pilot(n, axis, signal):
    pilot = np.zeros((1, n, 4))
    pilot[0, :, axis] = signal(np.arange(n) * DT)
    return pilot


def _reference_flight(plant, pilot, gains, n):
    """The same digital loop, integrated sample by sample with solve_ivp (DOP853)."""
    x = plant.trim.state.copy()
    states = [x]
    for k in range(n - 1):
        error = loops.feedback(x[None], plant.trim.state, plant.state_names)[0]
        stick = plant.trim.stick + pilot[k] - gains @ error
        solution = solve_ivp(lambda t, y: plant.derivatives(y[None], stick[None])[0],
                             (0.0, DT), x, method="DOP853", rtol=1e-11, atol=1e-12)
        x = solution.y[:, -1]
        states.append(x)
    return np.array(states)


@pytest.mark.parametrize("excited, axis", [("long", 0), ("ped", 3)])
def test_rk4_flight_matches_solve_ivp(plant, excited, axis):
    n = 300
    signal = Multistep("3211", 4.0, 0.3, start=0.5, trailing=2.0, sample_time=DT)
    pilot = _pilot(n, axis, signal)
    gains = _gains(plant, excited).matrix
    record = fly(plant, plant.trim.state, plant.trim.stick, pilot, [n], gains[None], DT,
                 substeps=4)
    reference = _reference_flight(plant, pilot[0], gains, n)
    scale = np.abs(reference - plant.trim.state).max(axis=0) + 1e-3
    error = np.abs(record.states[0] - reference).max(axis=0) / scale
    assert error.max() < 1e-5
    assert np.abs(record.states[0, :, plant.state_names.index("theta")]
                  - plant.trim.state[7]).max() > 1e-3  # the maneuver did move the aircraft


def test_recorded_stick_is_pilot_plus_loops_held_between_samples(plant):
    n = 250
    signal = Multistep("2311", -3.0, 0.3, start=0.5, trailing=1.0, sample_time=DT)
    pilot = _pilot(n, 1, signal)
    gains = _gains(plant, "lat").matrix
    record = fly(plant, plant.trim.state, plant.trim.stick, pilot, [n], gains[None], DT)
    loop = -loops.feedback(record.states[0], plant.trim.state, plant.state_names) @ gains.T
    np.testing.assert_allclose(record.stick[0], plant.trim.stick + pilot[0] + loop, atol=1e-12)
    assert np.abs(loop).max() > 0.1  # the loops were active
    # Between samples the actuator integrates the held stick: with a first-order lag the
    # actuator state one sample later is the exact ZOH response to the recorded stick.
    act = plant.state_names.index("act_lat")
    decay = math.exp(-DT / 0.03)
    predicted = (record.states[0, :-1, act] * decay
                 + record.stick[0, :-1, 1] * (1 - decay))
    np.testing.assert_allclose(record.states[0, 1:, act], predicted, atol=5e-5)  # RK4 error


@pytest.mark.parametrize("excited", [None, "long", "lat", "coll", "ped"])
def test_loops_stabilise_the_linearised_plant(plant, excited):
    a, b = loops.jacobians(plant, plant.trim.state, plant.trim.stick)
    bare = np.linalg.eigvals(a).real.max()
    assert bare > 0.2  # the hover phugoid is unstable without the loops
    step = 1e-6
    feedback = np.array([
        (loops.feedback((plant.trim.state + step * e)[None], plant.trim.state, plant.state_names)
         - loops.feedback((plant.trim.state - step * e)[None], plant.trim.state,
                          plant.state_names))[0] / (2 * step)
        for e in np.eye(plant.n_states)]).T
    closed = a - b @ _gains(plant, excited).matrix @ feedback
    assert np.linalg.eigvals(closed).real.max() < -0.005


def test_pitch_loop_gain_follows_the_design_crossover(plant):
    """Broken-loop response of the gentle pitch loop on the full linear plant (actuators and
    every coupling included, other loops open): above the phugoid it behaves as ω_c/ω, the
    integrator-like loop the design law aims at, and it stays below 0 dB from 1 rad/s up."""
    a, b = plant.linear_model()
    gains = _gains(plant, "long").matrix[0]
    names = plant.state_names
    c = np.zeros((1, plant.n_states))
    for signal in ("theta", "q", "u"):
        c[0, names.index(signal)] = gains[loops.FEEDBACK.index(signal)]
    eye = np.eye(plant.n_states)

    def magnitude(w):
        return abs((c @ np.linalg.solve(1j * w * eye - a, b[:, :1]))[0, 0])

    crossover = loops.LoopDesign().excited_crossover
    for w in (2.0, 3.0, 5.0):
        assert magnitude(w) * w / crossover == pytest.approx(1.0, rel=0.2)
    assert max(magnitude(w) for w in np.logspace(0, 1.5, 50)) < 1.0


def test_sensor_noise_sigma_and_seed(plant, tmp_path):
    source = HelisimSource(plant, trimmer=lambda p, kt: p.trim)
    settings = {"condition": "hover", "kinds": ["3211"], "axes": ["lat"],
                "duration_scale": 0.6}
    clean = source.generate({**settings, "noise": {c: 0.0 for c in SensorNoise().sigma}})
    noisy = source.generate({**settings, "seed": 7})
    again = source.generate({**settings, "seed": 7})
    other = source.generate({**settings, "seed": 8})
    residual = np.concatenate([n.outputs - c.outputs for n, c in zip(noisy, clean)])
    np.testing.assert_allclose(residual.std(axis=0), SensorNoise().vector, rtol=0.08)
    assert np.abs(residual.mean(axis=0)).max() < 0.02
    for a, b, c in zip(noisy, again, other):
        np.testing.assert_array_equal(a.outputs, b.outputs)
        assert not np.array_equal(a.outputs, c.outputs)
        np.testing.assert_array_equal(a.inputs, c.inputs)  # noise never feeds the flight


def test_sensor_noise_rejects_unknown_channels_and_negative_sigma():
    with pytest.raises(DataError, match="unknown channel"):
        SensorNoise({"nz": 0.1})
    with pytest.raises(DataError, match="≥ 0"):
        SensorNoise({"q": -1.0})


class CountingPlant(LinearHoverPlant):
    calls = 0

    def derivatives(self, x, stick):
        CountingPlant.calls += 1
        return super().derivatives(x, stick)


def test_cache_reuses_files_until_the_configuration_changes(tmp_path):
    plant = CountingPlant()
    source = HelisimSource(plant, trimmer=lambda p, kt: p.trim, cache_dir=tmp_path)
    settings = {"condition": "hover", "kinds": ["2311"], "axes": ["coll"], "quick": True}
    first = source.generate(settings)
    flown = CountingPlant.calls
    assert flown > 0 and (tmp_path / "hover" / "manifest.json").is_file()
    second = source.generate(settings)
    assert CountingPlant.calls == flown  # read back, not flown again
    for a, b in zip(first, second):
        assert a.name == b.name and a.metadata == b.metadata
        np.testing.assert_array_equal(a.outputs, b.outputs)
        np.testing.assert_array_equal(a.inputs, b.inputs)
    source.generate({**settings, "seed": 3})
    assert CountingPlant.calls > flown  # a new seed means a new data set
    source.generate({**settings, "directions": [1]})  # a smaller selection replaces the files
    assert sorted(p.name for p in (tmp_path / "hover").glob("*.npz")) == [
        "hover_2311_coll_pos.npz"]


def test_config_digest_covers_every_setting():
    base = DataSetConfig()
    variants = [DataSetConfig(seed=1), DataSetConfig(sample_rate=100.0),
                DataSetConfig(amplitude={"long": 6.0}), DataSetConfig(noise=SensorNoise({"q": 0.2})),
                DataSetConfig(loops=loops.LoopDesign(crossover=0.7)),
                DataSetConfig(duration_scale=0.5)]
    digests = {base.digest("p")} | {v.digest("p") for v in variants}
    assert len(digests) == len(variants) + 1
    assert base.digest("p") == DataSetConfig().digest("p")
    assert base.digest("p") != base.digest("other plant")


def test_loops_keep_the_stand_in_near_trim_through_the_full_data_set(plant):
    source = HelisimSource(plant, trimmer=lambda p, kt: p.trim)
    maneuvers = source.generate("hover")
    assert len(maneuvers) == 20
    for maneuver in maneuvers:
        excursion = maneuver.metadata["excursion"]
        assert max(excursion["theta_deg"], excursion["phi_deg"]) <= 10.0, maneuver.name
        assert max(excursion[k] for k in ("airspeed_kt", "u_kt", "v_kt", "w_kt")) <= 10.0
        # Back near trim at the end of the record.
        assert np.abs(maneuver.outputs[-50:, [3, 6]]).max() < 3.0, maneuver.name


def test_other_sample_rates(plant):
    source = HelisimSource(plant, trimmer=lambda p, kt: p.trim)
    [maneuver] = source.generate({"kinds": ["3211"], "axes": ["long"], "directions": [1],
                                  "sample_rate": 100.0, "quick": True})
    assert maneuver.dt == pytest.approx(0.01)
    changes = maneuver.time[1:][np.diff(maneuver.inputs[:, 0]) != 0]
    assert changes.size > 20  # the loop moves the stick every sample, not only at the steps
