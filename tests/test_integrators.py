"""Fixed-step Runge-Kutta integration under held inputs (rotorid.simulation.integrators),
checked against an independent fine-step solution of scipy's solve_ivp."""

import numpy as np
import pytest
from rotorid.errors import StructureError
from rotorid.simulation.integrators import Integration, integrate, integrate_with_tangents
from scipy.integrate import solve_ivp

DT = 0.05
TIME = np.arange(81) * DT
#: one input per row of the batch: a 3211-like staircase and a ramp-and-sine
INPUTS = np.stack([
    np.select([TIME < 0.5, TIME < 1.1, TIME < 1.5, TIME < 1.7, TIME < 1.9],
              [0.0, 1.0, -1.0, 1.0, -1.0], 0.0),
    0.4 * TIME + np.sin(3.0 * TIME),
], axis=1)[:, :, None]                                            # (N, B=2, m=1)
THETA = np.array([[9.0, 0.8, 2.0], [4.0, 0.3, 1.5]])              # ω², damping, gain per row


def pendulum(t, x, u, theta):
    """θ̈ = −ω² sin θ − c θ̇ + k u, vectorised over rows."""
    return np.stack([x[:, 1], -theta[:, 0] * np.sin(x[:, 0]) - theta[:, 1] * x[:, 1]
                     + theta[:, 2] * u[:, 0]], axis=1)


def reference(row: int, hold: str) -> np.ndarray:
    """solve_ivp (DOP853, tight tolerances) interval by interval with the held input."""
    x = np.array([0.2, 0.0])
    states = [x]
    u = INPUTS[:, row, 0]
    for n in range(TIME.size - 1):
        def held(t, n=n):
            fraction = (t - TIME[n]) / DT
            return u[n] if hold == "zoh" else u[n] + fraction * (u[n + 1] - u[n])

        def rhs(t, y):
            return pendulum(t, y[None, :], np.array([[held(t)]]), THETA[row][None, :])[0]

        x = solve_ivp(rhs, (TIME[n], TIME[n + 1]), x, method="DOP853", rtol=1e-12,
                      atol=1e-12).y[:, -1]
        states.append(x)
    return np.array(states)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_rk4_under_the_data_hold_matches_a_fine_step_solution(hold):
    x0 = np.tile([0.2, 0.0], (2, 1))
    states = integrate(pendulum, np.zeros(2), DT, x0, INPUTS, THETA, hold)
    assert states.shape == (TIME.size, 2, 2)
    for row in range(2):
        expected = reference(row, hold)
        np.testing.assert_allclose(states[:, row], expected, atol=2e-5)
        other = "foh" if hold == "zoh" else "zoh"
        assert np.max(np.abs(reference(row, other) - expected)) > 100 * 2e-5   # hold matters


def test_substeps_and_lower_order_schemes_converge_to_the_same_solution():
    x0 = np.tile([0.2, 0.0], (2, 1))
    expected = reference(0, "foh")
    errors = {}
    for scheme, substeps in [("euler", 4), ("euler", 8), ("heun", 4), ("rk4", 4)]:
        states = integrate(pendulum, np.zeros(2), DT, x0, INPUTS, THETA, "foh",
                           Integration(scheme, substeps))
        errors[scheme, substeps] = np.max(np.abs(states[:, 0] - expected))
    assert 1.7 < errors["euler", 4] / errors["euler", 8] < 2.3            # first order
    assert errors["heun", 4] < errors["euler", 8] / 10
    assert errors["rk4", 4] < 1e-7


def test_tangents_are_the_derivative_of_the_scheme():
    def jacobians(t, x, u, theta):
        f_x = np.zeros((x.shape[0], 2, 2))
        f_x[:, 0, 1] = 1.0
        f_x[:, 1, 0] = -theta[:, 0] * np.cos(x[:, 0])
        f_x[:, 1, 1] = -theta[:, 1]
        f_theta = np.zeros((x.shape[0], 2, 3))
        f_theta[:, 1] = np.stack([-np.sin(x[:, 0]), -x[:, 1], u[:, 0]], axis=1)
        return f_x, f_theta

    x0 = np.tile([0.2, 0.0], (2, 1))
    x0_tangent = np.zeros((2, 2, 4))
    x0_tangent[:, 0, 3] = 1.0                                # ψ = (ω², c, k, θ(0))
    states, tangents = integrate_with_tangents(
        pendulum, jacobians, np.zeros(2), DT, x0, x0_tangent, INPUTS, THETA,
        np.eye(3, 4), "foh")
    np.testing.assert_allclose(states, integrate(pendulum, np.zeros(2), DT, x0, INPUTS, THETA,
                                                 "foh"), rtol=1e-14)
    h = 1e-6
    for k in range(4):
        step_theta, step_x0 = THETA.copy(), x0.copy()
        if k < 3:
            step_theta[:, k] += h
        else:
            step_x0[:, 0] += h
        moved = integrate(pendulum, np.zeros(2), DT, step_x0, INPUTS, step_theta, "foh")
        np.testing.assert_allclose(tangents[..., k], (moved - states) / h, atol=2e-5)


def test_a_row_that_blows_up_stays_non_finite_and_leaves_the_others_alone():
    def unstable(t, x, u, theta):
        return theta * x * x

    states = integrate(unstable, np.zeros(2), 0.1, np.ones((2, 1)), np.zeros((60, 2, 1)),
                       np.array([[10.0], [-0.1]]))
    assert not np.isfinite(states[-1, 0, 0])
    # ẋ = −0.1 x² from 1: x(t) = 1/(1 + 0.1 t)
    assert states[-1, 1, 0] == pytest.approx(1 / (1 + 0.1 * 5.9), rel=1e-8)


def test_bad_integration_settings():
    with pytest.raises(StructureError, match="unknown integration scheme 'rk45'; use one of "
                                             "euler, heun, rk4"):
        Integration("rk45")
    with pytest.raises(StructureError, match="substeps must be at least 1"):
        Integration(substeps=0)
    with pytest.raises(StructureError, match="unknown input hold 'linear'"):
        integrate(pendulum, np.zeros(2), DT, np.zeros((2, 2)), INPUTS, THETA, "linear")
