"""Tischler's frequency-response mismatch cost J (Tischler & Remple, eq. 12.20).

For one pair, with ``ε = H_model/H_truth`` (so ``|T̂_c|_dB − |T|_dB = −20 log10|ε|`` and
``∠T̂_c − ∠T = −∠ε``)::

    J = (20/n) Σ_k W_γ(ω_k) [W_g Δ|T|_dB(ω_k)² + W_p Δ∠T_deg(ω_k)²]
    W_g = 1,  W_p = 0.01745,  W_γ = [1.58 (1 − exp(−γ²))]²

over ``n_points`` (20) frequencies log-spaced across the coherent range [ω_min, ω_max] of the
pair (γ² ≥ threshold: 0.6 by Tischler's rule, which the frequency-response estimator fits
with; as a verdict the verification builds it with its band's threshold and range, γ² ≥ 0.8
over 0.1–10 rad/s by default, :mod:`rotorid.verification.band`); magnitude (dB), unwrapped
phase and γ² are interpolated linearly in log ω to those points and points below the threshold are dropped
(``n`` counts the kept points). ``J ≤ 100`` is acceptable (``J ≤ 50`` nearly
indistinguishable); for multi-pair state-space fits ``J_ave ≤ 100`` with single ``J ≤ 200``.

As an envelope, the per-point bounds are the uniform errors that alone would give ``J`` equal
to the limit (±2.24 dB or ±16.9° for J = 100); a point is inside when its own weighted
contribution stays within the limit. The check passes when ``J ≤ limit``.
"""

from __future__ import annotations

import attrs
import numpy as np
from rotorid.verification.envelopes import (
    MISMATCH_COST_GUIDELINE_TEXT,
    EnvelopeBounds,
    EnvelopeCheck,
    error_db_deg,
    status_of,
    validate_check_inputs,
    wrap180,
)

W_GAIN = 1.0
W_PHASE = 0.01745
#: Coherence that defines the J frequency range of a fit (Tischler).
COST_THRESHOLD = 0.6


def coherence_weight(coherence):
    """``W_γ = [1.58 (1 − exp(−γ²))]²`` for magnitude-squared coherence ``γ²``."""
    return (1.58 * (1.0 - np.exp(-np.asarray(coherence, dtype=float)))) ** 2


@attrs.frozen
class MismatchCost:
    """The mismatch cost J as a validation check.

    Attributes:
        limit: J at or below which the pair passes (100; use 200 for single pairs of a
            multi-pair fit judged by J_ave).
        threshold: coherence defining the J frequency range and the kept points.
        n_points: number of log-spaced J points.
    """

    limit: float = 100.0
    threshold: float = COST_THRESHOLD
    n_points: int = 20
    name: str = "mismatch-cost"
    provenance: str = ("Tischler & Remple, Aircraft and Rotorcraft System Identification "
                       "(AIAA), eq. 12.20: W_g = 1, W_p = 0.01745, W_γ = [1.58(1 − e^(−γ²))]², "
                       "n = 20; guidelines J ≤ 100, J_ave ≤ 100")
    verified: bool = True
    kind = "cost"  # scores the pair; not drawn on the error plots

    def bounds(self, omega) -> EnvelopeBounds:
        """Uniform-error equivalents of the limit at unit coherence weight (constant)."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        mag = np.sqrt(self.limit / (20.0 * W_GAIN))
        phase = np.sqrt(self.limit / (20.0 * W_PHASE))
        ones = np.ones_like(omega)
        return EnvelopeBounds(self.name, omega, -mag * ones, mag * ones, -phase * ones,
                              phase * ones, np.zeros(omega.shape, bool))

    def points(self, omega: np.ndarray, coherence: np.ndarray) -> np.ndarray:
        """The J frequencies: log-spaced over the coherent range (empty if none)."""
        coherent = omega[coherence >= self.threshold]
        if coherent.size == 0:
            return np.zeros(0)
        if coherent.min() == coherent.max():
            return np.array([coherent.min()])
        return np.geomspace(coherent.min(), coherent.max(), self.n_points)

    def check(self, error, coherence, omega) -> EnvelopeCheck:
        """J of one pair from ``ε`` (complex, shape (M,)), coherence and ``omega`` (rad/s)."""
        error, coherence, omega = validate_check_inputs(error, coherence, omega)
        order = np.argsort(omega)
        error, coherence, omega = error[order], coherence[order], omega[order]
        valid = np.isfinite(error) & np.isfinite(coherence)
        error, coherence, omega = error[valid], coherence[valid], omega[valid]
        with np.errstate(invalid="ignore"):
            grid = self.points(omega, coherence)
        if grid.size == 0:
            empty = np.zeros(0)
            return EnvelopeCheck(self.name, self.provenance, self.verified, empty, empty,
                                 empty, empty, empty, empty, empty, empty, empty,
                                 self.threshold, None, status_of(None, self.verified), None)
        magnitude, phase = error_db_deg(error)
        log_omega, log_grid = np.log10(omega), np.log10(grid)
        mag = np.interp(log_grid, log_omega, magnitude)
        pha = wrap180(np.interp(log_grid, log_omega, np.degrees(np.unwrap(np.radians(phase)))))
        coh = np.interp(log_grid, log_omega, coherence)
        used = coh >= self.threshold
        weight = coherence_weight(coh)
        contribution = 20.0 * weight * (W_GAIN * mag ** 2 + W_PHASE * pha ** 2)
        cost = float(np.mean(contribution[used])) if used.any() else None
        bounds = self.bounds(grid)
        passed = None if cost is None else cost <= self.limit
        return EnvelopeCheck(
            envelope=self.name, provenance=self.provenance, verified=self.verified,
            omega=grid, magnitude_db=mag, phase_deg=pha, coherence=coh, used=used,
            inside=contribution <= self.limit, extrapolated=np.zeros(grid.shape, bool),
            margin_db=bounds.mag_upper_db - np.abs(mag),
            margin_deg=bounds.phase_upper_deg - np.abs(pha), threshold=self.threshold,
            passed=passed, status=status_of(passed, self.verified), cost=cost,
            cost_guideline=MISMATCH_COST_GUIDELINE_TEXT)
