"""Helicopter model templates: the states, controls and outputs of a linear structure.

A template fixes the shape of a :class:`~rotorid.model.structure.ModelStructure`: which states,
controls and outputs it has (in the order of its arrays) and so which derivatives it can hold.
Shipped templates:

* ``six-dof`` (the paper's, default): states ``u w q theta v p phi r``, controls
  ``long lat coll ped``, outputs ``ax az q theta ay p phi r``; 60 derivatives;
* ``longitudinal``: states ``u w q theta``, controls ``long coll``, outputs ``ax az q theta``;
  the X, Z and M derivatives over u w q long coll (15);
* ``lateral``: states ``v p phi r``, controls ``lat ped``, outputs ``ay p phi r``; the Y, L
  and N derivatives over v p r lat ped (15).

A subset's known gravity and kinematic terms are the six-dof's rows and columns of its states,
so a subset is the six-dof model with the other axes' states held at trim.
"""

from __future__ import annotations

import attrs

from rotorid.errors import StructureError
from rotorid.model.derivatives import (
    CONTROL_VARIABLES,
    EQUATION_OF_LETTER,
    FORCE_MOMENT_LETTERS,
    STATE_VARIABLES,
    Derivative,
)
from rotorid.model.signals import ModelSignals, Signal, SignalSet
from rotorid.units import CHANNEL_KINDS, UnitSystem

STATES = ("u", "w", "q", "theta", "v", "p", "phi", "r")
CONTROLS = CONTROL_VARIABLES
OUTPUTS = ("ax", "az", "q", "theta", "ay", "p", "phi", "r")


@attrs.frozen
class StructureTemplate:
    """The states, controls and outputs of a helicopter structure (names, array order)."""

    name: str
    states: tuple[str, ...]
    controls: tuple[str, ...]
    outputs: tuple[str, ...]
    summary: str

    def __attrs_post_init__(self):
        unknown = [n for n in self.states if n not in STATES]
        unknown += [n for n in self.controls if n not in CONTROLS]
        unknown += [n for n in self.outputs if n not in OUTPUTS]
        if unknown:
            raise StructureError(f"template {self.name!r}: {', '.join(unknown)} are not signals "
                                 f"of the six-dof helicopter model")

    @property
    def letters(self) -> tuple[str, ...]:
        """Force and moment equations whose state the template has (e.g. X Z M)."""
        return tuple(k for k in FORCE_MOMENT_LETTERS if EQUATION_OF_LETTER[k] in self.states)

    @property
    def variables(self) -> tuple[str, ...]:
        """Variables a derivative may multiply: the velocity and rate states, then controls."""
        return tuple(v for v in STATE_VARIABLES if v in self.states) + self.controls

    def derivative_names(self) -> tuple[str, ...]:
        """Every derivative of the fully populated structure, equation by equation."""
        return tuple(f"{k}_{v}" for k in self.letters for v in self.variables)

    def check(self, derivative: Derivative) -> None:
        """Raise when ``derivative`` drives an equation or reads a variable the template lacks."""
        if derivative.letter not in self.letters or derivative.variable not in self.variables:
            raise StructureError(
                f"derivative {derivative.name} does not fit the {self.name} template (equations "
                f"{' '.join(self.letters)}; variables {' '.join(self.variables)}); remove it "
                f"or choose a template that has it (six-dof has every derivative)")

    def signals(self, units: UnitSystem) -> ModelSignals:
        """The states, inputs and outputs as named signals in the unit system ``units``."""
        def signal_set(names):
            return SignalSet(Signal(n, units.label(n), CHANNEL_KINDS[n]) for n in names)

        return ModelSignals(signal_set(self.states), signal_set(self.controls),
                            signal_set(self.outputs))


SIX_DOF = StructureTemplate("six-dof", STATES, CONTROLS, OUTPUTS,
                            "coupled 6-DoF rigid body (the paper's model)")
LONGITUDINAL = StructureTemplate("longitudinal", ("u", "w", "q", "theta"), ("long", "coll"),
                                 ("ax", "az", "q", "theta"),
                                 "longitudinal axes only: surge, heave and pitch")
LATERAL = StructureTemplate("lateral", ("v", "p", "phi", "r"), ("lat", "ped"),
                            ("ay", "p", "phi", "r"),
                            "lateral-directional axes only: sway, roll and yaw")
TEMPLATES = {t.name: t for t in (SIX_DOF, LONGITUDINAL, LATERAL)}


def structure_template(template: str | StructureTemplate) -> StructureTemplate:
    """The template called ``template`` (or ``template`` itself); unknown names raise."""
    if isinstance(template, StructureTemplate):
        return template
    try:
        return TEMPLATES[str(template)]
    except KeyError:
        raise StructureError(f"unknown structure template {template!r}; use one of "
                             f"{', '.join(TEMPLATES)}") from None
