"""What an author declares and writes for a nonlinear model of their own (docs/models.md).

The author writes two functions of time, state, input and parameters, vectorised over a batch
of B rows (each row one parameter vector, or one maneuver, or one sample):

* ``derivatives(t, x, u, theta) -> (B, n)``: the state derivatives ẋ,
* ``outputs(t, x, u, theta) -> (B, ny)``: the outputs y,

with ``t`` (B,) in s, ``x`` (B, n), ``u`` (B, m), ``theta`` (B, p) in the units of the declared
signals; rows are independent, so the framework may stack any rows it likes into one call.
The model declares ``signals`` (:class:`~rotorid.model.signals.ModelSignals`) and ``parameters`` (a tuple of
:class:`Parameter`, in the order of ``theta``'s columns). It may also provide its own
derivatives, ``derivative_jacobians(t, x, u, theta) -> (∂f/∂x (B, n, n), ∂f/∂θ (B, n, p))``
and ``output_jacobians(t, x, u, theta) -> (∂h/∂x (B, ny, n), ∂h/∂θ (B, ny, p))``; with both,
sensitivities are exact instead of finite differences.
"""

from __future__ import annotations

import math
from typing import Protocol, runtime_checkable

import attrs
import numpy as np

from rotorid.errors import StructureError
from rotorid.model.signals import ModelSignals


@attrs.frozen
class Parameter:
    """One parameter θ_k of a nonlinear model: its start value, bounds and whether it is fixed.

    A fixed parameter keeps ``start`` and is not estimated; ``unit`` is free text for reports.
    """

    name: str
    start: float = attrs.field(converter=float)
    lower: float = attrs.field(default=-math.inf, converter=float)
    upper: float = attrs.field(default=math.inf, converter=float)
    fixed: bool = False
    unit: str = ""

    def __attrs_post_init__(self):
        if not self.name.isidentifier():
            raise StructureError(f"parameter name {self.name!r} is not an identifier; use "
                                 "letters, digits and underscores (e.g. 'C_Lalpha')")
        if not self.lower <= self.start <= self.upper:
            raise StructureError(f"parameter {self.name!r}: start {self.start:g} lies outside "
                                 f"its bounds [{self.lower:g}, {self.upper:g}]; move the start "
                                 "or widen the bounds")


@runtime_checkable
class NonlinearModel(Protocol):
    """The protocol of :mod:`rotorid.model.nonlinear` (see the module docstring)."""

    signals: ModelSignals
    parameters: tuple[Parameter, ...]

    def derivatives(self, t: np.ndarray, x: np.ndarray, u: np.ndarray,
                    theta: np.ndarray) -> np.ndarray: ...

    def outputs(self, t: np.ndarray, x: np.ndarray, u: np.ndarray,
                theta: np.ndarray) -> np.ndarray: ...


def has_own_jacobians(model) -> bool:
    """Whether ``model`` provides both ``derivative_jacobians`` and ``output_jacobians``."""
    return hasattr(model, "derivative_jacobians") and hasattr(model, "output_jacobians")
