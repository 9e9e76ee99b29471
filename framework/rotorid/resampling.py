"""Records brought down to the band a model describes: zero-phase low-pass, then decimation.

A linear model over the rigid body (or the body and the flapping) describes the aircraft up to
some frequency; above it lie the actuators, the coning, the inflow and the rotor's other modes.
Output error hardly notices them: its residuals are dominated by the low-frequency fit. An
estimator that weighs one-step prediction errors, as the filter-error method does, weighs every
frequency up to the sampling's Nyquist frequency alike, and there the model is wrong by the
whole of the response it lacks (docs/estimation.md, the heave pair in hover). Filtering inputs
and outputs with one linear filter keeps a linear system's input-output relation; dropping the
samples above the filter's band then leaves the estimator the band the model describes.

The filter is a Butterworth low-pass run forwards and backwards (``scipy.signal.sosfiltfilt``:
zero phase, the magnitude squared), applied to each channel's deviation from its first sample
so that a trim offset causes no start transient. Columns read from files can be decimated as
they are read (:mod:`rotorid.ingestion`, ``resample = "decimate"``: a FIR at the new Nyquist
frequency); this works on maneuvers in memory, generated ones included, with the cutoff
chosen by the band the model describes.
"""

from __future__ import annotations

import attrs
import numpy as np
import scipy.signal

from rotorid.data import Maneuver, ManeuverSet
from rotorid.errors import DataError

#: Order of the Butterworth low-pass (run twice: zero phase, 8th-order roll-off).
FILTER_ORDER = 4


def _low_pass(values: np.ndarray, sections: np.ndarray) -> np.ndarray:
    """``values`` (N, k) or (N,) filtered along time, about its first sample."""
    start = values[:1]
    return scipy.signal.sosfiltfilt(sections, values - start, axis=0) + start


def decimated_maneuver(maneuver: Maneuver, factor: int, cutoff_hz: float) -> Maneuver:
    """One record low-passed at ``cutoff_hz`` and kept at every ``factor``-th sample.

    Args:
        maneuver: a record (uniformly sampled, as every Maneuver is) of sample time dt.
        factor: samples per kept sample (≥ 1; 1 filters only).
        cutoff_hz: the low-pass's −3 dB frequency per pass (Hz), below the new Nyquist
            frequency 1/(2·factor·dt).
    Inputs, outputs and extra channels are filtered alike; time, units, names, metadata and
    the initial state are kept (the initial state is the first sample's, which stays).
    """
    if not isinstance(factor, (int, np.integer)) or factor < 1:
        raise DataError(f"decimation factor {factor!r}: give a whole number ≥ 1")
    time = maneuver.time
    dt = float(np.mean(np.diff(time)))
    nyquist = 0.5 / (factor * dt)
    if not 0.0 < cutoff_hz < nyquist:
        raise DataError(f"maneuver {maneuver.name!r}: cutoff {cutoff_hz!r} Hz must lie between "
                        f"0 and the decimated records' Nyquist frequency {nyquist:.4g} Hz "
                        f"(1/(2·{factor}·{dt:.4g} s)); lower the cutoff or the factor")
    sections = scipy.signal.butter(FILTER_ORDER, cutoff_hz, fs=1.0 / dt, output="sos")
    padding = 3 * (2 * len(sections) + 1)          # sosfiltfilt's default edge padding
    if time.size <= padding:
        raise DataError(f"maneuver {maneuver.name!r}: {time.size} samples are too few to "
                        f"filter (more than {padding} needed)")
    kept = slice(None, None, int(factor))
    return attrs.evolve(
        maneuver, time=time[kept], inputs=_low_pass(maneuver.inputs, sections)[kept],
        outputs=_low_pass(maneuver.outputs, sections)[kept],
        extra_channels={name: _low_pass(values, sections)[kept]
                        for name, values in maneuver.extra_channels.items()})


def decimated(maneuvers: ManeuverSet, factor: int, cutoff_hz: float) -> ManeuverSet:
    """Every record of ``maneuvers`` through :func:`decimated_maneuver` (same hold)."""
    return attrs.evolve(maneuvers, maneuvers=[decimated_maneuver(m, factor, cutoff_hz)
                                              for m in maneuvers])
