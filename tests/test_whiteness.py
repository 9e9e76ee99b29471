"""Whiteness of innovations (rotorid.estimation.whiteness) and filter error's note on it."""

import warnings

import numpy as np
import pytest
from rotorid.errors import IdentifiabilityWarning
from rotorid.estimation.whiteness import autocorrelation, coloured_outputs, whiteness_note
from test_filter_error import SMALL_TRUTH, estimator, noisy_data, structure


def _ar1(phi: float, n: int, rng) -> np.ndarray:
    x = np.zeros(n)
    shocks = rng.standard_normal(n)
    for k in range(1, n):
        x[k] = phi * x[k - 1] + shocks[k]
    return x


def test_the_autocorrelation_of_an_ar1_sequence_is_its_closed_form():
    """ρ_k = φ^k for x_k = φ x_k−1 + e_k, pooled over records."""
    rng = np.random.default_rng(3)
    records = [np.column_stack([_ar1(0.6, 4000, rng), rng.standard_normal(4000)])
               for _ in range(5)]
    rho = autocorrelation(records, 5)
    assert rho[:, 0] == pytest.approx(0.6 ** np.arange(1, 6), abs=0.02)
    assert np.all(np.abs(rho[:, 1]) < 0.02)


def test_only_the_coloured_output_is_named_with_its_largest_correlation():
    rng = np.random.default_rng(5)
    records = [np.column_stack([rng.standard_normal(750), _ar1(0.9, 750, rng)])
               for _ in range(4)]
    [(name, rho, lag)] = coloured_outputs(records, ("q", "az"), 0.02)
    assert name == "az" and rho == pytest.approx(0.9, abs=0.05) and lag == pytest.approx(0.02)
    assert whiteness_note([r[:, :1] for r in records], ("q",), 0.02) is None


def test_filter_error_without_a_noise_model_for_a_coloured_disturbance_says_so():
    """Data with a slow Gauss-Markov pitch disturbance (2 s) fitted by filter error with no
    process noise at all: the pitch outputs' innovations are correlated, and the note names
    them; with the disturbance modelled, no such note."""
    data = noisy_data({}, disturbances={"q": (3.0, 2.0)})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        bare = estimator(process_noise=()).estimate(structure(), data)
        modelled = estimator(process_noise=(), disturbances=("q",)).estimate(
            structure(), data, start={**SMALL_TRUTH, "D_q": 3.0, "T_q": 2.0})
    [note] = [n for n in bare.notes if n.startswith("innovations not white")]
    assert "q (ρ" in note and "theta (ρ" in note
    assert not [n for n in modelled.notes if n.startswith("innovations not white")]
