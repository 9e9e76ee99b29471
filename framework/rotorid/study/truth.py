"""The truth model's side of a case: its derivatives and equivalent delays, for comparison
with the identified model (only for data sources that give a truth model)."""

from __future__ import annotations

import numpy as np

from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.plugin.contracts import TruthModel
from rotorid.verification.equivalent_delays import (
    ROTOR_DERIVATIVES,
    EquivalentDelays,
    equivalent_delays,
)

#: Rows of the 6-DoF derivatives: force or moment letter and the state it drives.
_ROWS = (("X", "u"), ("Y", "v"), ("Z", "w"), ("L", "p"), ("M", "q"), ("N", "r"))
_VELOCITIES = ("u", "v", "w", "p", "q", "r")


def truth_derivatives(truth: TruthModel, condition: FlightCondition,
                      structure: ModelStructure) -> dict[str, float]:
    """The truth model's residualised 6-DoF derivatives in the structure's units, by name."""
    linear = truth.linearize(condition.airspeed_kt, units=structure.units.name)
    a = np.asarray(linear.A) - structure.known_state_matrix()
    b = np.asarray(linear.B)
    values = {}
    for letter, row in _ROWS:
        i = structure.states.index(row)
        for j, state in enumerate(structure.states):
            if state in _VELOCITIES:
                values[f"{letter}_{state}"] = float(a[i, j])
        for j, control in enumerate(structure.controls):
            values[f"{letter}_{control}"] = float(b[i, j])
    return values


def truth_equivalent_delays(truth: TruthModel, condition: FlightCondition,
                            delayed: ModelStructure) -> EquivalentDelays | None:
    """The truth model's equivalent delays (:mod:`rotorid.verification.equivalent_delays`)
    for the rotor delays the identified model kept, or ``None`` when it kept none."""
    names = [d.name for d in delayed.free_delays if d.name in ROTOR_DERIVATIVES]
    if not names:
        return None
    units = delayed.units.name
    return equivalent_delays(truth.linearize(condition.airspeed_kt, full=True, units=units),
                             truth.linearize(condition.airspeed_kt, units=units), names)
