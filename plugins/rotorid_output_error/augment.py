"""Model wrappers that add per-maneuver parameters: output biases and initial states."""

from __future__ import annotations

import attrs
import numpy as np
from rotorid.data import ManeuverSet
from rotorid.estimation.models import finite_difference_sensitivities, measured_outputs
from rotorid.simulation.simulator import Simulator


class _AppendedParameters:
    """The part both wrappers share: the wrapped model's parameters (``n_base`` of them)
    followed by per-maneuver ones that start at zero and are unbounded."""

    def initial_values(self) -> np.ndarray:
        extra = len(self.parameter_names) - self.n_base
        return np.concatenate([self.model.initial_values(), np.zeros(extra)])

    def bounds(self):
        lower, upper = self.model.bounds()
        extra = len(self.parameter_names) - self.n_base
        return (np.concatenate([lower, np.full(extra, -np.inf)]),
                np.concatenate([upper, np.full(extra, np.inf)]))


class WithOutputBiases(_AppendedParameters):
    """A model plus one constant bias per maneuver and output (``bias_<maneuver>_<output>``).

    The biases are appended to the wrapped model's parameters and start at zero.
    """

    def __init__(self, model, maneuver_names):
        self.model = model
        self.maneuver_names = tuple(maneuver_names)
        self.output_names = model.output_names
        self.output_units = tuple(getattr(model, "output_units", ()))
        self.n_base = len(model.parameter_names)
        self.parameter_names = tuple(model.parameter_names) + tuple(
            f"bias_{m}_{o}" for m in self.maneuver_names for o in self.output_names)
        self.parameter_units = dict(getattr(model, "parameter_units", {}))
        self.parameter_units.update(
            {f"bias_{m}_{o}": unit for m in self.maneuver_names
             for o, unit in zip(self.output_names, self.output_units)})

    def measured(self, maneuvers, columns=None):
        return measured_outputs(self.model, maneuvers, columns)

    def _biases(self, values):
        return np.asarray(values[self.n_base:]).reshape(len(self.maneuver_names), -1)

    def simulate(self, values, maneuvers):
        base = self.model.simulate(values[: self.n_base], maneuvers)
        return [y + b for y, b in zip(base, self._biases(values))]

    def sensitivities(self, values, maneuvers):
        if hasattr(self.model, "sensitivities"):
            base, sens = self.model.sensitivities(values[: self.n_base], maneuvers)
        else:
            base, sens = finite_difference_sensitivities(self.model, values[: self.n_base],
                                                         maneuvers)
        n_o = len(self.output_names)
        outputs, full = [], []
        for i, (y, s) in enumerate(zip(base, sens)):
            outputs.append(y + self._biases(values)[i])
            extra = np.zeros((y.shape[0], len(self.parameter_names) - self.n_base, n_o))
            for k in range(n_o):
                extra[:, i * n_o + k, k] = 1.0
            full.append(np.concatenate([s, extra], axis=1))
        return outputs, full


class WithInitialStates(_AppendedParameters):
    """A linear model plus the initial perturbation state of every maneuver
    (``x0_<maneuver>_<state>``, 8 per maneuver, structure units, states ``u w q θ v p φ r``).

    The outputs are linear in the initial states, so their sensitivities are the free
    responses: the structure simulated with zero inputs from each unit initial state, all
    maneuvers and states in one batched simulation.

    Args:
        model: a :class:`rotorid.estimation.models.LinearModel`.
        maneuver_names: names of the maneuvers, in the order of the fitted sets.
    """

    def __init__(self, model, maneuver_names):
        self.model = model
        self.structure = model.structure
        self.maneuver_names = tuple(maneuver_names)
        self.output_names = model.output_names
        self.output_units = model.output_units
        self.n_base = len(model.parameter_names)
        self.parameter_names = tuple(model.parameter_names) + tuple(
            f"x0_{m}_{s}" for m in self.maneuver_names for s in self.structure.states)
        states = self.structure.signals.states
        self.parameter_units = {**model.parameter_units,
                                **{f"x0_{m}_{s.name}": s.unit for m in self.maneuver_names
                                   for s in states}}
        self.n_states = self.structure.n_states

    def start_states(self, maneuvers) -> np.ndarray:
        """Each maneuver's initial state of the structure's states
        (:meth:`rotorid.data.Maneuver.initial_values`), flattened to (n·M,)."""
        return np.concatenate([m.initial_values(self.structure.states) for m in maneuvers])

    def _simulator(self, values, maneuvers) -> Simulator:
        states = np.asarray(values[self.n_base:], dtype=float).reshape(len(maneuvers),
                                                                        self.n_states)
        return Simulator(self.structure, maneuvers, initial_states=states)

    def simulate(self, values, maneuvers):
        return self._simulator(values, maneuvers).outputs(values[: self.n_base])

    def _free_responses(self, values, maneuvers) -> list[np.ndarray]:
        """Per maneuver (N_i, n, n_o): outputs of zero inputs from each unit initial state."""
        n = self.n_states
        quiet = ManeuverSet([attrs.evolve(m, name=f"{m.name}#{j}", inputs=np.zeros_like(m.inputs))
                             for m in maneuvers for j in range(n)], hold=maneuvers.hold)
        units = np.tile(np.eye(n), (len(maneuvers), 1))
        responses = Simulator(self.structure, quiet, initial_states=units).outputs(
            values[: self.n_base])
        return [np.stack(responses[n * i: n * i + n], axis=1) for i in range(len(maneuvers))]

    def sensitivities(self, values, maneuvers):
        outputs, sens = self._simulator(values, maneuvers).outputs_and_sensitivities(
            values[: self.n_base])
        full = []
        for i, (s, free) in enumerate(zip(sens, self._free_responses(values, maneuvers))):
            n = self.n_states
            extra = np.zeros((s.shape[0], n * len(maneuvers), s.shape[2]))
            extra[:, n * i: n * i + n] = free
            full.append(np.concatenate([s, extra], axis=1))
        return outputs, full
