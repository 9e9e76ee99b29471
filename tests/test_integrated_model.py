"""Nonlinear models of one's own through the model protocol (rotorid.estimation.integrated):
batched sensitivities against closed forms, identification within Cramér-Rao bounds, channel
maps and initial conditions, errors."""

import re
from pathlib import Path

import attrs
import numpy as np
import pytest
import rotorid
from rotorid import Maneuver, ManeuverSet
from rotorid.errors import StructureError
from rotorid.estimation.integrated import InitialConditions, IntegratedModel
from rotorid.estimation.models import as_model, measured_outputs
from rotorid.model.nonlinear import Parameter
from rotorid.model.signals import ChannelLink, ChannelMap, ModelSignals, Signal, SignalSet

RATE, ANGLE, STICK = ("rad/s", "rate"), ("rad", "angle"), ("%", "control")


class FirstOrder:
    """q̇ = −a q + b δ, outputs q and p = c q: linear in the state, closed-form sensitivities."""

    signals = ModelSignals(states=SignalSet([Signal("q", *RATE)]),
                           inputs=SignalSet([Signal("long", *STICK)]),
                           outputs=SignalSet([Signal("q", *RATE), Signal("p", *RATE)]))
    parameters = (Parameter("a", 2.0, lower=0.0), Parameter("b", 0.5), Parameter("c", -1.5),
                  Parameter("unused", 7.0, fixed=True))

    def __init__(self):
        self.calls = 0

    def derivatives(self, t, x, u, theta):
        self.calls += 1
        return -theta[:, :1] * x + theta[:, 1:2] * u

    def outputs(self, t, x, u, theta):
        return np.concatenate([x, theta[:, 2:3] * x], axis=1)


class FirstOrderWithJacobians(FirstOrder):
    def derivative_jacobians(self, t, x, u, theta):
        f_theta = np.zeros((x.shape[0], 1, 4))
        f_theta[:, 0, 0], f_theta[:, 0, 1] = -x[:, 0], u[:, 0]
        return np.broadcast_to(-theta[:, 0, None, None], (x.shape[0], 1, 1)), f_theta

    def output_jacobians(self, t, x, u, theta):
        h_x = np.stack([np.ones_like(x), theta[:, 2:3]], axis=1)        # (B, 2, 1)
        h_theta = np.zeros((x.shape[0], 2, 4))
        h_theta[:, 1, 2] = x[:, 0]
        return h_x, h_theta


def step_maneuvers():
    """Unit steps from t = 0: two records at 100 Hz of different lengths, one at 50 Hz."""
    records = []
    for name, dt, n in (("long_a", 0.01, 301), ("short", 0.01, 151), ("coarse", 0.02, 101)):
        time = 1.0 + dt * np.arange(n)
        inputs = np.zeros((n, 4))
        inputs[:, 0] = 1.0
        records.append(Maneuver(name, time, inputs, np.zeros((n, 8)), units="si"))
    return ManeuverSet(records)


def closed_form(t, a=2.0, b=0.5, c=-1.5, x0=0.4):
    """Outputs (N, 2) and sensitivities (N, 4, 2) to (a, b, c, x0) of the exact solution
    x = x0 e^−at + b/a (1 − e^−at), y = (x, c x)."""
    decay = np.exp(-a * t)
    x = x0 * decay + b / a * (1 - decay)
    dx = np.stack([-x0 * t * decay - b / a**2 * (1 - decay) + b / a * t * decay,
                   (1 - decay) / a, np.zeros_like(t), decay], axis=1)
    outputs = np.stack([x, c * x], axis=1)
    sens = np.stack([dx, c * dx], axis=2)
    sens[:, 2, 1] = x
    return outputs, sens


@pytest.mark.parametrize("method, cls, tolerance", [
    ("central", FirstOrder, 2e-7), ("forward", FirstOrder, 2e-6),
    ("model", FirstOrderWithJacobians, 2e-7)])
def test_batched_sensitivities_match_the_closed_form(method, cls, tolerance):
    maneuvers = step_maneuvers()
    model = cls()
    fitted = IntegratedModel(model, sensitivities=method, maneuvers=maneuvers,
                             initial=InitialConditions(fixed={"q": 0.4}, estimated=("q",)))
    assert fitted.parameter_names == ("a", "b", "c", "x0_long_a_q", "x0_short_q",
                                      "x0_coarse_q")
    assert fitted.fixed == {"unused": 7.0}
    values = fitted.initial_values()
    np.testing.assert_array_equal(values, [2.0, 0.5, -1.5, 0.4, 0.4, 0.4])
    model.calls = 0
    outputs, sens = fitted.sensitivities(values, maneuvers)
    if method != "model":       # one batched simulation per sample time, whatever P is
        assert model.calls == 4 * (300 + 100)
    for i, m in enumerate(maneuvers):
        expected, expected_sens = closed_form(m.time - m.time[0])
        np.testing.assert_allclose(outputs[i], expected, atol=1e-9)
        own = sens[i][:, [0, 1, 2, 3 + i], :]
        np.testing.assert_allclose(own, expected_sens, atol=tolerance)
        others = np.delete(sens[i], [0, 1, 2, 3 + i], axis=1)
        assert np.all(others == 0.0)        # another maneuver's initial state does not act


