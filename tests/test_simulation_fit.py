"""SimulationFit: one simulation of a model, its metrics and det R against the records, and
fit_unless_diverging, which gives None for a model whose simulation diverges."""

import numpy as np
import pytest
import rotorid
from rotorid.errors import SimulationDivergedError
from rotorid.model.modelfile import parse_model
from rotorid.simulation.simulator import simulate
from rotorid.verification.simulation_fit import fit_unless_diverging, simulation_fit

def hover_model(units: str = "flight-test", derivatives=("M_q", "M_long")) -> dict:
    """A model-file mapping: the hover six-dof template in ``units`` with only
    ``derivatives`` free."""
    return {"units": units, "condition": {"airspeed_kt": 0.0},
            "structure": {"populate": "none"}, "derivatives": {n: {} for n in derivatives}}


STRUCTURE = parse_model(hover_model(), "test")


def _records(seed=1):
    time = np.arange(501) * 0.02
    inputs = np.zeros((time.size, 4))
    inputs[(time > 1.0) & (time < 2.0), 0] = 1.0
    maneuver = rotorid.Maneuver("doublet", time, inputs, np.zeros((time.size, 8)))
    clean = rotorid.ManeuverSet([maneuver])
    outputs = simulate(STRUCTURE, [-2.0, 0.8], clean)[0]
    noise = np.random.default_rng(seed).normal(scale=0.1, size=outputs.shape)
    return rotorid.ManeuverSet([maneuver.with_outputs(outputs + noise)])


def test_the_fit_holds_the_simulation_and_its_measures():
    records = _records()
    fit = simulation_fit(STRUCTURE, [-1.5, 0.7], records)
    simulated = simulate(STRUCTURE, [-1.5, 0.7], records)
    np.testing.assert_array_equal(fit.outputs[0], simulated[0])
    residuals = records[0].outputs - simulated[0]
    assert fit.metrics.rmse == pytest.approx(np.sqrt(np.mean(residuals**2)), rel=1e-12)
    assert fit.det_r == pytest.approx(np.linalg.det(np.cov(residuals.T, bias=True)
                                                    + np.outer(*[residuals.mean(0)] * 2)),
                                      rel=1e-9)
    assert fit.summary()["det_r"] == fit.det_r


def test_a_diverging_model_gives_none_or_raises():
    records = _records()
    assert fit_unless_diverging(STRUCTURE, [80.0, 0.8], records) is None
    with pytest.raises(SimulationDivergedError):
        simulation_fit(STRUCTURE, [80.0, 0.8], records)


def test_an_si_model_has_the_metrics_of_the_same_model_in_flight_test_units():
    """One pitch model and its records, once in flight-test units and once converted by hand
    to SI: RMSE and J_rms are the same numbers (residuals counted in ft/s², deg/s, deg), per
    output RMSE stays in each output's own unit."""
    feet, degrees = 0.3048, np.pi / 180.0
    records = _records(seed=3)
    units = STRUCTURE.signals.outputs.units
    factors = np.array([feet if u == "ft/s²" else degrees for u in units])
    si_records = rotorid.ManeuverSet([rotorid.Maneuver(m.name, m.time, m.inputs,
                                                       m.outputs * factors, units="si")
                                      for m in records])
    si_structure = parse_model(hover_model("si"), "test")
    flight_test = simulation_fit(STRUCTURE, [-1.5, 0.7], records)
    si = simulation_fit(si_structure, [-1.5, 0.7 * degrees], si_records)
    assert si_structure.signals.outputs.units != units
    assert si.metrics.rmse == pytest.approx(flight_test.metrics.rmse, rel=1e-9)
    assert si.metrics.j_rms == pytest.approx(flight_test.metrics.j_rms, rel=1e-9)
    np.testing.assert_allclose(si.metrics.overall.rmse_per_output,
                               flight_test.metrics.overall.rmse_per_output * factors,
                               rtol=1e-9)
    assert si.metrics.overall.summary()["pooled_units"]["q"] == "deg/s"
    assert si.metrics.overall.summary()["rmse_per_output_units"]["q"] == "rad/s"
    assert " rad/s" in si.metrics.report().splitlines()[1]
