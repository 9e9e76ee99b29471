"""Edge cases of the simulation engine: nothing to force, records shorter than a delay,
and the interval integrals of the discretisation against the block matrix exponential."""

import warnings

import numpy as np
import pytest
import scipy.linalg
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.errors import SimulationDivergedError, StructureError
from rotorid.simulation.discretisation import _integrals
from rotorid.simulation.simulator import Simulator

#: The six-dof states' force and moment rows: u w q v p r.
EQUATION_ROWS = (0, 1, 2, 4, 5, 7)

CONDITION = FlightCondition.from_airspeed(40.0)


def test_zero_inputs_and_zero_derivatives_give_trim_and_finite_sensitivities():
    structure = ModelStructure.six_dof(CONDITION).with_delays(["L_lat"])
    t = np.arange(50) * 0.02
    maneuvers = ManeuverSet([Maneuver("quiet", t, np.zeros((50, 4)), np.zeros((50, 8)))])
    y, sens = Simulator(structure, maneuvers).outputs_and_sensitivities(None)
    assert np.array_equal(y[0], np.zeros((50, 8)))
    assert sens[0].shape == (50, structure.n_parameters, 8)
    assert np.array_equal(sens[0], np.zeros_like(sens[0]))


def test_initial_state_drives_sensitivities_without_inputs():
    structure = ModelStructure.six_dof(CONDITION)
    values = structure.as_vector({"L_p": -3.0, "M_q": -1.5})
    t = np.arange(40) * 0.02
    x0 = np.zeros(8)
    x0[5] = 2.0  # roll rate
    maneuver = Maneuver("free", t, np.zeros((40, 4)), np.zeros((40, 8)), initial_state=x0)
    y, sens = Simulator(structure, ManeuverSet([maneuver])).outputs_and_sensitivities(values)
    p = structure.outputs.index("p")
    assert np.allclose(y[0][:, p], 2.0 * np.exp(-3.0 * t), rtol=1e-9)
    expected = t * 2.0 * np.exp(-3.0 * t)   # ∂/∂L_p of 2·exp(L_p·t)
    k = structure.parameter_names.index("L_p")
    assert np.allclose(sens[0][:, k, p], expected, rtol=1e-8, atol=1e-12)


def test_delay_longer_than_the_record_leaves_the_input_unseen():
    structure = ModelStructure.six_dof(CONDITION).with_delays(["L_lat"])
    values = structure.as_vector({"L_p": -3.0, "L_lat": 1.0, "tau_L_lat": 0.2})
    t = np.arange(6) * 0.02
    u = np.zeros((6, 4))
    u[:, 1] = 1.0
    y = Simulator(structure, ManeuverSet([Maneuver("short", t, u, np.zeros((6, 8)))])
                  ).outputs(values)[0]
    assert np.array_equal(y, np.zeros_like(y))


@pytest.mark.parametrize("scale", [0.1, 3.0, 40.0])  # no doubling, a few, many
def test_interval_integrals_match_the_block_exponential(scale):
    rng = np.random.default_rng(4)
    a = rng.normal(size=(2, 8, 8)) * scale
    s = np.array([[0.02, 0.007], [0.02, 0.0131]])
    phi, gam, kin = _integrals(a.astype(complex), s.astype(complex), EQUATION_ROWS)
    rows = list(EQUATION_ROWS)
    for d in range(2):
        for j in range(2):
            block = np.zeros((20, 20))
            block[:8, :8] = a[d]
            block[rows, 8 + np.arange(6)] = 1.0
            block[8 + np.arange(6), 14 + np.arange(6)] = 1.0
            ex = scipy.linalg.expm(block * s[d, j])
            for mine, ref in ((phi, ex[:8, :8]), (gam, ex[:8, 8:14]), (kin, ex[:8, 14:])):
                assert np.max(np.abs(mine[d, j] - ref)) <= 1e-12 * np.max(np.abs(ref))


def test_complex_step_through_the_integrals_gives_the_frechet_derivative():
    rng = np.random.default_rng(5)
    a = rng.normal(size=(8, 8)) * 5.0
    direction = np.zeros((8, 8))
    direction[2, 5] = 1.0
    h = 1e-30
    phi, _, _ = _integrals((a + 1j * h * direction)[None], np.array([[0.02 + 0j]]),
                           EQUATION_ROWS)
    _, frechet = scipy.linalg.expm_frechet(a * 0.02, direction * 0.02)
    assert np.max(np.abs(phi[0, 0].imag / h - frechet)) <= 1e-12 * np.max(np.abs(frechet))


def test_a_model_far_out_diverges_with_an_error_and_no_numpy_warning():
    """A trial step far out (M_q = −10¹⁵⁰ 1/s, as a profile fit may try): e^{A·dt} overflows in
    the discretisation's doublings, silently, and the simulation says it diverged."""
    structure = ModelStructure.six_dof(CONDITION)
    values = structure.as_vector({"M_q": -1e150, "M_long": 1.0})
    t = np.arange(20) * 0.02
    u = np.zeros((20, 4))
    u[5:, 0] = 1.0
    maneuvers = ManeuverSet([Maneuver("far", t, u, np.zeros((20, 8)))])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        with pytest.raises(SimulationDivergedError, match="simulation diverged"):
            Simulator(structure, maneuvers).outputs(values)


def test_negative_delays_are_rejected_by_name():
    structure = ModelStructure.six_dof(CONDITION).with_delays(["L_lat", "M_long"])
    t = np.arange(10) * 0.02
    maneuvers = ManeuverSet([Maneuver("m", t, np.ones((10, 4)), np.zeros((10, 8)))])
    with pytest.raises(StructureError, match="negative delay.*tau_M_long.*bound them below"):
        Simulator(structure, maneuvers).outputs({"tau_M_long": -0.01})
