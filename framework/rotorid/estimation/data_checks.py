"""Checks of identification data before a fit: what would make the output-error cost
meaningless (a fitted output that never varies, two fitted outputs that are the same
record, fewer samples than parameters) is named with the channel and the cause instead of
surfacing as a diverging or singular fit."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rotorid.data import OUTPUT_CHANNELS, ManeuverSet
from rotorid.errors import DataError

#: An output whose standard deviation over all maneuvers is below this fraction of its
#: largest magnitude (or exactly zero) carries no information.
CONSTANT_FRACTION = 1e-9


def check_fit_data(maneuvers: ManeuverSet, outputs: Sequence[str] | None,
                   n_parameters: int) -> None:
    """Raise :class:`DataError` naming the channel and the fix when ``maneuvers`` cannot
    inform a fit of ``n_parameters`` parameters on ``outputs`` (``None``: all eight)."""
    names = tuple(n for n in (outputs or OUTPUT_CHANNELS) if n in OUTPUT_CHANNELS)
    columns = [OUTPUT_CHANNELS.index(n) for n in names]
    records = np.concatenate([m.outputs[:, columns] for m in maneuvers])
    for name, record in zip(names, records.T):
        if np.std(record) <= CONSTANT_FRACTION * np.max(np.abs(record)):
            raise DataError(f"output {name!r} is constant in every maneuver (value "
                            f"{record[0]:.6g}): it carries no information and makes the noise "
                            f"covariance singular; check the recording or leave it out with "
                            f"--outputs")
    for i, first in enumerate(names):
        for j in range(i + 1, len(names)):
            if np.array_equal(records[:, i], records[:, j]):
                raise DataError(f"outputs {first!r} and {names[j]!r} hold the same record in "
                                f"every maneuver (a channel recorded twice?); leave one out "
                                f"with --outputs")
    if records.size < n_parameters:
        raise DataError(f"{records.size} output samples cannot determine {n_parameters} "
                        f"parameters; give longer or more maneuvers or fewer parameters")
