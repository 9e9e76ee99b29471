"""The MUAD envelopes: bounds on ``ε = H_model/H_truth`` from four transfer functions.

Upper/lower gain bounds are ``20 log10 |G(jω)|``; upper/lower phase bounds are the phase of
``P(jω)·e^{−τ jω}`` in deg, taken as the principal value at 0.1 rad/s and unwrapped
continuously from there (never shifted by 360°). Coefficients and provenance live in
``muad.toml``; outside 0.1–10 rad/s the bounds are extrapolated and flagged.
"""

from __future__ import annotations

import attrs
import numpy as np
from rotorid.verification.band import DEFAULT_BAND
from rotorid.verification.envelopes import EnvelopeBounds, check_bounds

from .tomlfile import PACKAGE_DIR, load_definition, omega_range, require

#: Frequency at which the phase bounds take their principal value, rad/s.
PHASE_REFERENCE = 0.1


@attrs.frozen
class TransferFunction:
    """``num(s)/den(s)·e^{−delay·s}``; coefficients highest power first, delay in s."""

    numerator: tuple[float, ...] = attrs.field(converter=lambda c: tuple(map(float, c)))
    denominator: tuple[float, ...] = attrs.field(converter=lambda c: tuple(map(float, c)))
    delay: float = 0.0

    def __call__(self, omega: np.ndarray) -> np.ndarray:
        s = 1j * np.asarray(omega, dtype=float)
        return (np.polyval(self.numerator, s) / np.polyval(self.denominator, s)
                * np.exp(-self.delay * s))

    def magnitude_db(self, omega: np.ndarray) -> np.ndarray:
        return 20.0 * np.log10(np.abs(self(omega)))

    def phase_deg(self, omega: np.ndarray) -> np.ndarray:
        """Continuous phase in deg, principal value at :data:`PHASE_REFERENCE`."""
        omega = np.asarray(omega, dtype=float)
        low = min(PHASE_REFERENCE, float(omega.min()))
        high = max(PHASE_REFERENCE, float(omega.max()))
        dense = np.unique(np.concatenate([np.geomspace(low, high, 4000), omega,
                                          [PHASE_REFERENCE]]))
        rational = attrs.evolve(self, delay=0.0)(dense)
        phase = np.unwrap(np.angle(rational))
        reference = np.searchsorted(dense, PHASE_REFERENCE)
        phase += np.angle(rational[reference]) - phase[reference]
        phase -= self.delay * dense
        return np.degrees(phase[np.searchsorted(dense, omega)])


def _transfer_function(definition: dict, key: str) -> TransferFunction:
    where = f"MUAD definition [{key}]"
    table = require(definition, key, dict, "MUAD definition")
    return TransferFunction(require(table, "numerator", list, where),
                            require(table, "denominator", list, where),
                            float(table.get("delay", 0.0)))


@attrs.frozen
class MuadEnvelope:
    """MUAD envelope; build it with :meth:`packaged` or :meth:`from_definition`.

    ``threshold`` is the coherence a point needs to count; ``delay_terms=False`` drops the
    e^{±τs} factors of the phase bounds (for comparison with sources that omit them).
    """

    upper_gain: TransferFunction
    lower_gain: TransferFunction
    upper_phase: TransferFunction
    lower_phase: TransferFunction
    omega_range: tuple[float, float] = (0.1, 10.0)
    provenance: str = ""
    verified: bool = False
    threshold: float = DEFAULT_BAND.coherence
    name: str = "MUAD"
    kind = "bounds"

    @classmethod
    def from_definition(cls, definition: dict, *, threshold: float = DEFAULT_BAND.coherence,
                        delay_terms: bool = True) -> "MuadEnvelope":
        phases = [_transfer_function(definition, k) for k in ("upper_phase", "lower_phase")]
        if not delay_terms:
            phases = [attrs.evolve(p, delay=0.0) for p in phases]
        return cls(_transfer_function(definition, "upper_gain"),
                   _transfer_function(definition, "lower_gain"), *phases,
                   omega_range=omega_range(definition, "MUAD definition"),
                   provenance=require(definition, "provenance", str, "MUAD definition"),
                   verified=require(definition, "verified", bool, "MUAD definition"),
                   threshold=float(threshold),
                   name=str(definition.get("name", "MUAD")))

    @classmethod
    def packaged(cls, **options) -> "MuadEnvelope":
        """The MUAD envelope from the packaged ``muad.toml``."""
        return cls.from_definition(load_definition(PACKAGE_DIR / "muad.toml"), **options)

    def bounds(self, omega) -> EnvelopeBounds:
        """Bounds at ``omega`` (rad/s, shape (M,)); extrapolated outside ``omega_range``."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        low, high = self.omega_range
        return EnvelopeBounds(
            name=self.name, omega=omega,
            mag_lower_db=self.lower_gain.magnitude_db(omega),
            mag_upper_db=self.upper_gain.magnitude_db(omega),
            phase_lower_deg=self.lower_phase.phase_deg(omega),
            phase_upper_deg=self.upper_phase.phase_deg(omega),
            extrapolated=(omega < low * (1 - 1e-9)) | (omega > high * (1 + 1e-9)))

    def check(self, error, coherence, omega):
        """Hold ``ε`` against the bounds (see :func:`rotorid.verification.envelopes.check_bounds`)."""
        return check_bounds(self, error, coherence, omega)
