"""What envelopes exchange with the verification: bounds, checks and the shared check.

An envelope (a plugin of the ``rotorid_validation_envelopes`` family, contract
:class:`rotorid.plugin.contracts.ValidationEnvelope`) gives :class:`EnvelopeBounds` on the
verification error ``ε = H_model/H_truth`` and returns an :class:`EnvelopeCheck` for an error
on a frequency grid. :func:`check_bounds` is the check of every bounds-kind envelope.
"""

from __future__ import annotations

import re

import attrs
import numpy as np

from rotorid.errors import PluginError, VerificationError
from rotorid.frozen import readonly_array
from rotorid.plugin.returns import returned


def wrap180(angle_deg):
    """Angles in deg wrapped to (−180, 180]."""
    wrapped = np.mod(np.asarray(angle_deg, dtype=float) + 180.0, 360.0) - 180.0
    return np.where(wrapped == -180.0, 180.0, wrapped)


def error_db_deg(error) -> tuple[np.ndarray, np.ndarray]:
    """Magnitude in dB and phase in deg, wrapped to (−180, 180], of a complex ratio ``ε``.

    The phase comes from the complex ratio directly, never from the difference of separately
    unwrapped phases.
    """
    error = np.asarray(error, dtype=complex)
    with np.errstate(divide="ignore"):
        return 20.0 * np.log10(np.abs(error)), wrap180(np.angle(error, deg=True))


# ----------------------------------------------------------------- envelope results
@attrs.frozen(eq=False)
class EnvelopeBounds:
    """Bounds of an envelope on a frequency grid.

    Attributes:
        name: envelope name.
        omega: frequencies in rad/s, shape (M,).
        mag_lower_db, mag_upper_db: magnitude bounds of ``ε`` in dB, shape (M,).
        phase_lower_deg, phase_upper_deg: phase bounds of ``ε`` in deg, shape (M,).
        extrapolated: True where ``omega`` lies outside the range the envelope was defined
            on, shape (M,); the bounds there are extrapolated (MUAD) or NaN (tables).
        available: False when the envelope has no data (then every bound is NaN).
    """

    name: str
    omega: np.ndarray = attrs.field(converter=readonly_array)
    mag_lower_db: np.ndarray = attrs.field(converter=readonly_array)
    mag_upper_db: np.ndarray = attrs.field(converter=readonly_array)
    phase_lower_deg: np.ndarray = attrs.field(converter=readonly_array)
    phase_upper_deg: np.ndarray = attrs.field(converter=readonly_array)
    extrapolated: np.ndarray = attrs.field(converter=lambda m: readonly_array(m, bool))
    available: bool = True

    def __attrs_post_init__(self):
        shapes = {name: getattr(self, name).shape for name in (
            "mag_lower_db", "mag_upper_db", "phase_lower_deg", "phase_upper_deg",
            "extrapolated")}
        wrong = {name: shape for name, shape in shapes.items() if shape != self.omega.shape}
        if wrong:
            raise VerificationError(
                f"envelope {self.name!r}: bounds on {self.omega.size} frequencies need arrays "
                f"of shape {self.omega.shape}, got " + ", ".join(
                    f"{name} {shape}" for name, shape in wrong.items())
                + "; fix the envelope's bounds(omega)")


#: The usual guideline for the mismatch cost J (Tischler & Remple, ch. 12): J ≤ 100 per pair,
#: or, for a multi-pair model, an average ≤ 100 with a few pairs up to 200.
MISMATCH_COST_GUIDELINE = {"pair_max": 100.0, "few_pairs_max": 200.0, "average_max": 100.0}
#: The guideline in words, stated beside every J.
MISMATCH_COST_GUIDELINE_TEXT = "J ≤ 100 (a few pairs ≤ 200, average ≤ 100)"


