"""Nonlinear Bo-105 truth model: interface, rotor aerodynamics, flapping, inflow, mixing.

References are truth-model.md (the project's reference document, cited by section) and
closed forms derived independently of the blade-element quadrature.
"""

import math

import numpy as np
import pytest
from rotorid.errors import DataError, StructureError
from rotorid_helisim import inflow, rotor
from rotorid_helisim.model import Bo105Model
from rotorid_helisim.parameters import Bo105Config, StickMixing

CONFIG = Bo105Config()


def _loads(mu=(0.0, 0.0, 0.0), rates=(0.0, 0.0, 0.0), flap=(0.0, 0.0, 0.0),
           flap_rate=(0.0, 0.0, 0.0), lam=(0.05, 0.0, 0.0), pitch=(0.2, 0.0, 0.0), twist=None):
    row = lambda v: np.asarray(v, dtype=float)[None, :]  # noqa: E731
    return rotor.rotor_loads(
        row(mu), row(rates), row(flap), row(flap_rate), row(lam), row(pitch),
        solidity=CONFIG.solidity, lift_slope=CONFIG.lift_slope,
        twist=CONFIG.twist if twist is None else twist, lock_number=CONFIG.lock_number,
        profile_drag=CONFIG.profile_drag)


# ---------------------------------------------------------------- interface contract
def test_state_layout_rigid_body_first(truth_model):
    assert truth_model.state_names[:9] == ("u", "v", "w", "p", "q", "r", "phi", "theta", "psi")
    assert truth_model.n_states == len(truth_model.state_names) == 21
    assert truth_model.state_names[-4:] == ("theta0", "theta1s", "theta1c", "theta0T")
    pitt = Bo105Model(Bo105Config(inflow="pitt-peters"))
    assert pitt.n_states == 23 and "lambda1c" in pitt.state_names


def test_batch_equals_row_by_row(truth_model, hover_trim):
    rng = np.random.default_rng(1)
    x = hover_trim.state + 0.01 * rng.standard_normal((5, truth_model.n_states))
    stick = hover_trim.stick + 5.0 * rng.standard_normal((5, 4))
    batch = truth_model.derivatives(x, stick)
    assert batch.shape == (5, truth_model.n_states)
    rows = np.vstack([truth_model.derivatives(x[i:i + 1], stick[i:i + 1]) for i in range(5)])
    np.testing.assert_allclose(batch, rows, rtol=1e-12, atol=1e-12)
    assert truth_model.measurements(x, stick).shape == (5, 8)


def test_bad_shapes_raise_clear_errors(truth_model):
    with pytest.raises(DataError, match="states must have shape"):
        truth_model.derivatives(np.zeros(truth_model.n_states), np.zeros(4))
    with pytest.raises(DataError, match="stick must have shape"):
        truth_model.derivatives(np.zeros((2, truth_model.n_states)), np.zeros((2, 3)))
    with pytest.raises(StructureError, match="inflow"):
        Bo105Config(inflow="vortex")


def test_hover_measurements_are_specific_forces(truth_model, hover_trim):
    y = truth_model.measurements(hover_trim.state[None], hover_trim.stick[None])[0]
    ax, az, q, theta, ay, p, phi, r = y
    # in trim the specific force balances gravity: (ax, ay, az) = −g·(−sinθ, cosθ sinφ, cosθ cosφ)
    th, ph = math.radians(hover_trim.theta_deg), math.radians(hover_trim.phi_deg)
    g = CONFIG.gravity
    np.testing.assert_allclose([ax, ay, az], [g * math.sin(th), -g * math.cos(th) * math.sin(ph),
                                              -g * math.cos(th) * math.cos(ph)], atol=1e-8)
    assert az == pytest.approx(-g, rel=0.01)
    assert theta == pytest.approx(th) and phi == pytest.approx(ph)
    assert p == q == r == 0.0


# ---------------------------------------------------------------- rotor aerodynamics
@pytest.mark.parametrize("mu_x", [0.0, 0.1, 0.2, 0.3])
def test_thrust_matches_padfield_closed_form(mu_x):
    """Uniform-inflow thrust (reference §2.4, Padfield ch. 3) with no flapping or rates."""
    theta0, theta1s, twist, mu_z, lam0 = 0.22, -0.03, CONFIG.twist, 0.01, 0.04
    loads = _loads(mu=(mu_x, 0.0, mu_z), lam=(lam0, 0.0, 0.0), pitch=(theta0, theta1s, 0.0))
    closed = (theta0 * (1 / 3 + mu_x**2 / 2) + mu_x / 2 * theta1s + (mu_z - lam0) / 2
              + (1 + mu_x**2) * twist / 4)
    assert loads.thrust[0] / (CONFIG.lift_slope * CONFIG.solidity / 2) == pytest.approx(closed,
                                                                                        rel=1e-12)


