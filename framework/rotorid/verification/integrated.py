"""Verification of a model of one's own (:class:`~rotorid.estimation.integrated.IntegratedModel`)
on sweeps: its signals read from the sweeps through its channel map, the model integrated
over each sweep from the sweep's own first samples, and the simulated comparison of
:func:`rotorid.verification.compare.compare_sweeps` (a nonlinear model has no analytic
response to compare with a conditioned one)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import attrs
import numpy as np

from rotorid.data import Maneuver, ManeuverSet
from rotorid.errors import VerificationError
from rotorid.estimation.integrated import InitialConditions, IntegratedModel
from rotorid.plugin.contracts import ValidationEnvelope
from rotorid.verification.band import DEFAULT_BAND, VerificationBand
from rotorid.verification.compare import VerificationResult, compare_sweeps
from rotorid.verification.pairs import default_pairs, primary_axis


def signal_sweeps(model: IntegratedModel, sweeps: ManeuverSet) -> ManeuverSet:
    """``sweeps`` in the model's own signals: its inputs and measured outputs read through
    its channel map (signal units), a sweep's ``axis`` naming a linked column read as the
    input it links."""
    inputs = model.signals.inputs.names
    read = []
    for m in sweeps:
        metadata = dict(m.metadata)
        if isinstance(metadata.get("axis"), str):
            metadata["axis"] = model.channels.signal_of(metadata["axis"])
        [record] = model.records(ManeuverSet([m]))
        read.append(Maneuver(m.name, m.time, record.inputs, model.measured(ManeuverSet([m]))[0],
                             units=m.units, metadata=metadata, input_names=inputs,
                             output_names=model.output_names))
    return ManeuverSet(read, hold=sweeps.hold)


def verify_integrated(model: IntegratedModel, values: Mapping[str, float], sweeps: ManeuverSet,
                      pairs: Sequence[str] | None = None,
                      envelopes: Mapping[str, ValidationEnvelope] | None = None,
                      band: VerificationBand = DEFAULT_BAND, **options) -> VerificationResult:
    """Verify ``model`` at ``values`` (its parameters by name; estimated initial states of
    the identification records are ignored) on ``sweeps``: each sweep starts from its own
    first samples (or the model's fixed initial states), and the model's simulated
    responses are compared with the measured ones pair by pair (``pairs`` of its outputs and
    inputs; default every output over every swept input)."""
    simulated = IntegratedModel(model.model, channels=model.channels,
                                initial=InitialConditions(fixed=model.initial.fixed),
                                integration=model.integration, anticipate=False)
    missing = [n for n in simulated.parameter_names if n not in values]
    if missing:
        raise VerificationError(f"the result gives no value for {', '.join(missing)}; verify "
                                f"the model the result was estimated with")
    read = signal_sweeps(simulated, sweeps)
    outputs = simulated.simulate([values[n] for n in simulated.parameter_names], sweeps)
    diverged = [m.name for m, y in zip(sweeps, outputs) if not np.all(np.isfinite(y))]
    if diverged:
        raise VerificationError(f"the model's simulation diverges on sweep(s) "
                                f"{', '.join(diverged)}: it cannot follow them open loop")
    if pairs is None:
        axes = {primary_axis(m) for m in read}
        pairs = [p for p in default_pairs(simulated.output_names, simulated.signals.inputs.names)
                 if p.split("/")[1] in axes]
    result = compare_sweeps(read, outputs, pairs, envelopes, band=band,
                            output_names=simulated.output_names,
                            input_names=simulated.signals.inputs.names,
                            output_units=simulated.output_units, **options)
    note = ("a model of one's own: compared through its simulation of each sweep, started "
            "from the sweep's first samples (it has no analytic response)")
    return attrs.evolve(result, notes=[note, *result.notes])
