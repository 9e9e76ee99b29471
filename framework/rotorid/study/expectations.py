"""Published sign and magnitude expectations of key Bo-105 derivatives, and the check against them.

The reference values are those of Padfield's Helisim Bo-105 model (G. D. Padfield,
*Helicopter Flight Dynamics*, 2nd ed., Blackwell 2007, chapter 4 and appendix 4B), hover and the
mean of the 60 and 80 kt values, as collected in ``truth-model.md`` §8. They are stored in SI-rad
units (1/s, or rad/s² per m/s for the moment derivatives of velocities) and converted to the
structure's unit system on use. L and N derivatives are the inertia-coupled ("primed") ones.

Known caveats of the source, applied here: M_w in hover is about zero, so its sign is not
checked; in forward flight the Bo-105 has M_w > 0 (hingeless hub, small tailplane). X_v, Y_u
and Y_v have no published value: their expected sign is that of the truth model's own
linearisation.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import attrs

from rotorid.model.derivatives import EQUATION_OF_LETTER, parse_name
from rotorid.model.parameter_units import control_unit
from rotorid.model.parameter_units import derivative_unit as unit_of_derivative
from rotorid.model.templates import HYBRID, StructureTemplate
from rotorid.units import CHANNEL_KINDS, channel_scale, unit_system

#: name → (hover, 70 kt) reference values in SI-rad units (derivatives without a published
#: value are absent).
REFERENCE_SI: dict[str, tuple[float, float]] = {
    "X_u": (-0.02, -0.0295),
    "Z_w": (-0.32, -0.79),
    "M_u": (0.10, 0.032),
    "M_w": (-0.015, 0.018),
    "M_q": (-3.75, -3.95),
    "L_v": (-0.41, -0.28),
    "L_p": (-14.2, -13.7),
    "N_v": (-0.017, 0.116),
    "N_r": (-0.32, -1.07),
}
#: Derivatives whose reference is too close to zero for a sign check, by regime.
SIGN_UNCHECKED = {("M_w", "hover")}
#: A sign counts only when |value| ≥ this many Cramér-Rao bounds.
SIGNIFICANCE = 2.0
#: Airspeed ranges (kt) in which the hover and the 60–80 kt references apply.
REGIMES = {"hover": (0.0, 15.0), "forward": (50.0, 100.0)}


def regime_of(airspeed_kt: float) -> str | None:
    """``"hover"``, ``"forward"`` or None (no published reference at this speed)."""
    for name, (low, high) in REGIMES.items():
        if low <= airspeed_kt <= high:
            return name
    return None


def derivative_scale(name: str, units: str) -> float:
    """Factor turning an SI-rad value of derivative ``name`` into ``units`` (states only):
    A′ = s_row·A/s_column as in :func:`rotorid.units.convert_state_space`."""
    letter, variable = parse_name(name)
    row, column = channel_scale((EQUATION_OF_LETTER[letter], variable), unit_system(units))
    return float(row / column)


def derivative_unit(name: str, units: str, template: StructureTemplate = HYBRID) -> str:
    """Unit label of a derivative of ``template`` in the unit system ``units``, e.g. ``'1/s'``
    or ``'deg/s² per ft/s'`` (default: the hybrid's equations and signals, which include the
    six-dof's); spelled as a fit report spells it
    (:func:`rotorid.model.parameter_units.derivative_unit`)."""
    letter, variable = parse_name(name)
    system = unit_system(units)
    kinds = {**CHANNEL_KINDS, **template.kind_of}
    state = dict(template.equations)[letter]
    variable_unit = (control_unit(variable) if kinds[variable] == "control"
                     else system.unit_of(kinds[variable]))
    return unit_of_derivative(system.unit_of(kinds[state]), variable_unit)


@attrs.frozen
class SignCheck:
    """One key derivative: identified, truth linearisation, published reference, verdict.

    Values are in the structure's units; ``identified`` is None when the derivative was
    removed from the structure. ``verdict`` is ``"agrees"``, ``"differs"``, ``"removed"``,
    ``"undetermined"`` (|value| below two Cramér-Rao bounds: the data do not fix the sign) or
    ``"not checked"`` (reference about zero, or nothing to compare with).
    """

    name: str
    unit: str
    identified: float | None
    cramer_rao: float | None
    truth_linearisation: float | None
    reference: float | None
    expected_sign: int | None
    basis: str
    verdict: str

    @property
    def ratio_to_truth(self) -> float | None:
        """identified / truth linearisation (None when either is missing or zero)."""
        if self.identified is None or not self.truth_linearisation:
            return None
        return self.identified / self.truth_linearisation

    def as_dict(self) -> dict:
        return {**attrs.asdict(self), "ratio_to_truth": self.ratio_to_truth}


def check_signs(names, identified: Mapping[str, tuple[float, float]], airspeed_kt: float,
                units: str, truth: Mapping[str, float] | None = None,
                published: bool = True) -> list[SignCheck]:
    """Sign checks of ``names``.

    Args:
        identified: name → (value, Cramér-Rao bound) of the identified model (structure units).
        airspeed_kt: trim airspeed; picks the hover or the 60–80 kt reference.
        truth: name → the truth model's linearised derivative in the same units, or None.
        published: compare with the published Bo-105 values (False for another aircraft's
            data: the expected sign then comes from the truth model, if any).
    """
    regime = regime_of(airspeed_kt) if published else None
    checks = []
    for name in names:
        reference = None
        if regime is not None and name in REFERENCE_SI:
            reference = (REFERENCE_SI[name][0 if regime == "hover" else 1]
                         * derivative_scale(name, units))
        linearised = None if truth is None else truth.get(name)
        if (name, regime) in SIGN_UNCHECKED:
            expected, basis = None, f"{regime} reference ≈ 0"
        elif reference is not None:
            expected, basis = int(math.copysign(1, reference)), f"Helisim Bo-105 ({regime})"
        elif linearised:
            expected, basis = int(math.copysign(1, linearised)), "truth linearisation"
        else:
            expected, basis = None, "no reference"
        value, bound = identified.get(name, (None, None))
        if value is None:
            verdict = "removed"
        elif expected is None:
            verdict = "not checked"
        elif bound is not None and abs(value) < SIGNIFICANCE * bound:
            verdict = "undetermined"
        else:
            verdict = "agrees" if math.copysign(1, value) == expected else "differs"
        checks.append(SignCheck(name, derivative_unit(name, units), value, bound, linearised,
                                reference, expected, basis, verdict))
    return checks