def test_quadrature_is_exact(monkeypatch):
    """The 12 × 3 grid integrates the polynomial integrands exactly: a 29 × 6 grid shifted in
    azimuth gives the same loads for a general forward-flight rotor state."""
    rng = np.random.default_rng(7)
    args = [rng.uniform(-0.05, 0.05, (4, 3)) + base for base in (
        np.array([0.25, 0.03, 0.01]), np.zeros(3), np.array([0.03, 0.0, 0.0]), np.zeros(3),
        np.array([0.03, 0.0, 0.0]), np.array([0.2, 0.0, 0.0]))]
    options = dict(solidity=CONFIG.solidity, lift_slope=CONFIG.lift_slope, twist=CONFIG.twist,
                   lock_number=CONFIG.lock_number, profile_drag=CONFIG.profile_drag)
    coarse = rotor.rotor_loads(*args, **options)
    n, nodes = 29, np.polynomial.legendre.leggauss(6)
    psi = 0.37 + 2 * np.pi * np.arange(n) / n
    basis = np.stack([np.ones(n), np.cos(psi), np.sin(psi)])
    monkeypatch.setattr(rotor, "_BASIS", basis)
    monkeypatch.setattr(rotor, "_PROJECT", basis.T / n)
    monkeypatch.setattr(rotor, "WEIGHTS", 0.5 * nodes[1])
    monkeypatch.setattr(rotor, "_R", (0.5 * (nodes[0] + 1))[None, None, :])
    fine = rotor.rotor_loads(*args, **options)
    for name in ("force", "torque", "thrust", "roll_moment", "pitch_moment", "flap_forcing"):
        np.testing.assert_allclose(getattr(coarse, name), getattr(fine, name), rtol=1e-11,
                                   atol=1e-15, err_msg=name)


def test_hover_thrust_check_value():
    """Reference §2.4: with W = mg and λ0 = √(C_T/2), hover θ0 ≈ 14.2°."""
    ct = CONFIG.mass * CONFIG.gravity / (CONFIG.air_density * math.pi * CONFIG.radius**2
                                         * CONFIG.tip_speed**2)
    assert ct == pytest.approx(0.00489, abs=2e-5)
    lam0 = math.sqrt(ct / 2)
    assert lam0 == pytest.approx(0.0495, abs=2e-4)
    # thrust is linear in θ0: solve for the θ0 giving C_T
    t1 = _loads(lam=(lam0, 0, 0), pitch=(0.2, 0, 0)).thrust[0]
    t2 = _loads(lam=(lam0, 0, 0), pitch=(0.3, 0, 0)).thrust[0]
    theta0 = 0.2 + (ct - t1) / (t2 - t1) * 0.1
    assert math.degrees(theta0) == pytest.approx(14.2, abs=0.1)


def test_hover_torque_matches_momentum_plus_profile_power():
    """Hover C_Q = C_T·λ0 + (profile term) integrated independently for uniform c_d."""
    lam0 = 0.05
    loads = _loads(lam=(lam0, 0, 0), pitch=(0.2, 0, 0), twist=0.0)
    base = Bo105Config(profile_drag=(0.01, 0.0, 0.0))
    row = lambda v: np.asarray(v, dtype=float)[None, :]  # noqa: E731
    uniform = rotor.rotor_loads(row((0, 0, 0)), row((0, 0, 0)), row((0, 0, 0)), row((0, 0, 0)),
                                row((lam0, 0, 0)), row((0.2, 0, 0)), solidity=base.solidity,
                                lift_slope=base.lift_slope, twist=0.0,
                                lock_number=base.lock_number, profile_drag=base.profile_drag)
    assert uniform.torque[0] == pytest.approx(
        uniform.thrust[0] * lam0 + base.solidity * 0.01 / 8, rel=1e-12)
    assert loads.torque[0] > loads.thrust[0] * lam0  # HEROES c_d(α) adds profile torque


