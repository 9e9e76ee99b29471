"""Analytic frequency response of the delayed linear model.

H(jω) = C(jω) (jωI − A(jω))⁻¹ B(jω) + D(jω), where every delayed term carries e^(−jωτ):
the delays are exact, not approximated.
"""

from __future__ import annotations

import numpy as np

from rotorid.errors import StructureError
from rotorid.model.structure import CONTROLS, OUTPUTS, STATES, ModelStructure


def frequency_response(structure: ModelStructure, values, omega) -> np.ndarray:
    """Complex frequency response of every output to every control.

    Args:
        structure: model structure; values: parameter vector, mapping or ``None`` (initial).
        omega: frequencies in rad/s, shape (F,).
    Returns:
        complex array (F, 8, 4): outputs [ax az q theta ay p phi r] × controls
        [long lat coll ped], in the structure's units per control unit.
    """
    omega = _checked_omega(omega)
    a, b, c, d = _delayed_matrices(structure, structure.terms(values), omega)
    return c @ state_response(a, b, omega) + d


def response_sensitivities(structure: ModelStructure, values, omega
                           ) -> tuple[np.ndarray, np.ndarray]:
    """The frequency response and its exact derivatives with respect to the parameters.

    With R = (jωI − A)⁻¹, X = R·B and Y = C·R, a term of gain g and delay τ that drives
    equation row e from source s (and output row o when it also feeds a specific force)
    enters as t = g·e^(−jωτ), and ∂H/∂t = (Y[:, e] + 1_o) ⊗ X[s, :] for a state source,
    (Y[:, e] + 1_o) in control column s for a control. Then ∂H/∂g = e^(−jωτ)·∂H/∂t and
    ∂H/∂τ = −jω·g·e^(−jωτ)·∂H/∂t.

    Args: as :func:`frequency_response`.
    Returns:
        ``(H, dH)``: H complex (F, 8, 4) as :func:`frequency_response`; dH complex
        (F, P, 8, 4), ∂H/∂θ_p in ``structure.parameter_names`` order (per s for a delay).
    """
    omega = _checked_omega(omega)
    table = structure.terms(values)
    a, b, c, d = _delayed_matrices(structure, table, omega)
    resolvent = np.linalg.inv(1j * omega[:, None, None] * np.eye(len(STATES)) - a)
    x = resolvent @ b                                        # (F, 8, 4)
    y = c @ resolvent                                        # (F, 8, 8)
    index = {name: i for i, name in enumerate(structure.parameter_names)}
    sensitivities = np.zeros((omega.size, len(index), len(OUTPUTS), len(CONTROLS)), complex)
    for k, derivative in enumerate(structure.derivatives):
        gain_index = index.get(derivative.name)
        delay_index = index.get(derivative.delay_name) if derivative.delay else None
        if gain_index is None and delay_index is None:
            continue
        left = y[:, :, table.equation[k]].copy()            # (F, 8)
        if table.output[k] >= 0:
            left[:, table.output[k]] += 1.0
        source = table.source[k]
        if source < len(STATES):
            unit = left[:, :, None] * x[:, source, None, :]
        else:
            unit = np.zeros((omega.size, len(OUTPUTS), len(CONTROLS)), complex)
            unit[:, :, source - len(STATES)] = left
        unit *= np.exp(-1j * omega * table.delay[k])[:, None, None]
        if gain_index is not None:
            sensitivities[:, gain_index] += unit
        if delay_index is not None:
            sensitivities[:, delay_index] += (-1j * omega * table.gain[k])[:, None, None] * unit
    return c @ x + d, sensitivities


def _checked_omega(omega) -> np.ndarray:
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    if omega.ndim != 1 or not np.all(np.isfinite(omega)):
        raise StructureError("omega must be a 1-D array of finite frequencies in rad/s")
    return omega


def _delayed_matrices(structure: ModelStructure, table, omega: np.ndarray):
    """A (F, 8, 8), B (F, 8, 4), C (F, 8, 8), D (F, 8, 4) at each frequency, every delayed
    term multiplied by e^(−jωτ)."""
    n_f = omega.size
    a = np.repeat(structure.known_state_matrix()[None].astype(complex), n_f, axis=0)
    b = np.zeros((n_f, 8, 4), dtype=complex)
    c = np.repeat(structure.known_output_matrix()[None].astype(complex), n_f, axis=0)
    d = np.zeros((n_f, 8, 4), dtype=complex)
    for eq, src, gain, tau, out in zip(table.equation, table.source, table.gain, table.delay,
                                       table.output):
        term = gain * np.exp(-1j * omega * tau)
        if src < 8:
            a[:, eq, src] += term
            if out >= 0:
                c[:, out, src] += term
        else:
            b[:, eq, src - 8] += term
            if out >= 0:
                d[:, out, src - 8] += term
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
    if output not in OUTPUTS:
        raise StructureError(f"unknown output {output!r}; outputs: {', '.join(OUTPUTS)}")
    if control not in CONTROLS:
        raise StructureError(f"unknown control {control!r}; controls: {', '.join(CONTROLS)}")
    response = frequency_response(structure, values, omega)
    return response[:, OUTPUTS.index(output), CONTROLS.index(control)]


__all__ = ["frequency_response", "pair_response", "response_sensitivities", "state_response",
           "STATES"]
