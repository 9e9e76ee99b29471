"""The truth model's optional rotor channels: coning and tip-path-plane tilts (docs/hybrid.md).

Off by default, so every existing data set keeps its settings, digest and numbers; when on,
the tilts agree with the truth model's own linearisation flown through the recorded sticks
(an independent simulation: scipy's exact zero-order-hold discretisation of the full linear
model with the actuator lags added by hand)."""

import attrs
import numpy as np
import pytest
from rotorid.errors import DataError
from rotorid_helisim.datasets import DataSetConfig
from rotorid_helisim.linearize import linearize
from rotorid_helisim.sensors import ROTOR_CHANNELS, ROTOR_SIGMA, SensorNoise
from rotorid_helisim.source import HelisimSource
from scipy.signal import cont2discrete

QUIET_ROTOR = {c: 0.0 for c in ROTOR_CHANNELS}


def _config(**options) -> DataSetConfig:
    return DataSetConfig.for_condition("forward", duration_scale=0.3, kinds=("3211",),
                                       axes=("long", "lat", "coll"), directions=(1,), **options)


@pytest.fixture(scope="module")
def flown(truth_model, trim_70kt):
    """(without, with rotor channels) of the same 70 kt maneuvers, rotor channels noise-free."""
    source = HelisimSource(truth_model, trimmer=lambda plant, kt: trim_70kt)
    plain = source.generate(_config())
    rotor = source.generate(_config(rotor_channels=True, noise=QUIET_ROTOR))
    return plain, rotor


def test_rotor_channels_are_off_by_default_and_leave_the_body_channels_alone(flown):
    plain, rotor = flown
    with pytest.raises(DataError, match="rotor_channels must be true or false"):
        _config(rotor_channels="yes")
    assert "rotor_channels" not in _config().as_dict()
    assert _config().digest() != _config(rotor_channels=True).digest()
    for without, with_rotor in zip(plain, rotor):
        assert not without.extra_channels
        assert sorted(with_rotor.extra_channels) == sorted(ROTOR_CHANNELS)
        assert np.array_equal(without.outputs, with_rotor.outputs)


def test_rotor_channels_follow_the_truth_models_linearisation(flown, truth_model, trim_70kt):
    """Flap angles in deg, perturbations from trim: the full linearisation (per % stick, deg)
    with first-order actuator lags on the stick, driven by each maneuver's recorded stick
    from trim. The multisteps move the disc by 0.04–0.24 deg RMS; what is left is the truth
    model's nonlinearity, 0.3–6 % of each channel's RMS (measured), checked below 10 %."""
    _, rotor = flown
    full = linearize(truth_model, trim_70kt, full=True, units="flight-test")
    n, lag = len(full.states), truth_model.config.actuator_time_constant
    a = np.block([[full.A, full.B], [np.zeros((4, n)), -np.eye(4) / lag]])
    b = np.vstack([np.zeros((n, 4)), np.eye(4) / lag])
    rows = [full.states.index(c) for c in ROTOR_CHANNELS]
    for maneuver in rotor:
        phi, gamma, *_ = cont2discrete((a, b, np.eye(n + 4), 0), maneuver.dt, "zoh")
        x, linear = np.zeros(n + 4), []
        for stick in maneuver.inputs:
            linear.append(x[rows])
            x = phi @ x + gamma @ stick
        linear = np.array(linear)
        recorded = maneuver.columns(ROTOR_CHANNELS)
        rms = np.sqrt(np.mean(recorded**2, axis=0))
        error = np.sqrt(np.mean((recorded - linear) ** 2, axis=0))
        assert rms.max() > 0.03, maneuver.name
        assert np.all(error < 0.1 * rms + 1e-3), (maneuver.name, error / rms)


def test_rotor_channels_carry_the_sensor_noise(truth_model, trim_70kt, flown):
    """Default σ ROTOR_SIGMA deg, white, from a generator of their own: the body channels'
    noise is the same as without rotor channels."""
    _, quiet = flown
    source = HelisimSource(truth_model, trimmer=lambda plant, kt: trim_70kt)
    noisy = source.generate(attrs.evolve(_config(), rotor_channels=True))
    plain = source.generate(_config())
    for clean, with_noise, body in zip(quiet, noisy, plain):
        assert np.array_equal(with_noise.outputs, body.outputs)
        noise = with_noise.columns(ROTOR_CHANNELS) - clean.columns(ROTOR_CHANNELS)
        assert np.std(noise, axis=0) == pytest.approx([ROTOR_SIGMA] * 3, rel=0.25)
    assert SensorNoise({"beta1c": 0.05}).rotor_vector.tolist() == [ROTOR_SIGMA, 0.05,
                                                                    ROTOR_SIGMA]


def test_generate_writes_rotor_channels_when_asked(tmp_path, monkeypatch, capsys):
    """``rotorid generate --rotor-channels`` asks the source for them (the flight itself is
    the one tested above)."""
    from rotorid.cli.main import main

    asked = []

    def generate_into(self, settings, directory):
        asked.append(dict(settings))
        return (), True

    monkeypatch.setattr(HelisimSource, "generate_into", generate_into)
    assert main(["generate", "hover", "--out", str(tmp_path / "a"), "--quick"]) == 0
    assert main(["generate", "hover", "--out", str(tmp_path / "b"), "--rotor-channels"]) == 0
    assert "rotor_channels" not in asked[0] and asked[1]["rotor_channels"] is True
    assert DataSetConfig.from_mapping({k: v for k, v in asked[1].items()
                                       if k != "turbulence"}).rotor_channels


def test_noise_realisations_carry_the_rotor_channels(truth_model, trim_70kt, tmp_path):
    """A Monte Carlo's data set for a seed equals (to 1e-12) the one flown with that seed,
    rotor channels included: the noise-free flight is stored once and each seed adds its
    noise."""
    source = HelisimSource(truth_model, trimmer=lambda plant, kt: trim_70kt)
    settings = {"condition": "forward", "duration_scale": 0.3, "axes": ["coll"],
                "directions": [1], "identification": ["3211"], "verification": ["2311"],
                "rotor_channels": True}
    realisations = source.noise_realisations(settings, tmp_path / "clean")
    trim_part = realisations.clean[0].columns(ROTOR_CHANNELS)[:50]  # before the first step
    assert np.abs(trim_part).max() < 1e-9
    flown = source.case_data({**settings, "seed": 4}, tmp_path / "seed-4").identification
    for drawn, reference in zip(realisations(4), flown):
        assert np.allclose(drawn.outputs, reference.outputs, rtol=0.0, atol=1e-12)
        assert np.allclose(drawn.columns(ROTOR_CHANNELS), reference.columns(ROTOR_CHANNELS),
                           rtol=0.0, atol=1e-12)
