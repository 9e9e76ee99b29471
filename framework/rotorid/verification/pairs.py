"""Response pairs: ``output/input`` names such as ``q/long``, the paper's pairs, and the input
axis a sweep excites (the sweeps a pair is verified on)."""

from __future__ import annotations

import numpy as np

from rotorid.data import INPUT_CHANNELS, OUTPUT_CHANNELS
from rotorid.errors import RotoridError, VerificationError

#: The paper's verification pairs (figs. 4, 5, 12, 14): ``output/input``.
PAPER_PAIRS = ("q/long", "p/long", "q/lat", "p/lat", "r/coll", "az/coll", "r/ped", "ay/ped")


def parse_pair(pair: str) -> tuple[str, str]:
    """``"q/long"`` → ``("q", "long")`` (output, input); the error lists the valid names."""
    parts = str(pair).strip().split("/")
    if (len(parts) != 2 or parts[0] not in OUTPUT_CHANNELS
            or parts[1] not in INPUT_CHANNELS):
        raise VerificationError(
            f"unknown response pair {pair!r}; write OUTPUT/INPUT with OUTPUT one of "
            f"{', '.join(OUTPUT_CHANNELS)} and INPUT one of {', '.join(INPUT_CHANNELS)}, "
            f"e.g. 'q/long'")
    return parts[0], parts[1]


def primary_axis(maneuver) -> str:
    """The input axis a sweep excites: ``metadata['axis']``, else the input of largest RMS."""
    axis = maneuver.metadata.get("axis")
    if axis is not None:
        if axis not in INPUT_CHANNELS:
            raise VerificationError(f"maneuver {maneuver.name!r}: metadata axis {axis!r} is "
                                    f"not an input ({', '.join(INPUT_CHANNELS)})")
        return axis
    centred = maneuver.inputs - maneuver.inputs.mean(axis=0)
    return INPUT_CHANNELS[int(np.argmax(np.sqrt(np.mean(centred ** 2, axis=0))))]


def sweeps_exciting(sweeps, control: str, pair: str,
                    error: type[RotoridError] = VerificationError):
    """The sweeps of the :class:`~rotorid.data.ManeuverSet` ``sweeps`` whose
    :func:`primary_axis` is ``control``, as a ManeuverSet; when none is, raises ``error``
    naming ``pair`` and the axes the sweeps do excite."""
    axes = [primary_axis(m) for m in sweeps]
    names = {m.name for m, axis in zip(sweeps, axes) if axis == control}
    if not names:
        raise error(f"pair {pair}: no sweep excites {control!r}; the sweeps excite "
                    f"{', '.join(sorted(set(axes)))}")
    return sweeps.select(lambda m: m.name in names)
