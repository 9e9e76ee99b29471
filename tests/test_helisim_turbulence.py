"""Dryden turbulence in the truth model: spectra, presets, seeds, the air-relative hooks and
still air unchanged."""

import math

import numpy as np
import pytest
import scipy.signal
from rotorid.errors import DataError
from rotorid.units import FOOT, KNOT
from rotorid_helisim.datasets import DataSetConfig
from rotorid_helisim.model import Bo105Model
from rotorid_helisim.source import HelisimSource, resolve_case
from rotorid_helisim.trim import trim
from rotorid_helisim.turbulence import Turbulence, gust_generator, turbulence_setting

SMALL = {"condition": "hover", "quick": True, "kinds": ["3211"], "axes": ["lat"], "seed": 3}


@pytest.mark.parametrize("speed", [5.0, 36.0])
def test_gust_spectra_match_the_dryden_psd(speed):
    """Welch spectra of a long record against the closed-form one-sided PSDs, band by band
    (ω from 0.3 rad/s, a hundred Welch bins, to a quarter of the Nyquist frequency)."""
    turbulence = Turbulence((2.0, 1.5, 1.0), (150.0, 100.0, 30.0))
    dt = 0.05
    gusts = turbulence.gusts(2**17, dt, speed, np.random.default_rng(7))
    frequency, density = scipy.signal.welch(gusts, fs=1 / dt, nperseg=4096, axis=0)
    omega = 2 * np.pi * frequency
    measured = density / (2 * np.pi)                # per Hz → per rad/s
    expected = turbulence.psd(omega, speed)
    edges = np.geomspace(0.3, np.pi / dt / 4, 6)
    for low, high in zip(edges[:-1], edges[1:]):
        band = (omega >= low) & (omega < high)
        ratio = measured[band].mean(axis=0) / expected[band].mean(axis=0)
        assert np.all(np.abs(ratio - 1) < 0.2), (low, high, ratio)


def test_gust_variances_match_the_integrated_psd():
    turbulence = Turbulence.preset("moderate")
    speed = turbulence.speed(0.0)
    omega = np.linspace(0, 2000, 2_000_001)
    variance = np.trapezoid(turbulence.psd(omega, speed), omega, axis=0)
    assert variance[:3] == pytest.approx(np.square(turbulence.sigma), rel=1e-3)
    a, b, c = turbulence.forming_filter(speed)
    import scipy.linalg
    stationary = scipy.linalg.solve_continuous_lyapunov(a, -math.pi * b @ b.T)
    assert np.diag(c @ stationary @ c.T) == pytest.approx(variance, rel=2e-3)


def test_presets_follow_mil_f_8785c_low_altitude():
    light, moderate = Turbulence.preset("light"), Turbulence.preset("moderate")
    factor = 0.177 + 0.000823 * 100.0
    assert moderate.sigma[2] == pytest.approx(3.0 * KNOT)          # 0.1 · W20 = 3 kt
    assert moderate.sigma[0] == pytest.approx(3.0 * KNOT / factor**0.4)
    assert moderate.scale == pytest.approx((100 * FOOT / factor**1.2,) * 2 + (100 * FOOT,))
    assert light.sigma == pytest.approx(tuple(s / 2 for s in moderate.sigma))
    assert turbulence_setting("still") is None
    assert turbulence_setting({"preset": "light", "min_speed": 8.0}).min_speed == 8.0
    with pytest.raises(DataError, match="preset"):
        turbulence_setting("severe")


def test_seeds_reproduce_and_streams_differ():
    turbulence = Turbulence.preset("light")
    first = turbulence.gusts(500, 0.02, 0.0, gust_generator(4, "hover_3211_lat_pos"))
    again = turbulence.gusts(500, 0.02, 0.0, gust_generator(4, "hover_3211_lat_pos"))
    other = turbulence.gusts(500, 0.02, 0.0, gust_generator(5, "hover_3211_lat_pos"))
    assert first.tobytes() == again.tobytes()
    assert not np.allclose(first, other)
    settings = {**SMALL, "turbulence": "light"}
    source = HelisimSource()
    one, two = source.generate(settings), source.generate(settings)
    assert all(a.outputs.tobytes() == b.outputs.tobytes() for a, b in zip(one, two))
    assert one[0].metadata["turbulence"]["sigma"] == list(turbulence.sigma)


def test_a_turbulent_record_carries_the_gusts_it_flew_through(tmp_path):
    """Each turbulent record holds its maneuver's own gust draw as extra channels g_u … g_r
    (ft/s and deg/s, no sensor noise), kept through a maneuver file; still air has none."""
    from rotorid_files.formats import read_maneuver, write_maneuver

    flown = HelisimSource().generate({**SMALL, "turbulence": "light"})
    for record in flown:
        drawn = Turbulence.preset("light").gusts(record.n_samples, record.dt, 0.0,
                                                 gust_generator(SMALL["seed"], record.name))
        recorded = np.column_stack([record.channel(f"g_{c}") for c in "uvwpqr"])
        np.testing.assert_allclose(recorded[:, :3], drawn[:, :3] / FOOT, rtol=1e-12)
        np.testing.assert_allclose(recorded[:, 3:], np.degrees(drawn[:, 3:]), rtol=1e-12)
    path = write_maneuver(flown[0], tmp_path / "turbulent.csv")
    np.testing.assert_allclose(read_maneuver(path).channel("g_w"), flown[0].channel("g_w"))
    assert not set(HelisimSource().generate(SMALL)[0].extra_channels)


