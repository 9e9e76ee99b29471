"""Linearisation of the truth model against Padfield's Helisim Bo-105 (truth-model.md §6, §8, §9).

The reference hover A and B are Padfield (2007) pp. 287–291 as tabulated in truth-model.md §6
and held once in ``rotorid_helisim.linear_plant`` (states u w q θ v p φ r, SI, ṗ and ṙ rows
primed, B per rad of blade angle).
"""

import json

import numpy as np
import pytest
from rotorid.units import FOOT
from rotorid_helisim.linear_plant import HOVER_A as REFERENCE_A
from rotorid_helisim.linear_plant import HOVER_B as REFERENCE_B
from rotorid_helisim.linearize import PADFIELD_STATES, jacobians, linearize
from rotorid_helisim.model import Bo105Model
from rotorid_helisim.parameters import Bo105Config
from rotorid_helisim.trim import trim
from scipy.linalg import expm

STATE = {name: i for i, name in enumerate(PADFIELD_STATES)}
CONTROL = {"theta0": 0, "theta1s": 1, "theta1c": 2, "theta0T": 3}
ROW = {"X": "u", "Z": "w", "M": "q", "Y": "v", "L": "p", "N": "r"}

#: Dominant stability derivatives of the Done criteria (row letter, state).
DOMINANT = ["X_u", "Z_w", "M_u", "M_q", "Y_v", "L_v", "L_p"]
#: Main control derivatives: the on-axis and the large cross-coupling ones.
MAIN_CONTROLS = ["Z_theta0", "N_theta0", "X_theta1s", "M_theta1s", "L_theta1s", "Y_theta1c",
                 "L_theta1c", "M_theta1c", "N_theta1c", "Y_theta0T", "L_theta0T", "N_theta0T"]


def _entry(matrix_a, matrix_b, name):
    letter, column = name.split("_", 1)
    row = STATE[ROW[letter]]
    if column in CONTROL:
        return matrix_b[row, CONTROL[column]]
    return matrix_a[row, STATE[column]]


# ---------------------------------------------------------------- hover against Helisim (§6)
@pytest.mark.parametrize("name", DOMINANT + MAIN_CONTROLS)
def test_hover_dominant_derivatives_within_30_percent(hover_linear, name):
    ours = _entry(hover_linear.A, hover_linear.B, name)
    reference = _entry(REFERENCE_A, REFERENCE_B, name)
    assert np.sign(ours) == np.sign(reference)
    assert ours == pytest.approx(reference, rel=0.30)


@pytest.mark.xfail(strict=True, reason=(
    "documented difference (docs/truth-model.md, 'Comparison'; reference §2.0 expects a "
    "larger N'_r): primed N'_r is −0.43 against Helisim's −0.32 because of the I_xz coupling "
    "with L_r, whose sign differs (shaft-tilt projection of the yaw rate on the hub roll "
    "rate); the unprimed yaw damping agrees within 10 %, see the next test"))
def test_hover_yaw_damping_within_30_percent(hover_linear):
    assert _entry(hover_linear.A, hover_linear.B, "N_r") == pytest.approx(REFERENCE_A[7, 7],
                                                                          rel=0.30)


def test_hover_documented_differences(hover_linear):
    """Differences stated in docs/truth-model.md with their expected size (reference §2.0)."""
    ratio = lambda name: (_entry(hover_linear.A, hover_linear.B, name)  # noqa: E731
                          / _entry(REFERENCE_A, REFERENCE_B, name))
    # N'_r about 35 % larger (same sign); unprimed N_r/I_zz = N'_r − (I_xz/I_zz)·L'_r agrees
    assert 1.2 < ratio("N_r") < 1.6
    k = 660.0 / 4099.0
    unprimed = lambda a: a[STATE["r"], STATE["r"]] - k * a[STATE["p"], STATE["r"]]  # noqa: E731
    assert unprimed(hover_linear.A) == pytest.approx(unprimed(REFERENCE_A), rel=0.10)
    # unprimed L_r/I_xx: same magnitude as Helisim, opposite sign (shaft-tilt rate projection)
    kx = 660.0 / 1433.0
    roll_yaw = lambda a: a[STATE["p"], STATE["r"]] - kx * a[STATE["r"], STATE["r"]]  # noqa: E731
    assert -roll_yaw(hover_linear.A) == pytest.approx(roll_yaw(REFERENCE_A), rel=0.30)
    # blade-element in-plane force: X_q and Y_p about half of Helisim
    assert 0.35 < ratio("X_q") < 0.75
    assert 0.35 < ratio("Y_p") < 0.75
    # primed N'_p is mostly I_xz·L_p: within 30 %
    assert ratio("N_p") == pytest.approx(1.0, abs=0.3)


