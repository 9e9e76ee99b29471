"""The response pairs a model and its sweeps can produce, and why the others are skipped.

A pair ``output/input`` cannot be verified when the model lacks its output or input (the
paper's lateral pairs of a longitudinal model), when no sweep excites the input, when the
model's output does not respond to the input at all (a decoupled model: its response is
identically zero and ε would be infinite), when the sweeps do not record the output, or when
the measured output never moves on the input's sweeps (a padded column: the measured response
is zero). :func:`producible_pairs` sorts the pairs into those to verify and those skipped, with
the reason.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import attrs
import numpy as np

from rotorid.data import INPUT_CHANNELS, OUTPUT_CHANNELS
from rotorid.model.statespace import responding_outputs
from rotorid.verification.pairs import parse_pair, primary_axis, sweeps_exciting, unexcited


@attrs.frozen
class PairSelection:
    """``pairs`` to verify, in the order given, and ``skipped``: pair → reason."""

    pairs: tuple[str, ...] = attrs.field(converter=tuple)
    skipped: Mapping[str, str] = attrs.field(converter=dict)


def producible_pairs(structure, values, sweeps, pairs: Sequence[str]) -> PairSelection:
    """Split ``pairs`` into those the model at ``values`` and the ``sweeps`` can produce and
    those they cannot (see the module docstring)."""
    responding = responding_outputs(structure, values)
    axes = [primary_axis(m) for m in sweeps]
    kept, skipped = [], {}
    for pair in pairs:
        output, control = parse_pair(pair, (*OUTPUT_CHANNELS, *structure.outputs),
                                     (*INPUT_CHANNELS, *structure.controls))
        missing = ([f"output {output!r}"] if output not in structure.outputs else []) + (
            [f"input {control!r}"] if control not in structure.controls else [])
        if missing:
            skipped[pair] = (f"the model has no {' and no '.join(missing)} (outputs "
                             f"{', '.join(structure.outputs)}; inputs "
                             f"{', '.join(structure.controls)})")
        elif (reason := unexcited(control, axes)):
            skipped[pair] = reason
        elif output not in responding[control]:
            skipped[pair] = (f"the model's {output} does not respond to {control} (no "
                             f"derivative couples them): its response is identically zero")
        elif output not in sweeps.output_names:
            skipped[pair] = (f"the sweeps record no {output} (their outputs: "
                             f"{', '.join(sweeps.output_names)})")
        elif (reason := _still(output, control, sweeps_exciting(sweeps, control, pair))):
            skipped[pair] = reason
        else:
            kept.append(pair)
    return PairSelection(kept, skipped)


def _still(output: str, control: str, chosen) -> str | None:
    """Why the measured ``output`` cannot be verified on the ``chosen`` sweeps of
    ``control`` (it never moves on them), or None when it moves."""
    if not all(np.ptp(m.channel(output)) == 0 for m in chosen):
        return None
    return (f"the measured {output} never moves on the {control} sweeps "
            f"({', '.join(chosen.names)}); is the column padded?")


__all__ = ["PairSelection", "producible_pairs"]
