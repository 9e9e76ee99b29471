"""Pilot input signals: multisteps (3211, 2311, doublet) and the logarithmic frequency sweep.

Every signal is a frozen value and a callable ``signal(time) -> ndarray``: ``time`` in s (any
shape), the result in % of control travel, a perturbation from trim, of the same shape. Each has
a ``duration`` in s that includes the quiet trim time before and after the excitation.

With ``sample_time`` set, a signal switches only on sample instants ``k·sample_time``: it is the
zero-order hold of its law sampled at those instants, so a stick recorded at that rate is exact.
Multisteps then require their start and step width to be whole numbers of samples (they are
rejected otherwise, with the nearest valid values in the message).

Input design follows validation.md §6: the multistep sequences of Koehler / Plaetschke & Schulz
(3211 = +3 −2 +1 −1, 2311 = +2 −3 +1 −1, doublet = +1 −1, in units of the step width Δt) and the
Tischler & Remple exponential sweep ω(t) = ω_min + K(t)(ω_max − ω_min),
K(t) = C2·(exp(C1·t/T_rec) − 1), C1 = 4, C2 = 0.0187, preceded by two cycles at ω_min.
"""

from __future__ import annotations

import math

import attrs
import numpy as np
from rotorid.errors import DataError

#: Multistep sequences: (width in step units, sign) per pulse.
PATTERNS = {
    "3211": ((3, 1), (2, -1), (1, 1), (1, -1)),
    "2311": ((2, 1), (3, -1), (1, 1), (1, -1)),
    "doublet": ((1, 1), (1, -1)),
}
#: Relative tolerance for "a whole number of samples".
_GRID_TOLERANCE = 1e-6


def _positive(instance, attribute, value):
    if not (math.isfinite(value) and value > 0):
        raise DataError(f"{type(instance).__name__}: {attribute.name} must be a finite number "
                        f"> 0, got {value!r}")


def _non_negative(instance, attribute, value):
    if not (math.isfinite(value) and value >= 0):
        raise DataError(f"{type(instance).__name__}: {attribute.name} must be a finite number "
                        f"≥ 0 s, got {value!r}")


def _finite(instance, attribute, value):
    if not math.isfinite(value):
        raise DataError(f"{type(instance).__name__}: {attribute.name} must be finite, "
                        f"got {value!r}")


def _optional_positive(instance, attribute, value):
    if value is not None:
        _positive(instance, attribute, value)


def _optional_float(value):
    return None if value is None else float(value)


def _samples(instance, name: str, seconds: float, sample_time: float) -> int:
    """``seconds`` as a whole number of samples, or a DataError naming the nearest choices."""
    count = seconds / sample_time
    whole = round(count)
    if abs(count - whole) > _GRID_TOLERANCE * max(1.0, count):
        lower, upper = math.floor(count) * sample_time, math.ceil(count) * sample_time
        raise DataError(f"{type(instance).__name__}: {name} = {seconds} s is not a whole number "
                        f"of samples at sample_time = {sample_time} s; use {lower:.6g} s or "
                        f"{upper:.6g} s so that the signal switches on sample instants")
    return int(whole)


def _held(time: np.ndarray, sample_time: float | None) -> np.ndarray:
    """The sample instant at or before each time (the time itself without a sample time)."""
    time = np.asarray(time, dtype=float)
    if sample_time is None:
        return time
    return np.floor(time / sample_time + _GRID_TOLERANCE) * sample_time


