"""Fixed-wing templates: known terms by hand, output equations (α and β about the trim, q̇ = ΣM, specific
forces) against independent references, and sensitivities against finite differences.

References: the small-perturbation body-axis equations (e.g. Etkin & Reid, *Dynamics of Flight*,
ch. 4) written out below by hand; the delayed simulation against the fine-step trapezoidal
solution of :mod:`delay_reference`; q̇'s analytic response against jω times q's.
"""

import math

import numpy as np
import pytest
from delay_reference import sampled_outputs
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.errors import DataFileError, StructureError
from rotorid.simulation.simulator import Simulator, sensitivities
from rotorid.simulation.transfer import frequency_response, response_sensitivities
from rotorid.units import G_SI

U0, W0, THETA0 = 50.0, 2.0, math.atan2(2.0, 50.0)
CONDITION = FlightCondition(u0=U0, w0=W0, theta0=THETA0)
VALUES = {"X_u": -0.04, "X_w": 0.08, "X_elevator": 0.5, "X_throttle": 2.0, "Z_u": -0.3,
          "Z_w": -2.0, "Z_q": -1.5, "Z_elevator": -6.0, "M_u": 0.01, "M_w": -0.08,
          "M_q": -2.5, "M_elevator": -12.0, "tau_M_elevator": 0.065}


def _structure(**delays):
    structure = ModelStructure.populated(CONDITION, "fixed-wing-longitudinal", "si")
    keep = {name for name in VALUES if not name.startswith("tau_")}
    structure = structure.without(*[n for n in structure.names if n not in keep])
    return structure.with_delays(["M_elevator"], upper=0.5)


def test_longitudinal_known_terms_match_the_hand_derivation():
    structure = _structure()
    assert structure.states == ("u", "w", "q", "theta")
    assert structure.outputs == ("u", "alpha", "q", "theta", "q_dot", "ax", "az")
    g = G_SI
    expected_a = np.array([[0, 0, -W0, -g * math.cos(THETA0)],
                           [0, 0, U0, -g * math.sin(THETA0)],
                           [0, 0, 0, 0],
                           [0, 0, 1, 0]])
    np.testing.assert_allclose(structure.known_state_matrix(), expected_a, atol=1e-12)
    expected_c = np.zeros((7, 4))
    expected_c[0, 0] = expected_c[2, 2] = expected_c[3, 3] = 1.0
    # α = atan(w/u) differentiated at the trim's (U0, W0) by central differences
    h = 1e-6
    expected_c[1, 0] = (math.atan2(W0, U0 + h) - math.atan2(W0, U0 - h)) / (2 * h)
    expected_c[1, 1] = (math.atan2(W0 + h, U0) - math.atan2(W0 - h, U0)) / (2 * h)
    np.testing.assert_allclose(structure.known_output_matrix(), expected_c, atol=1e-9)
    measured = structure.known_terms().measured
    assert [(structure.outputs[j], structure.states[i]) for j, i in zip(*np.nonzero(measured))] \
        == [("q_dot", "q"), ("ax", "u"), ("az", "w")]


def test_lateral_template_reads_beta_in_the_unit_systems_angle_unit():
    structure = ModelStructure.populated(CONDITION, "fixed-wing-lateral", "flight-test")
    assert structure.controls == ("aileron", "rudder")
    c = structure.known_output_matrix()
    # β = asin(v/V) differentiated at v = 0, V0 = √(U0² + W0²), in ft/s
    h, v0_ft = 1e-6, math.hypot(U0, W0) / 0.3048
    beta = lambda v: math.asin(v / math.sqrt(v0_ft**2 + v**2))   # noqa: E731
    assert c[structure.outputs.index("beta"), structure.states.index("v")] == pytest.approx(
        math.degrees((beta(h) - beta(-h)) / (2 * h)), rel=1e-8)
    assert structure.signals.outputs["beta"].unit == "deg"


