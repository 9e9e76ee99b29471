"""Exact discretisation of the delayed linear model and the parameter derivatives of its maps.

Between two samples t_n and t_n+1 = t_n + T the model is

    x' = A_u x + Σ_c g_c e_c z_c(t − τ_c)

where A_u holds the known terms and the undelayed state derivatives, and every other term c
(control derivatives, delayed state derivatives) is a forcing signal: its gain g_c, equation row
e_c, source z_c (a state or a control) and delay τ_c = m_c·T + f_c (0 ≤ f_c < T).

How each source is known between samples decides the forcing exactly:

* controls under zero-order hold are piecewise constant, switching at σ = f_c inside the interval;
* controls under first-order hold and delayed states are linear between their samples (the state
  history is interpolated, never extrapolated; for τ_c < T the end sample x_n+1 enters and the
  step becomes implicit, solved exactly since it is linear).

The forcing integrals ∫ e^{A_u(T−σ)} w(σ) dσ of constant and ramp signals over [0, f_c] and
[f_c, T] follow from e^{A_u s}, Γ(s) = ∫₀ˢ e^{A_u σ} dσ and K(s) = ∫₀ˢ e^{A_u σ}(s − σ) dσ for
each distinct sub-interval length s (T and T − f_c). All of them, for every direction and
sub-interval at once, come from the Taylor series of e^X, φ₁(X) and φ₂(X) (X = A_u s, scaled
by 2^−m until ‖X‖₁ ≤ 1/2, where 18 terms reach machine precision) and m doubling steps.
The result is a linear recursion with lagged maps::

    x_n+1 = Σ_j Ps[j] x_n−j + Σ_j Pu[j] u_n−j       y_n = Σ_j Cs[j] x_n−j + Σ_j Du[j] u_n−j

and the map Pe of an unmeasured acceleration f_n held over the sample on each equation row
(a disturbance), x_n+1 gaining Pe f_n: Γ(T)E, folded like the rest of the step.

The maps are computed for a batch of complex parameter vectors, so that their derivatives with
respect to every parameter follow by the complex-step method (Im f(θ + i·h·e_k)/h, exact to
machine precision, no subtractive cancellation); the series and the doubling steps are
analytic, as the complex step requires.
"""

from __future__ import annotations

import math

import attrs
import numpy as np

from rotorid.errors import StructureError
from rotorid.model.structure import ModelStructure

#: Complex-step size; any tiny value works because no difference is taken.
COMPLEX_STEP = 1e-30


@attrs.frozen(eq=False)
class DiscreteMaps:
    """Lagged maps of the discrete recursion and their parameter derivatives.

    Every map is a dict lag → array. ``Ps``/``Cs`` map the n states and ``Pu``/``Du`` the m
    controls; values have shape (n, n), (n, m), (p, n) or (p, m). The ``d*`` variants carry a
    leading parameter axis (P, ·, ·) and are empty when derivatives were not requested.
    ``state_history`` lists, per lag ≥ 1 of ``Ps``, the state columns it reads. ``Pe``
    (n, e) maps an acceleration held over the sample on each of the structure's equation rows
    (``equation_rows`` order) into x_n+1; ``dPe`` (P, n, e) its derivatives.
    """

    dt: float
    Ps: dict
    Pu: dict
    Cs: dict
    Du: dict
    dPs: dict
    dPu: dict
    dCs: dict
    dDu: dict
    state_history: dict
    Pe: np.ndarray
    dPe: np.ndarray


#: Taylor terms of the scaled series; with ‖X‖₁ ≤ 1/2 the remainder is below 1e−21.
_TAYLOR_TERMS = 18
_TAYLOR_NORM = 0.5


def _integrals(a: np.ndarray, s: np.ndarray, rows: tuple[int, ...]):
    """e^{As}, Γ(s)E and K(s)E for a batch of matrices and sub-interval lengths.

    Args:
        a: (D, n, n) complex.
        s: (D, S) complex sub-interval lengths in s.
        rows: the e rows that derivative terms drive (the columns of E).
    Returns:
        phi (D, S, n, n); gam (D, S, n, e) = ∫₀ˢ e^{Aσ} dσ·E; kin (D, S, n, e) =
        ∫₀ˢ e^{Aσ}(s − σ) dσ·E.

    The lengths are scaled by 2^−m so that ‖A·s‖₁ ≤ 1/2, the three series are summed there
    (e^X = Σ X^k/k!, Γ = s·Σ X^k/(k+1)!, K = s²·Σ X^k/(k+2)!), and m doubling steps
    φ(2t) = φ(t)², Γ(2t) = Γ(t) + φ(t)Γ(t), K(2t) = K(t) + tΓ(t) + φ(t)K(t) restore s.
    """
    d, n_s = s.shape
    n_x, n_e = a.shape[-1], len(rows)
    # A trial step far out (a profile's fit with its delay fixed far from the optimum) can
    # make A's powers or e^{A·s} overflow: the maps then hold inf or nan, and the simulation
    # that uses them raises SimulationDivergedError, which the fit treats as a rejected step.
    with np.errstate(over="ignore", invalid="ignore"):
        norm = np.abs(a.real).sum(axis=1).max() * np.abs(s.real).max()
        doublings = max(0, math.ceil(math.log2(norm / _TAYLOR_NORM))) if norm > 0 else 0
        step = s / 2.0**doublings                                          # (D, S)
        powers = np.empty((d, _TAYLOR_TERMS, n_x, n_x), dtype=complex)     # A^k
        powers[:, 0] = np.eye(n_x)
        for k in range(1, _TAYLOR_TERMS):
            powers[:, k] = a @ powers[:, k - 1]
        k = np.arange(_TAYLOR_TERMS + 2)
        scaled = step[..., None] ** k / np.array([math.factorial(i) for i in k])  # (D, S, K+2)
        flat = powers.reshape(d, _TAYLOR_TERMS, -1)
        phi = (scaled[..., :-2] @ flat).reshape(d, n_s, n_x, n_x)
        columns = powers[..., list(rows)].reshape(d, _TAYLOR_TERMS, -1)
        gam = (scaled[..., 1:-1] @ columns).reshape(d, n_s, n_x, n_e)
        kin = (scaled[..., 2:] @ columns).reshape(d, n_s, n_x, n_e)
        for _ in range(doublings):
            kin = kin + step[..., None, None] * gam + phi @ kin
            gam = gam + phi @ gam
            phi = phi @ phi
            step = 2.0 * step
        return phi, gam, kin


