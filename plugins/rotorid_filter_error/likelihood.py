"""The innovations' likelihood, shared by the linear and the nonlinear filter-error problems.

With innovations ν_n and their covariance B the negative log-likelihood is
L = ½ Σ ν_nᵀ B⁻¹ ν_n + ½ N ln det B, reported as the cost exp(2L/N); B's part of the Fisher
information and of the gradient is ½ N tr(B⁻¹∂B_i B⁻¹∂B_j) and ½ tr(B⁻¹∂B_i B⁻¹(N·B − Σννᵀ)).
"""

from __future__ import annotations

import numpy as np
from rotorid.errors import EstimationError


class InnovationLikelihood:
    """Cost and failure of a problem that provides ``innovations(values)`` (time-major
    (N, M, p) and B (p, p)), ``per_maneuver(innovations)`` (one (N_i, p) array per maneuver),
    ``n_samples``, ``output_names`` and ``rmse_scale`` (p,)."""

    def evaluate(self, values):
        """(cost exp(2L/N), B, innovations per maneuver, innovation RMSE); cost = inf when the
        filter does not exist, the innovations overflow or ``values`` are not finite (a
        step from a non-finite information matrix)."""
        if not np.all(np.isfinite(values)):
            return np.inf, None, None, np.inf
        try:
            innovations, b = self.innovations(values)
        except (EstimationError, np.linalg.LinAlgError):
            return np.inf, None, None, np.inf
        if not _positive_definite(b):
            return np.inf, None, None, np.inf
        log_det = np.linalg.slogdet(b)[1]                  # B is positive definite here
        with np.errstate(over="ignore", invalid="ignore"):
            scatter = np.einsum("nmi,nmj->ij", innovations, innovations)
            quadratic = np.trace(np.linalg.solve(b, scatter)) / self.n_samples
            cost = float(np.exp(quadratic + log_det))
        if not np.isfinite(cost):
            return np.inf, None, None, np.inf
        rmse = float(np.sqrt(np.sum((innovations * self.rmse_scale)**2)
                             / (len(self.output_names) * self.n_samples)))
        return cost, b, self.per_maneuver(innovations), rmse

    def failure(self, values) -> str:
        """Why the cost at ``values`` is infinite: the filter's own error, or B."""
        try:
            innovations, b = self.innovations(values)
        except (EstimationError, np.linalg.LinAlgError) as error:
            return f"the Kalman filter does not exist ({error})"
        if not np.all(np.isfinite(innovations)):
            return "the innovations overflow (the model diverges at these values)"
        if not np.all(np.isfinite(b)):
            return "the innovation covariance B is not finite at these values"
        if not _positive_definite(b):
            return (f"the innovation covariance B is not positive definite (smallest "
                    f"eigenvalue {np.linalg.eigvalsh(b).min():.3g}): the filter's Riccati "
                    f"solution is not a covariance at these values")
        scatter = np.einsum("nmi,nmj->ij", innovations, innovations)
        quadratic = np.trace(np.linalg.solve(b, scatter)) / self.n_samples
        return (f"the innovations are far larger than their covariance B says (mean νᵀB⁻¹ν = "
                f"{quadratic:.3g}, so exp(2L/N) overflows): the noise sizes or R start far "
                f"too small for these data")


def _positive_definite(b: np.ndarray) -> bool:
    """Whether the symmetric matrix ``b`` (its lower triangle) is positive definite. A
    determinant's sign cannot tell: B with two negative eigenvalues has det B > 0 (seen on a
    hover fit whose steady-state solution P had gone indefinite, B's eigenvalues down to
    −8.6·10⁸)."""
    try:
        np.linalg.cholesky(b)
    except np.linalg.LinAlgError:
        return False
    return True


def covariance_terms(d_covariance: np.ndarray, b: np.ndarray, residuals, n_samples: int):
    """B's part of the information (P, P) and of the gradient (P,) of L, from ∂B/∂θ_i
    ``d_covariance`` (P, p, p), B and the innovations per maneuver."""
    b_inv = np.linalg.inv(b)
    db = b_inv @ d_covariance                                         # B⁻¹ ∂B/∂θ_i
    scatter = sum(e.T @ e for e in residuals)
    information = 0.5 * n_samples * np.einsum("iab,jba->ij", db, db)
    gradient = 0.5 * np.einsum("iab,ba->i", db, b_inv @ (n_samples * b - scatter))
    return information, gradient