def test_alpha_and_beta_need_forward_flight():
    with pytest.raises(StructureError, match="needs forward flight"):
        ModelStructure.populated(FlightCondition(), "fixed-wing-longitudinal").known_terms()


def _maneuvers(hold):
    dt = 0.02
    t = np.arange(0.0, 6.0 + dt / 2, dt)
    elevator = np.where((t > 0.5) & (t < 1.5), 0.02, 0.0) - np.where((t > 1.5) & (t < 2.5),
                                                                      0.02, 0.0)
    throttle = np.where(t > 3.0, 0.1, 0.0)
    inputs = np.column_stack([elevator, throttle])
    maneuver = Maneuver("doublet", t, np.zeros((t.size, 0)), np.zeros((t.size, 0)),
                        input_names=(), output_names=(), units="si",
                        extra_channels={"elevator": elevator, "throttle": throttle})
    return t, inputs, ManeuverSet([maneuver], hold=hold)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_delayed_simulation_matches_the_fine_step_reference(hold):
    structure = _structure()
    t, inputs, maneuvers = _maneuvers(hold)
    simulated = Simulator(structure, maneuvers).outputs(VALUES)[0]
    reference = sampled_outputs(structure, structure.as_vector(VALUES), t, inputs, 0.02, hold,
                                fine=0.001)
    scale = np.max(np.abs(reference), axis=0)
    np.testing.assert_allclose(simulated / scale, reference / scale, atol=2e-4)


def test_q_dot_response_is_j_omega_times_the_q_response():
    structure = _structure()
    omega = np.logspace(-1, 1.5, 40)
    response = frequency_response(structure, VALUES, omega)
    q, q_dot = structure.outputs.index("q"), structure.outputs.index("q_dot")
    np.testing.assert_allclose(response[:, q_dot], 1j * omega[:, None] * response[:, q],
                               rtol=1e-10)
    alpha, w = structure.outputs.index("alpha"), structure.outputs.index("az")
    assert np.all(np.isfinite(response[:, alpha])) and np.any(response[:, w])


def test_sensitivities_match_central_differences():
    structure = _structure()
    _, _, maneuvers = _maneuvers("zoh")
    values = structure.as_vector(VALUES)
    outputs, exact = sensitivities(structure, values, maneuvers)
    simulator = Simulator(structure, maneuvers)
    for k, name in enumerate(structure.parameter_names):
        step = 1e-6 * max(1.0, abs(values[k]))
        up, down = values.copy(), values.copy()
        up[k] += step
        down[k] -= step
        numeric = (simulator.outputs(up)[0] - simulator.outputs(down)[0]) / (2 * step)
        scale = np.max(np.abs(numeric)) + 1e-12
        np.testing.assert_allclose(exact[0][:, k, :] / scale, numeric / scale, atol=1e-5,
                                   err_msg=name)


def test_frequency_sensitivities_match_central_differences():
    structure = _structure()
    omega = np.array([0.5, 2.0, 8.0])
    values = structure.as_vector(VALUES)
    _, exact = response_sensitivities(structure, values, omega)
    for k in range(values.size):
        step = 1e-7 * max(1.0, abs(values[k]))
        up, down = values.copy(), values.copy()
        up[k] += step
        down[k] -= step
        numeric = (frequency_response(structure, up, omega)
                   - frequency_response(structure, down, omega)) / (2 * step)
        np.testing.assert_allclose(exact[:, k], numeric, rtol=1e-5, atol=1e-7)


#: Δα = (u0·Δw − w0·Δu)/(u0² + w0²) at the declared trim (u0, w0) = (50, 2) m/s.
ALPHA_GAINS = {"alpha_u": repr(-2.0 / 2504.0), "alpha_w": repr(50.0 / 2504.0)}