def test_hover_kinematic_and_gravity_rows(hover_linear, hover_trim):
    """Rows θ̇, φ̇ and the gravity terms follow the trim attitude exactly."""
    theta, phi = np.radians(hover_trim.theta_deg), np.radians(hover_trim.phi_deg)
    a = hover_linear.A
    assert a[STATE["theta"], STATE["q"]] == pytest.approx(np.cos(phi), abs=1e-6)
    assert a[STATE["theta"], STATE["r"]] == pytest.approx(-np.sin(phi), abs=1e-6)
    assert a[STATE["phi"], STATE["p"]] == pytest.approx(1.0, abs=1e-6)
    assert a[STATE["u"], STATE["theta"]] == pytest.approx(-9.80665 * np.cos(theta), rel=1e-4)
    assert a[STATE["v"], STATE["phi"]] == pytest.approx(
        9.80665 * np.cos(theta) * np.cos(phi), rel=1e-4)


def test_hover_eigenvalues_in_the_reference_places(hover_linear):
    eig = hover_linear.eigenvalues
    real = eig[np.abs(eig.imag) < 1e-9].real
    # roll subsidence −14.21, pitch subsidence −3.836
    assert np.min(real) == pytest.approx(-14.21, rel=0.30)
    assert np.sort(real)[1] == pytest.approx(-3.836, rel=0.30)
    # unstable hover oscillation +0.236 ± 0.525i and stable coupled oscillation −0.210 ± 0.599i
    unstable = eig[(eig.real > 0) & (eig.imag > 0)]
    assert unstable.size == 1
    assert unstable[0].real == pytest.approx(0.236, rel=0.30)
    assert unstable[0].imag == pytest.approx(0.525, rel=0.30)
    stable = eig[(eig.real < 0) & (eig.imag > 0.1)]
    assert stable.size == 1 and stable[0] == pytest.approx(-0.210 + 0.599j, abs=0.1)
    # heave/yaw near-real pair −0.325 ± 0.005i: ours is real, both near −0.3…−0.5
    slow = real[(real > -1.0)]
    assert slow.size == 2 and np.all((slow > -0.6) & (slow < -0.2))


# ---------------------------------------------------------------- numerical correctness
def test_linear_full_model_predicts_the_nonlinear_response(truth_model, hover_trim):
    """A small perturbation of the nonlinear model (RK4) against exp(A t) of the full
    linearisation: an independent check of the central-difference Jacobian."""
    names, a, _ = jacobians(truth_model, hover_trim)
    columns = [truth_model.index[n] for n in names]
    dx0 = np.zeros(len(names))
    dx0[names.index("u")] = 0.05
    dx0[names.index("p")] = 0.005
    dx0[names.index("beta1c")] = 2e-4
    x = hover_trim.state[None].copy()
    x[0, columns] += dx0
    stick = hover_trim.stick[None]
    dt, steps = 0.002, 250
    for _ in range(steps):
        k1 = truth_model.derivatives(x, stick)
        k2 = truth_model.derivatives(x + 0.5 * dt * k1, stick)
        k3 = truth_model.derivatives(x + 0.5 * dt * k2, stick)
        k4 = truth_model.derivatives(x + dt * k3, stick)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    nonlinear = x[0, columns] - hover_trim.state[columns]
    linear = expm(a * dt * steps) @ dx0
    for name in ("u", "q", "p", "theta", "phi"):
        i = names.index(name)
        assert nonlinear[i] == pytest.approx(linear[i], rel=0.02, abs=1e-5), name


