"""The measured responses a fit matches: one pair's magnitude, phase and coherence weight on
the points of its cost J, and how the model's responses combine into the one compared.

The points follow the mismatch cost of :mod:`rotorid_envelopes.cost` (Tischler & Remple,
eq. 12.20): ``n_points`` log-spaced frequencies over the pair's coherent range (γ² ≥ 0.6),
points below the threshold dropped; from sweeps, the range ends at the highest frequency
they excite (:func:`excited_band`).

From sweeps, each pair's measured response is the single-input composite estimate of its
output over its sweep axis, and the model's response is its *apparent* response on the same
records (:func:`rotorid.verification.frequency.apparent_response`): Σ_k κ_k(ω)·H_k(ω) over the
inputs k, with κ_k the records' cross-spectral ratio G_{u,u_k}/G_{u,u} merged over the windows
with the measured estimate's weights, times the input hold's response. The feedback that
moves the other inputs with the swept one (hover stabilisation) thus acts on model and data
alike, where a conditioned response would be unreliable (input coherence above ~0.5).
"""

from __future__ import annotations

from collections.abc import Sequence

import attrs
import numpy as np
from rotorid.data import ManeuverSet
from rotorid.errors import EstimationError
from rotorid.frozen import readonly_array
from rotorid.verification.compare import default_omega, sweep_frequency
from rotorid.verification.frequency import (
    FrequencyResponse,
    apparent_response,
    response_from_maneuvers,
)
from rotorid.verification.pairs import parse_pair, primary_axis, sweeps_exciting
from rotorid_envelopes.cost import COST_THRESHOLD, MismatchCost, coherence_weight


@attrs.frozen(eq=False)
class PairData:
    """One pair's measured response on its n J points.

    Attributes:
        output, control: channel names (``"q"``, ``"long"``).
        omega: J frequencies in rad/s, shape (n,).
        magnitude_db: measured 20 log10|Ĥ|, shape (n,); phase_deg: measured unwrapped phase
            in deg, shape (n,).
        weight: coherence weight W_γ = [1.58 (1 − e^(−γ²))]², shape (n,).
        mixing: κ, shape (n, k) complex: the model's compared response is
            Σ_k κ[:, k]·H[:, output, inputs[k]] (a model without input k has no response
            to it).
        inputs: the k inputs the columns of ``mixing`` weigh.
    """

    output: str
    control: str
    omega: np.ndarray = attrs.field(converter=readonly_array)
    magnitude_db: np.ndarray = attrs.field(converter=readonly_array)
    phase_deg: np.ndarray = attrs.field(converter=readonly_array)
    weight: np.ndarray = attrs.field(converter=readonly_array)
    mixing: np.ndarray = attrs.field(converter=lambda v: readonly_array(v, complex))
    inputs: tuple[str, ...] = attrs.field(converter=tuple)

    @property
    def pair(self) -> str:
        return f"{self.output}/{self.control}"


def cost_points(response: FrequencyResponse, n_points: int = 20,
                threshold: float = COST_THRESHOLD, band=(0.0, np.inf)) -> np.ndarray:
    """The J frequencies of one measured response in rad/s (empty when none is coherent),
    within ``band`` (lowest, highest frequency in rad/s)."""
    finite = np.isfinite(response.response) & np.isfinite(response.coherence)
    finite &= (response.omega >= band[0]) & (response.omega <= band[1])
    omega, coherence = response.omega[finite], response.coherence[finite]
    order = np.argsort(omega)
    return MismatchCost(threshold=threshold, n_points=n_points).points(omega[order],
                                                                        coherence[order])


def pair_data(response: FrequencyResponse, n_points: int = 20,
              threshold: float = COST_THRESHOLD, band=(0.0, np.inf)) -> PairData | None:
    """The J points of a measured response that the model's own response matches directly
    (magnitude, unwrapped phase and γ² interpolated linearly in log ω); ``None`` when no
    frequency is coherent."""
    points = cost_points(response, n_points, threshold, band)
    finite = np.isfinite(response.response) & np.isfinite(response.coherence)
    if points.size == 0:
        return None
    order = np.argsort(response.omega[finite])
    log_omega, log_points = np.log10(response.omega[finite][order]), np.log10(points)

    def at_points(values):
        return np.interp(log_points, log_omega, values[finite][order])

    coherence = at_points(response.coherence)
    kept = coherence >= threshold
    return PairData(response.output, response.input, points[kept],
                    at_points(response.magnitude_db)[kept], at_points(response.phase_deg)[kept],
                    coherence_weight(coherence[kept]), np.ones((int(kept.sum()), 1)),
                    (response.input,))


def excited_band(sweeps: ManeuverSet, band=(0.0, np.inf)) -> tuple[float, float]:
    """``band`` (lowest, highest frequency in rad/s) ended at the highest frequency the
    ``sweeps`` excite, when every one's metadata records it (``omega_max``): above it the
    input holds no excitation, only the loops' and the signal's harmonics, whose coherence
    can stay high while the estimate is no response of the aircraft."""
    tops = [sweep_frequency(m, "omega_max") for m in sweeps]
    if any(top is None for top in tops):
        return band
    return band[0], min(band[1], max(tops))


def all_pairs(maneuvers: ManeuverSet) -> tuple[str, ...]:
    """Every recorded output over every recorded input that a sweep of ``maneuvers``
    excites."""
    axes = {primary_axis(m) for m in maneuvers}
    return tuple(f"{o}/{c}" for c in maneuvers.input_names if c in axes
                 for o in maneuvers.output_names)


def sweep_pair_data(maneuvers: ManeuverSet, pairs: Sequence[str] | None = None,
                    n_points: int = 20, threshold: float = COST_THRESHOLD,
                    band=(0.0, np.inf), windows: Sequence[float] | None = None
                    ) -> tuple[PairData | str, ...]:
    """Each pair's J points from the sweeps whose axis is its input (see the module
    docstring); a pair without coherent frequencies gives its name instead."""
    pairs = all_pairs(maneuvers) if pairs is None else tuple(pairs)
    grid = default_omega(maneuvers)
    inputs = maneuvers.input_names
    found = []
    for name in pairs:
        output, control = parse_pair(name, maneuvers.output_names, inputs)
        subset = sweeps_exciting(maneuvers, control, name, EstimationError)
        points = cost_points(response_from_maneuvers(subset, control, output, grid,
                                                     windows=windows),
                             n_points, threshold, excited_band(subset, band))
        if points.size == 0:
            found.append(name)
            continue
        mixing, measured = [], None
        for unit in np.eye(len(inputs)):
            model, measured = apparent_response(
                subset, control, output, points,
                np.broadcast_to(unit, (points.size, unit.size)).astype(complex),
                windows=windows)
            mixing.append(model.response)
        kept = measured.coherence >= threshold
        found.append(PairData(output, control, points[kept], measured.magnitude_db[kept],
                              measured.phase_deg[kept], coherence_weight(
                                  measured.coherence[kept]),
                              np.column_stack(mixing)[kept], inputs) if kept.any() else name)
    return tuple(found)
