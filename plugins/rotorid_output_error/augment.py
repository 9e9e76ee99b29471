"""Model wrappers that add per-maneuver parameters: output biases."""

from __future__ import annotations

import numpy as np

from rotorid.models import finite_difference_sensitivities


class WithOutputBiases:
    """A model plus one constant bias per maneuver and output (``bias_<maneuver>_<output>``).

    The biases are appended to the wrapped model's parameters and start at zero.
    """

    def __init__(self, model, maneuver_names):
        self.model = model
        self.maneuver_names = tuple(maneuver_names)
        self.output_names = model.output_names
        self.n_base = len(model.parameter_names)
        self.parameter_names = tuple(model.parameter_names) + tuple(
            f"bias_{m}_{o}" for m in self.maneuver_names for o in self.output_names)

    def initial_values(self) -> np.ndarray:
        extra = len(self.parameter_names) - self.n_base
        return np.concatenate([self.model.initial_values(), np.zeros(extra)])

    def bounds(self):
        lower, upper = self.model.bounds()
        extra = len(self.parameter_names) - self.n_base
        return (np.concatenate([lower, np.full(extra, -np.inf)]),
                np.concatenate([upper, np.full(extra, np.inf)]))

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
