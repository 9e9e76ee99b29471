"""Unit systems and the conversions between them.

rotorid works in *flight-test units* by default, the units of the paper: velocities in ft/s,
angular rates in deg/s, attitudes in deg, specific forces in ft/s², controls in % of travel.
The *SI-rad* system (m/s, rad/s, rad, m/s²) is offered for comparison with the literature.
Controls are never rescaled by a unit system: they stay in whatever unit the data carry
(% of travel for stick data, rad for blade angles).

Conversions happen here and nowhere else: :func:`channel_scale` gives, per channel, the factor
that turns an SI-rad value into the target system; :data:`UNITS` lists every unit a named signal
or a data column may carry and :func:`conversion_factor` converts between two of them.
"""

from __future__ import annotations

import math

import attrs
import numpy as np

from rotorid.errors import SignalError, StructureError

FOOT = 0.3048  #: metres per foot (exact)
KNOT = 1852.0 / 3600.0  #: metres per second per knot (exact)
G_SI = 9.80665  #: standard gravity, m/s²
POUND_FORCE = 4.4482216152605  #: newtons per pound-force (exact)
DEGREE = math.pi / 180.0  #: radians per degree

#: Every unit a named signal or a data column may carry: label → (dimension, SI-rad value of
#: one unit). ASCII spellings with ``^2`` (``"ft/s^2"``) are accepted for the ``²`` labels.
UNITS = {
    "m/s": ("speed", 1.0), "ft/s": ("speed", FOOT), "kt": ("speed", KNOT),
    "m/s²": ("acceleration", 1.0), "ft/s²": ("acceleration", FOOT), "g": ("acceleration", G_SI),
    "rad": ("angle", 1.0), "deg": ("angle", DEGREE),
    "rad/s": ("angular rate", 1.0), "deg/s": ("angular rate", DEGREE),
    "rad/s²": ("angular acceleration", 1.0), "deg/s²": ("angular acceleration", DEGREE),
    "%": ("travel", 1.0),
    "N": ("force", 1.0), "lbf": ("force", POUND_FORCE),
    "s": ("time", 1.0), "ms": ("time", 1e-3), "us": ("time", 1e-6),
}

#: Physical kinds of named signals and the dimensions their units may have. A control is a
#: stick travel (%), a surface or blade deflection (rad, deg) or a force such as thrust.
KIND_DIMENSIONS = {
    "velocity": ("speed",),
    "acceleration": ("acceleration",),
    "angle": ("angle",),
    "rate": ("angular rate",),
    "angular-acceleration": ("angular acceleration",),
    "control": ("travel", "angle", "force"),
    "time": ("time",),
}

#: Physical kind of every named channel; decides how it scales between unit systems.
CHANNEL_KINDS = {
    "u": "velocity", "v": "velocity", "w": "velocity",
    "p": "rate", "q": "rate", "r": "rate",
    "theta": "angle", "phi": "angle", "alpha": "angle", "beta": "angle",
    "ax": "acceleration", "ay": "acceleration", "az": "acceleration",
    "p_dot": "angular-acceleration", "q_dot": "angular-acceleration",
    "r_dot": "angular-acceleration",
    "beta0": "angle", "beta1c": "angle", "beta1s": "angle", "vi": "velocity",
    "g_u": "velocity", "g_v": "velocity", "g_w": "velocity",
    "g_p": "rate", "g_q": "rate", "g_r": "rate",
    "long": "control", "lat": "control", "coll": "control", "ped": "control",
    "elevator": "control", "aileron": "control", "rudder": "control", "throttle": "control",
    "time": "time",
}


