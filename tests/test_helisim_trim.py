"""Trim of the Bo-105 truth model against the flight-test values of truth-model.md §5."""

import json
import math

import numpy as np
import pytest
from rotorid.errors import ExitStatus, TrimError
from rotorid.units import KNOT
from rotorid_helisim.model import Bo105Model
from rotorid_helisim.parameters import Bo105Config
from rotorid_helisim.trim import body_velocity, resolve_airspeed, trim


@pytest.fixture(scope="module")
def cruise80(truth_model):
    return trim(truth_model, 80.0)


# ---------------------------------------------------------------- flight-test comparison (§5)
def test_hover_matches_flight_test(hover_trim):
    """Padfield flight test: θ ≈ 2.7°, θ0 ≈ 14.3°; CR-3144 case 29: φ = −2.97°, θ0T = 10.17°."""
    assert hover_trim.theta_deg == pytest.approx(2.7, abs=2.0)
    assert hover_trim.blade_angles_deg[0] == pytest.approx(14.3, abs=2.0)
    assert hover_trim.phi_deg == pytest.approx(-2.97, abs=2.0)
    assert hover_trim.blade_angles_deg[3] == pytest.approx(10.17, abs=2.0)
    assert hover_trim.power_kw == pytest.approx(393.0, rel=0.15)


@pytest.mark.xfail(strict=True, reason=(
    "documented modelling difference (docs/truth-model.md, 'Trim'): ideal induced power "
    "(uniform momentum inflow, no tip loss) gives a main-rotor torque ≈ 15 % below the "
    "flight-test value, so the tail-rotor collective is 8.4° against Padfield's 10.6° "
    "(reference §2.4: 9–10° needs 350–393 kW of torque)"))
def test_hover_tail_rotor_collective_matches_padfield_flight_test(hover_trim):
    assert hover_trim.blade_angles_deg[3] == pytest.approx(10.6, abs=2.0)


def test_80kt_matches_flight_test(cruise80):
    """Padfield flight test at 80 kt: θ ≈ −2.3°, θ0 ≈ 13.1°."""
    assert cruise80.theta_deg == pytest.approx(-2.3, abs=2.0)
    assert cruise80.blade_angles_deg[0] == pytest.approx(13.1, abs=2.0)


@pytest.mark.xfail(strict=True, reason=(
    "documented modelling difference (docs/truth-model.md, 'Trim'): the model has the "
    "fuselage drag of the Padfield polynomial (f = 1.02 m²), no rotor-hub drag and ideal "
    "induced power, so the 80 kt power is ≈ 200 kW against 265 kW in flight test"))
def test_80kt_power_matches_flight_test(cruise80):
    assert cruise80.power_kw == pytest.approx(265.0, rel=0.15)


@pytest.mark.parametrize("airspeed, theta, phi", [(0.0, 2.2, -2.6), (60.0, 0.2, -1.5),
                                                  (80.0, -1.2, -1.6)])
def test_attitudes_match_helisim(truth_model, airspeed, theta, phi):
    """Helisim-implied trim attitudes (reference §2.0) within 1°."""
    result = trim(truth_model, airspeed)
    assert result.theta_deg == pytest.approx(theta, abs=1.0)
    assert result.phi_deg == pytest.approx(phi, abs=1.0)


# ---------------------------------------------------------------- trim definition
@pytest.mark.parametrize("inflow", ["baseline", "pitt-peters"])
@pytest.mark.parametrize("airspeed", [0.0, 70.0, 140.0])
def test_trim_is_an_equilibrium(airspeed, inflow):
    model = Bo105Model(Bo105Config(inflow=inflow))
    result = trim(model, airspeed)
    dx = model.derivatives(result.state[None], result.stick[None])[0]
    # everything at rest except the heading (ψ̇ = 0 too at zero rates)
    np.testing.assert_allclose(dx, 0.0, atol=1e-8)
    assert np.all(np.abs(result.stick) <= 100.0)
    i = model.index
    speed = math.sqrt(sum(result.state[i[n]] ** 2 for n in ("u", "v", "w")))
    assert speed == pytest.approx(airspeed * KNOT, abs=1e-9)
    assert result.state[i["v"]] == pytest.approx(0.0, abs=1e-12)


