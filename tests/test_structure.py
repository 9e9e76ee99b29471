"""Flight condition and model structure: the known terms against a hand-derived case, unit
systems, and the editing operations."""

import math

import attrs
import numpy as np
import pytest
from rotorid.errors import DerivativeError, StructureError
from rotorid.model.derivatives import Delay, Derivative
from rotorid.model.structure import (
    CONTROLS,
    OUTPUTS,
    PAPER_DELAYED,
    STATES,
    FlightCondition,
    ModelStructure,
)
from rotorid.units import (
    FLIGHT_TEST,
    FOOT,
    KNOT,
    SI,
    channel_scale,
    convert_state_space,
)

# The hand-derived case: U0 = 100 ft/s, V0 = 2 ft/s, W0 = 8 ft/s, Θ0 = 5°, Φ0 = -3°.
U0_FT, V0_FT, W0_FT = 100.0, 2.0, 8.0
THETA0, PHI0 = math.radians(5.0), math.radians(-3.0)
CONDITION = FlightCondition(U0_FT * FOOT, V0_FT * FOOT, W0_FT * FOOT, THETA0, PHI0)


# The known terms of the small-perturbation equations at this trim, worked out by hand.
# Trig: sin 5° = 0.0871557, cos 5° = 0.9961947, tan 5° = 0.0874887, sin(−3°) = −0.0523360,
# cos(−3°) = 0.9986295. Flight-test units: g = 9.80665/0.3048 = 32.17405 ft/s², angles and
# rates in deg, so every force term carries k = π/180 = 0.01745329 rad/deg; SI: U0 = 30.48,
# V0 = 0.6096, W0 = 2.4384 m/s, g = 9.80665 m/s², k = 1.
#
#   u' = −W0 q + V0 r − g cosΘ0 θ          −8·k = −0.1396263; 2·k = 0.0349066;
#                                           −32.17405·0.9961947·k = −0.559406
#   v' = −U0 r + W0 p + g cosΘ0 cosΦ0 φ     −100·k = −1.745329; 8·k = 0.1396263;
#        − g sinΘ0 sinΦ0 θ                  32.17405·0.9961947·0.9986295·k = 0.558640;
#                                           −32.17405·0.0871557·(−0.0523360)·k = +0.00256141
#   w' = −V0 p + U0 q − g cosΦ0 sinΘ0 θ     −2·k = −0.0349066; 100·k = 1.745329;
#        − g sinΦ0 cosΘ0 φ                  −32.17405·0.9986295·0.0871557·k = −0.0488746;
#                                           −32.17405·(−0.0523360)·0.9961947·k = +0.0292771
#   θ' = q cosΦ0 − r sinΦ0                  0.9986295; +0.0523360
#   φ' = p + q sinΦ0 tanΘ0 + r cosΦ0 tanΘ0  1; −0.0523360·0.0874887 = −0.00457880;
#                                           0.9986295·0.0874887 = 0.0873688
KINEMATIC = {("theta", "q"): 0.9986295, ("theta", "r"): 0.0523360, ("phi", "p"): 1.0,
             ("phi", "q"): -0.00457880, ("phi", "r"): 0.0873688}
KNOWN_FLIGHT_TEST = {
    ("u", "q"): -0.1396263, ("u", "r"): 0.0349066, ("u", "theta"): -0.559406,
    ("v", "r"): -1.745329, ("v", "p"): 0.1396263, ("v", "phi"): 0.558640,
    ("v", "theta"): 0.00256141,
    ("w", "p"): -0.0349066, ("w", "q"): 1.745329, ("w", "theta"): -0.0488746,
    ("w", "phi"): 0.0292771, **KINEMATIC}
KNOWN_SI = {
    ("u", "q"): -2.4384, ("u", "r"): 0.6096, ("u", "theta"): -9.76933,
    ("v", "r"): -30.48, ("v", "p"): 2.4384, ("v", "phi"): 9.75594, ("v", "theta"): 0.0447318,
    ("w", "p"): -0.6096, ("w", "q"): 30.48, ("w", "theta"): -0.853535,
    ("w", "phi"): 0.511287, **KINEMATIC}