@attrs.frozen
class UnitSystem:
    """A consistent set of units for states, outputs and derivatives.

    Attributes:
        name: ``"flight-test"`` or ``"si"``.
        length_per_metre: length unit per metre (1/FOOT for feet, 1 for metres).
        angle_per_radian: angle unit per radian (180/π for degrees, 1 for radians).
        length_label, angle_label: labels used in reports and plots.
    """

    name: str
    length_per_metre: float
    angle_per_radian: float
    length_label: str
    angle_label: str

    @property
    def g(self) -> float:
        """Standard gravity in this system's length unit per s²."""
        return G_SI * self.length_per_metre

    @property
    def radian_per_angle(self) -> float:
        """Radians per angle unit: the factor the known gravity/kinematic terms need."""
        return 1.0 / self.angle_per_radian

    def factor(self, kind: str) -> float:
        """Factor turning an SI-rad quantity of ``kind`` into this system."""
        try:
            return {
                "velocity": self.length_per_metre,
                "acceleration": self.length_per_metre,
                "rate": self.angle_per_radian,
                "angular-acceleration": self.angle_per_radian,
                "angle": self.angle_per_radian,
                "control": 1.0,
                "time": 1.0,
            }[kind]
        except KeyError:
            raise StructureError(f"unknown physical kind {kind!r}") from None

    def label(self, channel: str, control_label: str = "%") -> str:
        """Unit label of a channel, e.g. ``'ft/s'`` for ``u``, ``'deg/s'`` for ``q``."""
        kind = CHANNEL_KINDS.get(channel)
        if kind is None:
            raise StructureError(f"unknown channel {channel!r}; known: {', '.join(CHANNEL_KINDS)}")
        return self.unit_of(kind, control_label)

    def unit_of(self, kind: str, control_label: str = "%") -> str:
        """Unit label of a signal of physical ``kind`` in this system (controls: ``control_label``)."""
        try:
            return {
                "velocity": f"{self.length_label}/s",
                "acceleration": f"{self.length_label}/s²",
                "rate": f"{self.angle_label}/s",
                "angular-acceleration": f"{self.angle_label}/s²",
                "angle": self.angle_label,
                "control": control_label,
                "time": "s",
            }[kind]
        except KeyError:
            raise StructureError(f"unknown physical kind {kind!r}; use one of "
                                 f"{', '.join(KIND_DIMENSIONS)}") from None


FLIGHT_TEST = UnitSystem("flight-test", 1.0 / FOOT, 180.0 / math.pi, "ft", "deg")
SI = UnitSystem("si", 1.0, 1.0, "m", "rad")

_SYSTEMS = {"flight-test": FLIGHT_TEST, "si": SI, "si-rad": SI}


def unit_system(name: str | UnitSystem) -> UnitSystem:
    """Return the unit system called ``name`` (``"flight-test"``, ``"si"`` or ``"si-rad"``)."""
    if isinstance(name, UnitSystem):
        return name
    try:
        return _SYSTEMS[str(name).lower()]
    except KeyError:
        raise StructureError(
            f"unknown unit system {name!r}; use 'flight-test' (ft, deg, %) or 'si' (m, rad)"
        ) from None


def channel_kind(channel: str, kinds=None) -> str | None:
    """Physical kind of ``channel``: ``kinds(channel)`` when that function gives one (a
    model's own signals), else :data:`CHANNEL_KINDS`'s, else ``None``."""
    return (kinds(channel) if kinds is not None else None) or CHANNEL_KINDS.get(channel)


def channel_scale(channels, target: UnitSystem, source: UnitSystem = SI,
                  kinds=None) -> np.ndarray:
    """Per-channel factors that convert values in ``source`` units into ``target`` units.

    Args:
        channels: channel names such as ``("u", "w", "q", "theta")``.
        kinds: optional ``name -> kind`` function for names beyond :data:`CHANNEL_KINDS`
            (a model's own signals); unknown names raise.
    Returns:
        array of shape ``(len(channels),)``.
    """
    def kind(channel):
        found = channel_kind(channel, kinds)
        if found is None:
            raise StructureError(f"channel {channel!r} has no physical kind, so it cannot be "
                                 f"converted between unit systems; declare it as a signal of "
                                 f"the model (with its kind)")
        return found

    return np.array([target.factor(kind(c)) / source.factor(kind(c)) for c in channels])


