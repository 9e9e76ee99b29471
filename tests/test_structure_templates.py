"""Structure templates: the six-dof helicopter model and its longitudinal and lateral subsets.

A subset's simulation, sensitivities and frequency response are checked against the six-dof
structure holding the same derivatives, in a trim where the axes do not couple through the
known terms (V0 = 0, Φ0 = 0): there the six-dof model's longitudinal outputs driven by long
and coll alone are the longitudinal model's.
"""

import math
import tomllib

import numpy as np
import pytest
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.errors import StructureError
from rotorid.model.modelfile import format_model, parse_model
from rotorid.model.statespace import responding_outputs, state_space
from rotorid.model.templates import TEMPLATES
from rotorid.simulation.simulator import sensitivities
from rotorid.simulation.transfer import frequency_response, response_sensitivities
from rotorid.units import FOOT, G_SI

# Level trim at 60 ft/s forward and 4 ft/s down, nose 4° up: U0 and W0 but no V0 or Φ0.
U0_FT, W0_FT, THETA0 = 60.0, 4.0, math.radians(4.0)
CONDITION = FlightCondition(u0=U0_FT * FOOT, w0=W0_FT * FOOT, theta0=THETA0)
LONGITUDINAL_VALUES = {"X_u": -0.02, "X_w": 0.01, "X_q": 0.3, "X_long": -0.08, "Z_u": -0.05,
                       "Z_w": -0.4, "Z_q": 0.2, "Z_coll": -0.9, "M_u": 0.003, "M_w": 0.004,
                       "M_q": -1.1, "M_long": 0.35, "M_coll": 0.05}


def test_subsets_hold_their_axes_derivatives_in_six_dof_order():
    longitudinal = ModelStructure.populated(CONDITION, "longitudinal")
    assert longitudinal.names == (
        "X_u", "X_w", "X_q", "X_long", "X_coll", "Z_u", "Z_w", "Z_q", "Z_long", "Z_coll",
        "M_u", "M_w", "M_q", "M_long", "M_coll")
    lateral = ModelStructure.populated(CONDITION, "lateral")
    assert lateral.names == (
        "Y_v", "Y_p", "Y_r", "Y_lat", "Y_ped", "L_v", "L_p", "L_r", "L_lat", "L_ped",
        "N_v", "N_p", "N_r", "N_lat", "N_ped")
    assert (lateral.states, lateral.controls, lateral.outputs) == (
        ("v", "p", "phi", "r"), ("lat", "ped"), ("ay", "p", "phi", "r"))
    assert ModelStructure.six_dof(CONDITION).equation_rows == (0, 1, 2, 4, 5, 7)
    assert longitudinal.equation_rows == (0, 1, 2)
    assert set(TEMPLATES) == {"six-dof", "longitudinal", "lateral", "fixed-wing-longitudinal",
                              "fixed-wing-lateral", "hybrid", "hybrid-flap", "hybrid-inflow",
                              "hybrid-inflow-flap"}


def test_longitudinal_known_terms_match_the_hand_derived_values():
    """u̇ = −W0·q − g·cosΘ0·θ, ẇ = U0·q − g·sinΘ0·θ, θ̇ = q (flight-test units: ft/s, deg)."""
    a = ModelStructure.populated(CONDITION, "longitudinal").known_state_matrix()
    per_deg = math.pi / 180.0
    g_ft = G_SI / FOOT
    expected = np.zeros((4, 4))
    expected[0, 2] = -W0_FT * per_deg
    expected[0, 3] = -g_ft * math.cos(THETA0) * per_deg
    expected[1, 2] = U0_FT * per_deg
    expected[1, 3] = -g_ft * math.sin(THETA0) * per_deg
    expected[3, 2] = 1.0
    np.testing.assert_allclose(a, expected, rtol=1e-12, atol=1e-15)


def test_signals_carry_the_structure_units():
    signals = ModelStructure.populated(CONDITION, "longitudinal", units="si").signals
    assert signals.states.names == ("u", "w", "q", "theta")
    assert signals.states.units == ("m/s", "m/s", "rad/s", "rad")
    assert signals.inputs.units == ("%", "%")
    assert signals.outputs.units == ("m/s²", "m/s²", "rad/s", "rad")


def test_foreign_derivatives_and_signs_are_refused_by_name():
    longitudinal = ModelStructure.populated(CONDITION, "longitudinal")
    with pytest.raises(StructureError, match="derivative L_p does not fit the longitudinal template"):
        longitudinal.without("L_p")
    with pytest.raises(StructureError, match="Y_v does not fit the longitudinal template"):
        ModelStructure(CONDITION, [*longitudinal.derivatives[:2],
                                   ModelStructure.six_dof(CONDITION).derivative("Y_v")],
                       template="longitudinal")
    with pytest.raises(StructureError, match="lateral template does not have.*M_q"):
        ModelStructure.populated(CONDITION, "lateral", signs={"M_q": "negative"})
    with pytest.raises(StructureError, match="unknown structure template 'vertical'"):
        ModelStructure.populated(CONDITION, "vertical")