@attrs.frozen
class Multistep:
    """A multistep: pulses of alternating sign held for whole multiples of ``step_width``.

    Attributes:
        kind: pattern name, a key of :data:`PATTERNS` (``"3211"``, ``"2311"``, ``"doublet"``).
        amplitude: pulse height in % of control travel; its sign is the direction of the
            first pulse.
        step_width: the basic time step Δt in s (3211 lasts 7·Δt).
        start: trim time before the first pulse, s.
        trailing: trim time after the last pulse, s.
        sample_time: if set, the switching grid in s (see the module docstring).
    """

    kind: str = attrs.field()
    amplitude: float = attrs.field(converter=float, validator=_finite)
    step_width: float = attrs.field(converter=float, validator=_positive)
    start: float = attrs.field(default=1.0, converter=float, validator=_non_negative)
    trailing: float = attrs.field(default=8.0, converter=float, validator=_non_negative)
    sample_time: float | None = attrs.field(default=None, converter=_optional_float,
                                            validator=_optional_positive)

    @kind.validator
    def _known_kind(self, attribute, value):
        if value not in PATTERNS:
            raise DataError(f"unknown multistep kind {value!r}; use one of "
                            f"{', '.join(PATTERNS)}")

    def __attrs_post_init__(self):
        if self.sample_time is not None:
            _samples(self, "start", self.start, self.sample_time)
            _samples(self, "step_width", self.step_width, self.sample_time)

    @property
    def pattern(self) -> tuple[tuple[int, int], ...]:
        return PATTERNS[self.kind]

    @property
    def units(self) -> int:
        """Length of the excitation in step widths (7 for a 3211)."""
        return sum(width for width, _ in self.pattern)

    @property
    def duration(self) -> float:
        """Record length in s: start + excitation + trailing trim."""
        return self.start + self.units * self.step_width + self.trailing

    def switch_times(self) -> np.ndarray:
        """Instants in s where the signal changes level, shape (pulses + 1,)."""
        widths = np.array([width for width, _ in self.pattern], dtype=float)
        return self.start + self.step_width * np.concatenate(([0.0], np.cumsum(widths)))

    def __call__(self, time) -> np.ndarray:
        time = np.asarray(time, dtype=float)
        levels = np.array([0.0] + [sign * self.amplitude for _, sign in self.pattern] + [0.0])
        if self.sample_time is None:
            edges = self.switch_times()
            position = time + 1e-12 * max(1.0, self.duration)
        else:
            # Count in whole samples so switching is exact on the grid.
            edges = np.round(self.switch_times() / self.sample_time)
            position = np.floor(time / self.sample_time + _GRID_TOLERANCE)
        return levels[np.searchsorted(edges, position, side="right")]


