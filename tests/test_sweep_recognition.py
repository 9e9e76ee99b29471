"""Telling a frequency sweep from a step input (rotorid.verification.pairs), and the time
histories' zoom outputs for controls outside the helicopter's four (report.plots.case)."""

import numpy as np
import pytest
from rotorid.data import Maneuver, ManeuverSet
from rotorid.report.plots.case import _zoomed
from rotorid.verification.pairs import input_reversals, not_a_sweep, step_input_notes

DT = 0.02
TIME = np.arange(0.0, 30.0, DT)


def _pulse(start, length, amplitude):
    return np.where((TIME >= start) & (TIME < start + length), amplitude, 0.0)


MULTISTEP_3211 = (_pulse(1, 3, 1.0) - _pulse(4, 2, 1.0) + _pulse(6, 1, 1.0) - _pulse(7, 1, 1.0))
DOUBLET = _pulse(1, 1, 1.0) - _pulse(2, 1, 1.0)
#: 0.1 to 1 Hz over 30 s: about 16 cycles, 32 reversals.
CHIRP = np.sin(2 * np.pi * np.cumsum(0.1 + 0.9 * TIME / TIME[-1]) * DT)


def _maneuver(name, aileron, rudder=None, **metadata):
    inputs = np.column_stack([aileron, np.zeros_like(aileron) if rudder is None else rudder])
    return Maneuver(name, TIME, inputs, np.zeros((TIME.size, 2)), metadata=metadata,
                    units="si", input_names=("aileron", "rudder"), output_names=("p", "r"))


@pytest.mark.parametrize("signal, reversals", [
    (MULTISTEP_3211, 3),      # + − + −
    (DOUBLET, 1),
    (np.sin(2 * np.pi * 0.5 * TIME), 29),     # 15 cycles from 0: 30 crossings, the first at 0
    (np.zeros_like(TIME), 0),
])
def test_reversals_are_counted_as_a_hand_count_gives_them(signal, reversals):
    assert input_reversals(signal) == reversals


def test_noise_about_the_trim_does_not_count_as_reversals():
    noisy = DOUBLET + np.random.default_rng(0).normal(0.0, 0.05, TIME.size)
    assert input_reversals(noisy) == 1


def test_a_sweep_passes_and_step_inputs_are_named_with_their_input_and_count():
    assert not_a_sweep(_maneuver("sweep", CHIRP)) is None
    why = not_a_sweep(_maneuver("rudder doublet", 0.01 * DOUBLET, DOUBLET))
    assert why.startswith("its input rudder reverses 1 time(s) in 30 s: a step input")
    notes = step_input_notes(ManeuverSet([_maneuver("sweep", CHIRP),
                                          _maneuver("ail_3211", MULTISTEP_3211)]))
    assert len(notes) == 1 and notes[0].startswith("ail_3211: its input aileron reverses 3")


def test_maneuvers_that_state_their_kind_are_not_second_guessed():
    stated = ManeuverSet([_maneuver("ail_3211", MULTISTEP_3211, kind="sweep")])
    assert step_input_notes(stated) == []


def test_the_zoom_of_a_control_outside_the_helicopters_shows_the_rates_it_drives():
    """Outputs beta, p, phi, r, ay; the rudder drives r's rate directly, the roll follows;
    beta and ay (no rates) come after both rates whatever their correlation."""
    outputs, rates = ("beta", "p", "phi", "r", "ay"), ("p", "r")
    rudder = DOUBLET
    r = np.cumsum(rudder) * DT                        # ṙ = rudder
    p = 0.3 * np.cumsum(r) * DT                       # ṗ follows r, not the rudder
    beta = 0.5 * rudder                               # β̇ a sharp response to the steps
    response = np.column_stack([beta, p, np.cumsum(p) * DT, r, rudder])
    assert _zoomed("rudder", outputs, rates, rudder, response) == ("r", "p")
    assert _zoomed("long", ("q", "p", "az"), ("q", "p"), rudder, response) == ("q", "p")
    assert _zoomed("rudder", outputs, rates, rudder, None) == ("beta", "p")
    assert _zoomed("rudder", outputs, rates, np.zeros_like(rudder), response) == ("beta", "p")
