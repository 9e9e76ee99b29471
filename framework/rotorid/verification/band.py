"""The verification band: the points of a sweep comparison that every verdict uses.

MUAD, AEE, the mismatch cost J and the analytic comparison all count the same points: those
whose measured coherence reaches ``coherence`` (γ², partial γ² for conditioned responses)
and whose frequency lies in [``omega_min``, ``omega_max``] rad/s. The default, γ² ≥ 0.8 over
0.1–10 rad/s, is the paper's MUAD practice: it holds the error "within the acceptable bounds
in the frequencies where the coherence function is greater than 0.8", and the MUAD envelopes
are defined on the LOES matching range 0.1–10 rad/s (MIL-STD-1797A; above it they are
extrapolation). Tischler & Remple's γ² ≥ 0.6 defines the range a model is *fitted* over; as a
verdict J here uses the stricter band, so no verdict rests on points another one ignores
(docs/verification.md, "The verification band").
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import attrs
import numpy as np

from rotorid.errors import VerificationError

#: The keys of a band in a case file's ``[verification]`` table.
BAND_KEYS = ("coherence", "omega_min", "omega_max")


@attrs.frozen
class VerificationBand:
    """Coherence threshold γ² (dimensionless, in (0, 1]) and frequency range in rad/s."""

    coherence: float = 0.8
    omega_min: float = 0.1
    omega_max: float = 10.0

    def __attrs_post_init__(self) -> None:
        if not (isinstance(self.coherence, (int, float)) and 0.0 < self.coherence <= 1.0):
            raise VerificationError(f"verification band: coherence must be a γ² in (0, 1], "
                                    f"e.g. 0.8, got {self.coherence!r}")
        low, high = self.omega_min, self.omega_max
        if not (isinstance(low, (int, float)) and isinstance(high, (int, float))
                and math.isfinite(low) and math.isfinite(high) and 0.0 < low < high):
            raise VerificationError(f"verification band: needs 0 < omega_min < omega_max in "
                                    f"rad/s, e.g. 0.1 and 10, got {low!r} and {high!r}")

    @classmethod
    def from_mapping(cls, mapping: Mapping, where: str) -> "VerificationBand":
        """The band from the :data:`BAND_KEYS` of ``mapping`` (missing keys take the
        defaults); ``where`` names the source in errors."""
        values = {}
        for key in BAND_KEYS:
            if key in mapping:
                value = mapping[key]
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    raise VerificationError(f"{where}: {key} must be a number, got {value!r}")
                values[key] = float(value)
        try:
            return cls(**values)
        except VerificationError as error:
            raise VerificationError(f"{where}: {error}") from None

    def in_range(self, omega) -> np.ndarray:
        """Whether each frequency (rad/s, shape (M,)) lies in the band's range."""
        omega = np.asarray(omega, dtype=float)
        return (omega >= self.omega_min * (1 - 1e-9)) & (omega <= self.omega_max * (1 + 1e-9))

    def selects(self, omega, coherence) -> np.ndarray:
        """Whether each point is checked: in range and γ² ≥ :attr:`coherence`, shape (M,)."""
        with np.errstate(invalid="ignore"):
            return self.in_range(omega) & (np.asarray(coherence, dtype=float) >= self.coherence)

    def restrict(self, omega, coherence) -> np.ndarray:
        """``coherence`` with NaN outside the band's range, so no check uses those points."""
        return np.where(self.in_range(omega), np.asarray(coherence, dtype=float), np.nan)

    def describe(self) -> str:
        """E.g. ``"γ² ≥ 0.8 over 0.1–10 rad/s"``."""
        return f"γ² ≥ {self.coherence:g} over {self.omega_min:g}–{self.omega_max:g} rad/s"

    def as_dict(self) -> dict:
        return attrs.asdict(self)


#: The band of every verdict unless a case or caller sets another.
DEFAULT_BAND = VerificationBand()
