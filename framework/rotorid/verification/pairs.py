"""Response pairs: ``output/input`` names such as ``q/long``, the paper's pairs, a model's
default pairs, and the input axis a sweep excites (the sweeps a pair is verified on)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rotorid.data import INPUT_CHANNELS, OUTPUT_CHANNELS
from rotorid.errors import RotoridError, VerificationError

#: The paper's verification pairs (figs. 4, 5, 12, 14): ``output/input``.
PAPER_PAIRS = ("q/long", "p/long", "q/lat", "p/lat", "r/coll", "az/coll", "r/ped", "ay/ped")


def parse_pair(pair: str, outputs: Sequence[str] = OUTPUT_CHANNELS,
               inputs: Sequence[str] = INPUT_CHANNELS) -> tuple[str, str]:
    """``"q/long"`` → ``("q", "long")`` (output, input), with the output one of ``outputs``
    and the input one of ``inputs`` (default the helicopter's channels; a model's own signals
    for a model); the error lists the valid names."""
    parts = str(pair).strip().split("/")
    if len(parts) != 2 or parts[0] not in outputs or parts[1] not in inputs:
        raise VerificationError(
            f"unknown response pair {pair!r}; write OUTPUT/INPUT with OUTPUT one of "
            f"{', '.join(outputs)} and INPUT one of {', '.join(inputs)}, "
            f"e.g. '{outputs[0]}/{inputs[0]}'")
    return parts[0], parts[1]


def default_pairs(outputs: Sequence[str], inputs: Sequence[str]) -> tuple[str, ...]:
    """The pairs a model with these outputs and inputs is verified on by default: the paper's
    pairs it has (q/long and az/coll for the longitudinal template), else every
    ``output/input`` pair of the model."""
    own = tuple(p for p in PAPER_PAIRS
                if p.split("/")[0] in outputs and p.split("/")[1] in inputs)
    return own or tuple(f"{o}/{i}" for i in inputs for o in outputs)


def primary_axis(maneuver) -> str:
    """The input axis a sweep excites: ``metadata['axis']``, else the input of largest RMS."""
    axis = maneuver.metadata.get("axis")
    names = maneuver.input_names
    if axis is not None:
        if axis not in names:
            raise VerificationError(f"maneuver {maneuver.name!r}: metadata axis {axis!r} is "
                                    f"not one of its inputs ({', '.join(names)})")
        return axis
    centred = maneuver.inputs - maneuver.inputs.mean(axis=0)
    return names[int(np.argmax(np.sqrt(np.mean(centred ** 2, axis=0))))]


#: Fewest reversals of a frequency sweep's input (a sweep runs through many cycles; a 3211
#: multistep reverses 3 times, a doublet once).
SWEEP_REVERSALS = 6
#: Hysteresis of a reversal, relative to the input's half range about its median.
REVERSAL_HYSTERESIS = 0.25


def input_reversals(signal: np.ndarray) -> int:
    """How often ``signal`` (N,) crosses from above to below its median or back, each
    crossing counted once it passes :data:`REVERSAL_HYSTERESIS` of its half range."""
    centred = np.asarray(signal, dtype=float) - np.median(signal)
    threshold = REVERSAL_HYSTERESIS * 0.5 * float(np.ptp(signal))
    sides = np.sign(centred[np.abs(centred) > threshold]) if threshold > 0.0 else ()
    return int(np.count_nonzero(np.diff(sides))) if len(sides) else 0


def lowest_swept_frequency(maneuver) -> float | None:
    """The lowest frequency a sweep's input (:func:`primary_axis`) runs through, rad/s: π over
    its longest half cycle between reversals (:data:`REVERSAL_HYSTERESIS`), the quiet start
    and end left out; None for an input that reverses fewer than :data:`SWEEP_REVERSALS`
    times. A sweep's slowest cycles have its full amplitude, so the hysteresis finds them."""
    signal = maneuver.channel(primary_axis(maneuver))
    centred = np.asarray(signal, dtype=float) - np.median(signal)
    threshold = REVERSAL_HYSTERESIS * 0.5 * float(np.ptp(signal))
    if threshold <= 0.0:
        return None
    outside = np.flatnonzero(np.abs(centred) > threshold)
    sides = np.sign(centred[outside])
    changes = outside[1:][np.diff(sides) != 0]
    if changes.size < SWEEP_REVERSALS:
        return None
    longest = float(np.max(np.diff(maneuver.time[changes])))
    return float(np.pi / longest)


def not_a_sweep(maneuver) -> str | None:
    """Why ``maneuver`` looks like a step input (multistep, doublet) rather than a frequency
    sweep: its excited input (:func:`primary_axis`) reverses fewer than
    :data:`SWEEP_REVERSALS` times. None when it looks like a sweep."""
    axis = primary_axis(maneuver)
    reversals = input_reversals(maneuver.channel(axis))
    if reversals >= SWEEP_REVERSALS:
        return None
    return (f"its input {axis} reverses {reversals} time(s) in {maneuver.duration:.0f} s: a "
            f"step input (multistep, doublet), not a frequency sweep. Its frequency responses "
            f"are coherent only near the few frequencies it excites, so the verdicts rest on "
            f"few points; verify on frequency sweeps")


def step_input_notes(sweeps) -> list[str]:
    """``"NAME: why"`` for each maneuver of ``sweeps`` that looks like a step input
    (:func:`not_a_sweep`); none when the maneuvers state their ``kind`` (the sweeps were then
    chosen by it)."""
    if any("kind" in m.metadata for m in sweeps):
        return []
    return [f"{m.name}: {doubt}" for m in sweeps if (doubt := not_a_sweep(m)) is not None]


def unexcited(control: str, axes) -> str | None:
    """Why no sweep can verify a pair on ``control`` when the sweeps excite ``axes`` (their
    :func:`primary_axis`), or None when one of them excites it."""
    if control in axes:
        return None
    return f"no sweep excites {control!r} (the sweeps excite {', '.join(sorted(set(axes)))})"


def sweeps_exciting(sweeps, control: str, pair: str,
                    error: type[RotoridError] = VerificationError):
    """The sweeps of the :class:`~rotorid.data.ManeuverSet` ``sweeps`` whose
    :func:`primary_axis` is ``control``, as a ManeuverSet; when none is, raises ``error``
    naming ``pair`` and the axes the sweeps do excite (:func:`unexcited`)."""
    axes = [primary_axis(m) for m in sweeps]
    reason = unexcited(control, axes)
    if reason is not None:
        raise error(f"pair {pair}: {reason}")
    names = {m.name for m, axis in zip(sweeps, axes) if axis == control}
    return sweeps.select(lambda m: m.name in names)
