"""Residualisation: a linear model over fewer states, the others taken as quasi-steady.

Setting the time derivatives of the dropped states d to zero and solving their rows for them
leaves the model over the kept states k::

    A = A_kk − A_kd·A_dd⁻¹·A_dk        B = B_k − A_kd·A_dd⁻¹·B_d

Two uses: the truth model's 6-DoF derivatives drop every rotor and inflow state; the hybrid
reference (docs/hybrid.md) keeps the tip-path-plane tilts β1c, β1s and drops their rates,
the coning and the inflow, which turns second-order flapping into the first-order
tip-path-plane equations (the regressing flap mode kept, the advancing and coning modes
removed). :func:`derivatives_of` reads a structure's derivatives from such a model.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rotorid.errors import StructureError
from rotorid.model.structure import ModelStructure


def residualise(a: np.ndarray, b: np.ndarray, states: Sequence[str],
                keep: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """The model ẋ = A·x + B·u over the states ``keep`` (in that order).

    Args:
        a: (n, n) state matrix over ``states``; b: (n, m) input matrix.
        states: the n state names; keep: the names kept, a subset of ``states``.
    Returns:
        A (k, k) and B (k, m) over ``keep``.
    """
    states = list(states)
    missing = [name for name in keep if name not in states]
    if missing:
        raise StructureError(f"residualise: {', '.join(missing)} are not states of the model "
                             f"({', '.join(states)}); keep only states it has")
    kept = [states.index(name) for name in keep]
    dropped = [i for i in range(len(states)) if i not in kept]
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    a_dd = a[np.ix_(dropped, dropped)]
    if dropped and np.linalg.cond(a_dd) > 1e12:
        raise StructureError(
            f"residualise: the dropped states ({', '.join(states[i] for i in dropped)}) have "
            f"no quasi-steady solution (their A block is singular); keep the states with "
            f"neutral dynamics (attitudes, heading)")
    gain = np.linalg.solve(a_dd, np.hstack([a[np.ix_(dropped, kept)], b[dropped]]))
    a_kd = a[np.ix_(kept, dropped)]
    return (a[np.ix_(kept, kept)] - a_kd @ gain[:, :len(kept)],
            b[kept] - a_kd @ gain[:, len(kept):])


def derivatives_of(structure: ModelStructure, a, b) -> dict[str, float]:
    """Every derivative of ``structure``'s template (each equation letter over each variable)
    read from a linear model over its states and controls, by name.

    Args:
        a: (n, n) and b: (n, m), known terms included, in the structure's units.
    """
    coefficients = np.hstack([np.asarray(a) - structure.known_state_matrix(), np.asarray(b)])
    columns = structure.states + structure.controls
    return {f"{letter}_{variable}": float(coefficients[structure.states.index(state),
                                                       columns.index(variable)])
            for letter, state in structure.template.equations
            for variable in structure.template.variables}