@attrs.frozen(eq=False)
class EnvelopeCheck:
    """Result of holding a verification error against one envelope.

    Attributes:
        envelope: envelope name; ``provenance`` and ``verified`` describe its source.
        omega: frequencies in rad/s, shape (M,); for the mismatch cost, the J points.
        magnitude_db, phase_deg: the error ``ε`` in dB and deg (wrapped), shape (M,).
        coherence: coherence used for selection, shape (M,).
        used: points that count for pass/fail (coherence ≥ threshold, inside the envelope's
            range), shape (M,).
        inside: points whose magnitude and phase are both within the bounds, shape (M,).
        extrapolated: points outside the envelope's range, shape (M,).
        margin_db, margin_deg: distance to the nearest magnitude/phase bound per point,
            positive inside, shape (M,).
        threshold: coherence threshold.
        passed: True/False over the used points; None when not available or no point used.
        status: ``"pass"``, ``"fail"``, ``"pass (unverified envelope)"``,
            ``"fail (unverified envelope)"``, ``"not available"`` or ``"no coherent points"``.
        cost: a cost-kind envelope's score of the pair (the mismatch cost J), else None.
        cost_guideline: the guideline the cost is read by, in words (the mismatch cost's
            :data:`MISMATCH_COST_GUIDELINE_TEXT`; empty where the envelope states none).
    """

    envelope: str
    provenance: str
    verified: bool
    omega: np.ndarray = attrs.field(converter=readonly_array)
    magnitude_db: np.ndarray = attrs.field(converter=readonly_array)
    phase_deg: np.ndarray = attrs.field(converter=readonly_array)
    coherence: np.ndarray = attrs.field(converter=readonly_array)
    used: np.ndarray = attrs.field(converter=lambda m: readonly_array(m, bool))
    inside: np.ndarray = attrs.field(converter=lambda m: readonly_array(m, bool))
    extrapolated: np.ndarray = attrs.field(converter=lambda m: readonly_array(m, bool))
    margin_db: np.ndarray = attrs.field(converter=readonly_array)
    margin_deg: np.ndarray = attrs.field(converter=readonly_array)
    threshold: float
    passed: bool | None
    status: str
    cost: float | None = None
    cost_guideline: str = ""

    @property
    def n_used(self) -> int:
        return int(self.used.sum())

    @property
    def n_inside(self) -> int:
        """Used points inside the envelope."""
        return int((self.used & self.inside).sum())

    @property
    def n_outside(self) -> int:
        """Used points outside the envelope."""
        return self.n_used - self.n_inside

    @property
    def fraction_inside(self) -> float:
        return self.n_inside / self.n_used if self.n_used else float("nan")

    @property
    def worst_margin_db(self) -> float:
        """Smallest magnitude margin over the used points (negative: outside), dB."""
        return _worst(self.margin_db, self.used)

    @property
    def worst_margin_deg(self) -> float:
        """Smallest phase margin over the used points (negative: outside), deg."""
        return _worst(self.margin_deg, self.used)

    def outside_text(self) -> str:
        """Where the used points fall outside the envelope, e.g. ``"; outside at 0.42–0.6
        rad/s"`` (empty when none does)."""
        outside = self.omega[self.used & ~self.inside]
        if not outside.size:
            return ""
        low, high = float(outside.min()), float(outside.max())
        return f"; outside at {low:.2g} rad/s" if low == high else \
            f"; outside at {low:.2g}–{high:.2g} rad/s"

    @property
    def source_sentence(self) -> str:
        """The first sentence of the envelope's provenance, without its full stop (a full
        stop ends a sentence where a capital follows it: ``eq. 12.20`` does not)."""
        return re.split(r"\.\s+(?=[A-Z])", self.provenance)[0].rstrip(".")

    def summary(self) -> dict:
        """JSON-ready summary (no per-point arrays)."""
        return {
            "envelope": self.envelope, "status": self.status, "passed": self.passed,
            "verified": self.verified, "provenance": self.provenance,
            "threshold": self.threshold, "points_used": self.n_used,
            "points_inside": self.n_inside, "points_outside": self.n_outside,
            "fraction_inside": _finite_or_none(self.fraction_inside),
            "worst_margin_db": _finite_or_none(self.worst_margin_db),
            "worst_margin_deg": _finite_or_none(self.worst_margin_deg),
            "cost": self.cost,
            **({"cost_guideline": self.cost_guideline} if self.cost_guideline else {}),
        }

    def report(self) -> str:
        """One line: envelope, status, points, worst margins, source status."""
        source = ("verified source" if self.verified else "UNVERIFIED source") + (
            f": {self.source_sentence}" if self.source_sentence else "")
        if self.status == "not available":
            return f"{self.envelope}: not available, no point checked [{source}]"
        line = (f"{self.envelope}: {self.status}; {self.n_inside}/{self.n_used} points inside "
                f"(γ² ≥ {self.threshold:g})")
        if np.isfinite(self.worst_margin_db) or np.isfinite(self.worst_margin_deg):
            line += (f"; worst margin {self.worst_margin_db:+.2f} dB, "
                     f"{self.worst_margin_deg:+.1f}°")
        if self.cost is not None:
            line += (f"; J = {self.cost:.1f} (guideline {self.cost_guideline})"
                     if self.cost_guideline else f"; cost {self.cost:.4g}")
        if self.passed is None and self.status == "no coherent points":
            line += (f" — the measured coherence never reaches {self.threshold:g}: check that "
                     f"the sweeps excite this input and the output responds, or lower the "
                     f"envelope's threshold")
        return f"{line} [{source}]"


