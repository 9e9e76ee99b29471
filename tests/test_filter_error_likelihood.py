"""The innovations' likelihood rejects an innovation covariance that is not a covariance."""

import numpy as np
import pytest
from rotorid_filter_error.likelihood import InnovationLikelihood


class _Innovations(InnovationLikelihood):
    """A likelihood whose innovations (20 samples of 3 outputs) and B are given."""

    output_names = ("a", "b", "c")
    rmse_scale = np.ones(3)
    n_samples = 20

    def __init__(self, b):
        self.b = np.asarray(b, dtype=float)
        self.nu = np.random.default_rng(0).standard_normal((20, 1, 3))

    def innovations(self, values):
        return self.nu, self.b

    def per_maneuver(self, innovations):
        return [innovations[:, 0]]


def test_an_indefinite_innovation_covariance_with_a_positive_determinant_is_refused():
    """B with two negative eigenvalues has det B > 0, so its log-determinant alone looked
    valid; the cost is infinite and the failure names B's smallest eigenvalue."""
    indefinite = np.diag([-4.0, -0.5, 2.0])
    assert np.linalg.det(indefinite) > 0
    likelihood = _Innovations(indefinite)
    cost, b, _, rmse = likelihood.evaluate(np.zeros(1))
    assert cost == np.inf and b is None and rmse == np.inf
    message = likelihood.failure(np.zeros(1))
    assert "not positive definite (smallest eigenvalue -4)" in message


def test_a_positive_definite_innovation_covariance_gives_the_likelihood_cost():
    """exp(2L/N) = det B · exp(mean νᵀB⁻¹ν), against its direct evaluation."""
    b = np.array([[2.0, 0.3, 0.0], [0.3, 1.0, 0.1], [0.0, 0.1, 0.5]])
    likelihood = _Innovations(b)
    cost, returned, _, _ = likelihood.evaluate(np.zeros(1))
    nu = likelihood.nu[:, 0]
    quadratic = np.mean([v @ np.linalg.solve(b, v) for v in nu])
    assert cost == pytest.approx(np.linalg.det(b) * np.exp(quadratic), rel=1e-12)
    assert returned is b


def test_innovations_far_beyond_their_covariance_are_named():
    """B positive definite but a thousand times too small for the innovations: exp(2L/N)
    overflows, the cost is infinite and the failure names the quadratic form and the noise
    starts, not a singular B."""
    likelihood = _Innovations(np.eye(3) * 1e-4)
    assert likelihood.evaluate(np.zeros(1))[0] == np.inf
    message = likelihood.failure(np.zeros(1))
    assert message.startswith("the innovations are far larger than their covariance B says")
    assert "exp(2L/N) overflows" in message and "singular" not in message
