"""Verification with per-maneuver input biases and output reference shifts."""

import numpy as np
import pytest
import rotorid
from rotorid.data import Maneuver, ManeuverSet
from rotorid.model.derivatives import Derivative
from rotorid.verification.shifts import simulate_with_shifts

HOVER = rotorid.FlightCondition.from_airspeed(0.0)
TRUTH = {"L_p": -3.0, "L_lat": 0.9, "M_q": -1.5, "M_long": 0.6, "X_u": -0.05,
         "X_long": -0.2, "tau_L_lat": 0.06}


def _structure():
    return rotorid.ModelStructure(HOVER, [Derivative(n) for n in (
        "L_p", "L_lat", "M_q", "M_long", "X_u", "X_long")]).with_delays(["L_lat"])


def _maneuver(name, seed):
    time = np.arange(0.0, 12.0, 0.02)
    rng = np.random.default_rng(seed)
    inputs = np.zeros((time.size, 4))
    for k in (0, 1):                        # 3211-like steps on both cyclic inputs
        inputs[:, k] = np.repeat(rng.choice([-1.0, 1.0], 12), time.size // 12 + 1)[:time.size]
    return Maneuver(name, time, inputs, np.zeros((time.size, 8)))


def test_biases_and_shifts_of_each_maneuver_are_recovered_exactly():
    """Measured outputs made by simulating the inputs plus known biases (a separate
    simulation, not the linear superposition the fit uses) plus known output shifts."""
    structure = _structure()
    maneuvers = ManeuverSet([_maneuver("a", 0), _maneuver("b", 1)])
    biases = np.array([[0.3, -0.2, 0.1, 0.05], [-0.1, 0.4, -0.3, 0.2]])     # % of travel
    shifts = np.array([[0.5 * j - 1.0 for j in range(8)], [0.2 * j for j in range(8)]])
    biased = ManeuverSet([Maneuver(m.name, m.time, m.inputs + b, m.outputs)
                          for m, b in zip(maneuvers, biases)])
    measured = ManeuverSet([
        Maneuver(m.name, m.time, m.inputs, y + r)
        for m, y, r in zip(maneuvers, rotorid.simulate(structure, TRUTH, biased), shifts)])
    fit = simulate_with_shifts(structure, TRUTH, measured)
    controls = [rotorid.CONTROLS.index(c) for c in ("long", "lat")]
    # only the inputs this structure responds to are determined
    assert np.allclose(fit.input_biases[:, controls], biases[:, controls], atol=1e-9)
    assert np.allclose(fit.reference_shifts, shifts, atol=1e-9)
    for m, y in zip(measured, fit.outputs):
        assert np.allclose(y, m.outputs, atol=1e-9)


def test_the_fit_never_raises_the_rmse_of_the_plain_simulation():
    structure = _structure()
    maneuvers = ManeuverSet([_maneuver("a", 2)])
    wrong = {**TRUTH, "L_p": -2.0, "M_long": 0.8}
    rng = np.random.default_rng(5)
    measured = ManeuverSet([Maneuver(m.name, m.time, m.inputs,
                                     y + 0.3 + 0.1 * rng.standard_normal(y.shape))
                            for m, y in zip(maneuvers, rotorid.simulate(structure, TRUTH,
                                                                        maneuvers))])
    plain = rotorid.simulate(structure, wrong, measured)[0]
    shifted = simulate_with_shifts(structure, wrong, measured).outputs[0]
    z = measured[0].outputs
    assert np.sqrt(np.mean((z - shifted) ** 2)) < np.sqrt(np.mean((z - plain) ** 2))
    assert shifted.flags.writeable is False
    with pytest.raises(rotorid.SimulationDivergedError):
        simulate_with_shifts(structure, {**TRUTH, "L_p": 30.0, "M_q": 30.0}, measured)