def _distinct_integrals(a: np.ndarray, s: np.ndarray, rows: tuple[int, ...]):
    """:func:`_integrals` computed once for the nominal direction 0 and for the directions
    that change A or a sub-interval; the others (control gains, outputs) share direction 0's.
    """
    changed = (np.any(a != a[:1], axis=(1, 2)) | np.any(s != s[:1], axis=1))
    changed[0] = True
    distinct = np.flatnonzero(changed)
    source = np.cumsum(changed) - 1          # direction → its row among the distinct ones
    source[~changed] = 0
    return tuple(part[source] for part in _integrals(a[distinct], s[distinct], rows))


@attrs.frozen(eq=False)
class _Terms:
    """The structure's terms split by role, with parameter bookkeeping."""

    equation: np.ndarray      # (K,) state row driven
    eq_col: np.ndarray        # (K,) column in E
    source: np.ndarray        # (K,) 0 … n−1 states, n … n+m−1 controls
    output: np.ndarray        # (K,) output row or −1
    weight: np.ndarray        # (K,) weight of the term in that output
    delayed: np.ndarray       # (K,) bool: carries a delay
    gain: np.ndarray          # (K,) real
    delay: np.ndarray         # (K,) real
    gain_param: np.ndarray    # (K,) parameter index of the gain or −1
    delay_param: np.ndarray   # (K,) parameter index of the delay or −1


def _terms(structure: ModelStructure, values) -> _Terms:
    table = structure.terms(values)
    index = {n: i for i, n in enumerate(structure.parameter_names)}
    gain_param, delay_param, delayed = [], [], []
    for d in structure.derivatives:
        gain_param.append(-1 if d.fixed else index[d.name])
        delayed.append(d.delay is not None)
        has_free_delay = d.delay is not None and not d.delay.fixed
        delay_param.append(index[d.delay_name] if has_free_delay else -1)
    row_col = {row: k for k, row in enumerate(structure.equation_rows)}
    return _Terms(table.equation, np.array([row_col[e] for e in table.equation]), table.source,
                  table.output, table.weight, np.array(delayed, dtype=bool), table.gain,
                  table.delay,
                  np.array(gain_param), np.array(delay_param))


def _directions(terms: _Terms, n_params: int, with_derivatives: bool):
    """Complex gains and delays per direction: (D, K) each; D = 1 (+ n_params)."""
    n_dir = 1 + (n_params if with_derivatives else 0)
    gain = np.repeat(terms.gain[None].astype(complex), n_dir, axis=0)
    delay = np.repeat(terms.delay[None].astype(complex), n_dir, axis=0)
    if with_derivatives:
        for k in range(len(terms.gain)):
            if terms.gain_param[k] >= 0:
                gain[1 + terms.gain_param[k], k] += 1j * COMPLEX_STEP
            if terms.delay_param[k] >= 0:
                delay[1 + terms.delay_param[k], k] += 1j * COMPLEX_STEP
    return gain, delay


def _add(maps: dict, lag: int, value: np.ndarray) -> None:
    if lag in maps:
        maps[lag] = maps[lag] + value
    else:
        maps[lag] = value