def test_central_differences_are_converged(truth_model, hover_trim, monkeypatch):
    """Halving every perturbation step changes the residualised derivatives by < 0.1 %."""
    import rotorid_helisim.linearize as lin

    base = linearize(truth_model, hover_trim)
    monkeypatch.setattr(lin, "_STEPS", {k: v / 2 for k, v in lin._STEPS.items()})
    monkeypatch.setattr(lin, "_INFLOW_STEP", lin._INFLOW_STEP / 2)
    monkeypatch.setattr(lin, "_BLADE_STEP", lin._BLADE_STEP / 2)
    half = linearize(truth_model, hover_trim)
    for name in DOMINANT + MAIN_CONTROLS + ["N_r"]:
        assert _entry(half.A, half.B, name) == pytest.approx(_entry(base.A, base.B, name),
                                                             rel=1e-3), name


def test_flight_test_units_per_percent_stick(truth_model, hover_trim, hover_linear):
    ft = linearize(truth_model, hover_trim, units="flight-test")
    assert ft.controls == ("long", "lat", "coll", "ped")
    gain = truth_model.config.mixing.gain
    deg = 180 / np.pi
    # M_long [deg/s² per %] = M_θ1s [1/s² per rad] · (rad per %) · deg/rad
    assert ft.derivative("q", "long") == pytest.approx(
        hover_linear.derivative("q", "theta1s") * gain[1] * deg, rel=1e-12)
    # Z_coll [ft/s² per %]
    assert ft.derivative("w", "coll") == pytest.approx(
        hover_linear.derivative("w", "theta0") * gain[0] / FOOT, rel=1e-12)
    # M_u [deg/s² per ft/s]
    assert ft.derivative("q", "u") == pytest.approx(
        hover_linear.derivative("q", "u") * deg * FOOT, rel=1e-12)
    np.testing.assert_allclose(np.sort_complex(ft.eigenvalues),
                               np.sort_complex(hover_linear.eigenvalues),
                               rtol=1e-9, atol=1e-12)


def test_bad_options_are_named(truth_model, hover_trim):
    from rotorid.errors import StructureError

    with pytest.raises(StructureError, match="unknown unit system"):
        linearize(truth_model, hover_trim, units="imperial")
    other = Bo105Model(Bo105Config(inflow="pitt-peters"))
    with pytest.raises(StructureError, match="other states"):
        linearize(other, hover_trim)
    with pytest.raises(ValueError):
        hover_trim.state[0] = 1.0  # results are read-only values


