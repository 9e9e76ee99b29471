"""Verification of an identified model on sweeps: simulate it (in one piece or, when it is too
unstable to follow a long sweep open loop, in segments and through its apparent response) and
compare it with the recorded sweeps (:func:`rotorid.verification.compare.compare_sweeps`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import attrs
import numpy as np

from rotorid.plugin.contracts import ValidationEnvelope
from rotorid.simulation.simulator import simulate
from rotorid.simulation.transfer import frequency_response
from rotorid.verification.band import DEFAULT_BAND, VerificationBand
from rotorid.verification.compare import VerificationResult, compare_sweeps, envelopes_by_name
from rotorid.verification.pairs import step_input_notes
from rotorid.verification.segments import segmented_simulation

#: Growth of the unstable mode over the longest sweep above which the model's open-loop
#: simulation counts as drifting: it is compared through its apparent response instead
#: (see :func:`verify_model`).
DRIFT_LIMIT = 100.0


def verify_model(structure, values, sweeps, pairs: Sequence[str] | None = None,
                 envelopes: Mapping[str, ValidationEnvelope] | Sequence[str] | None = None,
                 segment: float | None = None, manager=None,
                 band: VerificationBand = DEFAULT_BAND, **options) -> VerificationResult:
    """Verify an identified model on sweeps not used for identification.

    Simulates ``structure`` at ``values`` (vector, name→value mapping or None) on the
    recorded inputs of every sweep (:func:`rotorid.simulation.simulator.simulate`, with the sweeps'
    input hold) and compares the pairs ``pairs`` of its outputs and inputs (default
    :func:`rotorid.verification.pairs.default_pairs` of the structure's signals), estimates
    truth and model responses with identical processing and holds
    ``ε = H_model/H_truth`` against the envelopes; also compares the analytic response with
    exact delays (:func:`rotorid.simulation.transfer.frequency_response`) with the truth's conditioned
    response. ``envelopes`` may be envelope objects by name or registered envelope names.

    An unstable model (the hover phugoid is unstable) cannot follow a long sweep open loop
    when its unstable mode grows more than :data:`DRIFT_LIMIT`-fold over the longest sweep
    (σ·T > ln 100 for the largest unstable real part σ): its simulation drifts away from the
    data. For such a model the frequency comparison uses its *apparent* response instead
    (:func:`rotorid.verification.frequency.apparent_response`: the analytic responses combined through the
    recorded inputs' cross-spectra, which is what a single-input estimate from its simulation
    would give if it did not drift), and the time-domain metrics come from a simulation in
    segments of 2/σ s (at least 5 s) restarted from the data (:func:`segmented_simulation`).
    A slower instability is simulated in one piece. ``segment`` given explicitly simulates in
    segments of that length and uses the simulated comparison. The result's notes say which
    was done, and name any maneuver that looks like a step input rather than a sweep
    (:func:`~rotorid.verification.pairs.step_input_notes`). Envelope names are built from
    ``manager`` (default the current plugin manager). Every check counts the points of ``band``
    (:class:`~rotorid.verification.band.VerificationBand`). Other keyword options go to
    :func:`compare_sweeps`.
    """
    if envelopes is not None and not isinstance(envelopes, Mapping):
        envelopes = envelopes_by_name(tuple(envelopes), manager, band)
    eigenvalues = np.linalg.eigvals(structure.matrices(values)[0])
    growth = float(np.max(eigenvalues.real))
    longest = max(m.duration for m in sweeps)
    notes = _stability_notes(eigenvalues, growth * longest) + step_input_notes(sweeps)
    drifts = growth * longest > math.log(DRIFT_LIMIT)
    comparison = "apparent" if drifts and segment is None else "simulated"
    if segment is None and drifts:
        segment = max(5.0, 2.0 / growth)
        notes.append(f"the model's unstable mode grows e^{growth * longest:.0f}-fold over the "
                     f"longest sweep: frequency responses compared through its apparent "
                     f"response (analytic responses and the recorded inputs' cross-spectra); "
                     f"time-domain metrics from segments of {segment:.1f} s restarted from "
                     f"the measured and reconstructed state")
    elif segment is not None:
        notes.append(f"the model was simulated in segments of {segment:.1f} s, each restarted "
                     f"from the measured and reconstructed state")
    outputs = (simulate(structure, values, sweeps) if segment is None
               else segmented_simulation(structure, values, sweeps, segment))
    result = compare_sweeps(
        sweeps, outputs, pairs, envelopes,
        analytic=lambda omega: frequency_response(structure, values, omega),
        model_response=comparison, band=band, output_names=structure.outputs,
        input_names=structure.controls, output_units=structure.signals.outputs.units,
        **options)
    return attrs.evolve(result, notes=[*notes, *result.notes])


def _stability_notes(eigenvalues: np.ndarray, growth_over_sweep: float) -> list[str]:
    """A note listing the unstable eigenvalues of A (delays set to zero), if any, and how
    much their mode grows over the longest sweep (``growth_over_sweep`` = σ·T)."""
    unstable = eigenvalues[eigenvalues.real > 1e-9]
    if not unstable.size:
        return []
    shown = ", ".join(f"{v.real:.3g}{v.imag:+.3g}j" for v in unstable if v.imag >= 0)
    return [f"the model is unstable (eigenvalues {shown} 1/s, delays ignored): its open-loop "
            f"response grows e^{growth_over_sweep:.1f}-fold over the longest sweep"]
