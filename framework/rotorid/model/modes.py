"""The modes of a linear model: its eigenvalues as frequency and damping or time constant,
and the states that carry each (the Dutch roll in v and r, the roll subsidence in p)."""

from __future__ import annotations

import math

import attrs
import numpy as np

#: States named for a mode: those whose share of its eigenvector is at least this fraction of
#: the largest share (:func:`modes`).
DOMINANT_SHARE = 0.3


@attrs.frozen
class Mode:
    """One mode: a real eigenvalue, or a complex pair given once (positive imaginary part).

    Attributes:
        eigenvalue: λ in 1/s (complex).
        states: the states that carry it, largest share first.
    """

    eigenvalue: complex
    states: tuple[str, ...]

    @property
    def oscillatory(self) -> bool:
        return abs(self.eigenvalue.imag) > 0.0

    @property
    def frequency(self) -> float:
        """Undamped natural frequency ω_n = |λ|, rad/s."""
        return abs(self.eigenvalue)

    @property
    def damping(self) -> float:
        """Damping ratio ζ = −Re λ / |λ| (negative: a growing mode)."""
        return -self.eigenvalue.real / abs(self.eigenvalue) if self.eigenvalue else 0.0

    @property
    def time_constant(self) -> float:
        """For a real mode, −1/λ in s (negative: it grows); inf at λ = 0."""
        return -1.0 / self.eigenvalue.real if self.eigenvalue.real else math.inf

    @property
    def eigenvalue_text(self) -> str:
        """``"-1.133 ± 2.301j"`` for a pair, ``"-6.915"`` for a real mode."""
        value = self.eigenvalue
        return (f"{value.real:.4g} ± {value.imag:.4g}j" if self.oscillatory
                else f"{value.real:.4g}")

    def describe(self) -> str:
        """``"ω_n 2.59 rad/s, ζ 0.227"`` or ``"time constant 0.17 s"`` (``"doubles in 3.1 s"``
        when it grows)."""
        if self.oscillatory:
            return f"ω_n {self.frequency:.3g} rad/s, ζ {self.damping:.3g}"
        if self.eigenvalue.real > 0:
            return f"doubles in {math.log(2.0) / self.eigenvalue.real:.3g} s"
        if self.eigenvalue.real == 0:
            return "neutral (λ = 0)"
        return f"time constant {self.time_constant:.3g} s"


def modes(structure, values=None) -> tuple[Mode, ...]:
    """The modes of ``structure``'s A at ``values`` (delays set to zero), slowest first.

    A state's share of a mode is the size of its eigenvector component in the model's units
    (ft/s and deg/s count alike in flight-test units, m/s and rad/s in SI): read the named
    states as the mode's character, not as a measure of energy."""
    a = structure.matrices(values)[0]
    eigenvalues, vectors = np.linalg.eig(a)
    found = []
    for k in np.argsort(np.abs(eigenvalues)):
        value = complex(eigenvalues[k])
        if value.imag < 0:
            continue
        share = np.abs(vectors[:, k])
        top = share.max()
        order = [i for i in np.argsort(-share) if top > 0 and share[i] >= DOMINANT_SHARE * top]
        found.append(Mode(value, tuple(structure.states[i] for i in order)))
    return tuple(found)
