"""Envelopes defined by breakpoint tables (the AEE, or any user table).

A table file (TOML or JSON) holds ``name``, ``provenance`` (required free text: document,
edition, table/figure, page, transcriber, date), ``verified`` (required boolean: true only
after a second person checked the numbers against the source), ``omega_range`` [rad/s] and
four breakpoint lists ``mag_upper``, ``mag_lower`` (dB) and ``phase_upper``, ``phase_lower``
(deg), each a list of ``[omega, value]`` pairs with increasing omega. Bounds are linear in
``(log10 ω, value)``; outside ``omega_range`` they are NaN and flagged, never extrapolated.
A table with no breakpoints is "not available".
"""

from __future__ import annotations

import attrs
import numpy as np
from rotorid.errors import VerificationError
from rotorid.frozen import readonly_array
from rotorid.verification.band import DEFAULT_BAND
from rotorid.verification.envelopes import EnvelopeBounds, check_bounds

from .tomlfile import PACKAGE_DIR, load_definition, omega_range, require

BOUND_KEYS = ("mag_upper", "mag_lower", "phase_upper", "phase_lower")


def _readonly(points: np.ndarray) -> np.ndarray:
    """Breakpoints as a read-only array of shape (K, 2)."""
    return readonly_array(points).reshape(-1, 2)


def _breakpoints(value, key: str, where: str) -> np.ndarray:
    """Breakpoints as an array of shape (K, 2), checked."""
    if not isinstance(value, list):
        raise VerificationError(f"{where}: {key} must be a list of [omega, value] pairs")
    if not value:
        return np.zeros((0, 2))
    try:
        points = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise VerificationError(f"{where}: {key} must hold numeric [omega, value] "
                                f"pairs") from None
    if points.ndim != 2 or points.shape[1] != 2 or points.shape[0] < 2:
        raise VerificationError(f"{where}: {key} needs at least two [omega, value] pairs")
    if not np.all(np.isfinite(points)) or np.any(points[:, 0] <= 0):
        raise VerificationError(f"{where}: {key} needs finite values and positive omega")
    if np.any(np.diff(points[:, 0]) <= 0):
        raise VerificationError(f"{where}: {key} omega must increase strictly")
    return points


@attrs.frozen(eq=False)
class TableEnvelope:
    """Breakpoint-table envelope; build with :meth:`from_file` or :meth:`packaged_aee`."""

    name: str
    provenance: str
    verified: bool
    omega_range: tuple[float, float]
    mag_upper: np.ndarray = attrs.field(converter=_readonly)
    mag_lower: np.ndarray = attrs.field(converter=_readonly)
    phase_upper: np.ndarray = attrs.field(converter=_readonly)
    phase_lower: np.ndarray = attrs.field(converter=_readonly)
    threshold: float = DEFAULT_BAND.coherence
    kind = "bounds"

    @classmethod
    def from_definition(cls, definition: dict, where: str = "envelope table", *,
                        threshold: float = DEFAULT_BAND.coherence) -> "TableEnvelope":
        tables = [_breakpoints(definition.get(k, []), k, where) for k in BOUND_KEYS]
        sizes = {t.shape[0] > 0 for t in tables}
        if len(sizes) > 1:
            raise VerificationError(f"{where}: give all four of {', '.join(BOUND_KEYS)} or "
                                    f"none of them")
        low, high = omega_range(definition, where)
        for key, table in zip(BOUND_KEYS, tables):
            if table.size and (table[0, 0] > low or table[-1, 0] < high):
                raise VerificationError(f"{where}: {key} breakpoints must cover omega_range "
                                        f"[{low}, {high}] rad/s")
        return cls(require(definition, "name", str, where),
                   require(definition, "provenance", str, where),
                   require(definition, "verified", bool, where), (low, high), *tables,
                   threshold=float(threshold))

    @classmethod
    def from_file(cls, path, **options) -> "TableEnvelope":
        """A table from a TOML or JSON file (see the module docstring for the fields)."""
        return cls.from_definition(load_definition(path), f"envelope file {path}", **options)

    @classmethod
    def packaged_aee(cls, **options) -> "TableEnvelope":
        """The packaged AEE table (unverified; see its provenance)."""
        path = PACKAGE_DIR / "aee.toml"
        return cls.from_definition(load_definition(path), "packaged AEE table", **options)

    @property
    def available(self) -> bool:
        return self.mag_upper.shape[0] > 0

    def bounds(self, omega) -> EnvelopeBounds:
        """Bounds at ``omega`` (rad/s, shape (M,)); NaN outside ``omega_range``."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        low, high = self.omega_range
        outside = (omega < low * (1 - 1e-9)) | (omega > high * (1 + 1e-9))

        def interpolate(table):
            if not self.available:
                return np.full(omega.shape, np.nan)
            values = np.interp(np.log10(omega), np.log10(table[:, 0]), table[:, 1])
            return np.where(outside, np.nan, values)

        return EnvelopeBounds(self.name, omega, interpolate(self.mag_lower),
                              interpolate(self.mag_upper), interpolate(self.phase_lower),
                              interpolate(self.phase_upper), outside, self.available)

    def check(self, error, coherence, omega):
        """Hold ``ε`` against the table (see :func:`rotorid.verification.envelopes.check_bounds`)."""
        return check_bounds(self, error, coherence, omega)
