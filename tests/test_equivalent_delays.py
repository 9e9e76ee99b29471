"""Equivalent delays fitted to a full linear model's cyclic responses.

References: a full model that is the residualised one (the fit is then exact with no delay), the
residualised model with its cyclic inputs delayed through a high-order Padé approximant (the fit
must return that delay on the control terms and none on the rate terms), and the Bo-105 truth
model (the time-domain identification is compared with its fit in tests/test_report.py).
"""

from __future__ import annotations

import math

import attrs
import numpy as np
import pytest
import rotorid
import scipy.interpolate
import scipy.signal
from rotorid.errors import StructureError
from rotorid.model.structure import STATES
from rotorid.verification.equivalent_delays import equivalent_delays

CONTROLS = ("long", "lat", "coll", "ped")


@attrs.frozen
class Linear:
    states: tuple
    controls: tuple
    A: np.ndarray
    B: np.ndarray


def residualised_model():
    """A stable coupled 8-state model with helicopter-like roll/pitch terms."""
    rng = np.random.default_rng(3)
    a = rng.normal(size=(8, 8)) * 0.05
    q, p = STATES.index("q"), STATES.index("p")
    a[np.diag_indices(8)] = -0.6
    a[q, q], a[p, p], a[q, p], a[p, q] = -3.5, -12.0, -0.3, 0.6
    a[STATES.index("theta"), q] = a[STATES.index("phi"), p] = 1.0
    b = rng.normal(size=(8, 4)) * 0.1
    b[q, :2], b[p, :2] = (-4.0, 1.2), (8.0, 15.0)
    return Linear(STATES, CONTROLS, a, b)


def delayed_cyclic(model, tau, order=6):
    """The model with the cyclic inputs of its q and p rows delayed by ``tau`` through an
    ``order``/``order`` Padé approximant of e^(−sτ) (relative error below 1e-9 up to
    ωτ = 0.5), realised as ``order`` extra states per cyclic input."""
    taylor = [(-1.0) ** k / math.factorial(k) for k in range(2 * order + 1)]   # e^(−x)
    numerator, denominator = scipy.interpolate.pade(taylor, order)
    powers = tau ** np.arange(order, -1, -1)                                   # x = sτ
    fa, fb, fc, fd = scipy.signal.tf2ss(numerator.coeffs * powers, denominator.coeffs * powers)
    q, p = STATES.index("q"), STATES.index("p")
    n = 8 + 2 * order
    a = np.zeros((n, n))
    a[:8, :8] = model.A
    b = np.zeros((n, 4))
    b[:8] = model.B
    for k, control in enumerate((0, 1)):
        block = slice(8 + k * order, 8 + (k + 1) * order)
        gain = model.B[[q, p], control][:, None]
        a[block, block] = fa
        b[block, control] = fb[:, 0]
        a[[q, p], block] = gain * fc[0]
        b[[q, p], control] = gain[:, 0] * fd[0, 0]
    return Linear(STATES + tuple(f"pade{i}" for i in range(2 * order)), CONTROLS, a, b)


def test_a_full_model_equal_to_the_residualised_one_needs_no_delay():
    model = residualised_model()
    fit = equivalent_delays(model, model)
    assert fit.relative_rms < 1e-8
    assert max(fit.delays.values()) < 1e-6
    assert fit.gains["M_q"] == pytest.approx(-3.5, rel=1e-6)
    assert fit.gains["L_lat"] == pytest.approx(15.0, rel=1e-6)


def test_a_delay_on_the_cyclic_is_recovered_with_the_other_terms_undelayed():
    model = residualised_model()
    fit = equivalent_delays(delayed_cyclic(model, 0.05), model)
    assert fit.relative_rms < 1e-6
    for name in ("M_long", "M_lat", "L_long", "L_lat"):
        assert fit.delays[name] == pytest.approx(0.05, abs=1e-6), name
    for name in ("M_q", "M_p", "L_q", "L_p"):
        assert fit.delays[name] < 1e-6, name
    assert fit.gains["M_long"] == pytest.approx(-4.0, rel=1e-6)
    assert fit.gains["L_p"] == pytest.approx(-12.0, rel=1e-6)


def test_bo105_cyclic_delays_are_rotor_sized_and_the_fit_is_close():
    source = rotorid.create("data-sources", "helisim")
    full = source.linearize(70.0, full=True, units="flight-test")
    fit = equivalent_delays(full, source.linearize(70.0, units="flight-test"))
    assert fit.relative_rms < 0.05
    # flap lag τ_f = 16/(γΩ) ≈ 0.07 s (truth-model.md §9): control and roll delays below it
    for name in ("M_long", "L_long", "L_lat", "L_p"):
        assert 0.0 < fit.delays[name] < 0.08, name


def test_bad_requests_are_named():
    model = residualised_model()
    with pytest.raises(StructureError, match="not \\['N_r'\\]"):
        equivalent_delays(model, model, delayed=("N_r",))
    with pytest.raises(StructureError, match="band"):
        equivalent_delays(model, model, band=(10.0, 1.0))
    with pytest.raises(StructureError, match="residualised linear model must have the states"):
        equivalent_delays(model, Linear(STATES[::-1], CONTROLS, model.A, model.B))
    with pytest.raises(StructureError, match="lacks"):
        equivalent_delays(Linear(("a",) * 8, CONTROLS, model.A, model.B), model)
