"""The steady-state Kalman filter of a batch of discrete systems, complex-step safe.

For x_n+1 = Φ x_n + w_n, y_n = H x_n + v_n with cov w = Q and cov v = R (diagonal), the a
priori state covariance P solves the discrete algebraic Riccati equation (DARE)

    P = Φ P Φᵀ − Φ P Hᵀ (H P Hᵀ + R)⁻¹ H P Φᵀ + Q,

the innovations have the covariance B = H P Hᵀ + R and the filter gain is K = P Hᵀ B⁻¹.

P comes from the structured doubling algorithm (Chu, Fan & Lin), which needs only products and
inverses: it runs on complex parameter directions (the inputs' imaginary parts), so the
derivatives of P, B and K follow by the complex step, and it converges quadratically also when
Φ is unstable, to the limit of the filter started from a known state.

The doubling also iterates the dual equation, which diverges when the process noise leaves an
unstable mode unexcited. Where that overflows before P has converged (a hover model whose only
process noise is a slow gust, say), or converges to a P that is not positive semi-definite
(lost precision), the real system's P comes from the doubling run on the real
parts alone or, where that overflows too, is the stabilising solution of the generalised Schur
method (``scipy.linalg.solve_discrete_are``); the directions (dots) then follow from the DARE
differentiated at the predictor gain K̄ = ΦPHᵀB⁻¹, A_c = Φ − K̄H (the gain's own variation
drops out there, as K̄ minimises the one-step covariance)::

    Ṗ = A_c Ṗ A_cᵀ + (Φ̇ − K̄Ḣ) P A_cᵀ + A_c P (Φ̇ − K̄Ḣ)ᵀ + K̄ Ṙ K̄ᵀ + Q̇

one Stein equation per direction, all solved with one factorisation of I − A_c ⊗ A_c.
"""

from __future__ import annotations

import attrs
import numpy as np
import scipy.linalg
from rotorid.errors import EstimationError

#: Doubling steps allowed; each squares the closed-loop contraction.
MAX_DOUBLINGS = 60
#: Relative change of P (real and imaginary parts) at which the doubling stops.
TOLERANCE = 1e-13


@attrs.frozen(eq=False)
class SteadyStateFilter:
    """Per direction (leading axis D): ``covariance`` P (D, S, S), ``innovation`` B
    (D, n_o, n_o) and ``gain`` K (D, S, n_o)."""

    covariance: np.ndarray
    innovation: np.ndarray
    gain: np.ndarray


def _t(a):
    return np.swapaxes(a, -1, -2)


def _relative_change(new, old) -> float:
    """The larger of the real and the imaginary parts' largest change, each relative to its
    own size (the imaginary parts, the directions, are far smaller than the real ones)."""
    change = 0.0
    for part in (np.real, np.imag):
        scale = np.max(np.abs(part(new)), initial=0.0)
        if scale > 0:
            change = max(change, np.max(np.abs(part(new) - part(old))) / scale)
    return change


#: Why a filter has no steady state (the general case; :func:`_no_solution` tells which).
_NO_SOLUTION = ("the Kalman filter's Riccati equation has no stabilising solution: the model "
                "has a mode that does not decay and that the outputs do not observe or the "
                "process noise does not excite; make it observable or stable, add process "
                "noise on its states, or start from other values")
#: A discrete mode with |λ| at least this does not decay.
_NEUTRAL = 1.0 - 1e-9


def _no_solution(transition, output) -> EstimationError:
    """The error of one real system without a stabilising DARE solution, naming a mode with
    |λ| ≥ 1 that the outputs H do not observe (the Popov-Belevitch-Hautus test: no filter can
    correct it) where there is one."""
    values, vectors = np.linalg.eig(transition)
    scale = max(1.0, float(np.max(np.abs(transition))))
    for value, vector in zip(values, vectors.T):
        if abs(value) < _NEUTRAL:
            continue
        shown = f"{value.real:.4g}" if value.imag == 0 else f"{value:.4g}"
        seen = np.linalg.norm(output @ vector) > 1e-9 * scale * np.linalg.norm(vector)
        if not seen:
            return EstimationError(
                f"no stabilising Kalman filter: a mode that does not decay (discrete "
                f"eigenvalue {shown}) moves no output; keep a derivative that lets an "
                f"output see its state or one that damps it (a velocity whose terms were "
                f"removed, an integrator no output reads)")
    return EstimationError(_NO_SOLUTION)


def steady_state_filter(transition, output, process, measurement) -> SteadyStateFilter:
    """The steady-state filter of Φ (D, S, S), H (D, n_o, S), Q (D, S, S) and the diagonal of
    R (D, n_o) (all > 0); real, or complex with complex-step directions.

    Raises:
        EstimationError: the filter has no steady state (no solution of the DARE).
    """
    with np.errstate(over="ignore", invalid="ignore"):
        covariance = _doubling(transition, output, process, measurement)
    if not _is_covariance(covariance):
        covariance = _fallback(transition, output, process, measurement)
    innovation = output @ covariance @ _t(output) + measurement[..., :, None] * np.eye(
        output.shape[-2])
    gain = covariance @ _t(output) @ np.linalg.inv(innovation)
    return SteadyStateFilter(covariance, innovation, gain)


