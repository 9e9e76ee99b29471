"""The truth model's side of a case: its derivatives and equivalent delays, for comparison
with the identified model (only for data sources that give a truth model)."""

from __future__ import annotations

import numpy as np

from rotorid.model.residualisation import derivatives_of, residualise
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.plugin.contracts import TruthModel
from rotorid.verification.equivalent_delays import (
    ROTOR_DERIVATIVES,
    EquivalentDelays,
    equivalent_delays,
)


def truth_derivatives(truth: TruthModel, condition: FlightCondition,
                      structure: ModelStructure) -> dict[str, float]:
    """The truth model's derivatives in the structure's units, by name.

    A rigid-body structure reads its states' rows and columns of the truth's 6-DoF
    linearisation (rotor and inflow residualised); a structure with rotor states (``hybrid``)
    reads the full linearisation with every state it lacks residualised: the flap-coupled
    model, not the 6-DoF one (docs/hybrid.md).
    """
    units = structure.units.name
    linear = truth.linearize(condition.airspeed_kt, units=units)
    states = list(linear.states)
    if set(structure.states) <= set(states):
        rows = [states.index(name) for name in structure.states]
        a, b = np.asarray(linear.A)[np.ix_(rows, rows)], np.asarray(linear.B)[rows]
        controls = linear.controls
    else:
        full = truth.linearize(condition.airspeed_kt, full=True, units=units)
        a, b = residualise(full.A, full.B, full.states, structure.states)
        controls = full.controls
    # the structure's controls may be fewer, in another order (long, coll of `longitudinal`)
    b = np.asarray(b)[:, [list(controls).index(name) for name in structure.controls]]
    return derivatives_of(structure, a, b)


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