def test_aerodynamics_see_the_air_relative_motion():
    """A body moving at V with rates ω in still air and a body at rest in a gust of −V, −ω
    (every point meets −(V + ω × r)) carry the same aerodynamic specific force."""
    plant = Bo105Model()
    point = trim(plant, 0.0)
    moving = np.array(point.state, dtype=float)
    motion = np.array([1.5, -0.8, 0.6, 0.05, -0.04, 0.03])
    moving[:6] += motion
    still = np.array(point.state, dtype=float)
    stick = np.asarray(point.stick, dtype=float)[None]
    accelerometers = [0, 1, 4]                      # ax az ay: aerodynamic force / mass
    in_gust = plant.measurements(still[None], stick, gust=-motion[None])[:, accelerometers]
    in_motion = plant.measurements(moving[None], stick)[:, accelerometers]
    assert in_gust == pytest.approx(in_motion, rel=1e-12, abs=1e-12)


#: Per maneuver of :data:`SMALL` in still air: the RMS of each input and output channel,
#: recorded before turbulence existed (re-recorded 2026-11-27 to 12 digits when the byte hash
#: it replaces proved platform-bound: the same code on another BLAS kernel,
#: OPENBLAS_CORETYPE=Haswell or Prescott, flies arrays that differ by 4e-12 and 4e-11
#: relative, so a hash cannot tell a change of the model from the machine's round-off).
STILL_AIR_RMS = {
    "hover_3211_lat_pos": ([0.128425531357, 1.77425670549, 0.00684727906226, 0.200275160198],
                           [0.206817299880, 0.195562671110, 0.436166951655, 0.212621814434,
                            0.213172336724, 1.87527073373, 0.805023842488, 0.423243237879]),
    "hover_3211_lat_neg": ([0.128346477122, 1.77444791500, 0.0100500225364, 0.208539489327],
                           [0.223128013329, 0.204066033432, 0.430853468319, 0.216555512105,
                            0.207781941570, 1.88393352642, 0.794109783863, 0.421635497025]),
}


def test_still_air_data_are_unchanged():
    """The RMS of every channel of a still-air set, and its cache key, as recorded before
    turbulence existed: to 1e-9 relative, far above the platforms' round-off (1e-11) and far
    below any change of the model, the maneuvers or the sensors."""
    flown = HelisimSource().generate(SMALL)
    assert [m.name for m in flown] == list(STILL_AIR_RMS)
    for m in flown:
        inputs, outputs = STILL_AIR_RMS[m.name]
        assert np.sqrt(np.mean(m.inputs ** 2, axis=0)) == pytest.approx(inputs, rel=1e-9)
        assert np.sqrt(np.mean(m.outputs ** 2, axis=0)) == pytest.approx(outputs, rel=1e-9)
    assert resolve_case({**SMALL, "turbulence": "still"}).digest() == (
        "7489a568a03fa648ac02f8203cb01537fbef25362b534b11f03d30b3989b0f62")
    assert "turbulence" not in flown[0].metadata


def test_zero_intensity_turbulence_flies_as_still_air():
    calm = DataSetConfig.from_mapping({**SMALL, "turbulence": {"sigma": (0, 0, 0),
                                                               "scale": (100, 100, 30)}})
    source = HelisimSource()
    still, calm_set = source.generate(SMALL), source.generate(calm)
    assert all(a.outputs.tobytes() == b.outputs.tobytes() for a, b in zip(still, calm_set))


def test_monte_carlo_flights_in_turbulence_fly_each_seed(tmp_path):
    """In turbulence the Monte Carlo data of a seed are that seed's own flight (gusts and
    noise drawn anew): equal to the case data flown with the seed, different between seeds,
    and read back from the store the second time."""
    settings = {"condition": "hover", "quick": True, "axes": ["lat"], "turbulence": "light",
                "identification": ["3211"], "verification": []}
    source = HelisimSource()
    flights = source.noise_realisations(settings, tmp_path / "runs")
    for seed in (3, 4):
        case = source.case_data({**settings, "seed": seed}, tmp_path / f"case-{seed}")
        flown = flights(seed)
        assert [m.name for m in flown] == [m.name for m in case.identification]
        assert all(a.outputs.tobytes() == b.outputs.tobytes()
                   for a, b in zip(flown, case.identification))
    assert not np.allclose(flights(3)[0].outputs, flights(4)[0].outputs)
    assert (tmp_path / "runs" / "seed-3").is_dir()
