"""The apparent model response: verification of models whose open-loop simulation drifts."""

import numpy as np
import pytest
from rotorid.data import Maneuver, ManeuverSet
from rotorid.model.derivatives import Derivative
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.simulation.simulator import simulate
from rotorid.simulation.transfer import frequency_response
from rotorid.verification.compare import compare_sweeps
from rotorid.verification.verify import verify_model
from rotorid.verification.frequency import (
    apparent_response,
    log_grid,
    response_from_maneuvers,
)
from scipy import signal
from sweeps import DT, log_sweep

OMEGA = log_grid(0.5, 12.0, 60)
Q = 2   # output column of q


def _pitch(m_q: float, extra=()) -> ModelStructure:
    return ModelStructure(FlightCondition(), [Derivative("M_q", m_q), Derivative("M_long", 30.0),
                                              *extra])


def _sweep_inputs(rng, n):
    inputs = np.zeros((n, 4))
    inputs[:, 0] = 2.0 * log_sweep(duration=70.0, omega_max=15.0)[:n]
    return inputs


def test_apparent_response_equals_the_single_input_estimate_of_a_simulation():
    """Stable model, lateral input moved by a loop that follows the longitudinal one: the
    apparent response is what the single-input estimate of the model's simulation gives."""
    model = _pitch(-3.0, [Derivative("M_lat", 8.0), Derivative("L_p", -5.0),
                          Derivative("L_lat", 10.0)])
    rng = np.random.default_rng(3)
    n = log_sweep(duration=70.0, omega_max=15.0).size
    inputs = _sweep_inputs(rng, n)
    follow = signal.lfilter([0.05], [1.0, -0.95], inputs[:, 0])      # a lagging loop
    inputs[:, 1] = 0.8 * follow + 0.05 * rng.standard_normal(n)
    time = np.arange(n) * DT
    sweeps = ManeuverSet([Maneuver("s", time, inputs, np.zeros((n, 8)), {"axis": "long"})])
    simulated = simulate(model, None, sweeps)
    by_simulation = response_from_maneuvers(sweeps, "long", "q", OMEGA, outputs=simulated)
    analytic = frequency_response(model, None, OMEGA)[:, Q]
    apparent, truth = apparent_response(sweeps.select(lambda m: True), "long", "q", OMEGA,
                                        analytic)
    coherent = by_simulation.coherence >= 0.8
    assert coherent.sum() > 40
    ratio = apparent.response[coherent] / by_simulation.response[coherent]
    assert np.max(np.abs(ratio - 1.0)) < 0.03
    # ... and it differs from the model's own q/long response: the lateral loop matters.
    assert np.max(np.abs(apparent.response[coherent] / analytic[coherent, 0] - 1.0)) > 0.2
    # The returned truth estimate is the usual single-input estimate of the records.
    plain_truth = response_from_maneuvers(sweeps, "long", "q", OMEGA)
    assert np.allclose(truth.response, plain_truth.response, equal_nan=True)


@pytest.fixture(scope="module")
def closed_loop_sweep():
    """An unstable pitch axis (M_q > 0) swept under a pitch attitude/rate hold; recorded
    stick = pilot + loop, noise-free outputs."""
    truth = _pitch(0.25)
    a, b, c, d = truth.matrices()
    ad, bd, cd, dd, _ = signal.cont2discrete((a, b, c, d), DT, method="zoh")
    pilot = _sweep_inputs(None, log_sweep(duration=70.0, omega_max=15.0).size)
    n = pilot.shape[0]
    theta = truth.states.index("theta")
    gain = np.zeros((4, 8))
    gain[0, truth.states.index("q")], gain[0, theta] = 0.2, 0.3
    x = np.zeros(8)
    inputs, outputs = np.zeros((n, 4)), np.zeros((n, 8))
    for k in range(n):
        inputs[k] = pilot[k] - gain @ x
        outputs[k] = cd @ x + dd @ inputs[k]
        x = ad @ x + bd @ inputs[k]
    time = np.arange(n) * DT
    return truth, ManeuverSet([Maneuver("sweep-long", time, inputs, outputs,
                                        {"kind": "sweep", "axis": "long"})])


def test_an_unstable_model_is_verified_through_its_apparent_response(closed_loop_sweep):
    truth, sweeps = closed_loop_sweep
    wrong = truth.fixing("M_q", 0.08)
    growth = np.max(np.linalg.eigvals(wrong.matrices()[0]).real) * sweeps[0].duration
    assert growth > np.log(100)              # past the drift limit of verify_model
    open_loop = compare_sweeps(sweeps, simulate(wrong, None, sweeps), ["q/long"], omega=OMEGA)
    assert open_loop["q/long"].output_rms_ratio > 100          # the simulation drifts away
    result = verify_model(wrong, None, sweeps, ["q/long"], ["muad"], omega=OMEGA)
    assert any("apparent response" in note for note in result.notes)
    item = result["q/long"]
    assert item.model_source == "apparent" and item.summary()["model_source"] == "apparent"
    assert open_loop["q/long"].model_source == "simulated"
    coherent = item.coherence >= 0.8
    assert coherent.sum() > 40
    # Single input: the apparent response is the analytic one, and the truth's closed-loop
    # estimate recovers the unstable plant (within the few per cent of leakage that windows
    # on a long-memory plant leave), so ε is close to the analytic ratio of the two models.
    expected = (frequency_response(wrong, None, OMEGA)[:, Q, 0]
                / frequency_response(truth, None, OMEGA)[:, Q, 0])
    assert np.max(np.abs(expected[coherent] - 1.0)) > 0.3       # a visibly wrong model
    assert np.allclose(item.error[coherent], expected[coherent], rtol=0.05)
    exact = verify_model(truth, None, sweeps, ["q/long"], ["muad"], omega=OMEGA)
    assert exact["q/long"].checks["muad"].passed is True


def test_apparent_comparison_needs_the_analytic_response(closed_loop_sweep):
    from rotorid.errors import VerificationError

    truth, sweeps = closed_loop_sweep
    with pytest.raises(VerificationError, match="needs the analytic model response"):
        compare_sweeps(sweeps, simulate(truth, None, sweeps), ["q/long"],
                       model_response="apparent")
    with pytest.raises(VerificationError, match="must be 'simulated' or 'apparent'"):
        compare_sweeps(sweeps, simulate(truth, None, sweeps), ["q/long"], model_response="x")


def test_default_grid_starts_at_the_lowest_frequency_the_sweeps_excite():
    from rotorid.verification.compare import default_omega
    from rotorid.verification.frequency import default_windows, lowest_frequency

    n = 5000                                  # 100 s: the window limit is about 0.25 rad/s
    time = np.arange(n) * DT
    inputs, outputs = np.zeros((n, 4)), np.zeros((n, 8))

    def sweep(name, metadata):
        return Maneuver(name, time, inputs, outputs, {"axis": "long", **metadata})

    window_limit = lowest_frequency(default_windows(sweep("a", {}).duration)[0])
    assert default_omega([sweep("a", {})])[0] == pytest.approx(window_limit)
    recorded = [sweep("a", {"signal": {"omega_min": 0.45}}), sweep("b", {"omega_min": 0.6})]
    assert default_omega(recorded)[0] == pytest.approx(0.45)
    assert default_omega([sweep("a", {"omega_min": 0.1})])[0] == pytest.approx(window_limit)
    from rotorid.errors import VerificationError

    with pytest.raises(VerificationError, match="omega_min must be the sweep's lowest"):
        default_omega([sweep("a", {"omega_min": "slow"})])
