"""Cramér-Rao bounds that account for coloured output-error residuals.

Output error's bounds, the diagonal of M⁻¹ with M = Σ Sᵀ Q S, hold when the residuals are white
with covariance R. Real residuals are coloured (turbulence, structure error), and the bounds
then understate the parameters' scatter, often several times. Morelli and Klein (*Accounting
for Non-White Residuals in Output-Error Parameter Estimation*, J. Guidance 20(4), 1997; the
method SIDPAC offers) keep the estimate and replace its covariance by

    Cov = M⁻¹ [Σ_i Σ_j S(i)ᵀ Q R_vv(i − j) Q S(j)] M⁻¹

with S(i) the output sensitivities (n_o × P) at sample i, Q the cost's weighting (R⁻¹ with the
output weights) and R_vv(k) the residuals' auto-covariance at lag k. Here R_vv(k) is the
sample estimate pooled over the maneuvers, tapered by a Bartlett lag window out to
:func:`correlation_lags` (which keeps the middle matrix positive semi-definite), and the
double sum is formed per maneuver in the frequency domain: with g(i) = S(i)ᵀ Q and the records
zero-padded past N + K, Σ_i Σ_j g(i) R(i − j) g(j)ᵀ = (1/L) Σ_f G(f)* Φ(f) G(f)ᵀ exactly, Φ the
DFT of the windowed R over lags −K … K.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rotorid.estimation.whiteness import WHITE_BAND, autocorrelation

#: The lag window reaches this multiple of the lag at which every output's residual
#: autocorrelation has first fallen inside the white band.
WINDOW_FACTOR = 4
#: At most this fraction of the shortest record is used as lags.
MAX_LAG_FRACTION = 0.25


def correlation_lags(residuals: Sequence[np.ndarray]) -> int:
    """K: :data:`WINDOW_FACTOR` times the first lag at which every output's residual
    autocorrelation lies within ±1.96/√N, at most :data:`MAX_LAG_FRACTION` of the shortest
    record (``residuals``: per maneuver (N_i, n_o)); 0 for white residuals."""
    shortest = min(len(r) for r in residuals)
    limit = max(1, int(MAX_LAG_FRACTION * shortest))
    rho = autocorrelation(residuals, limit)
    band = WHITE_BAND / np.sqrt(sum(len(r) for r in residuals))
    inside = np.all(np.abs(rho) <= band, axis=1)
    if inside[0]:
        return 0
    first = int(np.argmax(inside)) + 1 if inside.any() else limit
    return min(limit, WINDOW_FACTOR * first)


def residual_covariances(residuals: Sequence[np.ndarray], lags: int) -> np.ndarray:
    """R_vv(k) for k = 0 … ``lags``, shape (K + 1, n_o, n_o): Σ v(t + k) v(t)ᵀ / N pooled over
    the maneuvers (each (N_i, n_o)), N all their samples. The residuals' means stay in: a
    record's offset is correlated at every lag, and removing each record's mean would take
    the low-frequency part of the residuals' power out with it."""
    count = sum(len(r) for r in residuals)
    n_o = residuals[0].shape[1]
    covariances = np.zeros((lags + 1, n_o, n_o))
    for k in range(lags + 1):
        covariances[k] = sum(r[k:].T @ r[:len(r) - k] for r in residuals if len(r) > k) / count
    return covariances


def coloured_covariance(sensitivities: Sequence[np.ndarray], residuals: Sequence[np.ndarray],
                        weighting: np.ndarray, information: np.ndarray,
                        lags: int | None = None) -> tuple[np.ndarray, int]:
    """The parameters' covariance (P, P) for coloured residuals, and the lags K used.

    Args:
        sensitivities: per maneuver ∂y/∂θ, shape (N_i, P, n_o).
        residuals: per maneuver z − y at the estimate, shape (N_i, n_o).
        weighting: the cost's Q (n_o, n_o), R⁻¹ with the output weights.
        information: M = Σ Sᵀ Q S (P, P), the fit's information matrix (invertible).
        lags: K; default :func:`correlation_lags`. K = 0 gives M⁻¹ R-scaled by the residuals'
            own covariance (for white residuals with R their covariance, M⁻¹).
    """
    lags = correlation_lags(residuals) if lags is None else int(lags)
    window = 1.0 - np.arange(lags + 1) / (lags + 1.0)
    covariances = residual_covariances(residuals, lags) * window[:, None, None]
    p = information.shape[0]
    middle = np.zeros((p, p))
    for s, r in zip(sensitivities, residuals):
        length = int(2 ** np.ceil(np.log2(len(r) + lags + 1)))
        g = np.einsum("tpo,oq->tpq", s, weighting)                       # (N, P, n_o)
        spectrum = np.fft.fft(g, n=length, axis=0)                        # (L, P, n_o)
        phase = np.exp(-2j * np.pi * np.outer(np.fft.fftfreq(length), np.arange(lags + 1)))
        phi = np.einsum("fk,kab->fab", phase, covariances)
        phi = phi + np.conj(np.swapaxes(phi, 1, 2)) - covariances[0]     # lags −K … K
        middle += np.real(np.einsum("fpa,fab,fqb->pq", np.conj(spectrum), phi,
                                    spectrum)) / length
    inverse = np.linalg.inv(information)
    covariance = inverse @ middle @ inverse
    return (covariance + covariance.T) / 2.0, lags