DECLARED = """units = "si"
[condition]
u0_mps = 50.0
w0_mps = 2.0
theta0_deg = {theta0_deg}

[structure]
name = "written-out"
states = {{ u = "velocity", w = "velocity", q = "rate", theta = "angle" }}
controls = {{ elevator = "control", throttle = "control" }}
outputs = {{ u = "velocity", alpha = "angle", q = "rate", theta = "angle", q_dot = "angular-acceleration", ax = "acceleration", az = "acceleration" }}
equations = {{ X = "u", Z = "w", M = "q" }}
variables = ["u", "w", "q", "elevator", "throttle"]

[structure.known]
u = {{ q = {minus_w0}, theta = {minus_g_cos} }}
w = {{ q = 50.0, theta = {minus_g_sin} }}
theta = {{ q = 1.0 }}

[structure.output_equations]
alpha = {{ u = {alpha_u}, w = {alpha_w} }}
q_dot = {{ "d(q)" = 1.0 }}
ax = {{ "d(u)" = 1.0, q = 2.0, theta = {g_cos} }}
az = {{ "d(w)" = 1.0, q = -50.0, theta = {g_sin} }}
"""


def _written_out():
    """The fixed-wing-longitudinal template written out by hand as a declared structure: the
    accelerometers as the full state derivatives minus the known terms."""
    import tomllib

    from rotorid.model.modelfile import parse_model

    g_cos, g_sin = G_SI * math.cos(THETA0), G_SI * math.sin(THETA0)
    text = DECLARED.format(theta0_deg=repr(math.degrees(THETA0)), minus_w0=-W0,
                           minus_g_cos=-g_cos, minus_g_sin=-g_sin, g_cos=g_cos, g_sin=g_sin,
                           **ALPHA_GAINS)
    return parse_model(tomllib.loads(text), "written-out")


def test_a_declared_structure_reproduces_the_template_it_writes_out():
    declared = _written_out()
    template = ModelStructure.populated(declared.condition, "fixed-wing-longitudinal", "si")
    assert declared.names == template.names
    values = {name: 0.1 * (k + 1) * (-1) ** k for k, name in enumerate(template.names)}
    for mine, theirs in zip(declared.matrices(values), template.matrices(values)):
        np.testing.assert_allclose(mine, theirs, atol=1e-12)
    omega = np.logspace(-1, 1, 7)
    np.testing.assert_allclose(frequency_response(declared, values, omega),
                               frequency_response(template, values, omega), atol=1e-12)


def test_an_output_reading_a_control_directly_is_simulated_exactly():
    import tomllib

    from rotorid.model.modelfile import parse_model

    text = DECLARED.format(theta0_deg="0.0", minus_w0=-2.0, minus_g_cos=-G_SI, minus_g_sin=0.0,
                           g_cos=G_SI, g_sin=0.0, alpha_u=0.0, alpha_w=0.02).replace(
        'alpha = { u = 0.0, w = 0.02 }', 'alpha = { w = 0.02, elevator = 0.5 }')
    structure = parse_model(tomllib.loads(text), "feedthrough")
    assert structure.known_feedthrough()[1, 0] == 0.5
    values = {"X_u": -0.04, "Z_w": -2.0, "M_q": -2.5, "M_w": -0.1, "M_elevator": -12.0,
              "Z_elevator": -5.0, "X_throttle": 2.0}
    structure = structure.without(*[n for n in structure.names if n not in values])
    structure = structure.with_delays(["M_elevator"]).with_initial({"tau_M_elevator": 0.065})
    for hold in ("zoh", "foh"):
        t, inputs, maneuvers = _maneuvers(hold)
        simulated = Simulator(structure, maneuvers).outputs(values)[0]
        reference = sampled_outputs(structure, structure.as_vector(values), t, inputs, 0.02,
                                    hold, fine=0.001)
        scale = np.max(np.abs(reference), axis=0)
        np.testing.assert_allclose(simulated / scale, reference / scale, atol=2e-4)