def pendulum_data(seed: int, start_angles=(0.0, 0.0)):
    """Two stick 3211s on a damped pendulum, flight-test units (deg, deg/s), seeded noise."""
    model = Pendulum()
    t = np.arange(501) * 0.02
    blank = []
    for name, sign, angle in zip(("plus", "minus"), (1.0, -1.0), start_angles):
        stick = sign * 8.0 * np.select([(t >= 1) & (t < 1.6), (t >= 1.6) & (t < 2.0),
                                        (t >= 2.0) & (t < 2.2), (t >= 2.2) & (t < 2.4)],
                                       [1.0, -1.0, 1.0, -1.0], 0.0)
        inputs = np.zeros((t.size, 4))
        inputs[:, 0] = stick
        outputs = np.zeros((t.size, 8))
        outputs[0, 3] = angle                                # θ(0) in deg, read as the start
        blank.append(Maneuver(name, t, inputs, outputs))
    blank = ManeuverSet(blank)
    truth = IntegratedModel(model, channels=STICK_IN_LONG,
                            initial=InitialConditions(fixed={"q": 0.0}))
    clean = truth.simulate(PENDULUM_TRUTH, blank)
    rng = np.random.default_rng(seed)
    noisy = []
    for m, y in zip(blank, clean):
        outputs = np.zeros((m.n_samples, 8))
        outputs[:, [3, 2]] = np.degrees(y) + rng.normal(size=y.shape) * [0.05, 0.2]
        noisy.append(m.with_outputs(outputs))
    return model, ManeuverSet(noisy)


class Pendulum:
    """θ̈ = −ω² sin θ − c θ̇ + k δ (rad, rad/s; δ in % of stick); outputs θ and q = θ̇."""

    signals = ModelSignals(
        states=SignalSet([Signal("theta", *ANGLE), Signal("q", *RATE)]),
        inputs=SignalSet([Signal("stick", *STICK)]),
        outputs=SignalSet([Signal("theta", *ANGLE), Signal("q", *RATE)]))
    parameters = (Parameter("omega2", 5.0, lower=0.0), Parameter("damping", 0.3),
                  Parameter("gain", 0.05))

    def derivatives(self, t, x, u, theta):
        return np.stack([x[:, 1], -theta[:, 0] * np.sin(x[:, 0]) - theta[:, 1] * x[:, 1]
                         + theta[:, 2] * u[:, 0]], axis=1)

    def outputs(self, t, x, u, theta):
        return x


PENDULUM_TRUTH = np.array([9.0, 0.6, 0.12])
STICK_IN_LONG = ChannelMap([ChannelLink("long", "stick", "%")], source="test map")


def test_a_pendulum_is_identified_within_three_cramer_rao_bounds():
    model, data = pendulum_data(seed=11)
    # the records start at rest; taken from the data, θ(0) would carry the first sample's
    # noise into the whole response and bias the fit beyond its bounds
    fitted = IntegratedModel(model, channels=STICK_IN_LONG,
                             initial=InitialConditions(fixed={"theta": 0.0, "q": 0.0}))
    estimate = rotorid.create("estimators", "output-error").estimate(fitted, data)
    assert estimate.converged, estimate.stop_reason
    assert estimate.output_names == ("theta", "q")
    start = np.array([p.start for p in model.parameters])
    assert np.all(np.abs(start - PENDULUM_TRUTH) > 0.4 * PENDULUM_TRUTH)   # a real start error
    assert np.all(np.abs(estimate.values - PENDULUM_TRUTH) <= 3 * estimate.cramer_rao)
    # noise of the outputs in the model's units: 0.05 deg and 0.2 deg/s
    sigma = np.sqrt(np.diag(estimate.noise_covariance))
    np.testing.assert_allclose(sigma, np.radians([0.05, 0.2]), rtol=0.1)


