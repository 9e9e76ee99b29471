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
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    if omega.ndim != 1 or not np.all(np.isfinite(omega)):
        raise StructureError("omega must be a 1-D array of finite frequencies in rad/s")
    table = structure.terms(values)
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
    return c @ state_response(a, b, omega) + d


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


__all__ = ["frequency_response", "pair_response", "state_response", "STATES"]