def convert_state_space(a, b, states, controls, target: UnitSystem, source: UnitSystem = SI):
    """Convert ``ẋ = A x + B u`` from ``source`` to ``target`` units.

    With x' = S_x x, A' = S_x A S_x⁻¹ and B' = S_x B (controls keep their unit).
    Returns new arrays; the inputs are not modified.
    """
    sx = channel_scale(states, target, source)
    su = channel_scale(controls, target, source)
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return a * sx[:, None] / sx[None, :], b * sx[:, None] / su[None, :]


def canonical_unit(label: str) -> str:
    """The :data:`UNITS` label of ``label`` (``"ft/s^2"`` → ``"ft/s²"``); unknown labels raise."""
    unit = str(label).strip().replace("^2", "²").replace("µs", "us")
    if unit not in UNITS:
        raise SignalError(f"unknown unit {label!r}; use one of {', '.join(UNITS)}")
    return unit


def unit_fits_kind(unit: str, kind: str) -> bool:
    """Whether ``unit`` may carry a signal of physical ``kind`` (see :data:`KIND_DIMENSIONS`)."""
    if kind not in KIND_DIMENSIONS:
        raise SignalError(f"unknown signal kind {kind!r}; use one of {', '.join(KIND_DIMENSIONS)}")
    return UNITS[canonical_unit(unit)][0] in KIND_DIMENSIONS[kind]


def units_of_kind(kind: str) -> list[str]:
    """The units a signal of ``kind`` may carry."""
    return [u for u in UNITS if unit_fits_kind(u, kind)]


def same_dimension(unit: str, other: str) -> bool:
    """Whether values in ``unit`` convert into ``other``."""
    return UNITS[canonical_unit(unit)][0] == UNITS[canonical_unit(other)][0]


def units_like(unit: str) -> list[str]:
    """The units of the same dimension as ``unit``, ``unit`` included."""
    return [u for u in UNITS if same_dimension(u, unit)]


#: One unit of each dimension that the paper's RMSE guideline (eq. 18, RMSE ≤ 1.0 to 2.0; J_rms
#: in deg, deg/s, ft/s, ft/s²) measures residuals in: a residual divided by its reference unit
#: is a pure number, so the RMSE over outputs of different kinds is dimensionless.
RMSE_REFERENCE_UNITS = {"speed": "ft/s", "acceleration": "ft/s²", "angle": "deg",
                        "angular rate": "deg/s", "angular acceleration": "deg/s²"}


def rmse_reference_factors(units) -> np.ndarray | None:
    """Per-output factors turning residuals in ``units`` into multiples of their
    :data:`RMSE_REFERENCE_UNITS`, shape (len(units),); ``None`` when an output has no
    reference unit (an unknown unit, control travel, force) or ``units`` is empty (the
    model declares none)."""
    if not units:
        return None
    factors = []
    for unit in units:
        dimension = UNITS.get(unit, (None,))[0]
        if dimension not in RMSE_REFERENCE_UNITS:
            return None
        factors.append(conversion_factor(unit, RMSE_REFERENCE_UNITS[dimension]))
    return np.array(factors)


def conversion_factor(source: str, target: str) -> float:
    """Factor turning a value in unit ``source`` into unit ``target`` (same dimension).

    ``conversion_factor("kt", "m/s")`` is 1852/3600; ``conversion_factor("%", "deg")`` raises,
    since stick travel has no fixed relation to a deflection.
    """
    source, target = canonical_unit(source), canonical_unit(target)
    if source == target:
        return 1.0
    if not same_dimension(source, target):
        raise SignalError(f"cannot convert {source} ({UNITS[source][0]}) to {target} "
                          f"({UNITS[target][0]}); use one of {', '.join(units_like(target))}")
    return UNITS[source][1] / UNITS[target][1]
