"""ADS-33 bandwidth and phase delay against hand-computed values."""

import math

import numpy as np
import pytest
import rotorid
from rotorid.model.derivatives import Derivative
from rotorid.simulation.transfer import frequency_response
from rotorid.verification.frequency import FrequencyResponse
from rotorid.errors import VerificationError
from rotorid.verification.handling_qualities import (
    available_pairs,
    handling_qualities_table,
    bandwidth_phase_delay,
    measured_handling_qualities,
    model_handling_qualities,
)
from scipy.optimize import brentq

#: θ/δ = K e^(−τs) / (s (s + a)): pitch rate first order with a control delay.
K, A, TAU = 0.8, 2.0, 0.1


def _phase_deg(omega):
    """Hand-derived phase of K e^(−τs)/(s(s + a)) in deg."""
    return -90.0 - math.degrees(math.atan(omega / A)) - math.degrees(TAU * omega)


def _reference():
    omega_180 = brentq(lambda w: _phase_deg(w) + 180.0, 0.1, 50.0)
    omega_135 = brentq(lambda w: _phase_deg(w) + 135.0, 0.1, 50.0)
    gain = lambda w: 20 * math.log10(K / (w * math.hypot(w, A)))  # noqa: E731
    omega_gain = brentq(lambda w: gain(w) - gain(omega_180) - 6.0, 0.01, omega_180)
    delay = -(_phase_deg(2 * omega_180) + 180.0) / (57.3 * 2 * omega_180)
    return omega_180, omega_135, omega_gain, delay


def test_reference_matches_the_hand_computation():
    # ω180: atan(ω/2) + 0.1ω = π/2 → ω = 4.328 (atan 2.164 = 1.1383, + 0.4328 = 1.5711).
    # ω135: atan(ω/2) + 0.1ω = π/4 → ω = 1.481 (0.6375 + 0.1481 = 0.7856).
    # τ_p: at 2ω180 = 8.657 the lag is atan(4.328) + 0.8657 = 2.2094 rad, 36.6° beyond 90°,
    # so τ_p = 36.6 / (57.3 · 8.657) = 0.0738 s.
    omega_180, omega_135, _, delay = _reference()
    assert omega_180 == pytest.approx(4.328, abs=1e-3)
    assert omega_135 == pytest.approx(1.481, abs=1e-3)
    assert delay == pytest.approx(0.0738, abs=1e-4)


def test_model_bandwidth_and_phase_delay_match_the_hand_computation():
    structure = rotorid.ModelStructure(rotorid.FlightCondition.from_airspeed(0.0), [
        Derivative("M_q"), Derivative("M_long")]).with_delays(["M_long"])
    values = {"M_q": -A, "M_long": K, "tau_M_long": TAU}
    (pitch,) = model_handling_qualities(structure, values, np.geomspace(0.1, 100.0, 4000),
                                        pairs=["theta/long"])
    omega_180, omega_135, omega_gain, delay = _reference()
    assert pitch.omega_180 == pytest.approx(omega_180, rel=1e-4)
    assert pitch.phase_bandwidth == pytest.approx(omega_135, rel=1e-4)
    assert pitch.gain_bandwidth == pytest.approx(omega_gain, rel=1e-4)
    assert pitch.bandwidth == pytest.approx(min(omega_135, omega_gain), rel=1e-4)
    assert pitch.phase_delay == pytest.approx(delay, rel=1e-3)
    assert not pitch.sign_reversed


def test_default_pairs_are_the_models_own_and_a_missing_path_has_no_numbers():
    """Without ``pairs`` every attitude pair the structure's signals hold is computed; the
    pitch model has no roll or yaw path, so those pairs carry no numbers; a longitudinal
    template (no lat, ped) has theta/long alone."""
    structure = rotorid.ModelStructure(rotorid.FlightCondition.from_airspeed(0.0), [
        Derivative("M_q"), Derivative("M_long")]).with_delays(["M_long"])
    values = {"M_q": -A, "M_long": K, "tau_M_long": TAU}
    pitch, roll, heading = model_handling_qualities(structure, values,
                                                    np.geomspace(0.1, 100.0, 4000))
    assert (pitch.pair, roll.pair, heading.pair) == ("theta/long", "phi/lat", "psi/ped")
    assert pitch.phase_bandwidth == pytest.approx(_reference()[1], rel=1e-4)
    assert roll.bandwidth is None and heading.omega_180 is None
    longitudinal = rotorid.ModelStructure.populated(rotorid.FlightCondition.from_airspeed(0.0),
                                                    "longitudinal")
    assert available_pairs(longitudinal.outputs, longitudinal.controls) == ("theta/long",)
    with pytest.raises(VerificationError, match="phi/lat: the model has no phi/lat"):
        model_handling_qualities(longitudinal, longitudinal.initial_values(),
                                 pairs=["phi/lat"])


