"""Cramér-Rao bounds for coloured output-error residuals (Morelli & Klein): the frequency-
domain sandwich against the double sum written out, and a Monte Carlo on coloured noise."""

import numpy as np
import pytest
import rotorid
from rotorid.estimation.coloured_residuals import (
    coloured_covariance,
    correlation_lags,
    residual_covariances,
)
from rotorid.model.modelfile import parse_model
from rotorid.simulation.simulator import simulate
from scipy.signal import lfilter


def test_the_sandwich_is_the_double_sum_over_every_pair_of_samples():
    rng = np.random.default_rng(1)
    sizes, p, n_o, lags = (37, 23), 3, 2, 5
    sensitivities = [rng.normal(size=(n, p, n_o)) for n in sizes]
    residuals = [np.cumsum(rng.normal(size=(n, n_o)), axis=0) * 0.1 for n in sizes]
    weighting = np.array([[2.0, 0.3], [0.3, 1.0]])
    information = sum(np.einsum("tpa,ab,tqb->pq", s, weighting, s) for s in sensitivities)
    covariance, used = coloured_covariance(sensitivities, residuals, weighting, information,
                                           lags=lags)
    window = 1.0 - np.arange(lags + 1) / (lags + 1.0)
    r = residual_covariances(residuals, lags) * window[:, None, None]
    middle = np.zeros((p, p))
    for s in sensitivities:
        g = np.einsum("tpa,ab->tpb", s, weighting)
        for i in range(len(g)):
            for j in range(len(g)):
                k = i - j
                if abs(k) <= lags:
                    middle += g[i] @ (r[k] if k >= 0 else r[-k].T) @ g[j].T
    inverse = np.linalg.inv(information)
    assert used == lags
    assert covariance == pytest.approx(inverse @ middle @ inverse, rel=1e-10, abs=1e-14)


def test_white_residuals_give_the_white_bounds():
    """K = 0 with Q = R⁻¹ and R the residuals' own covariance: M⁻¹ itself; and white
    residuals take no lags."""
    rng = np.random.default_rng(2)
    residuals = [rng.normal(size=(400, 2)) * [0.5, 2.0]]
    r = residual_covariances(residuals, 0)[0]
    sensitivities = [rng.normal(size=(400, 3, 2))]
    weighting = np.linalg.inv(r)
    information = np.einsum("tpa,ab,tqb->pq", sensitivities[0], weighting, sensitivities[0])
    covariance, _ = coloured_covariance(sensitivities, residuals, weighting, information,
                                        lags=0)
    assert covariance == pytest.approx(np.linalg.inv(information), rel=1e-10)
    assert correlation_lags(residuals) == 0


def test_coloured_bounds_cover_the_scatter_that_white_bounds_understate():
    """40 records of a pitch 3211 with first-order coloured sensor noise (τ 0.5 s) on q and
    θ: the white-residual bounds are more than four times smaller than the estimates'
    scatter, the coloured ones within 0.75–1.4 of it (measured 1.19 and 1.27: the residuals'
    correlation is estimated from 20 s records, whose Bartlett window and fit take a little
    of it out)."""
    structure = parse_model({"units": "flight-test", "condition": {"airspeed_kt": 0.0},
                             "structure": {"populate": "none"},
                             "derivatives": {"M_q": {}, "M_long": {}}}, "pitch")
    dt = 0.02
    time = np.arange(1001) * dt
    inputs = np.zeros((time.size, 4))
    for start, end, level in ((1, 4, 1), (4, 6, -1), (6, 7, 1), (7, 7.5, -1)):
        inputs[(time >= start) & (time < end), 0] = level
    maneuver = rotorid.Maneuver("m3211", time, inputs, np.zeros((time.size, 8)))
    clean = simulate(structure, [-2.0, 0.8], rotorid.ManeuverSet([maneuver]))[0]
    decay = np.exp(-dt / 0.5)
    estimator = rotorid.create("estimators", "output-error", outputs=("q", "theta"),
                               coloured_residuals=True)
    values, white, coloured = [], [], []
    for seed in range(40):
        drive = np.random.default_rng(seed).normal(size=clean.shape) * 0.1
        noise = lfilter([np.sqrt(1 - decay**2)], [1, -decay], drive, axis=0)
        estimate = estimator.estimate(structure,
                                      rotorid.ManeuverSet([maneuver.with_outputs(clean + noise)]))
        values.append(estimate.values)
        white.append(np.sqrt(np.diag(np.linalg.inv(estimate.information))))
        coloured.append(estimate.cramer_rao)
    scatter = np.std(values, axis=0, ddof=1)
    assert np.all(scatter / np.mean(white, axis=0) > 4.0)
    ratio = scatter / np.mean(coloured, axis=0)
    assert np.all((ratio > 0.75) & (ratio < 1.4)), ratio
    assert any("coloured residuals (Morelli & Klein)" in n for n in estimate.notes)


def test_a_maneuver_that_fits_far_worse_is_named():
    from rotorid.estimation.fit_notes import outlying_maneuvers

    rng = np.random.default_rng(3)
    residuals = [rng.normal(size=(200, 2)) * scale for scale in (1.0, 1.1, 0.9, 3.0)]
    note = outlying_maneuvers(residuals, ["a", "b", "c", "gusty"], np.eye(2))
    assert note.startswith("maneuvers fitted far worse than the others") and "gusty (" in note
    assert "a (" not in note
    assert outlying_maneuvers(residuals[:3], ["a", "b", "c"], np.eye(2)) is None


def test_a_delay_an_accelerometer_reads_directly_is_named_under_the_held_input():
    from rotorid.estimation.fit_notes import direct_delayed_terms, held_delay_note

    structure = parse_model({"units": "flight-test", "condition": {"airspeed_kt": 0.0},
                             "structure": {"populate": "none"},
                             "derivatives": {"Z_w": {}, "Z_coll": {"delay": {"initial": 0.02}},
                                             "M_q": {}, "M_long": {"delay": {"initial": 0.02}}}},
                            "heave")
    assert direct_delayed_terms(structure) == {"Z_coll": ("az",)}
    assert "Z_coll (az)" in held_delay_note(structure, "zoh")
    assert held_delay_note(structure, "foh") is None
