"""Frequency responses from time histories against scipy, closed forms and known systems."""

import numpy as np
import pytest
from rotorid.data import Maneuver, ManeuverSet
from rotorid.errors import VerificationError
from rotorid.verification.frequency import (
    Spectra,
    cross_spectra,
    default_windows,
    effective_averages,
    estimate_responses,
    influential_inputs,
    log_grid,
    miso_response,
    moving_inputs,
    response_from_maneuvers,
)
from scipy import signal
from sweeps import DT, analytic, log_sweep, respond

ROLL = ([20.0], [1.0, 4.0])          # p/lat-like first-order rate response
PITCH = ([8.0], [1.0, 2.0, 4.0])     # second order, ζ = 0.5, ω_n = 2 rad/s


def test_log_grid_and_default_windows():
    grid = log_grid(0.1, 10.0, 3)
    assert np.allclose(grid, [0.1, 1.0, 10.0])
    assert np.allclose(default_windows(90.0), [45.0, 30.9, 21.22, 14.56, 10.0], atol=0.01)
    with pytest.raises(VerificationError, match="omega_min < omega_max"):
        log_grid(1.0, 0.5)


def test_effective_averages_closed_forms():
    taper = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(100) / 100)
    assert effective_averages(7, taper, hop=100) == pytest.approx(7.0)
    # 50 % overlap of a Hann window: ρ(1) = 1/6 exactly, ρ(j ≥ 2) = 0.
    n = 40
    assert effective_averages(n, taper, hop=50) == pytest.approx(
        n / (1 + 2 * (1 - 1 / n) / 36))


def test_cross_spectra_match_scipy_on_fft_bins():
    rng = np.random.default_rng(11)
    x = rng.standard_normal(3000)
    y = np.convolve(x, [0.5, 0.3, 0.2], mode="same") + 0.1 * rng.standard_normal(3000)
    nper, hop = 500, 100
    freqs = np.arange(1, 60) / (nper * DT)
    spectra = cross_spectra([np.column_stack([x, y])], DT, 2 * np.pi * freqs, nper * DT,
                            overlap=1 - hop / nper)
    options = dict(fs=1 / DT, window="hann", nperseg=nper, noverlap=nper - hop,
                   detrend="constant")
    _, pxx = signal.welch(x, **options)
    _, pxy = signal.csd(x, y, **options)
    assert np.allclose(spectra.matrix[:, 0, 0].real, pxx[1:60], rtol=1e-9)
    assert np.allclose(spectra.matrix[:, 0, 1], pxy[1:60], rtol=1e-9)
    _, coherence = signal.coherence(x, y, **options)
    ours = miso_response(spectra).coherence[:, 0]
    assert np.allclose(ours, coherence[1:60], rtol=1e-9)


def _noisy_records(system, n_records, noise, seed, delay=0.0):
    rng = np.random.default_rng(seed)
    u = log_sweep()
    records = []
    for k in range(n_records):
        x = (-1) ** k * u + 0.05 * rng.standard_normal(u.size)
        y = respond(*system, x, delay=delay)
        records.append(np.column_stack([x, y + noise * np.std(y) * rng.standard_normal(
            u.size)]))
    return records


def _normalised_errors(estimate, truth):
    """Magnitude and phase errors of the coherent points in units of ε_r (each component
    of the complex error has standard deviation ε_r)."""
    ok = estimate.coherence >= 0.8
    ratio = estimate.response[ok] / truth[ok]
    errors = np.concatenate([np.abs(np.abs(ratio) - 1.0), np.abs(np.angle(ratio))])
    return errors / np.tile(estimate.random_error[ok], 2), int(ok.sum())


def _assert_within_random_error(estimate, truth, min_points):
    normalised, n_coherent = _normalised_errors(estimate, truth)
    assert n_coherent >= min_points
    # ε_r is one standard deviation (calibrated over many records in
    # test_frequency_constants.py): nearly all errors lie inside 3σ.
    assert np.mean(normalised <= 3.0) >= 0.95
    assert normalised.max() <= 5.0