def test_hover_flap_equations_match_closed_form_matrices():
    """Reference §2.2: hover MBC flap equations β'' + Cβ' + Kβ = forcing (fixed hub)."""
    gamma, k = CONFIG.lock_number, CONFIG.flap_frequency_squared
    assert gamma == pytest.approx(5.07, abs=0.01) and k == pytest.approx(1.248, abs=1e-3)

    def acc(flap, rate):
        loads = _loads(flap=flap, flap_rate=rate, lam=(0.05, 0, 0), pitch=(0.2, 0, 0))
        zero = np.zeros((1, 3))
        return rotor.flap_accelerations(np.asarray(flap)[None], np.asarray(rate)[None],
                                        loads.flap_forcing, zero, zero, k)[0]

    base = acc((0, 0, 0), (0, 0, 0))
    h = 1e-6
    stiffness = np.column_stack([(acc(tuple(h * e), (0, 0, 0)) - base) / h for e in np.eye(3)])
    damping = np.column_stack([(acc((0, 0, 0), tuple(h * e)) - base) / h for e in np.eye(3)])
    cyclic_c = np.array([[gamma / 8, 2.0], [-2.0, gamma / 8]])
    cyclic_k = np.array([[k - 1, gamma / 8], [-gamma / 8, k - 1]])
    np.testing.assert_allclose(-damping[1:, 1:], cyclic_c, atol=1e-6)
    np.testing.assert_allclose(-stiffness[1:, 1:], cyclic_k, atol=1e-6)
    assert -damping[0, 0] == pytest.approx(gamma / 8, abs=1e-6)
    assert -stiffness[0, 0] == pytest.approx(k, abs=1e-6)
    # fixed-hub modes (reference §2.2 / §9), in rad/s
    omega = CONFIG.omega  # states β (rad) and dβ/dt (rad/s)
    a = np.block([[np.zeros((3, 3)), np.eye(3)], [omega**2 * stiffness, omega * damping]])
    eig = np.linalg.eigvals(a)
    eig = eig[eig.imag >= 0]
    expected = [-14.07 + 3.16j, -14.07 + 91.96j, -14.07 + 47.56j]
    for e in expected:
        assert np.min(np.abs(eig - e)) < 0.05, (e, eig)


def test_flap_gyroscopic_forcing_signs():
    """A steady nose-up pitch rate makes the disc lag behind (β1c' forcing +2·..., reference
    single-blade equation): the MBC forcing from hub rates is (0, 2p̄ + q̄', −2q̄ + p̄')."""
    zero = np.zeros((1, 3))
    out = rotor.flap_accelerations(zero, zero, zero, np.array([[0.1, 0.2, 0.0]]),
                                   np.array([[0.01, 0.03, 0.0]]), 1.2)
    np.testing.assert_allclose(out[0], [0.0, 2 * 0.1 + 0.03, -2 * 0.2 + 0.01])


# ---------------------------------------------------------------- inflow
def test_baseline_gradient_is_coleman():
    """λ1c = λ0·tan(χ/2) with χ = atan(μ/λ_tot) along the wind, positive aft (reference §1)."""
    lam0, mu_x = 0.02, 0.15
    l1s, l1c = inflow.baseline_harmonics(np.array([lam0]), np.array([[mu_x, 0.0, 0.0]]))
    chi = math.atan(mu_x / lam0)
    assert l1c[0] == pytest.approx(lam0 * math.tan(chi / 2), rel=1e-12) and l1s[0] == 0.0
    # wind from the right-front (μy > 0): gradient turns with the wind, magnitude unchanged
    l1s, l1c = inflow.baseline_harmonics(np.array([lam0]), np.array([[0.1, 0.1, 0.0]]))
    chi = math.atan(math.hypot(0.1, 0.1) / lam0)
    assert math.hypot(l1s[0], l1c[0]) == pytest.approx(lam0 * math.tan(chi / 2), rel=1e-12)
    assert l1c[0] > 0 and l1s[0] < 0


