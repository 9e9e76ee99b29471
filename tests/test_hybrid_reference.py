"""The hybrid model's reference: the truth model's full linearisation with the flap rates,
coning and inflow residualised (docs/hybrid.md), against the hand derivation of the
first-order tip-path-plane equations from the hover MBC flap equations.

Hand derivation (docs/hybrid.md, "Flap equations"): with g = γ/8, k = λβ² − 1 and
C = [[g, 2], [−2, g]], K = [[k, g], [−g, k]], dropping β̈ in hover gives

    β̇ = −Ω·C⁻¹K·β + [q, p] + Ω·g·C⁻¹·[θ1c, θ1s]

so 1/τ_f = Ω·g·(2 + k)/(g² + 4) and the rate feedback is exactly 1.
"""

import numpy as np
import pytest
from rotorid.errors import StructureError
from rotorid.model.residualisation import residualise
from rotorid_helisim.linearize import PADFIELD_STATES

HYBRID_STATES = PADFIELD_STATES + ("beta1c", "beta1s")


def test_residualise_hand_example():
    """ẋ1 = −x1 + 2·x2, ẋ2 = −10·x2 + 5·u: x2 = u/2 quasi-steady, so ẋ1 = −x1 + u."""
    a = np.array([[-1.0, 2.0], [0.0, -10.0]])
    b = np.array([[0.0], [5.0]])
    a_k, b_k = residualise(a, b, ("x1", "x2"), ("x1",))
    assert a_k == pytest.approx(np.array([[-1.0]]))
    assert b_k == pytest.approx(np.array([[1.0]]))


def test_residualise_refuses_unknown_and_neutral_states():
    a = np.array([[-1.0, 1.0], [0.0, 0.0]])
    with pytest.raises(StructureError, match="not states"):
        residualise(a, np.zeros((2, 1)), ("x1", "x2"), ("x3",))
    with pytest.raises(StructureError, match="singular"):
        residualise(a, np.zeros((2, 1)), ("x1", "x2"), ("x1",))


@pytest.fixture(scope="module")
def hover_full(truth_model, hover_trim):
    from rotorid_helisim.linearize import linearize

    return linearize(truth_model, hover_trim, full=True, units="si")


@pytest.fixture(scope="module")
def hand(truth_model):
    """The hand-derived first-order flap coefficients (SI, per rad of blade angle)."""
    config = truth_model.config
    g, k, omega = config.lock_number / 8.0, config.flap_frequency_squared - 1.0, config.omega
    c = np.array([[g, 2.0], [-2.0, g]])
    stiffness = np.array([[k, g], [-g, k]])
    return {"flap": -omega * np.linalg.solve(c, stiffness),
            "control": omega * g * np.linalg.inv(c),  # columns θ1c, θ1s
            "tau": (g * g + 4.0) / (omega * g * (2.0 + k)),
            "tau_classic": 16.0 / (config.lock_number * omega)}


def _hybrid(full):
    a, b = residualise(full.A, full.B, full.states, HYBRID_STATES)
    return a, b


def test_hand_time_constant_is_close_to_16_over_gamma_omega(hand):
    assert hand["tau"] == pytest.approx(0.0696, abs=5e-4)
    assert hand["tau"] == pytest.approx(hand["tau_classic"], rel=0.03)


def test_flap_rows_match_the_hand_derivation(hover_full, hand):
    a, b = _hybrid(hover_full)
    flap = [HYBRID_STATES.index("beta1c"), HYBRID_STATES.index("beta1s")]
    rates = [HYBRID_STATES.index("q"), HYBRID_STATES.index("p")]
    # time constants: the body's angular accelerations (ṗ, q̇ forcing the flap) shift them
    # by a few per cent
    assert -1.0 / np.diag(a[np.ix_(flap, flap)]) == pytest.approx([hand["tau"]] * 2, rel=0.05)
    # rate feedback: exactly the identity in the hand derivation
    assert a[np.ix_(flap, rates)] == pytest.approx(np.eye(2), abs=0.05)
    # control into flapping, columns θ1c and θ1s of the truth model's blade angles
    controls = [hover_full.controls.index("theta1c"), hover_full.controls.index("theta1s")]
    assert b[np.ix_(flap, controls)] == pytest.approx(hand["control"], rel=0.05, abs=0.3)


def test_hybrid_keeps_the_body_flap_modes(hover_full):
    """The first-order form keeps the full model's eigenvalues slower than 16 rad/s (the
    roll/flap pair and the pitch/flap subsidences) within 8 %."""
    a, _ = _hybrid(hover_full)
    reduced = np.linalg.eigvals(a)
    full = np.linalg.eigvals(np.asarray(hover_full.A))
    slow = full[np.abs(full) < 16.0]  # the inflow/coning mode is at −17.9
    assert len(reduced) == len(slow) == len(HYBRID_STATES)
    for value in slow:
        nearest = reduced[np.argmin(np.abs(reduced - value))]
        assert abs(nearest - value) <= 0.08 * max(abs(value), 1.0)


def test_hub_moment_per_disc_tilt(hover_full, truth_model, hover_trim):
    """M_β1c and L_β1s lie between the flap spring's moment (N_b/2)·K_β and that plus the
    full thrust tilt T·h_R (reference §2.2: at fixed controls the thrust tilts by about 40 % of
    the disc tilt), over I_yy and the primed roll inertia I_xx − I_xz²/I_zz."""
    a, _ = _hybrid(hover_full)
    c = truth_model.config
    spring = 0.5 * c.n_blades * c.flap_spring
    tilt = c.mass * c.gravity * (-c.hub_position[2])  # hover thrust ≈ weight, hub above CG
    i = {name: n for n, name in enumerate(HYBRID_STATES)}
    for row, flap, inertia in (("q", "beta1c", c.iyy),
                               ("p", "beta1s", c.ixx - c.ixz**2 / c.izz)):
        moment = -a[i[row], i[flap]] * inertia
        assert spring < moment < spring + tilt
