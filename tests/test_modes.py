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