def test_initial_states_from_the_data_fixed_or_estimated():
    model, data = pendulum_data(seed=3, start_angles=(5.0, -3.0))
    from_data = IntegratedModel(model, channels=STICK_IN_LONG)
    first = [y[0] for y in from_data.simulate(PENDULUM_TRUTH, data)]
    # θ(0) is the first measured sample (noisy), converted from deg to rad
    np.testing.assert_allclose([f[0] for f in first],
                               np.radians([m.channel("theta")[0] for m in data]))
    fixed = IntegratedModel(model, channels=STICK_IN_LONG,
                            initial=InitialConditions(fixed={"theta": 0.1, "q": 0.0}))
    assert [y[0, 0] for y in fixed.simulate(PENDULUM_TRUTH, data)] == [0.1, 0.1]
    estimated = IntegratedModel(model, channels=STICK_IN_LONG, maneuvers=data,
                                initial=InitialConditions(fixed={"q": 0.0},
                                                          estimated=("theta",)))
    estimate = rotorid.create("estimators", "output-error").estimate(estimated, data)
    assert estimate.converged, estimate.stop_reason
    truth = np.concatenate([PENDULUM_TRUTH, np.radians([5.0, -3.0])])
    assert estimate.parameter_names[3:] == ("x0_plus_theta", "x0_minus_theta")
    assert np.all(np.abs(estimate.values - truth) <= 3 * estimate.cramer_rao)


def test_the_estimator_wraps_a_nonlinear_model_and_honours_output_biases():
    maneuvers = step_maneuvers()
    fitted = as_model(FirstOrder())
    assert isinstance(fitted, IntegratedModel) and fitted.method == "central"
    assert as_model(FirstOrderWithJacobians()).method == "model"
    truth = IntegratedModel(FirstOrder(), initial=InitialConditions(fixed={"q": 0.0}))
    outputs = truth.simulate([2.5, 0.8, -1.2], maneuvers)
    columns = [rotorid.OUTPUTS.index("q"), rotorid.OUTPUTS.index("p")]
    records = []
    for m, y in zip(maneuvers, outputs):
        measured = np.zeros((m.n_samples, 8))
        measured[:, columns] = y + [0.01, -0.02]                  # biased sensors
        records.append(m.with_outputs(measured))
    data = ManeuverSet(records)
    assert np.allclose(measured_outputs(fitted, data)[0], outputs[0] + [0.01, -0.02])
    model = IntegratedModel(FirstOrder(), initial=InitialConditions(fixed={"q": 0.0}))
    estimate = rotorid.create("estimators", "output-error", output_biases=True,
                              horizons=()).estimate(model, data)
    np.testing.assert_allclose(estimate.values[:3], [2.5, 0.8, -1.2], rtol=1e-4)
    np.testing.assert_allclose(estimate.value("bias_short_p"), -0.02, atol=1e-6)


@pytest.mark.parametrize("options, message", [
    (dict(sensitivities="model"), "FirstOrder has no derivative_jacobians and output_jacobians"),
    (dict(sensitivities="adjoint"), "unknown sensitivity method 'adjoint'"),
    (dict(step=0.0), "the finite-difference step must be positive"),
    (dict(initial=InitialConditions(fixed={"alpha": 0.0})),
     "initial condition for 'alpha', which is not a state; states: q"),
    (dict(channels=ChannelMap([ChannelLink("az", "q", "g")], source="m.toml")),
     "m.toml: column 'az' has unit g, which does not fit signal 'q'"),
])
def test_bad_options_are_refused_when_the_model_is_built(options, message):
    with pytest.raises(rotorid.RotoridError, match=message):
        IntegratedModel(FirstOrder(), **options)


def test_bad_declarations_and_data():
    with pytest.raises(StructureError, match="is not a nonlinear model"):
        IntegratedModel(object())
    twice = FirstOrder()
    twice.parameters = (*FirstOrder.parameters, Parameter("b", 1.0))
    with pytest.raises(StructureError, match="parameter 'b' is declared twice"):
        IntegratedModel(twice)
    with pytest.raises(StructureError, match=r"parameter 'a': start 2 lies outside its bounds "
                                             r"\[0, 1\]"):
        Parameter("a", 2.0, lower=0.0, upper=1.0)
    model, data = pendulum_data(seed=1)
    with pytest.raises(rotorid.SignalError, match="maneuver 'plus' has no column 'stick' for "
                                                  "signal 'stick'"):
        IntegratedModel(model).simulate(PENDULUM_TRUTH, data)
    no_rate = ManeuverSet([Maneuver(m.name, m.time, m.inputs, m.columns(("theta",)),
                                    input_names=m.input_names, output_names=("theta",))
                           for m in data])
    with pytest.raises(StructureError, match=r"state 'q' starts each maneuver from the data, "
                                             r"but maneuver 'plus' has no column for it: give "
                                             r"its start, InitialConditions\(fixed=\{'q': "
                                             r"0.0\}\); with it in estimated as well"):
        IntegratedModel(model, channels=STICK_IN_LONG, maneuvers=no_rate,
                        initial=InitialConditions(estimated=("q",)))
    estimated = IntegratedModel(model, channels=STICK_IN_LONG, maneuvers=data,
                                initial=InitialConditions(estimated=("q",)))
    other = ManeuverSet([attrs.evolve(data[0], name="third")])
    with pytest.raises(StructureError, match="maneuver 'third' has no estimated initial state"):
        estimated.simulate(estimated.initial_values(), other)
    unbound = IntegratedModel(model, channels=STICK_IN_LONG,
                              initial=InitialConditions(estimated=("q",)))
    with pytest.raises(StructureError, match=r"give the model its maneuvers first, "
                                             r"model.for_maneuvers\(maneuvers\)"):
        unbound.simulate(unbound.initial_values(), data)
    bound = unbound.for_maneuvers(data)
    assert bound.parameter_names == estimated.parameter_names
    np.testing.assert_array_equal(bound.initial_values(), estimated.initial_values())


