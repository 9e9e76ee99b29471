"""Modes of a linear model against closed forms: a short-period pair and a roll subsidence."""

import math

import numpy as np
import pytest
from rotorid.model.modelfile import parse_model
from rotorid.model.modes import Mode, modes


def test_a_pitch_pair_and_a_roll_subsidence_by_their_closed_forms():
    """Hover, M_q = −2, M_u = 0.02 with gravity on θ and X_u = −0.1: the phugoid-like pair
    of u, θ; L_p = −6 alone: a real mode −6 in p (φ integrates it, λ = 0)."""
    structure = parse_model({"units": "flight-test", "condition": {"airspeed_kt": 0.0},
                             "structure": {"populate": "none"},
                             "derivatives": {"X_u": {}, "M_u": {}, "M_q": {}, "L_p": {}}},
                            "pair")
    values = {"X_u": -0.1, "M_u": 0.02, "M_q": -2.0, "L_p": -6.0}
    found = modes(structure, structure.as_vector(values))
    a = structure.matrices(structure.as_vector(values))[0]
    expected = sorted(np.linalg.eigvals(a), key=abs)
    shown = [m.eigenvalue for m in found]
    assert len(shown) == len([e for e in expected if e.imag >= 0])
    for value in shown:
        assert min(abs(value - e) for e in expected) < 1e-9
    roll = next(m for m in found if abs(m.eigenvalue + 6.0) < 1e-9)
    assert roll.states[0] == "p" and roll.time_constant == pytest.approx(1 / 6)
    assert roll.describe() == "time constant 0.167 s"
    pair = next(m for m in found if m.oscillatory)
    assert pair.frequency == pytest.approx(abs(pair.eigenvalue))
    assert pair.damping == pytest.approx(-pair.eigenvalue.real / abs(pair.eigenvalue))
    assert set(pair.states) <= {"u", "q", "theta"}
    assert pair.describe() == f"ω_n {abs(pair.eigenvalue):.3g} rad/s, ζ {pair.damping:.3g}"
    assert math.isinf(next(m for m in found if m.eigenvalue == 0).time_constant)
    assert Mode(0.2 + 0j, ("u",)).describe() == f"doubles in {math.log(2) / 0.2:.3g} s"


def _damped_sway(y_v: float):
    structure = parse_model({"units": "si", "condition": {"airspeed_kt": 0.0},
                             "structure": {"populate": "none"},
                             "derivatives": {"Y_v": {}, "Y_lat": {}, "L_v": {}, "L_p": {},
                                             "L_lat": {}}},
                            "sway")
    return structure, {"Y_v": y_v, "Y_lat": 20.0, "L_v": -0.5, "L_p": -4.0, "L_lat": 5.0}


def test_a_mode_settled_within_two_samples_is_named_with_the_derivatives_that_set_it():
    """Y_v = −100 1/s gives a real mode at −100 (v's row holds Y_v alone: closed form) that
    settles within two samples at 0.01 s (|λ|·dt = 1) but not at 0.001 s (0.1); the roll
    subsidence at −4 is never named."""
    from rotorid.estimation.fit_notes import fast_modes_note

    structure, values = _damped_sway(-100.0)
    note = fast_modes_note(structure, values, 0.01)
    assert note is not None and "-100 1/s" in note and "time constant 0.01 s" in note
    assert "set by Y_v;" in note and "L_p" not in note
    assert fast_modes_note(structure, values, 0.001) is None
    assert fast_modes_note(structure, {**values, "Y_v": -0.3}, 0.01) is None


def test_output_error_names_the_fast_mode_of_its_fit():
    """Fitted to data its own model simulated with Y_v = −80 1/s at 0.01 s, output error
    recovers that mode and says so in its notes, pointing to filter error for turbulence;
    filter error without a noise model points to gusts or disturbances instead."""
    import rotorid
    from rotorid.data import Maneuver, ManeuverSet
    from rotorid.simulation.simulator import simulate

    structure, values = _damped_sway(-80.0)
    time = np.arange(0.0, 6.0, 0.01)
    pulse = np.zeros((time.size, structure.n_controls))
    pulse[(time > 1.0) & (time < 1.5), structure.controls.index("lat")] = 1.0
    blank = np.zeros((time.size, len(structure.outputs)))
    plain = ManeuverSet([Maneuver(f"lat{sign:+.0f}", time, sign * pulse, blank, units="si",
                                  input_names=structure.controls,
                                  output_names=structure.outputs) for sign in (1.0, -1.0)])
    rng = np.random.default_rng(7)
    recorded = ManeuverSet([m.with_outputs(y + rng.normal(0.0, 1e-4, y.shape))
                            for m, y in zip(plain, simulate(structure, values, plain))])
    estimate = rotorid.create("estimators", "output-error").estimate(structure, recorded)
    assert estimate.value("Y_v") == pytest.approx(-80.0, rel=0.05)
    assert any(n.startswith("modes faster than the records resolve") and "Y_v" in n
               and "(fit with filter error)" in n for n in estimate.notes)
    # filter error without a noise model says what its own fit leaves out, not to use it
    filtered = rotorid.create("estimators", "filter-error", process_noise=()).estimate(
        structure, recorded)
    [note] = [n for n in filtered.notes if n.startswith("modes faster than the records")]
    assert "leaves out as output error does: give it gusts or disturbances" in note
    assert "fit with filter error" not in note


def test_smoothly_moving_inputs_under_the_zero_order_hold_are_named():
    """A doublet held by a computer jumps by its whole excursion within one sample; the same
    doublet through a 0.06 s actuator lag at 50 Hz moves at most 1 − e^(−0.02/0.06) = 28 % of
    it per sample: named under the zero-order hold, not under the first-order one."""
    import attrs
    from rotorid.data import Maneuver, ManeuverSet
    from rotorid.estimation.fit_notes import smooth_inputs_note

    time = np.arange(0.0, 4.0, 0.02)
    held = np.where((time >= 1.0) & (time < 1.5), 1.0, 0.0) - np.where(
        (time >= 1.5) & (time < 2.0), 1.0, 0.0)
    lagged = np.zeros_like(held)
    decay = math.exp(-0.02 / 0.06)
    for k in range(1, time.size):
        lagged[k] = decay * lagged[k - 1] + (1 - decay) * held[k - 1]

    def record(stick):
        inputs = np.zeros((time.size, 4))
        inputs[:, 0] = stick
        return ManeuverSet([Maneuver("doublet", time, inputs, np.zeros((time.size, 8)))])

    assert smooth_inputs_note(record(held)) is None
    note = smooth_inputs_note(record(lagged))
    assert note is not None and "above 28% of their excursion" in note and "--hold foh" in note
    assert smooth_inputs_note(attrs.evolve(record(lagged), hold="foh")) is None
