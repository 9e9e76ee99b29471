"""The Gauss-Newton products F = Σ Jᵀ Q J, G = −Σ Jᵀ Q e computed without storing J.

Reference: the same sums formed explicitly from the stored sensitivities (themselves checked
against central differences in test_simulation.py), summed sample by sample with einsum.
"""

from __future__ import annotations

import numpy as np
import pytest
from rotorid import Maneuver, ManeuverSet, ModelStructure
from rotorid.errors import DataError
from rotorid.estimation.models import LinearModel, gauss_newton_products
from rotorid.simulation.simulator import Simulator, weighting_factor
from test_simulation import CONDITION, multistep_inputs, stable_values

DELAYS = {"tau_L_lat": 0.061, "tau_M_q": 0.013, "tau_X_long": 0.005}


def problem(hold="zoh"):
    """A delayed structure, maneuvers of unequal length and two sample times, residuals."""
    structure = ModelStructure.six_dof(CONDITION).with_delays([n[4:] for n in DELAYS])
    values = stable_values(structure, delays=DELAYS)
    rng = np.random.default_rng(4)
    maneuvers = []
    for name, (n, dt, seed) in {"a": (150, 0.02, 1), "b": (110, 0.02, 2),
                                "c": (90, 0.025, 3)}.items():
        t, u = multistep_inputs(n, dt, seed, hold)
        maneuvers.append(Maneuver(name, t, u, rng.normal(size=(n, 8))))
    maneuvers = ManeuverSet(maneuvers, hold=hold)
    simulator = Simulator(structure, maneuvers)
    residuals = [m.outputs - y for m, y in zip(maneuvers, simulator.outputs(values))]
    return structure, values, maneuvers, simulator, residuals


def random_weighting(seed, zero=()):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(8, 8))
    q = a @ a.T + 8 * np.eye(8)
    for k in zero:
        q[k, :] = q[:, k] = 0.0
    return q


def explicit_products(simulator, values, residuals, q):
    _, sens = simulator.outputs_and_sensitivities(values)
    f = sum(np.einsum("npk,kl,nql->pq", s, q, s) for s in sens)
    g = -sum(np.einsum("npk,kl,nl->p", s, q, e) for s, e in zip(sens, residuals))
    return f, g


@pytest.mark.parametrize("hold", ["zoh", "foh"])
@pytest.mark.parametrize("zero", [(), (1, 6)])
@pytest.mark.parametrize("cores", [1, 2])
def test_products_match_the_explicit_sums(hold, zero, cores, monkeypatch):
    monkeypatch.setattr("rotorid.simulation.simulator.cpu_count", lambda: cores)
    _, values, _, simulator, residuals = problem(hold)
    q = random_weighting(5, zero)
    f, g = simulator.gauss_newton(values, residuals, q)
    f_ref, g_ref = explicit_products(simulator, values, residuals, q)
    assert np.allclose(f, f_ref, rtol=1e-10, atol=1e-10 * np.abs(f_ref).max())
    assert np.allclose(g, g_ref, rtol=1e-10, atol=1e-10 * np.abs(g_ref).max())
    assert np.array_equal(f, f.T)


def test_background_thread_gives_identical_sums(monkeypatch):
    _, values, _, simulator, residuals = problem()
    q = random_weighting(6)
    monkeypatch.setattr("rotorid.simulation.simulator.cpu_count", lambda: 1)
    serial = simulator.gauss_newton(values, residuals, q)
    monkeypatch.setattr("rotorid.simulation.simulator.cpu_count", lambda: 2)
    threaded = simulator.gauss_newton(values, residuals, q)
    assert np.array_equal(serial[0], threaded[0]) and np.array_equal(serial[1], threaded[1])


def test_the_generic_path_gives_the_same_products():
    """A model without its own products (here: a linear model hiding them) goes through its
    sensitivities; both paths agree."""
    structure, values, maneuvers, _, residuals = problem()

    class SensitivitiesOnly:
        def __init__(self):
            self.inner = LinearModel(structure)

        def sensitivities(self, values, maneuvers):
            return self.inner.sensitivities(values, maneuvers)

    q = random_weighting(7, zero=(3,))
    fast = gauss_newton_products(LinearModel(structure), values, maneuvers, residuals, q)
    generic = gauss_newton_products(SensitivitiesOnly(), values, maneuvers, residuals, q)
    for a, b in zip(fast, generic):
        assert np.allclose(a, b, rtol=1e-10, atol=1e-10 * np.abs(b).max())


def test_weighting_factor_is_a_square_root_with_the_leading_outputs_first():
    q = random_weighting(8, zero=(2,))
    factor = weighting_factor(q, leading=[0, 1, 4])
    assert factor.shape == (7, 8)
    assert np.allclose(factor.T @ factor, q)
    assert np.all(factor[:, 2] == 0)
    # the leading outputs' columns are non-zero only in the first three rows
    assert np.all(factor[3:][:, [0, 1, 4]] == 0)
    assert np.all(factor[:3][:, [0, 1, 4]][np.triu_indices(3)] != 0)


def test_bad_weightings_and_residuals_are_rejected():
    _, values, _, simulator, residuals = problem()
    with pytest.raises(DataError, match="positive semi-definite"):
        weighting_factor(-np.eye(8))
    with pytest.raises(DataError, match="positive definite on its weighted outputs"):
        weighting_factor(np.ones((8, 8)))
    with pytest.raises(DataError, match="finite square"):
        weighting_factor(np.full((8, 8), np.nan))
    with pytest.raises(DataError, match=r"must be \(8, 8\)"):
        simulator.gauss_newton(values, residuals, np.eye(3))
    with pytest.raises(DataError, match="residual arrays"):
        simulator.gauss_newton(values, residuals[:2], np.eye(8))
    with pytest.raises(DataError, match=r"residuals of maneuver 'b' have shape"):
        simulator.gauss_newton(values, [residuals[0], residuals[1][:5], residuals[2]],
                               np.eye(8))


def test_reusing_the_last_simulated_states_changes_nothing():
    structure, values, maneuvers, simulator, residuals = problem()
    q = random_weighting(9)
    reused = simulator.gauss_newton(values, residuals, q)        # problem() simulated values
    fresh = Simulator(structure, maneuvers).gauss_newton(values, residuals, q)
    simulator.outputs(values * 1.01)                               # other values in between
    again = simulator.gauss_newton(values, residuals, q)
    for a, b, c in zip(reused, fresh, again):
        assert np.allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())
        assert np.array_equal(b, c)
