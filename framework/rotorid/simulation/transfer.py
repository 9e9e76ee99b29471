"""Analytic frequency response of the delayed linear model.

H(jω) = C(jω) (jωI − A(jω))⁻¹ B(jω) + D(jω), where every delayed term carries e^(−jωτ):
the delays are exact, not approximated.
"""

from __future__ import annotations

import numpy as np

from rotorid.errors import StructureError
from rotorid.model.structure import ModelStructure


def frequency_response(structure: ModelStructure, values, omega) -> np.ndarray:
    """Complex frequency response of every output to every control.

    Args:
        structure: model structure; values: parameter vector, mapping or ``None`` (initial).
        omega: frequencies in rad/s, shape (F,).
    Returns:
        complex array (F, p, m): ``structure.outputs`` × ``structure.controls``, in the
        structure's units per control unit.
    """
    omega = _checked_omega(omega)
    a, b, c, d = _delayed_matrices(structure, structure.terms(values), omega)
    return c @ state_response(a, b, omega) + d


def response_sensitivities(structure: ModelStructure, values, omega
                           ) -> tuple[np.ndarray, np.ndarray]:
    """The frequency response and its exact derivatives with respect to the parameters:
    every output over every control, each entry a :func:`compared_response` of one output
    to one control.

    Args: as :func:`frequency_response`.
    Returns:
        ``(H, dH)``: H complex (F, p, m) as :func:`frequency_response`; dH complex
        (F, P, p, m), ∂H/∂θ_p in ``structure.parameter_names`` order (per s for a delay).
    """
    omega = _checked_omega(omega)
    n_f, n_y, n_u = omega.size, structure.n_outputs, structure.n_controls
    rows = np.tile(np.repeat(np.arange(n_y), n_u), n_f)             # (F·p·m,) f, y, u
    mixing = np.tile(np.eye(n_u), (n_f * n_y, 1))                   # (F·p·m, m)
    h, dh = compared_response(structure, values, np.repeat(omega, n_y * n_u), rows, mixing)
    return (h.reshape(n_f, n_y, n_u),
            dh.reshape(n_f, n_y, n_u, -1).transpose(0, 3, 1, 2))


