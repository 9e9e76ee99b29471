"""Declarative stability and control derivatives, with sign priors and optional time delays.

A derivative is named ``<letter>_<variable>``: the letter names the equation it drives, the
variable the state or input it multiplies. The rigid-body templates use the usual letters
(X, Y, Z forces per unit mass; L, M, N moments per unit inertia, L and N inertia-coupled) over
the states u v w p q r and the controls, so ``L_p`` is the roll damping and ``M_long`` the pitch
control power; a declared structure names its own letters and variables
(:mod:`rotorid.model.templates`), which decides which names fit it. A :class:`Derivative` is a
declaration, never a result: estimates live in :class:`rotorid.estimation.estimate.Estimate`.
"""

from __future__ import annotations

import enum
import math

import attrs

from rotorid.errors import DerivativeError

#: The rigid body's force and moment letters, velocity and rate states and helicopter controls.
FORCE_MOMENT_LETTERS = ("X", "Y", "Z", "L", "M", "N")
STATE_VARIABLES = ("u", "v", "w", "p", "q", "r")
CONTROL_VARIABLES = ("long", "lat", "coll", "ped")

#: Rigid-body equation (state derivative) each letter drives.
EQUATION_OF_LETTER = {"X": "u", "Y": "v", "Z": "w", "L": "p", "M": "q", "N": "r"}
#: Prefix of a delay's parameter name: ``tau_L_lat`` is the delay on ``L_lat``.
DELAY_PREFIX = "tau_"


def delay_parameter(derivative: str) -> str:
    """Parameter name of the delay on ``derivative``: ``"L_lat"`` → ``"tau_L_lat"``."""
    return f"{DELAY_PREFIX}{derivative}"


def delayed_derivative(parameter: str) -> str | None:
    """The derivative a delay parameter delays (``"tau_L_lat"`` → ``"L_lat"``), or ``None``
    when ``parameter`` is not a delay."""
    if parameter.startswith(DELAY_PREFIX):
        return parameter[len(DELAY_PREFIX):]
    return None


def parameter_label(parameter: str) -> str:
    """A parameter's name for tables and figures: ``"τ L_lat"`` for a delay, else the name."""
    derivative = delayed_derivative(parameter)
    return parameter if derivative is None else f"τ {derivative}"


class Sign(enum.Enum):
    """Sign prior of a derivative: the sign physics expects for it."""

    NONE = "none"
    NEGATIVE = "negative"
    POSITIVE = "positive"

    def admits(self, value: float) -> bool:
        """True when ``value`` does not contradict the prior (zero always does not)."""
        if self is Sign.NEGATIVE:
            return value <= 0.0
        if self is Sign.POSITIVE:
            return value >= 0.0
        return True


def _to_sign(value) -> Sign:
    if isinstance(value, Sign):
        return value
    if value is None:
        return Sign.NONE
    try:
        return Sign(str(value).lower())
    except ValueError:
        raise DerivativeError(
            f"unknown sign prior {value!r}; use 'negative', 'positive' or 'none'"
        ) from None


def _finite(name):
    def check(instance, attribute, value):
        if value is not None and not math.isfinite(value):
            raise DerivativeError(f"{name}: {attribute.name} must be finite, got {value!r}")

    return check


def _real(value) -> float:
    try:
        if isinstance(value, (str, bytes, bool)):
            raise TypeError
        return float(value)
    except (TypeError, ValueError):
        raise DerivativeError(
            f"derivative and delay values must be real numbers, got {value!r}") from None


def _optional_float(value):
    return None if value is None else _real(value)


#: Upper bound of an estimated delay that declares none, s: well above the equivalent delays
#: of rotor dynamics (below 0.3 s), so that a delay the data cannot determine stops at a bound
#: instead of wandering off to seconds.
DEFAULT_DELAY_UPPER = 1.0