def test_the_models_page_example_declares_an_identifiable_model():
    page = (Path(__file__).resolve().parents[1] / "docs" / "models.md").read_text()
    (code,) = [block for block in re.findall(r"^```python\n(.*?)^```$", page, flags=re.M | re.S)
               if "class Pendulum" in block]
    namespace = {}
    exec(code, namespace)
    fitted = as_model(namespace["Pendulum"]())
    assert fitted.parameter_names == ("omega2", "damping", "gain")
    assert fitted.output_names == ("theta", "q")
    model, data = pendulum_data(seed=0)
    documented = IntegratedModel(namespace["Pendulum"](), channels=STICK_IN_LONG)
    np.testing.assert_array_equal(documented.simulate(PENDULUM_TRUTH, data)[0],
                                  IntegratedModel(model, channels=STICK_IN_LONG).simulate(
                                      PENDULUM_TRUTH, data)[0])


class WithRollAcceleration(FirstOrder):
    """FirstOrder with a third output, an angular acceleration not among the fixed channels."""

    signals = ModelSignals(states=FirstOrder.signals.states, inputs=FirstOrder.signals.inputs,
                           outputs=SignalSet([*FirstOrder.signals.outputs,
                                              Signal("q_dot", "rad/s²", "angular-acceleration")]))

    def outputs(self, t, x, u, theta):
        return np.concatenate([super().outputs(t, x, u, theta),
                               self.derivatives(t, x, u, theta)], axis=1)


def test_extra_maneuver_channels_are_read_through_the_map():
    (m, *_) = step_maneuvers()
    recorded = attrs.evolve(m, extra_channels={"QDOT_DEG": np.full(m.n_samples, 90.0)})
    model = IntegratedModel(WithRollAcceleration(), initial=InitialConditions(fixed={"q": 0.0}),
                            channels=ChannelMap([ChannelLink("QDOT_DEG", "q_dot", "deg/s²")]))
    (measured,) = model.measured(ManeuverSet([recorded]))
    np.testing.assert_allclose(measured[:, 2], np.pi / 2)        # 90 deg/s² in rad/s²
    (simulated,) = model.simulate([2.0, 0.5, -1.5], ManeuverSet([recorded]))
    assert simulated[0, 2] == pytest.approx(0.5)                  # q̇(0) = b·1 from rest


def test_a_simulation_anticipates_the_sensitivities_at_its_values():
    maneuvers = step_maneuvers()
    fixed = InitialConditions(fixed={"q": 0.0})
    model = FirstOrder()
    anticipating = IntegratedModel(model, initial=fixed)
    plain = IntegratedModel(FirstOrder(), initial=fixed, anticipate=False)
    values = np.array([2.0, 0.5, -1.5])
    outputs = anticipating.simulate(values, maneuvers)
    assert model.calls == 4 * (300 + 100)          # one batched integration per sample time
    again, sens = anticipating.sensitivities(values.copy(), maneuvers)
    assert model.calls == 4 * (300 + 100)          # ready: nothing integrated again
    _, expected_sens = plain.sensitivities(values, maneuvers)
    for y, y2, s, s2, z in zip(outputs, again, sens, expected_sens,
                               plain.simulate(values, maneuvers)):
        assert y is y2 and not y.flags.writeable and not s.flags.writeable
        np.testing.assert_array_equal(s, s2)
        np.testing.assert_array_equal(y, z)
    anticipating.sensitivities(values + [0.1, 0.0, 0.0], maneuvers)
    assert model.calls == 2 * 4 * (300 + 100)      # other values: integrated afresh