@attrs.frozen
class Sweep:
    """Exponential (logarithmic) frequency sweep starting and ending in trim.

    The record is ``lead`` s of trim, ``low_cycles`` cycles at ``omega_min``, the exponential
    sweep of validation.md §6.1 over at most ``sweep_time`` s, then ``trail`` s of trim. The
    sweep stops at the last zero crossing of the sine before ``sweep_time`` so the stick returns
    to trim without a step; its final frequency is then within half a cycle of ``omega_max``.

    Attributes:
        amplitude: sine amplitude in % of control travel (its sign sets the initial direction).
        omega_min, omega_max: frequency range in rad/s.
        sweep_time: T_rec of the sweep law, s.
        lead, trail: trim time before and after, s.
        low_cycles: cycles at ``omega_min`` before the exponential sweep (2 per validation.md).
        amplitude_ratio: amplitude at ``omega_max`` over that at ``omega_min``; the amplitude
            grows linearly with the instantaneous frequency in between (1: constant). Pilots
            widen the sweep as the response falls with frequency (validation.md §6.1: small
            enough to stay near trim, large enough for coherence).
        c1, c2: sweep-law constants (4.0, 0.0187 so that K(T_rec) ≈ 1).
        sample_time: if set, the switching grid in s; then ``omega_max`` must leave at least
            10 samples per period (f_s ≥ 10·f_max).
    """

    amplitude: float = attrs.field(converter=float, validator=_finite)
    omega_min: float = attrs.field(converter=float, validator=_positive)
    omega_max: float = attrs.field(converter=float, validator=_positive)
    sweep_time: float = attrs.field(converter=float, validator=_positive)
    lead: float = attrs.field(default=3.0, converter=float, validator=_non_negative)
    trail: float = attrs.field(default=5.0, converter=float, validator=_non_negative)
    low_cycles: float = attrs.field(default=2.0, converter=float, validator=_non_negative)
    amplitude_ratio: float = attrs.field(default=1.0, converter=float, validator=_positive)
    c1: float = attrs.field(default=4.0, converter=float, validator=_positive)
    c2: float = attrs.field(default=0.0187, converter=float, validator=_positive)
    sample_time: float | None = attrs.field(default=None, converter=_optional_float,
                                            validator=_optional_positive)

    def __attrs_post_init__(self):
        if self.omega_max <= self.omega_min:
            raise DataError(f"Sweep: omega_max ({self.omega_max} rad/s) must exceed omega_min "
                            f"({self.omega_min} rad/s)")
        if self.sample_time is not None:
            limit = 2 * math.pi / (10 * self.sample_time)
            if self.omega_max > limit:
                raise DataError(
                    f"Sweep: omega_max = {self.omega_max} rad/s leaves fewer than 10 samples per "
                    f"period at sample_time = {self.sample_time} s; lower omega_max to ≤ "
                    f"{limit:.3g} rad/s or sample faster")
        if self._sweep_phase(self.sweep_time) < math.pi:
            raise DataError(f"Sweep: sweep_time = {self.sweep_time} s is too short for half a "
                            f"cycle; lengthen it")

    # ------------------------------------------------------------------ the law
    @property
    def dwell(self) -> float:
        """Time spent at ``omega_min`` before the exponential sweep, s."""
        return self.low_cycles * 2 * math.pi / self.omega_min

    def _sweep_phase(self, tau):
        """Phase in rad accumulated ``tau`` s into the exponential part (∫ω dτ)."""
        tau = np.asarray(tau, dtype=float)
        t_rec = self.sweep_time
        integral_k = self.c2 * (t_rec / self.c1 * np.expm1(self.c1 * tau / t_rec) - tau)
        return self.omega_min * tau + (self.omega_max - self.omega_min) * integral_k

    @property
    def sweep_end(self) -> float:
        """Length in s of the exponential part: its last zero crossing before ``sweep_time``."""
        from scipy.optimize import brentq

        half_cycles = math.floor(float(self._sweep_phase(self.sweep_time)) / math.pi)
        target = half_cycles * math.pi
        return float(brentq(lambda tau: float(self._sweep_phase(tau)) - target, 0.0,
                            self.sweep_time, xtol=1e-12))

    @property
    def duration(self) -> float:
        """Record length in s: lead + dwell + sweep + trail."""
        return self.lead + self.dwell + self.sweep_end + self.trail

    def frequency(self, time) -> np.ndarray:
        """Instantaneous frequency ω(t) in rad/s (0 in the trim parts)."""
        tau = np.asarray(time, dtype=float) - self.lead
        in_sweep = tau - self.dwell
        k = self.c2 * np.expm1(self.c1 * np.clip(in_sweep, 0.0, None) / self.sweep_time)
        omega = self.omega_min + k * (self.omega_max - self.omega_min)
        active = (tau >= 0) & (in_sweep <= self.sweep_end)
        return np.where(active, omega, 0.0)

    def phase(self, time) -> np.ndarray:
        """Phase θ(t) = ∫ω dt in rad, measured from the start of the excitation."""
        tau = np.clip(np.asarray(time, dtype=float) - self.lead, 0.0, None)
        dwell_phase = self.omega_min * np.minimum(tau, self.dwell)
        in_sweep = np.clip(tau - self.dwell, 0.0, self.sweep_end)
        return dwell_phase + self._sweep_phase(in_sweep)

    def envelope(self, time) -> np.ndarray:
        """Amplitude in % at ``time`` (0 in the trim parts)."""
        omega = self.frequency(time)
        fraction = (omega - self.omega_min) / (self.omega_max - self.omega_min)
        growth = 1.0 + (self.amplitude_ratio - 1.0) * fraction
        return np.where(omega > 0, self.amplitude * growth, 0.0)

    def __call__(self, time) -> np.ndarray:
        held = _held(time, self.sample_time)
        return self.envelope(held) * np.sin(self.phase(held))