def known_matrix(terms):
    """The (8, 8) matrix holding ``terms`` (row state, column state) → value, zero elsewhere."""
    a = np.zeros((8, 8))
    for (row, column), value in terms.items():
        a[STATES.index(row), STATES.index(column)] = value
    return a


def test_flight_test_gravity_is_the_standard_value_in_feet():
    assert FLIGHT_TEST.g == pytest.approx(32.174, abs=5e-4)
    assert SI.g == 9.80665


@pytest.mark.parametrize("units, terms", [("flight-test", KNOWN_FLIGHT_TEST), ("si", KNOWN_SI)])
def test_known_terms_match_the_hand_derived_values(units, terms):
    structure = ModelStructure.six_dof(CONDITION, units=units)
    np.testing.assert_allclose(structure.known_state_matrix(), known_matrix(terms), rtol=2e-6,
                               atol=0.0)


def test_known_output_terms_measure_rates_and_attitudes():
    c = ModelStructure.six_dof(CONDITION).known_output_matrix()
    for row, name in enumerate(OUTPUTS):
        expected = np.zeros(8)
        if name in ("q", "theta", "p", "phi", "r"):
            expected[STATES.index(name)] = 1.0
        np.testing.assert_array_equal(c[row], expected)


def test_full_model_in_both_unit_systems_is_consistent():
    """SI derivatives converted by hand give the same model as the converted SI matrices."""
    rng = np.random.default_rng(3)
    si = ModelStructure.six_dof(CONDITION, units="si")
    si = si.with_initial(dict(zip(si.names, rng.normal(size=60))))
    scale = dict(zip(STATES + CONTROLS, channel_scale(STATES + CONTROLS, FLIGHT_TEST)))
    ft = ModelStructure.six_dof(CONDITION).with_initial(
        {d.name: d.initial * scale[si.equation_of(d)] / scale[d.variable] for d in si.derivatives})
    a_si, b_si, c_si, d_si = si.matrices()
    a_ft, b_ft, c_ft, d_ft = ft.matrices()
    a_conv, b_conv = convert_state_space(a_si, b_si, STATES, CONTROLS, FLIGHT_TEST)
    np.testing.assert_allclose(a_ft, a_conv, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(b_ft, b_conv, rtol=1e-12, atol=1e-12)
    sy = channel_scale(OUTPUTS, FLIGHT_TEST)
    sx = channel_scale(STATES, FLIGHT_TEST)
    su = channel_scale(CONTROLS, FLIGHT_TEST)
    np.testing.assert_allclose(c_ft, sy[:, None] * c_si / sx[None, :], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(d_ft, sy[:, None] * d_si / su[None, :], rtol=1e-12, atol=1e-12)


def test_derivative_terms_land_in_their_matrix_entries():
    structure = ModelStructure(CONDITION, [Derivative("X_q", 0.5), Derivative("Z_coll", -2.0),
                                           Derivative("L_lat", 3.0), Derivative("M_p", 0.25)])
    a, b, c, d = structure.matrices()
    known = structure.known_state_matrix()
    i = STATES.index
    assert a[i("u"), i("q")] == pytest.approx(known[i("u"), i("q")] + 0.5)
    assert a[i("q"), i("p")] == 0.25
    assert b[i("w"), CONTROLS.index("coll")] == -2.0
    assert b[i("p"), CONTROLS.index("lat")] == 3.0
    # specific forces feed the accelerometers; moments do not
    assert c[OUTPUTS.index("ax"), i("q")] == 0.5
    assert d[OUTPUTS.index("az"), CONTROLS.index("coll")] == -2.0
    assert np.count_nonzero(c[[0, 1, 4]]) == 1 and np.count_nonzero(d) == 1


def test_six_dof_has_sixty_free_derivatives_at_zero():
    structure = ModelStructure.six_dof(CONDITION)
    assert structure.n_parameters == 60
    assert len(set(structure.names)) == 60
    assert structure.names[:3] == ("X_u", "X_v", "X_w") and structure.names[-1] == "N_ped"
    np.testing.assert_array_equal(structure.initial_values(), np.zeros(60))
    np.testing.assert_array_equal(structure.matrices()[0], structure.known_state_matrix())


def test_six_dof_signs_and_unknown_sign_names():
    structure = ModelStructure.six_dof(CONDITION, signs={"L_p": "negative"})
    assert structure.derivative("L_p").sign.value == "negative"
    with pytest.raises(StructureError, match=r"template does not have: \['L_x'\]"):
        ModelStructure.six_dof(CONDITION, signs={"L_x": "negative"})


def test_without_returns_a_new_structure():
    full = ModelStructure.six_dof(CONDITION)
    reduced = full.without("X_v", "M_w")
    assert reduced.n_parameters == 58 and "M_w" not in reduced.names
    assert full.n_parameters == 60
    with pytest.raises(StructureError, match="derivative M_w is not in this structure"):
        reduced.without("M_w")
    with pytest.raises(StructureError, match="does not fit the six-dof template"):
        full.without("M_x")


def test_fixing_keeps_the_value_but_not_the_parameter():
    structure = ModelStructure.six_dof(CONDITION).fixing("M_w", 0.3)
    assert "M_w" not in structure.parameter_names and structure.n_parameters == 59
    assert structure.matrices()[0][STATES.index("q"), STATES.index("w")] == 0.3


def test_delays_become_parameters_after_the_derivatives():
    structure = ModelStructure.six_dof(CONDITION).without("L_q").with_delays(initial=0.02)
    delayed = [n for n in PAPER_DELAYED if n != "L_q"]
    assert structure.parameter_names[59:] == tuple(f"tau_{n}" for n in delayed)
    assert structure.is_delay().sum() == len(delayed)
    lower, upper = structure.bounds()
    assert np.all(lower[structure.is_delay()] == 0.0)
    assert np.all(np.isinf(upper[~structure.is_delay()]))
    assert np.all(upper[structure.is_delay()] == 1.0)     # the default bound, s
    with pytest.raises(StructureError, match="derivative L_q is not in this structure"):
        ModelStructure.six_dof(CONDITION).without("L_q").with_delays(["L_q"], missing="error")


def test_terms_carry_delays_and_outputs():
    structure = ModelStructure(CONDITION, [Derivative("X_long", 1.0, delay=0.1),
                                           Derivative("L_p", -2.0)])
    table = structure.terms()
    np.testing.assert_array_equal(table.equation, [STATES.index("u"), STATES.index("p")])
    np.testing.assert_array_equal(table.source, [8 + CONTROLS.index("long"), STATES.index("p")])
    np.testing.assert_array_equal(table.delay, [0.1, 0.0])
    np.testing.assert_array_equal(table.output, [OUTPUTS.index("ax"), -1])
    table = structure.terms({"tau_X_long": 0.3, "L_p": -4.0})
    np.testing.assert_array_equal(table.gain, [1.0, -4.0])
    np.testing.assert_array_equal(table.delay, [0.3, 0.0])


def test_with_initial_sets_derivatives_and_delays():
    structure = ModelStructure(CONDITION, [Derivative("M_q", delay=Delay(0.01))])
    updated = structure.with_initial({"M_q": -1.5, "tau_M_q": 0.05})
    np.testing.assert_array_equal(updated.initial_values(), [-1.5, 0.05])
    with pytest.raises(StructureError, match="tau_M_q: derivative M_q has no delay"):
        ModelStructure(CONDITION, [Derivative("M_q")]).with_initial({"tau_M_q": 0.1})


def test_sign_priors_become_bounds_on_request():
    structure = ModelStructure(CONDITION, [Derivative("L_p", sign="negative"),
                                           Derivative("N_v", sign="positive"),
                                           Derivative("X_u", delay=Delay(0.0, upper=0.2))])
    lower, upper = structure.bounds(enforce_signs=True)
    np.testing.assert_array_equal(lower, [-np.inf, 0.0, -np.inf, 0.0])
    np.testing.assert_array_equal(upper, [0.0, np.inf, np.inf, 0.2])
    assert np.all(np.isinf(structure.bounds()[0][:3]))


@pytest.mark.parametrize("values, fragment", [
    ([1.0, 2.0], r"shape \(2,\); this structure has 3"),
    ({"L_q": 1.0}, r"unknown or non-free parameter\(s\) \['L_q'\]"),
    ([1.0, np.nan, 0.0], "non-finite parameter value"),
])
def test_bad_parameter_vectors_are_rejected(values, fragment):
    structure = ModelStructure(CONDITION, [Derivative("L_p"), Derivative("N_v"), Derivative("X_u")])
    with pytest.raises(StructureError, match=fragment):
        structure.as_vector(values)


def test_duplicate_and_foreign_derivatives_are_rejected():
    with pytest.raises(StructureError, match="L_p is declared twice"):
        ModelStructure(CONDITION, [Derivative("L_p"), Derivative("L_p", 1.0)])
    with pytest.raises(StructureError, match="must be Derivative objects"):
        ModelStructure(CONDITION, ["L_p"])


def test_structures_are_frozen():
    structure = ModelStructure.six_dof(CONDITION)
    with pytest.raises(attrs.exceptions.FrozenInstanceError):
        structure.units = SI


def test_unit_system_names():
    assert ModelStructure(CONDITION, [], units="si-rad").units is SI
    with pytest.raises(StructureError, match="unknown unit system 'metric'"):
        ModelStructure(CONDITION, [], units="metric")


def test_condition_from_airspeed_is_level_flight():
    condition = FlightCondition.from_airspeed(70.0, theta0_deg=4.0, phi0_deg=-2.0)
    speed = 70.0 * KNOT
    assert condition.u0 == pytest.approx(speed * math.cos(math.radians(4.0)))
    assert condition.w0 == pytest.approx(speed * math.sin(math.radians(4.0)))
    assert condition.v0 == 0.0 and condition.phi0 == pytest.approx(math.radians(-2.0))
    assert condition.airspeed_kt == pytest.approx(70.0)
    # 70 kt = 70 · 1852 m / 3600 s = 36.0111 m/s
    assert FlightCondition.from_airspeed(70.0).u0 == pytest.approx(36.0111, abs=1e-4)


def test_condition_from_mapping():
    assert FlightCondition.from_mapping({"u0_fps": 100.0, "w0_mps": 2.0}) == FlightCondition(
        30.48, 0.0, 2.0)
    assert FlightCondition.from_mapping({"airspeed_kt": 0.0}) == FlightCondition()


@pytest.mark.parametrize("build, fragment", [
    (lambda: FlightCondition(theta0=2.0), r"theta0 = .* is not within ±90°"),
    (lambda: FlightCondition(u0=float("nan")), "u0 must be finite"),
    (lambda: FlightCondition.from_airspeed(-5.0), "airspeed must be a finite number ≥ 0 kt"),
    (lambda: FlightCondition.from_mapping({"speed": 1.0}), r"unknown key\(s\) \['speed'\]"),
    (lambda: FlightCondition.from_mapping({"airspeed_kt": 1.0, "u0_mps": 1.0}), "not both"),
    (lambda: FlightCondition.from_mapping({"u0_fps": 1.0, "u0_mps": 1.0}), "not both"),
])
def test_bad_conditions_are_rejected(build, fragment):
    with pytest.raises(StructureError, match=fragment):
        build()


def test_a_condition_states_its_airspeed_in_the_unit_systems_speed():
    condition = FlightCondition(u0=40.0)
    assert condition.describe("si") == "40.0 m/s, Θ0 = 0.00°, Φ0 = 0.00°"
    assert condition.describe() == "77.8 kt, Θ0 = 0.00°, Φ0 = 0.00°"
    assert condition.airspeed_text("si", 0) == "40 m/s"
    from rotorid.report.figures import flight_label

    assert flight_label(condition, "si") == "40 m/s"
    assert flight_label(FlightCondition.from_airspeed(0.0), "si") == "hover"


def test_figure_titles_name_the_case_where_its_name_says_more_than_its_condition():
    import types

    from rotorid.report.figures import case_title

    def result(name, airspeed_kt):
        return types.SimpleNamespace(
            name=name, condition=FlightCondition.from_airspeed(airspeed_kt),
            estimates={"no delays": types.SimpleNamespace(units="flight-test")})

    assert case_title(result("hover", 0.0)) == "hover"
    assert case_title(result("quad-hover", 0.0)) == "quad-hover (hover)"
    assert case_title(result("forward", 70.0)) == "forward (70 kt)"
