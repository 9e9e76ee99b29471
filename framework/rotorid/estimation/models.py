"""The small model protocol estimators work on, and its adapter for linear structures.

An estimator never needs to know what it identifies. Any object with

* ``parameter_names`` (tuple of str) and ``output_names`` (tuple of str),
* ``initial_values() -> (P,)`` and ``bounds() -> ((P,), (P,))``,
* ``simulate(values, maneuvers) -> list of (N_i, n_o) arrays``,

is identifiable; ``sensitivities(values, maneuvers) -> (outputs, list of (N_i, P, n_o))`` is
optional (central finite differences are used otherwise, see
:func:`finite_difference_sensitivities`), and so is ``gauss_newton(values, maneuvers,
residuals, weighting) -> (F, G)``, the products of :func:`gauss_newton_products` computed
without storing the sensitivities. So are ``output_units`` (tuple of unit labels, one per
output) and ``parameter_units`` (name → unit), which the fit report prints; a model without
them is reported without units. Outputs are compared with the maneuvers' measured outputs
picked by ``output_names``, or with those of the optional ``measured(maneuvers) -> list of
(N_i, n_o)`` (a model that reads its own signals from the data, such as
:class:`rotorid.estimation.integrated.IntegratedModel`). A nonlinear model of one's own
(:class:`rotorid.model.nonlinear.NonlinearModel`) is wrapped in that adapter by :func:`as_model`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import StructureError
from rotorid.estimation.integrated import IntegratedModel
from rotorid.model.nonlinear import NonlinearModel
from rotorid.model.parameter_units import structure_parameter_units
from rotorid.model.structure import ModelStructure
from rotorid.simulation.simulator import Simulator, weighting_factor


@runtime_checkable
class IdentifiableModel(Protocol):
    """The protocol of :mod:`rotorid.estimation.models` (see the module docstring)."""

    parameter_names: tuple[str, ...]
    output_names: tuple[str, ...]

    def initial_values(self) -> np.ndarray: ...

    def bounds(self) -> tuple[np.ndarray, np.ndarray]: ...

    def simulate(self, values, maneuvers: ManeuverSet) -> list[np.ndarray]: ...


def measured_outputs(model, maneuvers: ManeuverSet, columns=None) -> list[np.ndarray]:
    """The measured outputs the model's ``output_names`` select (or its ``measured``
    gives), (N_i, n_o) per maneuver; with ``columns`` (indices into ``output_names``) those
    outputs only, so that an output left out of the fit need not be recorded."""
    if hasattr(model, "measured"):
        return model.measured(maneuvers, columns)
    names = model.output_names
    chosen = names if columns is None else [names[i] for i in np.atleast_1d(columns)]
    return [m.columns(chosen) for m in maneuvers]


def finite_difference_sensitivities(model, values, maneuvers: ManeuverSet,
                                    relative_step: float = 1e-6):
    """Outputs and central-difference sensitivities, per maneuver (N_i, P, n_o)."""
    values = np.asarray(values, dtype=float)
    outputs = model.simulate(values, maneuvers)
    lower, upper = model.bounds()
    sens = [np.zeros((y.shape[0], values.size, y.shape[1])) for y in outputs]
    for k in range(values.size):
        h = relative_step * max(abs(values[k]), 1.0)
        up, down = values.copy(), values.copy()
        up[k] = min(values[k] + h, upper[k])
        down[k] = max(values[k] - h, lower[k])
        width = up[k] - down[k]
        for s, yp, ym in zip(sens, model.simulate(up, maneuvers), model.simulate(down, maneuvers)):
            s[:, k, :] = (yp - ym) / width
    return outputs, sens


def output_sensitivities(model, values, maneuvers: ManeuverSet):
    """Outputs (N_i, n_o) and sensitivities (N_i, P, n_o) per maneuver: the model's own
    ``sensitivities`` where it has them, else central differences."""
    if hasattr(model, "sensitivities"):
        return model.sensitivities(values, maneuvers)
    return finite_difference_sensitivities(model, values, maneuvers)


def gauss_newton_products(model, values, maneuvers: ManeuverSet, residuals, weighting):
    """F = Σ Jᵀ Q J and G = −Σ Jᵀ Q e over all samples of all maneuvers, J = ∂y/∂θ.

    Args:
        model: an identifiable model; its ``gauss_newton`` is used when it has one, else its
            sensitivities (or finite differences).
        values: (P,) parameter vector.
        residuals: per maneuver (N_i, n_o) residuals e = z − y at ``values``.
        weighting: (n_o, n_o) symmetric positive semi-definite Q.
    Returns:
        F (P, P) and G (P,).
    """
    if hasattr(model, "gauss_newton"):
        return model.gauss_newton(values, maneuvers, residuals, weighting)
    _, sens = output_sensitivities(model, values, maneuvers)
    factor = weighting_factor(weighting)
    p = len(values)
    f = np.zeros((p, p))
    g = np.zeros(p)
    for e, s in zip(residuals, sens):
        jacobian = np.matmul(factor, s.transpose(0, 2, 1)).reshape(-1, p)
        f += jacobian.T @ jacobian
        g -= jacobian.T @ (e @ factor.T).reshape(-1)
    return f, g


class LinearModel:
    """A :class:`ModelStructure` seen through the model protocol.

    Simulators are cached per maneuver set, so repeated evaluations reuse their setup.
    ``enforce_signs`` turns the derivatives' sign priors into bounds.
    """

    def __init__(self, structure: ModelStructure, enforce_signs: bool = False):
        self.structure = structure
        self.enforce_signs = enforce_signs
        self.parameter_names = structure.parameter_names
        self.output_names = structure.outputs
        self.output_units = structure.signals.outputs.units
        self.parameter_units = structure_parameter_units(structure)
        self._simulators: dict[int, tuple[ManeuverSet, Simulator]] = {}

    def initial_values(self) -> np.ndarray:
        return self.structure.initial_values()

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.structure.bounds(enforce_signs=self.enforce_signs)

    def _simulator(self, maneuvers: ManeuverSet) -> Simulator:
        cached = self._simulators.get(id(maneuvers))
        if cached is None or cached[0] is not maneuvers:
            cached = (maneuvers, Simulator(self.structure, maneuvers))
            self._simulators[id(maneuvers)] = cached
        return cached[1]

    def simulate(self, values, maneuvers: ManeuverSet) -> list[np.ndarray]:
        return self._simulator(maneuvers).outputs(values)

    def sensitivities(self, values, maneuvers: ManeuverSet):
        return self._simulator(maneuvers).outputs_and_sensitivities(values)

    def gauss_newton(self, values, maneuvers: ManeuverSet, residuals, weighting):
        return self._simulator(maneuvers).gauss_newton(values, residuals, weighting)

    @property
    def signs(self) -> dict[str, str]:
        return {d.name: d.sign.value for d in self.structure.free_derivatives}

    @property
    def fixed(self) -> dict[str, float]:
        return {d.name: d.initial for d in self.structure.derivatives if d.fixed}

    def growth_rate(self, values) -> float:
        """The largest real part of the eigenvalues of A at ``values`` (1/s, delays left
        out): positive when the model is unstable."""
        a = self.structure.matrices(values)[0]
        return float(np.max(np.linalg.eigvals(a).real)) if a.size else 0.0

    def start_values(self, maneuvers: ManeuverSet) -> np.ndarray:
        """Equation-error start values (see :mod:`rotorid.estimation.equation_error`)."""
        from rotorid.estimation.equation_error import equation_error_start

        return equation_error_start(self.structure, maneuvers)


def as_model(model_or_structure):
    """Wrap a :class:`ModelStructure` in :class:`LinearModel` and a nonlinear model of one's
    own in :class:`IntegratedModel` (default options); pass other models through."""
    if isinstance(model_or_structure, ModelStructure):
        return LinearModel(model_or_structure)
    if isinstance(model_or_structure, NonlinearModel):
        return IntegratedModel(model_or_structure)
    if not isinstance(model_or_structure, IdentifiableModel):
        raise StructureError(
            f"{type(model_or_structure).__name__} is not an identifiable model: it needs "
            "parameter_names, output_names, initial_values(), bounds() and simulate()")
    return model_or_structure