def _paired_structures():
    """The longitudinal structure and the six-dof one with the same derivatives and delays."""
    names = list(LONGITUDINAL_VALUES)
    longitudinal = ModelStructure.populated(CONDITION, "longitudinal")
    longitudinal = longitudinal.without(*[n for n in longitudinal.names if n not in names])
    six_dof = ModelStructure.six_dof(CONDITION)
    six_dof = six_dof.without(*[n for n in six_dof.names if n not in names])
    delays = {"M_long": 0.05, "Z_coll": 0.013}
    pair = []
    for structure in (longitudinal, six_dof):
        structure = structure.with_delays(delays).with_initial(
            {**LONGITUDINAL_VALUES, **{f"tau_{n}": tau for n, tau in delays.items()}})
        pair.append(structure)
    return pair


def _maneuvers(seed: int) -> ManeuverSet:
    rng = np.random.default_rng(seed)
    t = np.arange(400) * 0.02
    inputs = np.zeros((t.size, 4))
    for column in (0, 2):  # long and coll only: the lateral axes stay in trim
        inputs[:, column] = np.repeat(rng.normal(size=t.size // 40), 40)
    return ManeuverSet([Maneuver(f"m{seed}", t, inputs, np.zeros((t.size, 8)))])


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_longitudinal_simulation_equals_the_six_dof_longitudinal_outputs(hold):
    longitudinal, six_dof = _paired_structures()
    maneuvers = ManeuverSet(_maneuvers(1).maneuvers, hold=hold)
    y_small, s_small = sensitivities(longitudinal, None, maneuvers)
    y_full, s_full = sensitivities(six_dof, None, maneuvers)
    rows = [six_dof.outputs.index(n) for n in longitudinal.outputs]
    assert longitudinal.parameter_names == six_dof.parameter_names
    assert y_small[0].shape == (400, 4) and s_small[0].shape == (400, 15, 4)
    scale = np.abs(y_full[0]).max()
    np.testing.assert_allclose(y_small[0], y_full[0][:, rows], rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(s_small[0], s_full[0][:, :, rows], rtol=0,
                               atol=1e-11 * np.abs(s_full[0]).max())
    lateral = [six_dof.outputs.index(n) for n in ("ay", "p", "phi", "r")]
    assert np.all(y_full[0][:, lateral] == 0.0)


def test_longitudinal_frequency_response_equals_the_six_dof_block():
    longitudinal, six_dof = _paired_structures()
    omega = np.logspace(-1, 1.3, 25)
    rows = [six_dof.outputs.index(n) for n in longitudinal.outputs]
    columns = [six_dof.controls.index(c) for c in longitudinal.controls]
    small = frequency_response(longitudinal, None, omega)
    full = frequency_response(six_dof, None, omega)
    np.testing.assert_allclose(small, full[:, rows][:, :, columns], rtol=1e-10)
    _, d_small = response_sensitivities(longitudinal, None, omega)
    _, d_full = response_sensitivities(six_dof, None, omega)
    np.testing.assert_allclose(d_small, d_full[:, :, rows][..., columns], rtol=1e-9,
                               atol=1e-12 * np.abs(d_full).max())


def test_a_model_file_selects_a_template_and_saves_it_back():
    text = ('[condition]\nairspeed_kt = 40.0\n[structure]\ntemplate = "lateral"\n'
            'remove = ["Y_p", "N_lat"]\n[derivatives.L_p]\nsign = "negative"\n')
    structure = parse_model(tomllib.loads(text), "lateral.toml")
    assert structure.template.name == "lateral"
    assert structure.n_parameters == 13
    assert structure.derivative("L_p").sign.value == "negative"
    saved = format_model(structure)
    assert 'template = "lateral"' in saved and 'populate = "all"' in saved
    assert parse_model(tomllib.loads(saved), "saved.toml") == structure


def test_a_lateral_structure_exports_with_its_own_signals():
    lateral = ModelStructure.populated(CONDITION, "lateral").with_initial(
        {"Y_v": -0.1, "L_v": -0.02, "L_p": -2.0, "L_lat": 1.0, "N_r": -0.4, "N_ped": 0.5})
    system = state_space(lateral)
    assert (system.states, system.inputs, system.outputs) == (
        ("v", "p", "phi", "r"), ("lat", "ped"), ("ay", "p", "phi", "r"))
    for ours, reference in zip((system.a, system.b, system.c, system.d), lateral.matrices()):
        np.testing.assert_array_equal(ours, reference)
    assert responding_outputs(lateral)["ped"] == ("ay", "p", "phi", "r")
