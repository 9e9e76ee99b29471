"""Simulation in segments restarted from the data: time-domain metrics of a model whose
open-loop simulation would drift away from a long record."""

from __future__ import annotations

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import VerificationError
from rotorid.estimation.equation_error import reconstructed_states
from rotorid.simulation.simulator import simulate


def segmented_simulation(structure, values, maneuvers, segment: float) -> list[np.ndarray]:
    """Outputs simulated in segments restarted from the data's state.

    Each maneuver is cut into segments of ``segment`` s (a remainder shorter than two samples
    joins the segment before it). A segment is simulated from the state at its start:
    measured q θ p φ r and u v w integrated from the measured specific forces
    (:func:`rotorid.estimation.equation_error.reconstructed_states`), and the segments are joined.
    Delayed terms see trim before each restart, and the reconstructed velocities carry
    integration error, so the restarts are approximate: on noise-free data of the model
    itself they reproduce its plain simulation to a few per cent (tested).
    Returns one (N_i, ny) array per maneuver, outputs in ``structure.outputs`` order.
    """
    if not segment > 0:
        raise VerificationError(f"segment must be a positive duration in s, got {segment!r}")
    pieces, counts = [], []              # counts: the number of pieces of each maneuver
    for m in maneuvers:
        states = reconstructed_states(structure, m)
        step = max(2, int(round(segment / m.dt)))
        starts = list(range(0, m.n_samples, step))
        if len(starts) > 1 and m.n_samples - starts[-1] < 2:
            starts.pop()
        for first, stop in zip(starts, starts[1:] + [m.n_samples]):
            pieces.append(attrs.evolve(
                m.samples(first, stop), name=f"{m.name}#{first}",
                initial_state=states[first], state_names=structure.states))
        counts.append(len(starts))
    simulated = iter(simulate(structure, values, ManeuverSet(pieces, hold=maneuvers.hold)))
    return [np.concatenate([next(simulated) for _ in range(count)]) for count in counts]