def test_pitt_peters_sign_and_magnitude_checks():
    """Reference §2.3 checks 1–4."""
    ct = 0.00489
    # 1. hover steady state λ0 = √(C_T/2), harmonic rows uncoupled
    lam0 = math.sqrt(ct / 2)
    rate = inflow.pitt_peters_rate(np.array([[lam0, 0, 0]]), np.zeros((1, 3)),
                                   np.array([[ct, 0, 0]]))
    np.testing.assert_allclose(rate, 0.0, atol=1e-15)
    # uncoupled time constant (8/3π)/(4λ0Ω) ≈ 0.097 s
    h = 1e-7
    d = inflow.pitt_peters_rate(np.array([[lam0 + h, 0, 0]]), np.zeros((1, 3)),
                                np.array([[ct, 0, 0]]))[0, 0] / h
    assert -1.0 / (d * CONFIG.omega) == pytest.approx(0.097, abs=0.002)
    # 2. thrust only in forward flight: λ1c same sign as λ0, ratio (15π/32)·tan(χ/2)
    mu = np.array([[0.15, 0.0, 0.0]])

    def steady(forcing, start):
        lam = np.array([start], dtype=float)
        for _ in range(200):  # Newton on the linear-in-harmonics steady state
            f = inflow.pitt_peters_rate(lam, mu, forcing)
            jac = np.column_stack([(inflow.pitt_peters_rate(lam + 1e-8 * e, mu, forcing) - f)[0]
                                   / 1e-8 for e in np.eye(3)])
            lam = lam - np.linalg.solve(jac, f[0])
        return lam[0]

    lam = steady(np.array([[ct, 0, 0]]), [0.02, 0, 0])
    chi = math.atan(0.15 / lam[0])
    assert lam[2] > 0 and lam[1] == pytest.approx(0.0, abs=1e-12)
    assert lam[2] / lam[0] == pytest.approx(15 * math.pi / 32 * math.tan(chi / 2), rel=1e-6)
    # 3. moment loading: lift at the front (C_1c < 0) → λ1c < 0; lift at ψ = 90° → λ1s > 0
    assert steady(np.array([[0.0, 0.0, -1e-4]]), [0.01, 0, 0])[2] < 0
    assert steady(np.array([[ct, 1e-4, 0.0]]), [0.02, 0, 0])[1] > lam[1]


# ---------------------------------------------------------------- controls and actuators
def test_stick_mixing_round_trip_and_signs():
    mixing = StickMixing()
    stick = np.array([[10.0, -20.0, 30.0, 40.0]])
    np.testing.assert_allclose(mixing.stick(mixing.blade_angles(stick)), stick, atol=1e-12)
    d = mixing.blade_angles(np.eye(4) * 10.0) - mixing.blade_angles(np.zeros(4))
    assert d[0, 1] < 0  # long forward → θ1s down (nose down)
    assert d[1, 2] < 0  # lat right → θ1c down (right roll)
    assert d[2, 0] > 0  # coll up → θ0 up
    assert d[3, 3] < 0  # right pedal → θ0T down (nose right)
    with pytest.raises(StructureError):
        StickMixing(gain=(0.0, 1.0, 1.0, 1.0))


def _rk4(truth_model, x, stick, dt, steps):
    for _ in range(steps):
        k1 = truth_model.derivatives(x, stick)
        k2 = truth_model.derivatives(x + 0.5 * dt * k1, stick)
        k3 = truth_model.derivatives(x + 0.5 * dt * k2, stick)
        k4 = truth_model.derivatives(x + dt * k3, stick)
        x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


def test_stick_steps_have_the_pilot_signs(truth_model, hover_trim):
    """Nonlinear response 0.3 s after 10 % stick steps from hover trim: long forward → nose
    down (q < 0), lat right → roll right (p > 0), coll up → climb (w < 0), right pedal → nose
    right (r > 0)."""
    stick = np.repeat(hover_trim.stick[None], 4, axis=0) + 10.0 * np.eye(4)
    x0 = np.repeat(hover_trim.state[None], 4, axis=0)
    x = _rk4(truth_model, x0, stick, 0.002, 150)
    i = truth_model.index
    assert x[0, i["q"]] < -0.05
    assert x[1, i["p"]] > 0.1
    assert x[2, i["w"]] < -0.1
    assert x[3, i["r"]] > 0.05
    # and the trim itself stays put
    still = _rk4(truth_model, x0[:1], hover_trim.stick[None], 0.002, 150)
    np.testing.assert_allclose(still, x0[:1], atol=1e-9)


def test_actuators_are_first_order_lags(truth_model, hover_trim):
    stick = hover_trim.stick.copy()
    stick[2] += 10.0
    dx = truth_model.derivatives(hover_trim.state[None], stick[None])[0]
    expected = 10.0 * truth_model.config.mixing.gain[0] / truth_model.config.actuator_time_constant
    assert dx[truth_model.index["theta0"]] == pytest.approx(expected, rel=1e-12)
    assert truth_model.config.actuator_time_constant == pytest.approx(0.03)
