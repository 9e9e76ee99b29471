"""Whiteness of a fit's one-step innovations (or residuals).

A filter-error fit whose noise model and structure are right leaves its innovations white:
their autocorrelation at every lag but 0 lies within ±1.96/√N of zero for 95 % of the lags.
Innovations correlated over many lags say that the noise model misses coloured turbulence
(white process noise where the gusts last seconds) or that the structure misses dynamics,
which the fit's Cramér-Rao bounds then do not cover (Jategaonkar, *Flight Vehicle System
Identification*, 2nd ed., 2015, on checking the innovations). :func:`whiteness_note` says so
in an estimate's notes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

#: The two-sided 95 % band of a white sequence's autocorrelation, in units of 1/√N.
WHITE_BAND = 1.96
#: Fraction of the lags outside the band above which an output's innovations count as
#: coloured (a white sequence puts about 5 % there).
COLOURED_FRACTION = 0.2
#: The lags looked at, s (at most :data:`MAX_LAGS` of them).
SPAN_S = 1.0
MAX_LAGS = 50


def autocorrelation(residuals: Sequence[np.ndarray], lags: int) -> np.ndarray:
    """ρ_k of each output for k = 1 … ``lags``, shape (lags, p), pooled over the maneuvers
    ``residuals`` (each (N_i, p), its mean removed): Σ e_t·e_t+k / Σ e_t² within each."""
    centred = [r - r.mean(axis=0) for r in residuals]
    power = sum(np.sum(r**2, axis=0) for r in centred)
    rho = np.zeros((lags, centred[0].shape[1]))
    for k in range(1, lags + 1):
        rho[k - 1] = sum(np.sum(r[:-k] * r[k:], axis=0) for r in centred if len(r) > k)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(power > 0, rho / power, 0.0)


def coloured_outputs(residuals: Sequence[np.ndarray], names: Sequence[str], dt: float,
                     ) -> list[tuple[str, float, float]]:
    """(output, the largest |ρ|, its lag in s) for each output whose innovations are not
    white: more than :data:`COLOURED_FRACTION` of the lags up to :data:`SPAN_S` outside the
    white band. ``dt`` is the innovations' interval, s."""
    count = sum(len(r) for r in residuals)
    lags = int(min(MAX_LAGS, max(1, round(SPAN_S / dt)), min(len(r) for r in residuals) - 1))
    if lags < 1 or count < 10:
        return []
    rho = autocorrelation(residuals, lags)
    outside = np.abs(rho) > WHITE_BAND / np.sqrt(count)
    found = []
    for j, name in enumerate(names):
        if outside[:, j].mean() > COLOURED_FRACTION:
            k = int(np.argmax(np.abs(rho[:, j])))
            found.append((name, float(rho[k, j]), (k + 1) * dt))
    return found


def coloured_text(residuals: Sequence[np.ndarray], names: Sequence[str], dt: float,
                  kind: str = "innovations") -> str | None:
    """``"<kind> not white: <outputs with their largest ρ and its lag>, where …"``, naming
    the outputs of :func:`coloured_outputs`; None when all are white."""
    found = coloured_outputs(residuals, names, dt)
    if not found:
        return None
    count = sum(len(r) for r in residuals)
    listed = ", ".join(f"{name} (ρ {rho:+.2f} at {lag:.2g} s)" for name, rho, lag in found)
    return (f"{kind} not white: {listed}, where a white sequence keeps 95 % of its "
            f"autocorrelations within ±{WHITE_BAND / np.sqrt(count):.2g}")


def whiteness_note(residuals: Sequence[np.ndarray], names: Sequence[str], dt: float
                   ) -> str | None:
    """A note naming the outputs whose innovations are not white (:func:`coloured_text`),
    with what it means and what to try; None when all are white."""
    coloured = coloured_text(residuals, names, dt)
    if coloured is None:
        return None
    return (f"{coloured}; the noise model misses coloured turbulence or the structure misses "
            f"dynamics, and the Cramér-Rao bounds do not cover that: model the turbulence as "
            f"gusts or disturbances (gusts, disturbances), or check the structure")
