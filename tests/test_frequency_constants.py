"""The constants of the frequency-domain method, each against a hand-computed or statistical
reference: the random-error formula and its calibration, the composite's 1/ε_r² weighting
and window coverage, and the coherence threshold of the envelopes."""

import math

import numpy as np
import pytest
import rotorid
from rotorid.verification.frequency import (
    MisoEstimate,
    Spectra,
    composite,
    estimate_responses,
    log_grid,
    miso_response,
    random_error,
)
from sweeps import DT, analytic, respond

ROLL = ([20.0], [1.0, 4.0])


def test_random_error_formula_by_hand():
    # γ² = 0.64, n_d = 10.5: sqrt(0.36) / (0.8 · sqrt(21)).
    assert random_error(np.array([0.64]), 10.5)[0] == pytest.approx(0.6 / (0.8 * math.sqrt(21)))
    # One conditioning input takes one average away: sqrt(2 (10.5 − 1)) = sqrt(19).
    assert random_error(np.array([0.64]), 10.5, 1)[0] == pytest.approx(0.6 / (0.8 * math.sqrt(19)))
    assert random_error(np.array([0.0]), 10.5)[0] == np.inf


def test_two_input_random_error_counts_one_conditioning_input():
    rng = np.random.default_rng(2)
    a = rng.standard_normal((3, 5)) + 1j * rng.standard_normal((3, 5))
    g = (a.conj() @ a.T)[None]
    result = miso_response(Spectra(np.array([1.0]), g, 10.0, 8, 6.0))
    gamma2 = result.coherence[0]
    np.testing.assert_allclose(result.random_error[0],
                               np.sqrt(1 - gamma2) / np.sqrt(gamma2 * 2 * (6.0 - 1)), rtol=1e-12)


def _window(response, error, coherence=0.9):
    """A one-input window estimate at two frequencies with the given response and error."""
    column = lambda values: np.array(values, dtype=complex)[:, None]  # noqa: E731
    return MisoEstimate(column(response), column([coherence] * 2).real,
                        np.full(2, coherence), column(error).real, np.zeros((2, 1)))


def test_composite_weights_each_window_by_its_inverse_squared_random_error():
    # Windows of 20 s and 10 s estimate from ω ≥ 4π/20 = 0.63 and 4π/10 = 1.26 rad/s.
    omega = np.array([1.0, 2.0])
    long = _window([1.0 + 1.0j, 2.0], [0.1, 0.1])
    short = _window([9.0, 4.0 - 1.0j], [0.5, 0.2])
    merged = composite([long, short], [20.0, 10.0], omega)
    # At 1 rad/s only the long window counts; at 2 rad/s the weights 1/0.1² = 100 and
    # 1/0.2² = 25 give shares 0.8 and 0.2.
    np.testing.assert_allclose(merged.response[:, 0], [1.0 + 1.0j, 0.8 * 2.0 + 0.2 * (4.0 - 1.0j)],
                               rtol=1e-12)
    np.testing.assert_allclose(merged.random_error[:, 0], [0.1, 0.8 * 0.1 + 0.2 * 0.2],
                               rtol=1e-12)
    uncovered = composite([long, short], [20.0, 10.0], np.array([0.5, 0.6]))
    assert np.all(np.isnan(uncovered.response))


def test_random_error_is_calibrated_over_many_realisations():
    """Over 40 independent white-noise records through a first-order roll response with
    output noise (γ² 0.75–0.96, about 24 independent averages), the magnitude and phase
    errors divided by ε_r have mean square 1 and about 68 % of them lie within ±1: a random
    error off by √2 would give 0.5 or 2, and 52 % or 84 %."""
    omega = log_grid(1.5, 10.0, 15)
    truth = analytic(*ROLL, omega)
    rng = np.random.default_rng(7)
    normalised = []
    for _ in range(40):
        x = rng.standard_normal(6000)
        y = respond(*ROLL, x)
        y = y + np.std(y) * rng.standard_normal(x.size)
        estimate = estimate_responses([np.column_stack([x, y])], DT, ["lat"], "p", omega,
                                      windows=(10.0,))[0]
        ratio = estimate.response / truth
        errors = np.concatenate([np.abs(ratio) - 1.0, np.angle(ratio)])
        normalised.append(errors / np.tile(estimate.random_error, 2))
    normalised = np.concatenate(normalised)
    assert 0.8 <= np.mean(normalised**2) <= 1.25
    assert 0.6 <= np.mean(np.abs(normalised) <= 1.0) <= 0.77


def test_every_bound_envelope_counts_points_from_the_coherence_threshold():
    for name in ("muad", "aee"):
        assert rotorid.create("validation-envelopes", name).threshold == 0.8, name
    muad = rotorid.create("validation-envelopes", "muad")
    check = muad.check(np.ones(2, dtype=complex), np.array([0.7999, 0.8]), np.array([1.0, 2.0]))
    assert check.used.tolist() == [False, True]
    # The mismatch cost keeps Tischler's own range rule (γ² ≥ 0.6).
    assert rotorid.create("validation-envelopes", "mismatch-cost").threshold == 0.6
