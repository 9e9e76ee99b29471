"""Time-domain verification with per-maneuver input biases and output reference shifts.

The practice of frequency-domain identification (Tischler & Remple's time-domain
verification, CIFER's VERIFY; docs/frequency.md): the identified model is held fixed and
simulated on dissimilar maneuvers, and for each maneuver only a constant bias on every
control input and a constant reference shift on every output are estimated. They absorb the
trim and measurement offsets that a frequency response cannot carry (it holds no information
at ω = 0), so the time-domain metrics judge the model's dynamics.

The model is linear in its inputs, so with y₀ the simulation of the recorded inputs and s_k
the response to a unit step on input k from the record's start,

    y(t) = y₀(t) + Σ_k b_k·s_k(t) + r,

and the biases b (one per input, in the input's unit) and shifts r (one per output, in the
output's unit) of each maneuver are the linear least-squares fit of y to the measured outputs,
every sample and output weighted alike (the RMSE's weighting).
"""

from __future__ import annotations

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.frozen import readonly_array
from rotorid.model.structure import ModelStructure
from rotorid.simulation.simulator import simulate


@attrs.frozen(eq=False)
class ShiftedSimulation:
    """A fixed model's simulation of some maneuvers after the bias and shift fit.

    Attributes:
        outputs: one (N_i, n_o) array per maneuver, biases and shifts applied.
        input_biases: (M, n_inputs), per maneuver, in the inputs' units.
        reference_shifts: (M, n_o), per maneuver, in the outputs' units.
    """

    outputs: tuple[np.ndarray, ...] = attrs.field(
        converter=lambda arrays: tuple(readonly_array(a) for a in arrays))
    input_biases: np.ndarray = attrs.field(converter=readonly_array)
    reference_shifts: np.ndarray = attrs.field(converter=readonly_array)


def _unit_steps(maneuvers: ManeuverSet) -> ManeuverSet:
    """Each maneuver repeated once per input with that input a unit step (the others zero),
    in maneuver-major order."""
    steps = []
    for m in maneuvers:
        for k in range(m.inputs.shape[1]):
            inputs = np.zeros_like(m.inputs)
            inputs[:, k] = 1.0
            steps.append(attrs.evolve(m, name=f"{m.name}#{k}", inputs=inputs))
    return ManeuverSet(steps, hold=maneuvers.hold)


def simulate_with_shifts(structure: ModelStructure, values, maneuvers: ManeuverSet
                         ) -> ShiftedSimulation:
    """Simulate ``structure`` at ``values`` (vector or name mapping, held fixed) on
    ``maneuvers`` and fit each maneuver's input biases and output reference shifts.

    Raises:
        SimulationDivergedError: the model's response grows without bound.
    """
    plain = simulate(structure, values, maneuvers)
    steps = simulate(structure, values, _unit_steps(maneuvers))
    outputs, biases, shifts = [], [], []
    start = 0
    for m, y in zip(maneuvers, plain):
        n_inputs, n_outputs = m.inputs.shape[1], y.shape[1]
        responses = steps[start:start + n_inputs]
        start += n_inputs
        columns = [s.reshape(-1) for s in responses] + [
            np.tile(np.eye(n_outputs)[j], y.shape[0]) for j in range(n_outputs)]
        design = np.column_stack(columns)
        solution = np.linalg.lstsq(design, (m.outputs - y).reshape(-1), rcond=None)[0]
        outputs.append(y + (design @ solution).reshape(y.shape))
        biases.append(solution[:n_inputs])
        shifts.append(solution[n_inputs:])
    return ShiftedSimulation(outputs, np.array(biases), np.array(shifts))