def _fallback(transition, output, process, measurement) -> np.ndarray:
    """P (D, S, S) where the doubling of the systems fails: real systems' from the Schur
    method; complex ones' real part from the doubling of the real parts alone (the Schur
    method's where that fails too), its directions from the differentiated DARE."""
    parts = tuple(np.asarray(x) for x in (transition, output, process, measurement))
    if not any(np.iscomplexobj(x) for x in parts):       # the doubling of these just failed
        return _schur_solutions(*parts)
    real = tuple(x.real for x in parts)
    shared = all(np.array_equal(x, x[:1].repeat(x.shape[0], axis=0)) for x in real)
    systems = tuple(x[:1] for x in real) if shared else real
    with np.errstate(over="ignore", invalid="ignore"):
        covariance = _doubling(*systems)
    if not _is_covariance(covariance):
        covariance = _schur_solutions(*systems)
    covariance = np.broadcast_to(covariance, real[2].shape)
    dots = tuple(x.imag if np.iscomplexobj(x) else np.zeros_like(x) for x in parts)
    return covariance + 1j * _directions(covariance, shared, *real, *dots)


#: Most negative eigenvalue of a covariance P, relative to its largest, that counts as rounding.
_NEGATIVE_EIGENVALUE = 1e-9


def _is_covariance(covariance) -> bool:
    """Whether ``covariance`` (D, S, S, or None) is a covariance: every real part positive
    semi-definite up to rounding. The doubling can converge to an indefinite P when its
    iterates lose precision (seen on a hover fit with 350 s gusts: B's eigenvalues down to
    −8.6·10⁸); the Schur method's solution is then the one to use."""
    if covariance is None:
        return False
    values = np.linalg.eigvalsh(np.real(covariance))
    largest = np.max(np.abs(values), axis=-1, keepdims=True)
    return bool(np.all(values >= -_NEGATIVE_EIGENVALUE * largest))


def _schur_solutions(transition, output, process, measurement) -> np.ndarray:
    """The stabilising P (D, S, S) of each real system (:func:`_schur_solution`)."""
    return np.stack([_schur_solution(*system)
                     for system in zip(transition, output, process, measurement)])


def _doubling(transition, output, process, measurement):
    """P (D, S, S) by the structured doubling algorithm, or None where it overflows or does
    not converge in :data:`MAX_DOUBLINGS` steps."""
    a = _t(transition)
    g = _t(output) @ (output / measurement[..., :, None])        # Hᵀ R⁻¹ H
    h = process
    identity = np.eye(a.shape[-1])
    for _ in range(MAX_DOUBLINGS):
        try:
            w = np.linalg.inv(identity + g @ h)
        except np.linalg.LinAlgError:
            return None
        aw = a @ w
        h_next = h + _t(a) @ h @ w @ a
        g = g + aw @ g @ _t(a)
        a = aw @ a
        if not np.all(np.isfinite(h_next)):
            return None
        converged = _relative_change(h_next, h) < TOLERANCE
        h = h_next
        if converged:
            return 0.5 * (h + _t(h))
    return None


def _schur_solution(transition, output, process, measurement) -> np.ndarray:
    """The stabilising P (S, S) of one real system."""
    try:
        p = scipy.linalg.solve_discrete_are(transition.T, output.T, process,
                                            np.diag(measurement))
    except (np.linalg.LinAlgError, ValueError):
        raise _no_solution(transition, output) from None
    if not np.all(np.isfinite(p)):
        raise _no_solution(transition, output)
    return 0.5 * (p + p.T)


def _directions(covariance, shared: bool, transition, output, process, measurement,
                transition_dot, output_dot, process_dot, measurement_dot) -> np.ndarray:
    """Ṗ (D, S, S) of every direction from the differentiated DARE (module docstring), at the
    real P (D, S, S) of each direction's system (``shared``: the same for every direction)."""
    innovation = output @ covariance @ _t(output) + measurement[..., :, None] * np.eye(
        output.shape[-2])
    gain = transition @ covariance @ _t(output) @ np.linalg.inv(innovation)   # K̄
    closed = transition - gain @ output
    moved = (transition_dot - gain @ output_dot) @ covariance @ _t(closed)
    forcing = (moved + _t(moved) + gain @ (measurement_dot[..., :, None] * _t(gain))
               + process_dot)
    size = closed.shape[-1]
    groups = [(closed[0], slice(None))] if shared else [
        (closed[d], slice(d, d + 1)) for d in range(closed.shape[0])]
    dot = np.empty_like(forcing)
    for loop, rows in groups:
        stein = np.eye(size * size) - np.kron(loop, loop)
        try:
            factor = scipy.linalg.lu_factor(stein, check_finite=True)
        except (np.linalg.LinAlgError, ValueError):
            raise EstimationError(_NO_SOLUTION) from None
        flat = forcing[rows].reshape(-1, size * size).T
        with np.errstate(all="ignore"):
            dot[rows] = scipy.linalg.lu_solve(factor, flat).T.reshape(-1, size, size)
    if not np.all(np.isfinite(dot)):
        raise EstimationError("the Kalman filter's steady state does not vary smoothly with "
                              "the parameters here (a closed-loop mode at the unit circle); "
                              "add process noise on the model's neutral states or start from "
                              "other values")
    return 0.5 * (dot + _t(dot))