def compared_response(structure: ModelStructure, values, omega, rows, mixing,
                      derivatives: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
    """One compared response per frequency and, when asked, its exact derivatives: at
    frequency f the response of output ``rows[f]`` to the inputs mixed by ``mixing[f]``,
    h_f = Σ_i mixing[f, i]·H[f, rows[f], i] (e.g. a fit's apparent response on a sweep).

    With R = (jωI − A)⁻¹, x = R·B·mixing and y = C[rows]·R per frequency, a term of gain g
    and delay τ that drives equation row e from source s (and output row o, with weight w,
    when it also feeds a specific force) enters as t = g·e^(−jωτ), and
    ∂h/∂t = (y[e] + w·[o = rows]) · (x[s] for a state source, mixing[s] for a control);
    then ∂h/∂g = e^(−jωτ)·∂h/∂t and ∂h/∂τ = −jω·g·e^(−jωτ)·∂h/∂t. The terms are reduced to
    the one mixed entry before they are formed: O(F·P), not O(F·P·p·m).

    Args:
        structure, values: as :func:`frequency_response`; omega: frequencies in rad/s (F,).
        rows: output index per frequency (F,), in ``structure.outputs`` order.
        mixing: complex (F, m): the weight of each control, ``structure.controls`` order.
        derivatives: also return ∂h/∂θ.
    Returns:
        ``(h, dh)``: h complex (F,) in the output's unit per control unit; dh complex
        (F, P) in ``structure.parameter_names`` order (per s for a delay), or None.
    """
    omega = _checked_omega(omega)
    rows, mixing = np.asarray(rows, dtype=int), np.asarray(mixing, dtype=complex)
    table = structure.terms(values)
    a, b, c, d = _delayed_matrices(structure, table, omega)
    n_x, points = structure.n_states, np.arange(omega.size)
    system = 1j * omega[:, None, None] * np.eye(n_x) - a
    c_row = c[points, rows]                                                # (F, n)
    x = np.linalg.solve(system, np.einsum("fnm,fm->fn", b, mixing)[..., None])[..., 0]
    h = np.einsum("fn,fn->f", c_row, x) + np.einsum("fm,fm->f", d[points, rows], mixing)
    if not derivatives:
        return h, None
    y = np.linalg.solve(np.swapaxes(system, 1, 2), c_row[..., None])[..., 0]   # (F, n)
    left = y[:, table.equation] + table.weight * (table.output == rows[:, None])
    state = table.source < n_x
    right = np.where(state, x[:, np.where(state, table.source, 0)],
                     mixing[:, np.where(state, 0, table.source - n_x)])
    unit = left * right * np.exp(-1j * np.outer(omega, table.delay))      # (F, K)
    gains, delays = _parameter_columns(structure)
    return h, unit @ gains + (unit * (-1j * np.outer(omega, table.gain))) @ delays


def _parameter_columns(structure: ModelStructure) -> tuple[np.ndarray, np.ndarray]:
    """(K, P) 0/1 matrices taking each derivative term's value to its gain's and its delay's
    parameter column (a zero row where the gain or the delay is fixed)."""
    index = {name: i for i, name in enumerate(structure.parameter_names)}
    shape = (len(structure.derivatives), len(index))
    gains, delays = np.zeros(shape), np.zeros(shape)
    for k, derivative in enumerate(structure.derivatives):
        if derivative.name in index:
            gains[k, index[derivative.name]] = 1.0
        if derivative.delay and derivative.delay_name in index:
            delays[k, index[derivative.delay_name]] = 1.0
    return gains, delays


def _checked_omega(omega) -> np.ndarray:
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    if omega.ndim != 1 or not np.all(np.isfinite(omega)):
        raise StructureError("omega must be a 1-D array of finite frequencies in rad/s")
    return omega


def _delayed_matrices(structure: ModelStructure, table, omega: np.ndarray):
    """A (F, n, n), B (F, n, m), C (F, p, n), D (F, p, m) at each frequency, every delayed
    term multiplied by e^(−jωτ)."""
    n_f, n_x, n_u = omega.size, structure.n_states, structure.n_controls
    known = structure.known_terms()
    a = np.repeat(known.a[None].astype(complex), n_f, axis=0)
    b = np.zeros((n_f, n_x, n_u), dtype=complex)
    c = np.repeat(known.c[None].astype(complex), n_f, axis=0)
    d = np.repeat(known.d[None].astype(complex), n_f, axis=0)
    for eq, src, gain, tau, out, weight in zip(table.equation, table.source, table.gain,
                                               table.delay, table.output, table.weight):
        term = gain * np.exp(-1j * omega * tau)
        if src < n_x:
            a[:, eq, src] += term
            if out >= 0:
                c[:, out, src] += weight * term
        else:
            b[:, eq, src - n_x] += term
            if out >= 0:
                d[:, out, src - n_x] += weight * term
    return a, b, c, d


def state_response(a: np.ndarray, b: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """(jωI − A)⁻¹B: state responses to the inputs, (F, n, m), for A (n, n) or (F, n, n) and
    B (n, m) or (F, n, m) (per frequency when they carry delays)."""
    identity = np.eye(np.shape(a)[-1])
    return np.linalg.solve(1j * omega[:, None, None] * identity - a,
                           np.broadcast_to(b, (omega.size, *np.shape(b)[-2:])))


def pair_response(structure: ModelStructure, values, omega, output: str,
                  control: str) -> np.ndarray:
    """Frequency response of one output/control pair, shape (F,)."""
    outputs, controls = structure.outputs, structure.controls
    if output not in outputs:
        raise StructureError(f"unknown output {output!r}; outputs: {', '.join(outputs)}")
    if control not in controls:
        raise StructureError(f"unknown control {control!r}; controls: {', '.join(controls)}")
    response = frequency_response(structure, values, omega)
    return response[:, outputs.index(output), controls.index(control)]
