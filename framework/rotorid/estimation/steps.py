"""The bounded Levenberg-Marquardt step shared by the iterative estimators."""

from __future__ import annotations

import numpy as np


def bounded_step(f, g, lam, values, lower, upper, shorten: bool = True):
    """Solve (F + λ·diag F) Δ = −G within bounds; returns Δ (P,).

    F (P, P) is a Gauss-Newton information matrix, G (P,) the gradient, ``values`` (P,) the
    current parameters and ``lower``/``upper`` (P,) their bounds. Parameters at a bound whose
    step points outward are frozen and the step is solved again for the others; the step is
    then shortened so that no parameter crosses its bound (``shorten``), or else each
    parameter that would cross stops at its bound (a projection: a parameter just inside its
    bound and heading for it then does not shrink the whole step). Diagonal (Marquardt)
    scaling lets parameters of very different magnitudes converge together.
    """
    p = values.size
    scale = np.sqrt(np.maximum(np.diag(f), 1e-12 * max(np.max(np.diag(f)), 1e-300)))
    free = np.ones(p, dtype=bool)
    for _ in range(p + 1):
        step = np.zeros(p)
        idx = np.flatnonzero(free)
        if idx.size == 0:
            return step
        fs = f[np.ix_(idx, idx)] / np.outer(scale[idx], scale[idx])
        fs[np.diag_indices_from(fs)] *= 1.0 + lam
        fs[np.diag_indices_from(fs)] += 1e-12
        step[idx] = np.linalg.solve(fs, -g[idx] / scale[idx]) / scale[idx]
        blocked = free & (((values <= lower) & (step < 0)) | ((values >= upper) & (step > 0)))
        if not np.any(blocked):
            break
        free &= ~blocked
    if not shorten:
        return np.clip(values + step, lower, upper) - values
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(step > 0, (upper - values) / step,
                        np.where(step < 0, (lower - values) / step, np.inf))
    alpha = min(1.0, float(np.min(room))) if room.size else 1.0
    return step * max(alpha, 0.0)
