"""Non-dimensional aerodynamic coefficients of an aeroplane's identified derivatives.

A dimensional derivative is an acceleration per unit of a variable; its coefficient is the
force or moment coefficient per unit of the variable made non-dimensional (Etkin & Reid,
*Dynamics of Flight*, ch. 4; Klein & Morelli, *Aircraft System Identification*, 2006, ch. 3),
with q̄ = ½ρV², V the trim airspeed, S the wing area, b the span and c̄ the mean chord:

* the equation: a velocity state's (X, Y, Z) reads the force coefficient C = d·m/(q̄S); a flow
  angle's (α̇ or β̇ equation) C = d·m·V/(q̄S); a rate's the moment coefficient C = d·I/(q̄S·ℓ),
  with (I, ℓ) = (Ixx, b) for L, (Iyy, c̄) for M and (Izz, b) for N. L and N are first freed of
  the product of inertia: the model's roll and yaw equations carry L' and N' (ṗ = L'·x), the
  moments L = L' − (Ixz/Ixx)·N' and N = N' − (Ixz/Izz)·L' (Ixz = ∫xz dm);
* the variable: a velocity is taken per V (u/V; w/V = α and v/V = β in body axes), a rate
  per 2V/ℓ (p·b/2V, q·c̄/2V, r·b/2V), an angle and a control deflection per radian. A control
  in % of travel or in N has no coefficient.

A velocity derivative's coefficient of a speed (X_u, Z_u, M_u) is the textbook C_Xu + 2·C_X0
(the dynamic pressure grows with u): the trim coefficient is folded in.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import attrs
import numpy as np

from rotorid.errors import UsageError
from rotorid.units import KNOT, UNITS

#: The aeroplane's data, SI: name → description (all positive but ``ixz``).
AIRCRAFT_FIELDS = {
    "mass_kg": "mass", "wing_area_m2": "wing area S", "span_m": "wing span b",
    "chord_m": "mean aerodynamic chord c̄", "ixx_kgm2": "roll moment of inertia",
    "iyy_kgm2": "pitch moment of inertia", "izz_kgm2": "yaw moment of inertia",
    "ixz_kgm2": "product of inertia Ixz (∫xz dm; may be 0 or negative)",
    "density_kgm3": "air density at the test point",
}
#: Coefficient letter of each equation letter (force C_X, C_Y, C_Z; moment C_l, C_m, C_n).
COEFFICIENT_LETTER = {"X": "X", "Y": "Y", "Z": "Z", "L": "l", "M": "m", "N": "n"}
#: The non-dimensional name of a body-axis velocity variable.
FLOW_ANGLE_OF = {"w": "alpha", "v": "beta"}
#: Rates and the reference length that makes them non-dimensional.
RATE_LENGTH = {"p": "span_m", "q": "chord_m", "r": "span_m"}


@attrs.frozen
class Aircraft:
    """Mass, inertia and reference geometry of an aeroplane and the air it flew in (SI).

    Attributes: see :data:`AIRCRAFT_FIELDS` (kg, m², m, m, kg·m², kg/m³).
    """

    mass_kg: float
    wing_area_m2: float
    span_m: float
    chord_m: float
    ixx_kgm2: float
    iyy_kgm2: float
    izz_kgm2: float
    ixz_kgm2: float
    density_kgm3: float

    @classmethod
    def from_mapping(cls, table: Mapping, source: str = "aircraft data") -> "Aircraft":
        """Build from a table (a TOML file's ``[aircraft]``), each value named as
        :data:`AIRCRAFT_FIELDS`; unknown, missing, non-finite or non-positive values are
        refused with the fix."""
        unknown = sorted(set(table) - set(AIRCRAFT_FIELDS))
        missing = [name for name in AIRCRAFT_FIELDS if name not in table]
        if unknown or missing:
            raise UsageError(
                f"{source}: " + "; ".join(filter(None, [
                    unknown and f"unknown key(s) {', '.join(unknown)}",
                    missing and f"missing {', '.join(missing)}"]))
                + "; give " + ", ".join(f"{k} ({v})" for k, v in AIRCRAFT_FIELDS.items()))
        values = {}
        for name in AIRCRAFT_FIELDS:
            value = table[name]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                    math.isfinite(value) and (value > 0 or name == "ixz_kgm2")):
                raise UsageError(f"{source}: {name} = {value!r}; give the "
                                 f"{AIRCRAFT_FIELDS[name]} as a finite "
                                 f"{'number' if name == 'ixz_kgm2' else 'positive number'}")
            values[name] = float(value)
        return cls(**values)

    def inertia(self, letter: str) -> float:
        """The moment of inertia about the axis of moment ``letter`` (L, M, N), kg·m²."""
        return {"L": self.ixx_kgm2, "M": self.iyy_kgm2, "N": self.izz_kgm2}[letter]

    def length(self, letter: str) -> float:
        """The reference length of moment ``letter``: b for L and N, c̄ for M, m."""
        return self.chord_m if letter == "M" else self.span_m


@attrs.frozen
class Coefficient:
    """One derivative's coefficient: ``name`` (e.g. ``Cm_alpha``), ``derivative`` (e.g.
    ``M_w``), ``value`` and ``bound`` (its Cramér-Rao bound through the conversion; NaN
    without an estimate), per radian where the variable is an angle."""

    name: str
    derivative: str
    value: float
    bound: float


def _si(signals, name: str) -> float:
    """SI-rad value of one unit of signal ``name`` (its unit's :data:`UNITS` factor)."""
    return UNITS[signals[name].unit][1]


def _variable_scale(structure, aircraft: Aircraft, variable: str, speed: float):
    """(non-dimensional variable name, factor turning the SI variable into it) or a reason
    for none."""
    signal = structure.signals.all[variable]
    if signal.kind == "velocity":
        return FLOW_ANGLE_OF.get(variable, variable), speed
    if signal.kind == "rate" and variable in RATE_LENGTH:
        return variable, 2 * speed / getattr(aircraft, RATE_LENGTH[variable])
    if signal.kind == "angle" or (signal.kind == "control"
                                  and UNITS[signal.unit][0] == "angle"):
        return variable, 1.0
    return f"{variable} is a {signal.kind} in {signal.unit}: no coefficient", None


def _equation_scale(structure, aircraft: Aircraft, letter: str, state: str, speed: float,
                    pressure: float):
    """Factor turning an SI equation term (per unit variable) into a force or moment
    coefficient, or None where the equation is no force or moment."""
    kind = structure.signals.all[state].kind
    if letter in "XYZ" and kind == "velocity":
        return aircraft.mass_kg / (pressure * aircraft.wing_area_m2)
    if letter in "XYZ" and kind == "angle":
        return aircraft.mass_kg * speed / (pressure * aircraft.wing_area_m2)
    if letter in "LMN" and kind == "rate":
        return aircraft.inertia(letter) / (pressure * aircraft.wing_area_m2
                                           * aircraft.length(letter))
    return None


def _inertia_coupling(structure, aircraft: Aircraft) -> dict[str, tuple[str, float]]:
    """For the roll and yaw equations (L, N on rate states): letter → (the other letter,
    the factor that takes its term off: Ixz/I_own in the own equation's units per the
    other's); empty without both equations or without Ixz."""
    equations = dict(structure.template.equations)
    signals = structure.signals.all
    if aircraft.ixz_kgm2 == 0.0 or not {"L", "N"} <= set(equations) or any(
            signals[equations[letter]].kind != "rate" for letter in "LN"):
        return {}
    return {letter: (other, aircraft.ixz_kgm2 / aircraft.inertia(letter)
                     * _si(signals, equations[other]) / _si(signals, equations[letter]))
            for letter, other in (("L", "N"), ("N", "L"))}


def trim_speed(structure) -> float:
    """The trim airspeed V of ``structure``'s condition, m/s."""
    return structure.condition.airspeed_kt * KNOT


def non_dimensional(structure, values: Mapping[str, float], aircraft: Aircraft,
                    estimate=None) -> tuple[list[Coefficient], list[str]]:
    """The coefficients of ``structure``'s derivatives at ``values`` (name → value of its
    free parameters; fixed derivatives at their values) for ``aircraft`` at the structure's
    trim airspeed, and the derivatives left out with the reason. With ``estimate`` (of the
    same structure) the bounds are its Cramér-Rao bounds propagated through the conversion.
    """
    speed = trim_speed(structure)
    if speed <= 0.0:
        raise UsageError("non-dimensional coefficients need the trim airspeed; the model's "
                         "condition has none (hover): give its [condition] an airspeed")
    pressure = 0.5 * aircraft.density_kgm3 * speed**2
    signals = structure.signals.all
    rows, skipped = [], []
    for derivative in structure.derivatives:
        letter, variable = derivative.letter, derivative.variable
        state = structure.equation_of(derivative)
        equation = _equation_scale(structure, aircraft, letter, state, speed, pressure)
        what, per_variable = _variable_scale(structure, aircraft, variable, speed)
        if equation is None or per_variable is None:
            skipped.append(f"{derivative.name}: " + (what if per_variable is None else
                           f"the {letter} equation of {state} is no force or moment"))
            continue
        to_si = _si(signals, state) / _si(signals, variable)
        rows.append((derivative, letter, variable,
                     f"C{COEFFICIENT_LETTER[letter]}_{what}", equation * per_variable * to_si))

    coupled = _inertia_coupling(structure, aircraft)

    def coefficients(vector) -> np.ndarray:
        named = dict(zip(names, vector))
        value = {d.name: named.get(d.name, d.initial) for d in structure.derivatives}
        result = []
        for derivative, letter, variable, _, scale in rows:
            moment = value[derivative.name]
            if letter in coupled:
                other, factor = coupled[letter]
                moment -= factor * value.get(f"{other}_{variable}", 0.0)
            result.append(moment * scale)
        return np.array(result)

    if estimate is None:
        names = tuple(values)
        centre = coefficients(np.array([values[n] for n in names]))
        bounds = np.full(len(rows), np.nan)
    else:
        names = estimate.parameter_names
        centre, bounds = estimate.propagated(coefficients)
    return ([Coefficient(name, derivative.name, float(v), float(b))
             for (derivative, _, _, name, _), v, b in zip(rows, centre, bounds)], skipped)