@pytest.mark.parametrize("system", [ROLL, PITCH], ids=["first-order", "second-order"])
def test_siso_estimate_within_random_error_of_analytic(system):
    omega = log_grid(0.4, 12.0, 60)
    response = estimate_responses(_noisy_records(system, 2, 0.2, seed=5), DT, ["lat"], "p",
                                  omega)[0]
    _assert_within_random_error(response, analytic(*system, omega), 40)


def test_conditioned_estimate_separates_correlated_inputs():
    rng = np.random.default_rng(21)
    u = log_sweep()
    h1, h2 = ROLL, ([6.0], [1.0, 1.5])
    records = []
    for k in range(2):
        x1 = (-1) ** k * u + 0.05 * rng.standard_normal(u.size)
        # secondary input: a stabilising loop reacting to x1 plus its own movement
        x2 = 0.5 * respond([2.0], [1.0, 2.0], x1) + rng.standard_normal(u.size)
        y = respond(*h1, x1) + respond(*h2, x2)
        records.append(np.column_stack([x1, x2, y + 0.1 * np.std(y) * rng.standard_normal(
            u.size)]))
    omega = log_grid(0.4, 10.0, 40)
    conditioned = estimate_responses(records, DT, ["lat", "long"], "p", omega)
    for estimate, system in zip(conditioned, (h1, h2)):
        _assert_within_random_error(estimate, analytic(*system, omega), 15)
    # the loop makes the inputs strongly correlated at low frequency, weakly at high
    input_coherence = conditioned[0].input_coherence
    assert np.nanmax(input_coherence) > 0.9 and np.nanmin(input_coherence) < 0.1
    siso = estimate_responses([r[:, [0, 2]] for r in records], DT, ["lat"], "p", omega)[0]
    assert np.all(siso.input_coherence == 0)
    normalised, _ = _normalised_errors(siso, analytic(*h1, omega))
    # the SISO estimate is biased by the correlated second input far beyond its error
    assert np.mean(normalised > 3.0) > 0.3 and normalised.max() > 10.0


def test_partial_coherence_matches_two_input_formula():
    rng = np.random.default_rng(2)
    a = rng.standard_normal((3, 5)) + 1j * rng.standard_normal((3, 5))
    g = (a.conj() @ a.T)[None]  # G_ij = Σ a_i* a_j: Hermitian positive definite, (1, 3, 3)
    result = miso_response(Spectra(np.array([1.0]), g, 10.0, 5, 5.0))
    g11, g22, gyy = g[0, 0, 0].real, g[0, 1, 1].real, g[0, 2, 2].real
    g12, g1y, g2y = g[0, 0, 1], g[0, 0, 2], g[0, 1, 2]
    assert result.input_coherence[0] == pytest.approx([abs(g12) ** 2 / (g11 * g22)] * 2)
    g11_2 = g11 - abs(g12) ** 2 / g22
    g1y_2 = g1y - g12 * g2y / g22
    gyy_2 = gyy - abs(g2y) ** 2 / g22
    assert result.response[0, 0] == pytest.approx(g1y_2 / g11_2)
    assert result.coherence[0, 0] == pytest.approx(abs(g1y_2) ** 2 / (g11_2 * gyy_2))
    h = result.response[0]
    assert result.multiple_coherence[0] == pytest.approx(
        (np.array([g1y, g2y]).conj() @ h).real / gyy)


def _maneuver(name, inputs, outputs, axis="lat"):
    n = inputs.shape[0]
    return Maneuver(name, np.arange(n) * DT, inputs, outputs, {"axis": axis})