def test_an_aeroplanes_pitch_attitude_over_its_elevator_has_the_same_numbers():
    """The fixed-wing template with M_q and a delayed M_elevator alone: θ/δe is the same
    K e^(−τs)/(s(s + a)) (u and w do not feed back into q), so the hand computation holds."""
    condition = rotorid.FlightCondition(u0=50.0, w0=0.0, theta0=0.0)
    structure = rotorid.ModelStructure.populated(condition, "fixed-wing-longitudinal", "si")
    structure = structure.without(*[n for n in structure.names
                                    if n not in ("M_q", "M_elevator")]).with_delays(
        ["M_elevator"])
    assert available_pairs(structure.outputs, structure.controls) == ("theta/elevator",)
    values = {"M_q": -A, "M_elevator": K, "tau_M_elevator": TAU}
    (pitch,) = model_handling_qualities(structure, values, np.geomspace(0.1, 100.0, 4000))
    omega_180, omega_135, omega_gain, delay = _reference()
    assert pitch.pair == "theta/elevator"
    assert pitch.omega_180 == pytest.approx(omega_180, rel=1e-4)
    assert pitch.bandwidth == pytest.approx(min(omega_135, omega_gain), rel=1e-4)
    assert pitch.phase_delay == pytest.approx(delay, rel=1e-3)


def test_measured_responses_heading_from_yaw_rate_and_reversed_sign():
    structure = rotorid.ModelStructure(rotorid.FlightCondition.from_airspeed(0.0), [
        Derivative("N_r"), Derivative("N_ped")]).with_delays(["N_ped"])
    values = {"N_r": -A, "N_ped": -K, "tau_N_ped": TAU}          # pedal reduces heading
    omega = np.geomspace(0.2, 40.0, 800)
    yaw = frequency_response(structure, values, omega)[:, rotorid.OUTPUTS.index("r"),
                                                        rotorid.CONTROLS.index("ped")]
    coherence = np.where(omega < 30.0, 0.9, 0.1)
    measured = FrequencyResponse("ped", "r", omega, yaw, coherence, np.zeros(omega.size))
    (heading,) = measured_handling_qualities([measured])
    omega_180, omega_135, omega_gain, delay = _reference()
    assert heading.pair == "psi/ped" and heading.source == "measured"
    assert heading.sign_reversed
    assert heading.omega_180 == pytest.approx(omega_180, rel=1e-3)
    assert heading.bandwidth == pytest.approx(min(omega_135, omega_gain), rel=1e-3)
    assert heading.phase_delay == pytest.approx(delay, rel=1e-2)


def test_phase_delay_is_none_beyond_the_grid():
    omega = np.geomspace(0.5, 6.0, 200)
    s = 1j * omega
    result = bandwidth_phase_delay(omega, K * np.exp(-TAU * s) / (s * (s + A)))
    assert result.omega_180 is not None and result.phase_delay is None


def test_table_takes_each_models_numbers_on_the_measured_coherent_frequencies():
    """With sweeps, a model's numbers come from the frequencies where the sweeps' response of
    the pair is coherent, so the true model and the measurement agree (within the composite
    estimate's 2° near −135°: 8 %). Without sweeps, every pair the model holds, over
    0.1–100 rad/s."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from test_frequency_response_estimator import TRUTH, _structure, _sweeps

    sweeps = rotorid.ManeuverSet(_sweeps(_structure(), TRUTH, noise=0.0, seed=0))
    table = handling_qualities_table({"truth": (_structure(), TRUTH)}, sweeps)
    measured = {q.pair: q for q in table["measured"]}
    model = {q.pair: q for q in table["truth"]}
    assert set(model) == set(measured) >= {"theta/long", "phi/lat"}
    for pair in ("theta/long", "phi/lat"):
        assert model[pair].bandwidth == pytest.approx(measured[pair].bandwidth, rel=0.08)
        assert model[pair].omega_180 == pytest.approx(measured[pair].omega_180, rel=0.08)
    without = {q.pair: q for q in handling_qualities_table({"truth": (_structure(), TRUTH)})[
        "truth"]}
    assert set(without) == {"theta/long", "phi/lat", "psi/ped"}