def test_level_flight_kinematics():
    """Reference §2.0: level flight, zero sideslip: v = 0, w = u·tanθ/cosφ."""
    theta, phi = np.array([0.05, -0.1]), np.array([-0.03, 0.02])
    u, v, w = body_velocity(70.0, 0.0, 0.0, theta, phi)
    np.testing.assert_allclose(w, u * np.tan(theta) / np.cos(phi), rtol=1e-12)
    np.testing.assert_allclose(v, 0.0, atol=1e-12)
    np.testing.assert_allclose(u**2 + w**2, (70 * KNOT) ** 2, rtol=1e-12)


def test_climb_and_sideslip_conditions(truth_model, trim_70kt):
    climb = trim(truth_model, 70.0, climb_rate_mps=3.0)
    level = trim_70kt
    th, ph = math.radians(climb.theta_deg), math.radians(climb.phi_deg)
    i = truth_model.index
    u, v, w = (climb.state[i[n]] for n in ("u", "v", "w"))
    vertical_down = -u * math.sin(th) + v * math.sin(ph) * math.cos(th) + w * math.cos(ph) * math.cos(th)
    assert vertical_down == pytest.approx(-3.0, abs=1e-9)
    # energy: the extra power is about the rate of change of potential energy over η
    # (the induced power falls a little in the climb)
    d_power = (climb.power_kw - level.power_kw) * 1e3
    config = truth_model.config
    potential = config.mass * config.gravity * 3.0 / config.drive_efficiency
    assert 0.8 < d_power / potential < 1.05
    slip = trim(truth_model, 70.0, sideslip_deg=5.0)
    speed = math.sqrt(sum(slip.state[i[n]] ** 2 for n in ("u", "v", "w")))
    assert slip.state[i["v"]] / speed == pytest.approx(math.sin(math.radians(5.0)), rel=1e-9)
    assert slip.blade_angles_deg[3] != pytest.approx(level.blade_angles_deg[3], abs=0.1)


def test_power_curve_has_a_bucket(truth_model):
    powers = [trim(truth_model, v).power_kw for v in (0.0, 70.0, 140.0)]
    assert powers[1] < powers[0] and powers[1] < powers[2]


# ---------------------------------------------------------------- errors and output
def test_no_trim_beyond_the_envelope(truth_model):
    with pytest.raises(TrimError, match="no trim"):
        trim(truth_model, 250.0)
    with pytest.raises(TrimError, match="power limit"):
        trim(truth_model, 0.0, climb_rate_mps=20.0)


@pytest.mark.parametrize("kwargs, message", [
    ({"airspeed_kt": -5.0}, "airspeed_kt must be"),
    ({"airspeed_kt": float("nan")}, "must be finite"),
    ({"airspeed_kt": 70.0, "sideslip_deg": 95.0}, "sideslip"),
])
def test_bad_conditions_are_named(truth_model, kwargs, message):
    with pytest.raises(TrimError, match=message):
        trim(truth_model, **kwargs)


def test_named_conditions():
    assert resolve_airspeed("hover", None) == 0.0
    assert resolve_airspeed("forward", None) == 70.0
    assert resolve_airspeed(None, 55.0) == 55.0
    with pytest.raises(TrimError, match="exactly one"):
        resolve_airspeed("hover", 10.0)
    with pytest.raises(TrimError, match="exactly one"):
        resolve_airspeed(None, None)


def test_as_dict_is_json(hover_trim):
    data = json.loads(json.dumps(hover_trim.as_dict()))
    assert data["blade_angles_deg"]["theta0"] == pytest.approx(hover_trim.blade_angles_deg[0])
    assert set(data["stick_percent"]) == {"long", "lat", "coll", "ped"}
    assert "power" in hover_trim.report()


def test_cli_trim_json(capsys):
    from rotorid.cli.main import main

    assert main(["trim", "--airspeed-kt", "80", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["airspeed_kt"] == 80.0 and data["theta_deg"] == pytest.approx(-1.3, abs=0.5)
    assert main(["trim", "hover", "--airspeed-kt", "3"]) == ExitStatus.ERROR
    assert "exactly one" in capsys.readouterr().err