def test_as_dict_and_cli_json(capsys, hover_linear):
    data = json.loads(json.dumps(hover_linear.as_dict()))
    assert data["states"] == list(PADFIELD_STATES)
    assert np.array(data["A"]).shape == (8, 8) and np.array(data["B"]).shape == (8, 4)
    from rotorid.cli.main import main

    assert main(["linearize", "forward", "--units", "flight-test", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["controls"] == ["long", "lat", "coll", "ped"] and out["airspeed_kt"] == 70.0
    assert len(out["eigenvalues"]) == 8
    assert main(["linearize", "--airspeed-kt", "60", "--full"]) == 0
    assert "beta1c" in capsys.readouterr().out


# ---------------------------------------------------------------- forward flight (§8)
#: Helisim 60 / 80 kt values of truth-model.md §8 (SI, primed L', N').
FORWARD = {
    "X_u": (-0.026, -0.033), "Z_w": (-0.75, -0.83), "M_u": (0.033, 0.031),
    "M_q": (-3.90, -4.00), "L_v": (-0.28, -0.28), "L_p": (-13.8, -13.6),
    "N_v": (0.104, 0.128), "N_r": (-0.98, -1.16),
}


@pytest.fixture(scope="module")
def sweep(truth_model):
    """Residualised linearisations every 10 kt from hover to 140 kt."""
    speeds = np.arange(0.0, 141.0, 10.0)
    return speeds, [linearize(truth_model, trim(truth_model, v)) for v in speeds]


@pytest.mark.parametrize("index, airspeed", [(0, 60.0), (1, 80.0)])
@pytest.mark.parametrize("name", sorted(FORWARD))
def test_forward_flight_signs_and_magnitudes(truth_model, name, index, airspeed):
    linear = linearize(truth_model, trim(truth_model, airspeed))
    ours = _entry(linear.A, linear.B, name)
    reference = FORWARD[name][index]
    assert np.sign(ours) == np.sign(reference)
    assert ours == pytest.approx(reference, rel=0.30)


@pytest.mark.parametrize("airspeed", [60.0, 70.0, 80.0])
def test_forward_flight_pitch_stiffness_is_small_and_positive(truth_model, airspeed):
    """Reference §8: the Bo-105 has a small M_w > 0 in forward flight (|M_w| ≲ 0.03)."""
    m_w = linearize(truth_model, trim(truth_model, airspeed)).derivative("q", "w")
    assert 0.0 < m_w < 0.03


def test_forward_flight_modes(linear_70kt):
    """Reference §8: lightly damped Dutch roll, roll and pitch subsidences near hover values,
    near-neutral long-period mode."""
    eig = linear_70kt.eigenvalues
    oscillations = eig[eig.imag > 0.05]
    dutch = oscillations[np.argmax(oscillations.imag)]
    assert -1.0 < dutch.real < 0.0 and 1.5 < dutch.imag < 4.0
    phugoid = oscillations[np.argmin(oscillations.imag)]
    assert abs(phugoid.real) < 0.1
    real = np.sort(eig[np.abs(eig.imag) < 1e-9].real)
    assert real[0] == pytest.approx(-14.2, rel=0.3) and real[1] == pytest.approx(-3.8, rel=0.3)


def test_derivatives_vary_smoothly_with_airspeed(sweep):
    speeds, models = sweep
    for name in DOMINANT + ["N_r", "N_v", "M_w", "Z_theta0", "M_theta1s", "L_theta1c",
                            "N_theta0T"]:
        values = np.array([_entry(m.A, m.B, name) for m in models])
        span = np.ptp(values) + 1e-3 * np.max(np.abs(values))
        second = np.abs(np.diff(values, 2))
        assert np.all(second < 0.25 * span), (name, values)
    for m in models:  # roll and pitch subsidences stay where they are across the envelope
        real = np.sort(m.eigenvalues[np.abs(m.eigenvalues.imag) < 1e-9].real)
        assert -15.0 < real[0] < -10.0


# ---------------------------------------------------------------- rotor modes (§9)
def test_full_hover_model_rotor_modes(truth_model, hover_trim):
    full = linearize(truth_model, hover_trim, full=True)
    eig = full.eigenvalues
    upper = eig[eig.imag > 0]

    def near(target, rel):
        return np.min(np.abs(upper - target) if target.imag else np.abs(eig - target)) \
            < rel * abs(target)

    assert near(-7.2 + 12.1j, 0.10)  # roll/flap (ω_n 14.1, ζ 0.51)
    assert near(-8.6 + 0j, 0.10) and near(-5.7 + 0j, 0.10)  # pitch/flap pair
    assert near(-17.0 + 0j, 0.10)  # uniform inflow coupled with thrust and coning
    assert near(-14.07 + 91.96j, 0.03)  # advancing flap
    roll = upper[np.argmin(np.abs(upper - (-7.2 + 12.1j)))]
    assert -roll.real / abs(roll) == pytest.approx(0.51, abs=0.05)


def test_pitt_peters_option_moves_the_rotor_modes():
    """Reference §9, full 3-state Pitt–Peters: roll/flap ζ ≈ 0.34, pitch −3.9 ± 4.5i, and
    L_q much larger than Helisim's 0.37."""
    model = Bo105Model(Bo105Config(inflow="pitt-peters"))
    hover_trim = trim(model, 0.0)
    full = linearize(model, hover_trim, full=True)
    assert full.states[-4:] == ("vi", "lambda1s", "lambda1c", "lambda0T")
    upper = full.eigenvalues[full.eigenvalues.imag > 1.0]
    pitch = upper[np.argmin(np.abs(upper - (-3.9 + 4.5j)))]
    assert pitch == pytest.approx(-3.9 + 4.5j, abs=0.6)
    roll = upper[np.argmin(np.abs(np.abs(upper) - 13.0))]
    assert -roll.real / abs(roll) == pytest.approx(0.34, abs=0.05)
    reduced = linearize(model, hover_trim)
    assert reduced.derivative("p", "q") > 1.5 * REFERENCE_A[5, 2]


def test_documented_example_runs():
    """The Python example of docs/truth-model.md runs as written."""
    import pathlib
    import re

    text = (pathlib.Path(__file__).parent.parent / "docs" / "truth-model.md").read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    namespace = {}
    exec(compile(code, "docs/truth-model.md", "exec"), namespace)
    assert namespace["lin"].controls == ("long", "lat", "coll", "ped")
    assert namespace["hover"].airspeed_kt == 0.0
