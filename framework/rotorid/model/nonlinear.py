"""What an author declares and writes for a nonlinear model of their own (docs/models.md).

The author writes two functions of time, state, input and parameters, vectorised over a batch
of B rows (each row one parameter vector, or one maneuver, or one sample):

* ``derivatives(t, x, u, theta) -> (B, n)``: the state derivatives ẋ,
* ``outputs(t, x, u, theta) -> (B, ny)``: the outputs y,

with ``t`` (B,) in s, ``x`` (B, n), ``u`` (B, m), ``theta`` (B, p) in the units of the declared
signals; rows are independent, so the framework may stack any rows it likes into one call.
The model declares ``signals`` (:class:`ModelSignals`) and ``parameters`` (a tuple of
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
from rotorid.model.signals import SignalSet


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


@attrs.frozen
class ModelSignals:
    """The states (n), inputs (m) and outputs (ny) of a model, in the order of its arrays.

    A name used in several roles (a state that is also measured, such as ``q``) must carry the
    same unit and kind in each; :attr:`all` is then the set of distinct signals.
    """

    states: SignalSet
    inputs: SignalSet
    outputs: SignalSet

    def __attrs_post_init__(self):
        seen = {}
        for role, signals in (("state", self.states), ("input", self.inputs),
                              ("output", self.outputs)):
            for signal in signals:
                first_role, first = seen.setdefault(signal.name, (role, signal))
                if (first.unit, first.kind) != (signal.unit, signal.kind):
                    raise StructureError(
                        f"signal {signal.name!r} is a {first_role} in {first.unit} "
                        f"({first.kind}) and an {role} in {signal.unit} ({signal.kind}); "
                        "declare one unit and kind for it or give the two different names")
                if "input" in (first_role, role) and first_role != role:
                    raise StructureError(f"signal {signal.name!r} is both a {first_role} and "
                                         f"an {role}; an input cannot be a state or an output")

    @property
    def all(self) -> SignalSet:
        """Every distinct signal: states, then inputs, then outputs not named before."""
        distinct = {}
        for signal in (*self.states, *self.inputs, *self.outputs):
            distinct.setdefault(signal.name, signal)
        return SignalSet(distinct.values())


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