def _worst(margin: np.ndarray, used: np.ndarray) -> float:
    values = margin[used & ~np.isnan(margin)]
    return float(values.min()) if values.size else float("nan")


def _finite_or_none(value: float):
    return float(value) if np.isfinite(value) else None


def status_of(passed: bool | None, verified: bool, available: bool = True) -> str:
    """Status text; an unverified envelope never gives a bare ``"pass"``."""
    if not available:
        return "not available"
    if passed is None:
        return "no coherent points"
    word = "pass" if passed else "fail"
    return word if verified else f"{word} (unverified envelope)"


def validate_check_inputs(error, coherence, omega) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Arrays for a check, with clear errors for wrong shapes and non-finite frequencies.

    NaN errors or coherences are allowed (points no window covered); they are never used.
    """
    error = np.asarray(error, dtype=complex)
    coherence = np.asarray(coherence, dtype=float)
    omega = np.asarray(omega, dtype=float)
    if not (error.ndim == coherence.ndim == omega.ndim == 1
            and error.shape == coherence.shape == omega.shape):
        raise VerificationError(f"error, coherence and omega must be 1-D arrays of one "
                                f"length; got shapes {error.shape}, {coherence.shape}, "
                                f"{omega.shape}")
    if np.any(~np.isfinite(omega)) or np.any(omega <= 0):
        raise VerificationError("omega must hold positive finite frequencies in rad/s")
    return error, coherence, omega


def check_bounds(envelope, error, coherence, omega) -> EnvelopeCheck:
    """The check shared by bounds-kind envelopes (MUAD, AEE tables, user envelopes).

    ``envelope`` is a :class:`rotorid.plugin.contracts.ValidationEnvelope` of kind
    ``"bounds"``.

    A point is used when its coherence is at least ``envelope.threshold`` and it is not
    extrapolated; the envelope passes when every used point is inside both the magnitude and
    the phase bounds.
    """
    error, coherence, omega = validate_check_inputs(error, coherence, omega)
    call = f"validation envelope {envelope.name!r}: bounds"
    bounds = returned(envelope.bounds(omega), EnvelopeBounds, call)
    if bounds.omega.shape != omega.shape:
        raise PluginError(f"{call}(omega) was asked for {omega.size} frequencies and returned "
                          f"bounds on {bounds.omega.size}; return them on the grid given")
    magnitude, phase = error_db_deg(error)
    with np.errstate(invalid="ignore"):
        margin_db = np.minimum(magnitude - bounds.mag_lower_db, bounds.mag_upper_db - magnitude)
        margin_deg = np.minimum(phase - bounds.phase_lower_deg,
                                bounds.phase_upper_deg - phase)
        inside = (margin_db >= 0) & (margin_deg >= 0)
        used = ((coherence >= envelope.threshold) & ~bounds.extrapolated
                & np.isfinite(error) & bounds.available)
    passed = bool(np.all(inside[used])) if used.any() and bounds.available else None
    return EnvelopeCheck(
        envelope=envelope.name, provenance=envelope.provenance, verified=envelope.verified,
        omega=omega, magnitude_db=magnitude, phase_deg=phase, coherence=coherence, used=used,
        inside=inside, extrapolated=bounds.extrapolated, margin_db=margin_db,
        margin_deg=margin_deg, threshold=envelope.threshold, passed=passed,
        status=status_of(passed, envelope.verified, bounds.available))
