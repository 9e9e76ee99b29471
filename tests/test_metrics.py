"""RMSE (paper eq. 18), J_rms and Theil's inequality coefficient on hand-computed cases."""

import numpy as np
import pytest
from rotorid.data import Maneuver, ManeuverSet
from rotorid.errors import DataError
from rotorid.verification.metrics import j_rms, rmse, tic, time_domain_metrics


def test_rmse_and_j_rms_hand_computed():
    measured = np.array([[1.0, 2.0], [3.0, 4.0]])
    simulated = np.array([[0.0, 2.0], [3.0, 1.0]])
    # residuals 1, 0, 0, 3 → sqrt((1 + 9)/4)
    assert rmse(measured, simulated) == pytest.approx(np.sqrt(10 / 4))
    assert j_rms(measured, simulated, remove_bias=False) == pytest.approx(np.sqrt(10 / 4))
    # weights multiply the squared residuals per output: (4·1 + 1·9)/4
    assert j_rms(measured, simulated, weights=[4.0, 1.0], remove_bias=False) == \
        pytest.approx(np.sqrt(13 / 4))
    # a pure per-record bias is removed by the J_rms procedure, not by RMSE
    biased = [measured, measured + 1.0], [measured + 2.0, measured - 3.0]
    assert j_rms(*biased) == pytest.approx(0.0, abs=1e-12)
    assert rmse(*biased) == pytest.approx(np.sqrt((4 + 4 + 4 + 4 + 16 * 4) / 8))


def test_tic_hand_computed():
    measured = np.array([[1.0, 0.0], [-1.0, 0.0]])
    simulated = np.array([[0.5, 0.0], [-0.5, 0.0]])
    # output 1: RMS error 0.5, RMS 1 and 0.5 → 0.5/1.5; output 2 silent in both → 0
    assert tic(measured, simulated) == pytest.approx([1 / 3, 0.0])
    assert tic(measured, measured) == pytest.approx([0.0, 0.0])
    assert tic(measured, -measured)[0] == pytest.approx(1.0)
    assert tic(measured, simulated, per_output=False) == pytest.approx(1 / 3)


def test_metrics_per_maneuver_and_pooled():
    t = np.arange(0.0, 2.0, 0.1)
    rng = np.random.default_rng(0)
    maneuvers = ManeuverSet([
        Maneuver(f"m{i}", t, rng.standard_normal((t.size, 4)), rng.standard_normal((t.size, 8)))
        for i in range(2)])
    simulated = [m.outputs + 0.5 * (i + 1) * np.sign(rng.standard_normal(m.outputs.shape))
                 for i, m in enumerate(maneuvers)]
    metrics = time_domain_metrics(maneuvers, simulated)
    assert [m.rmse for m in metrics.maneuvers] == pytest.approx([0.5, 1.0])
    assert metrics.maneuvers[1].rmse_per_output == pytest.approx(np.ones(8))
    assert metrics.rmse == pytest.approx(np.sqrt((0.25 + 1.0) / 2))
    assert metrics.overall.rmse_per_output == pytest.approx(np.full(8, np.sqrt(0.625)))
    assert metrics.tic.shape == (8,)
    assert metrics.tic == pytest.approx(tic([m.outputs for m in maneuvers], simulated))
    assert "m0" in metrics.report() and metrics.summary()["maneuvers"][1]["rmse"] == 1.0
    with pytest.raises(DataError, match="one simulated array per maneuver"):
        rmse([maneuvers[0].outputs], [])
    with pytest.raises(DataError, match="NaN"):
        rmse(np.full((2, 2), np.nan), np.zeros((2, 2)))
    with pytest.raises(DataError, match="one shape"):
        rmse(np.zeros((2, 2)), np.zeros((3, 2)))