def test_a_derivative_the_declared_structure_lacks_is_named_with_the_declared_fix():
    import tomllib

    from rotorid.model.modelfile import parse_model

    text = DECLARED.format(theta0_deg="0.0", minus_w0=-2.0, minus_g_cos=-G_SI, minus_g_sin=0.0,
                           g_cos=G_SI, g_sin=0.0, alpha_u=0.0, alpha_w=0.02) + "\n[derivatives.M_elev]\n"
    with pytest.raises(DataFileError, match=(
            r"written-out: derivative M_elev does not fit the declared structure written-out "
            r"\(equations X Z M; variables u w q elevator throttle\); correct its name, or "
            r"declare the equation or signal it needs in \[structure\]")):
        parse_model(tomllib.loads(text), "written-out")


def test_records_without_q_dot_and_throttle_fit_when_neither_is_used():
    """A data system that records neither q̇ nor the throttle: with the throttle's
    derivatives removed and q_dot left out of the fitted outputs, output error reads only
    what the records hold and recovers the derivatives its simulation used."""
    import rotorid

    structure = _structure()
    structure = structure.without(*[n for n in structure.names if n.endswith("_throttle")])
    values = {n: v for n, v in VALUES.items() if n in structure.parameter_names}
    _, _, maneuvers = _maneuvers("foh")
    recorded_outputs = ("u", "alpha", "q", "theta", "ax", "az")
    simulated = Simulator(structure, maneuvers).outputs(values)[0]
    noise = np.random.default_rng(3).normal(0.0, 1e-5, simulated.shape)
    record = maneuvers[0]
    columns = {name: (simulated + noise)[:, structure.outputs.index(name)]
               for name in recorded_outputs}
    lean = ManeuverSet([Maneuver("doublet", record.time, np.zeros((record.time.size, 0)),
                                 np.zeros((record.time.size, 0)), input_names=(),
                                 output_names=(), units="si",
                                 extra_channels={"elevator": record.channel("elevator"),
                                                 **columns})], hold="foh")
    estimate = rotorid.create("estimators", "output-error", outputs=recorded_outputs).estimate(
        structure, lean, start={n: 0.8 * v for n, v in values.items()})
    for name in ("Z_w", "M_q", "M_elevator"):
        assert estimate.value(name) == pytest.approx(VALUES[name], rel=1e-3), name
    with pytest.raises(rotorid.errors.DataError, match="leave the output out of the fit"):
        rotorid.create("estimators", "output-error").estimate(structure, lean)


def test_a_control_read_only_by_a_known_output_term_is_read_from_the_data():
    """Throttle without any derivative but read directly by alpha's known equation (0.5 per
    unit): the simulation reads it, so alpha steps by 0.5 with it; without that term it is
    not read at all."""
    import tomllib

    from rotorid.model.modelfile import parse_model

    text = DECLARED.format(theta0_deg="0.0", minus_w0=-2.0, minus_g_cos=-G_SI, minus_g_sin=0.0,
                           g_cos=G_SI, g_sin=0.0, alpha_u=0.0, alpha_w=0.02).replace(
        'alpha = { u = 0.0, w = 0.02 }', 'alpha = { w = 0.02, throttle = 0.5 }')
    structure = parse_model(tomllib.loads(text), "direct")
    structure = structure.without(*[n for n in structure.names if n.endswith("_throttle")])
    assert structure.read_controls == ("elevator", "throttle")
    _, _, maneuvers = _maneuvers("zoh")
    alpha = Simulator(structure, maneuvers).outputs({})[0][:, structure.outputs.index("alpha")]
    throttle = maneuvers[0].channel("throttle")
    np.testing.assert_allclose(alpha, 0.5 * throttle, atol=1e-12)
    plain = _structure()
    plain = plain.without(*[n for n in plain.names if n.endswith("_throttle")])
    assert plain.read_controls == ("elevator",)