@attrs.frozen
class Delay:
    """A pure time delay on one derivative's variable, in seconds.

    The lower bound is always 0 s (a delay cannot lead). ``upper`` is optional (estimation
    then bounds the delay by :data:`DEFAULT_DELAY_UPPER`); ``fixed`` keeps the delay at
    ``initial`` during estimation.
    """

    initial: float = attrs.field(default=0.0, converter=_real, validator=_finite("delay"))
    upper: float | None = attrs.field(
        default=None, converter=_optional_float, validator=_finite("delay")
    )
    fixed: bool = False

    def __attrs_post_init__(self):
        if self.initial < 0.0:
            raise DerivativeError(
                f"a delay cannot be negative (got {self.initial} s); delays are ≥ 0 s"
            )
        if self.upper is not None:
            if self.upper <= 0.0:
                raise DerivativeError(f"delay upper bound must be > 0 s, got {self.upper} s")
            if self.initial > self.upper:
                raise DerivativeError(
                    f"delay initial value {self.initial} s exceeds its upper bound {self.upper} s"
                )

    @classmethod
    def coerce(cls, value) -> "Delay | None":
        """Build a delay from ``None``, a number (initial, s), a mapping or a :class:`Delay`."""
        if value is None or isinstance(value, Delay):
            return value
        if isinstance(value, (int, float)):
            return cls(initial=value)
        if isinstance(value, dict):
            unknown = set(value) - {"initial", "upper", "fixed"}
            if unknown:
                raise DerivativeError(
                    f"unknown delay setting(s) {sorted(unknown)}; use initial, upper, fixed"
                )
            return cls(**value)
        raise DerivativeError(f"cannot make a delay from {value!r}")


def parse_name(name: str) -> tuple[str, str]:
    """Split a derivative name into (letter, variable) at its first underscore.

    The letter is an identifier without underscores, the variable any identifier; whether the
    pair fits a structure is the structure's template's decision.

    >>> parse_name("M_long")
    ('M', 'long')
    >>> parse_name("Bc_beta_1s")
    ('Bc', 'beta_1s')
    """
    parts = name.split("_", 1) if isinstance(name, str) else []
    if len(parts) != 2 or not all(part.isidentifier() for part in parts):
        raise DerivativeError(
            f"derivative name {name!r} must look like 'L_p' or 'M_long': "
            f"<equation letter>_<state or input>, e.g. one of the rigid body's "
            f"{'|'.join(FORCE_MOMENT_LETTERS)} and a state or control")
    return parts[0], parts[1]


@attrs.frozen
class Derivative:
    """One stability or control derivative of the linear model.

    Attributes:
        name: e.g. ``"L_p"``; units follow the structure's unit system, e.g. 1/s for ``L_p``,
            (deg/s²)/% for ``L_lat`` in flight-test units.
        initial: start value for estimation (the paper starts every derivative at 0).
        sign: sign prior (``Sign`` or ``"negative"``/``"positive"``/``"none"``).
        delay: optional :class:`Delay` on the derivative's variable.
        fixed: keep the value at ``initial`` (a known derivative) instead of estimating it.
    """

    name: str = attrs.field()
    initial: float = attrs.field(default=0.0, converter=_real)
    sign: Sign = attrs.field(default=Sign.NONE, converter=_to_sign)
    delay: Delay | None = attrs.field(default=None, converter=Delay.coerce)
    fixed: bool = False

    @name.validator
    def _check_name(self, attribute, value):
        parse_name(value)

    @initial.validator
    def _check_initial(self, attribute, value):
        if not math.isfinite(value):
            raise DerivativeError(f"{self.name}: initial value must be finite, got {value!r}")

    def __attrs_post_init__(self):
        if not self.sign.admits(self.initial):
            what = "fixed value" if self.fixed else "initial value"
            raise DerivativeError(
                f"{self.name}: {what} {self.initial} contradicts its {self.sign.value} sign prior; "
                f"change the value or drop the prior (sign='none')"
            )

    @property
    def letter(self) -> str:
        """Letter of the equation the derivative drives, e.g. ``M`` (rigid body: X Y Z L M N)."""
        return parse_name(self.name)[0]

    @property
    def variable(self) -> str:
        """State or control the derivative multiplies."""
        return parse_name(self.name)[1]

    @property
    def delay_name(self) -> str:
        """Parameter name of this derivative's delay, e.g. ``tau_L_lat``."""
        return delay_parameter(self.name)

    def with_delay(self, initial: float = 0.0, upper: float | None = None, fixed: bool = False):
        """Return a copy carrying a delay."""
        return attrs.evolve(self, delay=Delay(initial, upper, fixed))

    def fixed_at(self, value: float):
        """Return a copy fixed at ``value``."""
        return attrs.evolve(self, initial=value, fixed=True)