def discrete_maps(structure: ModelStructure, values, dt: float, hold: str = "zoh",
                  with_derivatives: bool = False) -> DiscreteMaps:
    """The recursion maps for sample time ``dt`` (s) at parameter vector ``values``.

    ``hold`` is the input hold between samples (``"zoh"`` or ``"foh"``). With
    ``with_derivatives`` the maps' derivatives with respect to every free parameter
    (structure.parameter_names order) are returned too.
    """
    terms = _terms(structure, values)
    negative = [d.delay_name for d, tau in zip(structure.derivatives, terms.delay) if tau < 0]
    if negative:
        raise StructureError(f"negative delay(s) {', '.join(negative)}: delays are lags ≥ 0 s "
                             f"(advances are not modelled); bound them below by 0")
    n_params = structure.n_parameters
    gain, delay = _directions(terms, n_params, with_derivatives)
    n_dir = gain.shape[0]
    T = float(dt)
    n_x, n_u, n_y = structure.n_states, structure.n_controls, structure.n_outputs

    in_a = (~terms.delayed) & (terms.source < n_x)
    a = np.repeat(structure.known_state_matrix()[None].astype(complex), n_dir, axis=0)
    for k in np.flatnonzero(in_a):
        a[:, terms.equation[k], terms.source[k]] += gain[:, k]

    forcing = np.flatnonzero(~in_a)
    lag_m = {k: int(np.floor(terms.delay[k] / T + 1e-9)) for k in forcing}
    frac = {k: delay[:, k] - lag_m[k] * T for k in forcing}          # (D,) complex
    # Sub-interval lengths: T, then T − f_k for each forcing term with a delay.
    delayed_forcing = [k for k in forcing if terms.delayed[k]]
    s = np.full((n_dir, 1 + len(delayed_forcing)), T, dtype=complex)
    for col, k in enumerate(delayed_forcing, start=1):
        s[:, col] = T - frac[k]
    phi, gam, kin = _distinct_integrals(a, s, structure.equation_rows)
    slot = {k: col for col, k in enumerate(delayed_forcing, start=1)}

    ps_raw = {0: phi[:, 0]}
    pu_raw: dict = {}
    implicit = np.zeros((n_dir, n_x, n_x), dtype=complex)
    known = structure.known_terms()
    cs = {0: np.repeat(known.c[None].astype(complex), n_dir, axis=0)}
    du: dict = {0: np.repeat(known.d[None].astype(complex), n_dir, axis=0)} if np.any(
        known.d) else {}
    history_columns: dict = {}
    for k in np.flatnonzero(in_a & (terms.output >= 0)):
        cs[0][:, terms.output[k], terms.source[k]] += terms.weight[k] * gain[:, k]

    for k in forcing:
        m, f, g, e = lag_m[k], frac[k], gain[:, k], terms.eq_col[k]
        j = slot.get(k)
        gam_t, kin_t = gam[:, 0, :, e], kin[:, 0, :, e]                  # (D, n)
        gam_f = gam[:, j, :, e] if j else gam_t
        kin_f = kin[:, j, :, e] if j else kin_t
        lam_t = T * gam_t - kin_t
        lam_f = (T - f)[:, None] * gam_f - kin_f
        d_gam, d_lam = gam_t - gam_f, lam_t - lam_f
        is_control = terms.source[k] >= n_x
        if is_control and hold == "zoh":
            pieces = {m + 1: d_gam, m: gam_f}
        else:
            ramp_early = ((2 * T - f)[:, None] * d_gam - d_lam) / T
            pieces = {m - 1: kin_f / T, m: gam_f - kin_f / T + ramp_early,
                      m + 1: d_gam - ramp_early}
        column = terms.source[k] - (n_x if is_control else 0)
        for lag, vector in pieces.items():
            vec = g[:, None] * vector                                      # (D, n)
            if is_control:
                target = np.zeros((n_dir, n_x, n_u), dtype=complex)
                target[:, :, column] = vec
                _add(pu_raw, lag, target)
            elif lag == -1:
                implicit[:, :, column] += vec
            else:
                target = np.zeros((n_dir, n_x, n_x), dtype=complex)
                target[:, :, column] = vec
                _add(ps_raw, lag, target)
                if lag > 0:
                    history_columns.setdefault(lag, set()).add(int(column))
        if terms.output[k] >= 0:
            out = terms.output[k]
            weights = ({m + 1: 1.0} if (is_control and hold == "zoh" and terms.delay[k] > 0)
                       else {m: 1.0} if (is_control and hold == "zoh")
                       else {m + 1: f / T, m: 1.0 - f / T})
            for lag, w in weights.items():
                shape = (n_dir, n_y, n_u if is_control else n_x)
                target = np.zeros(shape, dtype=complex)
                target[:, out, column] = terms.weight[k] * g * w
                _add(du if is_control else cs, lag, target)

    fold = np.linalg.inv(np.eye(n_x) - implicit)
    ps = {lag: fold @ m for lag, m in ps_raw.items()}
    pu = {lag: fold @ m for lag, m in pu_raw.items()}
    pe = fold @ gam[:, 0]
    history = {lag: np.array(sorted(columns)) for lag, columns in history_columns.items()}
    real = lambda maps: {lag: m[0].real.copy() for lag, m in maps.items()}  # noqa: E731
    deriv = (lambda maps: {lag: m[1:].imag / COMPLEX_STEP for lag, m in maps.items()}
             ) if with_derivatives else (lambda maps: {})
    return DiscreteMaps(T, real(ps), real(pu), real(cs), real(du), deriv(ps), deriv(pu),
                        deriv(cs), deriv(du), history, pe[0].real.copy(),
                        pe[1:].imag / COMPLEX_STEP)
