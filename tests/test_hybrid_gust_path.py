"""docs/examples/hybrid_gust_path.py: the frequency responses it compares, against
a modal decomposition's, and the claim docs/estimation.md draws from it."""

import numpy as np
import pytest
from docs_examples import load_example
from rotorid import FlightCondition, ModelStructure
from rotorid.model.hybrid import hybrid_from_six_dof
from rotorid.study.truth import truth_derivatives
from rotorid.units import FLIGHT_TEST, SI, channel_scale
from rotorid_helisim.linear_truth import LinearisedPlant
from rotorid_helisim.source import HelisimSource

OMEGA = np.array([0.1, 1.0, 6.0, 20.0])


@pytest.fixture(scope="module")
def example():
    return load_example("hybrid_gust_path")


def _modal_response(a, b, c, d, omega):
    """(F, p) response of one input column b (n,) from A's eigenvectors: C·V·diag(1/(jω − λ))·
    V⁻¹·b + d."""
    eigenvalues, vectors = np.linalg.eig(a)
    modal_input = np.linalg.solve(vectors, b)
    return np.array([(c @ vectors) @ (modal_input / (1j * w - eigenvalues)) + d
                     for w in omega])


def test_truth_gust_response_matches_scipy(example):
    source = HelisimSource()
    plant = LinearisedPlant.about(source.plant, source.trim(0.0), rotor=True)
    outputs = ("ax", "az", "q", "theta", "ay", "p", "phi", "r")
    response = example.truth_responses(plant, outputs, FLIGHT_TEST, OMEGA)
    reference = _modal_response(plant.a, plant.g[:, 1], plant.c, plant.h[:, 1], OMEGA)
    reference *= channel_scale(outputs, FLIGHT_TEST, SI) / channel_scale(("v",), FLIGHT_TEST,
                                                                          SI)[0]
    np.testing.assert_allclose(response[:, :, 4], reference, rtol=1e-9, atol=1e-12)


def test_hybrid_gust_response_is_minus_the_v_column(example):
    """The gust acts as v's negative in the derivative terms: the response of a system whose
    input matrix is −A's column of v and whose feedthrough is −C's derivative part."""
    condition = FlightCondition.from_airspeed(0.0, 3.0, -2.0)
    six_dof = ModelStructure.six_dof(condition)
    truth = truth_derivatives(HelisimSource(), condition, six_dof)
    hybrid = hybrid_from_six_dof(six_dof, six_dof.as_vector(truth))
    values = hybrid.initial_values()
    a, _, c, _ = hybrid.matrices(values)
    v = hybrid.states.index("v")
    reference = _modal_response(a, -a[:, v],
                                c, -(c[:, v] - hybrid.known_output_matrix()[:, v]), OMEGA)
    response = example.hybrid_responses(hybrid, values, OMEGA)
    np.testing.assert_allclose(response[:, :, -1], reference, rtol=1e-9, atol=1e-12)


def test_hybrid_can_carry_the_gust_path(example):
    """docs/estimation.md's claim: fitted to the stick and gust responses together, the hybrid
    keeps L_p and L_lat within 10 % of the truth and fits the gust better than from its start,
    without losing the sticks."""
    table = example.main()
    joint, start, truth = table["sticks + v_g"], table["start"], table["truth"]
    for key in ("L_p", "L_lat", "M_q", "N_r", "N_ped", "Z_w", "Z_coll"):
        assert abs(joint[key] / truth[key] - 1) < 0.10, key
    assert joint["misfit v_g"] < start["misfit v_g"]
    assert joint["misfit sticks"] < start["misfit sticks"]
