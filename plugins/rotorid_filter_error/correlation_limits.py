"""Upper limits of the coloured disturbances' and gusts' correlation times (s).

A Gauss-Markov disturbance whose correlation time approaches the record's length is, within
the record, a slow drift that the derivatives can explain as well: on the hover case in
moderate turbulence the heave disturbance's free T_w ran to about 28 s over 15 s records and
traded against Z_w (docs/estimation.md, "The heave disturbance's correlation time"). The
``longest_correlation`` option of the filter-error estimator caps chosen correlation times;
a fifth of the shortest record (so that every record spans at least five of them) is the rule
the documentation measures.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from rotorid.errors import EstimationError

#: Longest correlation time of a disturbance or gust without a limit of the user's, s (a
#: random walk for the record lengths flown).
UNLIMITED_CORRELATION = 1000.0


def correlation_limits(value) -> dict[str, float]:
    """The ``longest_correlation`` option checked: a mapping of correlation-time parameter
    names (``T_<state>`` of a disturbance, ``Tg_<state>`` of a gust) to positive finite
    limits in s; None is no limit."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise EstimationError(f"longest_correlation maps correlation times to limits in s, "
                              f"e.g. {{'T_w': 3.0}}; got {value!r}")
    limits = {}
    for name, limit in value.items():
        if not isinstance(name, str) or not name.startswith(("T_", "Tg_")):
            raise EstimationError(f"longest_correlation names {name!r}, which is no "
                                  f"correlation time: T_<state> of a disturbance or "
                                  f"Tg_<state> of a gust")
        try:
            seconds = float(limit)
        except (TypeError, ValueError):
            seconds = math.nan
        if not (math.isfinite(seconds) and seconds > 0):
            raise EstimationError(f"longest_correlation gives {name} the limit {limit!r}; "
                                  f"a limit is a positive time in s")
        limits[name] = seconds
    return limits


def correlation_names(disturbances: tuple[str, ...], gusts: tuple[str, ...]) -> tuple[str, ...]:
    """The correlation-time parameters of a noise model: ``T_<state>`` of each disturbance,
    then ``Tg_<state>`` of each gust."""
    return tuple(f"T_{s}" for s in disturbances) + tuple(f"Tg_{s}" for s in gusts)


def check_limited(limits: Mapping[str, float], disturbances: tuple[str, ...],
                  gusts: tuple[str, ...]) -> None:
    """Refuse ``limits`` on a correlation time the noise model (its ``disturbances`` and
    ``gusts``) does not have."""
    names = correlation_names(disturbances, gusts)
    unknown = [name for name in limits if name not in names]
    if unknown:
        having = (f"its correlation times are {', '.join(names)}" if names else
                  "it has no disturbances or gusts: give those first")
        raise EstimationError(f"longest_correlation names {', '.join(unknown)}, not a "
                              f"correlation time of this noise model; {having}")


def longest_correlations(limits: Mapping[str, float], disturbances: tuple[str, ...],
                         gusts: tuple[str, ...], shortest: np.ndarray) -> np.ndarray:
    """The upper bound of each correlation time (``correlation_names`` order), s: its limit
    (``limits`` checked by :func:`check_limited`), or :data:`UNLIMITED_CORRELATION`; a limit
    not above its ``shortest`` allowed value (same order, s) is refused."""
    names = correlation_names(disturbances, gusts)
    longest = np.array([limits.get(name, UNLIMITED_CORRELATION) for name in names])
    short = [f"{name} ({limit:g} s, shortest {low:g} s)"
             for name, limit, low in zip(names, longest, shortest) if limit <= low]
    if short:
        raise EstimationError(f"longest_correlation holds {', '.join(short)} at or below "
                              f"the shortest correlation time the fit allows; give a longer "
                              f"limit")
    return longest