def test_maneuver_front_end_conditioning_and_errors():
    rng = np.random.default_rng(4)
    u = log_sweep(duration=60.0)
    inputs = np.zeros((u.size, 4))
    inputs[:, 1] = u
    inputs[:, 0] = 0.3 * rng.standard_normal(u.size)
    outputs = np.zeros((u.size, 8))
    outputs[:, 5] = respond(*ROLL, u) + respond([3.0], [1.0, 2.0], inputs[:, 0])
    sweeps = ManeuverSet([_maneuver("lat1", inputs, outputs)])
    assert moving_inputs(sweeps, "lat") == ("long",)
    omega = log_grid(0.5, 8.0, 30)
    response = response_from_maneuvers(sweeps, "lat", "p", omega, conditioned_on=("long",))
    assert response.pair == "p/lat" and response.conditioned_on == ("long",)
    ok = response.coherence >= 0.8
    assert np.allclose(response.response[ok], analytic(*ROLL, omega)[ok], rtol=0.05)
    # a model output that does not respond: zero response and coherence, no error
    silent = response_from_maneuvers(sweeps, "lat", "q", omega)
    assert np.all(silent.response[np.isfinite(silent.response)] == 0)
    assert np.all(silent.coherence[np.isfinite(silent.coherence)] == 0)
    with pytest.raises(VerificationError, match="unknown output 'qq'"):
        response_from_maneuvers(sweeps, "lat", "qq", omega)
    with pytest.raises(VerificationError, match="did not move"):
        response_from_maneuvers(sweeps, "lat", "p", omega, conditioned_on=("ped",))
    with pytest.raises(VerificationError, match="no record is as long"):
        response_from_maneuvers(sweeps, "lat", "p", omega, windows=(500.0,))
    with pytest.raises(VerificationError, match="proportional"):
        estimate_responses([np.column_stack([u, 2 * u, u])], DT, ["lat", "long"], "p", omega,
                           windows=(20.0,))
    with pytest.raises(VerificationError, match="NaN"):
        cross_spectra([np.column_stack([u, u * np.nan])], DT, omega, 20.0)


def test_influential_inputs_weigh_each_input_by_the_models_response():
    """With constant responses h and a second input c times the first, the second's share
    is exactly c·|h_2/h_1|: in when that exceeds the fraction, out when not."""
    u = log_sweep(duration=30.0)
    inputs = np.column_stack([u, 0.02 * u, np.zeros_like(u), 0.5 * u])
    sweeps = ManeuverSet([_maneuver("long1", inputs, np.zeros((u.size, 8)), axis="long")])
    omega = log_grid(0.5, 8.0, 20)
    model = np.tile(np.array([1.0, 3.0, 100.0, -0.09j]), (omega.size, 1))
    # lat: 0.02·3 = 0.06 > 0.05; ped: 0.5·0.09 = 0.045 < 0.05; coll does not move
    assert influential_inputs(sweeps, "long", omega, model, ("long", "lat", "coll", "ped")) \
        == ("lat",)
    assert influential_inputs(sweeps, "long", omega, model, ("long", "lat", "coll", "ped"),
                              fraction=0.044) == ("lat", "ped")
    assert influential_inputs(sweeps, "long", omega, 0 * model,
                              ("long", "lat", "coll", "ped")) == ()
    with pytest.raises(VerificationError, match="unknown input 'pitch'"):
        influential_inputs(sweeps, "pitch", omega, model, ("long", "lat", "coll", "ped"))


def test_noise_free_output_fully_coherent_with_two_inputs_does_not_break_conditioning():
    """A simulated model output is an exact linear function of its inputs."""
    from rotorid.verification.frequency import cross_spectra, miso_response

    rng = np.random.default_rng(3)
    n, dt = 4000, 0.02
    u1 = rng.normal(size=n)
    u2 = 0.5 * u1 + rng.normal(size=n)
    y = np.convolve(u1, [0.5, 0.3, 0.1])[:n] + np.convolve(u2, [0.2, -0.1])[:n]
    omega = np.linspace(0.5, 10.0, 20)
    spectra = cross_spectra([np.column_stack([u1, u2, y])], dt, omega, window=20.0)
    estimate = miso_response(spectra)
    assert np.all(np.isfinite(estimate.coherence))
    assert np.all(estimate.coherence > 0.999)
