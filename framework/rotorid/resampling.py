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

Keep the decimated records' Nyquist frequency at or just above the cutoff
(:func:`white_noise_factor`). With more samples kept, the measurement noise, white before, is
band-limited below their Nyquist frequency and so correlated from one kept sample to the next
(:func:`noise_correlation`: 0.51 for a 4 Hz cutoff kept at every 4th of 50 Hz samples, 0.14 at
every 6th). The filter-error estimator can instead keep every sample (:func:`low_passed`) and
form its innovations at every N-th only (its ``update_every``): its model then steps through
the samples between with their recorded inputs, where decimated records hold or interpolate
the inputs over the kept interval. Every estimator here takes the measurement noise as white,
and its Cramér-Rao bounds come out too small by as much as √(1 + 2·Σ correlations) (×1.31 for the 4th sample,
×1.06 for the 6th); :func:`decimated_maneuver` warns when the neighbours' correlation exceeds
:data:`NOISE_CORRELATION_LIMIT`.
"""

from __future__ import annotations

import math
import warnings

import attrs
import numpy as np
import scipy.integrate
import scipy.signal

from rotorid.data import Maneuver, ManeuverSet
from rotorid.errors import DataError, DataWarning
from rotorid.progress import ordinal

#: Order of the Butterworth low-pass (run twice: zero phase, 8th-order roll-off).
FILTER_ORDER = 4
#: Correlation of white noise between neighbouring kept samples above which
#: :func:`decimated_maneuver` warns.
NOISE_CORRELATION_LIMIT = 0.2
#: Frequency points of the power response :func:`noise_correlation` integrates.
_RESPONSE_POINTS = 1 << 14


def _sections(dt: float, cutoff_hz: float) -> np.ndarray:
    return scipy.signal.butter(FILTER_ORDER, cutoff_hz, fs=1.0 / dt, output="sos")


def white_noise_factor(dt: float, cutoff_hz: float) -> int:
    """The largest decimation factor whose Nyquist frequency 1/(2·factor·dt) is at least
    ``cutoff_hz`` (Hz; dt the records' sample time in s): the one that leaves white
    measurement noise nearest to white (:func:`noise_correlation`)."""
    if not (dt > 0.0 and 0.0 < cutoff_hz < 0.5 / dt):
        raise DataError(f"cutoff {cutoff_hz!r} Hz must lie between 0 and the records' Nyquist "
                        f"frequency {0.5 / dt:.4g} Hz (sample time {dt!r} s)")
    return max(1, math.floor(0.5 / (dt * cutoff_hz) * (1.0 + 1e-9)))


def noise_correlation(dt: float, factor: int, cutoff_hz: float) -> float:
    """Correlation between neighbouring kept samples of white noise (sample time ``dt`` s)
    low-passed at ``cutoff_hz`` by :func:`decimated_maneuver`'s zero-phase filter and kept at
    every ``factor``-th sample: the filter's power response |H|⁴ (both passes) transformed to
    the autocorrelation at the lag factor·dt."""
    frequency, response = scipy.signal.sosfreqz(_sections(dt, cutoff_hz), _RESPONSE_POINTS,
                                                fs=1.0 / dt)
    power = np.abs(response) ** 4
    lagged = power * np.cos(2.0 * np.pi * frequency * factor * dt)
    integral = scipy.integrate.trapezoid
    return float(integral(lagged, frequency) / integral(power, frequency))


def _low_pass(values: np.ndarray, sections: np.ndarray) -> np.ndarray:
    """``values`` (N, k) or (N,) filtered along time, about its first sample."""
    start = values[:1]
    return scipy.signal.sosfiltfilt(sections, values - start, axis=0) + start


def decimated_maneuver(maneuver: Maneuver, factor: int | None, cutoff_hz: float) -> Maneuver:
    """One record low-passed at ``cutoff_hz`` and kept at every ``factor``-th sample.

    Args:
        maneuver: a record (uniformly sampled, as every Maneuver is) of sample time dt.
        factor: samples per kept sample (≥ 1; 1 filters only); None for
            :func:`white_noise_factor`.
        cutoff_hz: the low-pass's −3 dB frequency per pass (Hz), at most the new Nyquist
            frequency 1/(2·factor·dt).
    Inputs, outputs and extra channels are filtered alike; time, units, names and the initial
    state are kept (the initial state is the first sample's, which stays), and the metadata
    gains ``low_passed``, the filtering in words (after any earlier one, so that files written
    from the record, such as filter error's state estimates, say which band they hold).
    """
    time = maneuver.time
    dt = float(np.mean(np.diff(time)))
    if factor is None:
        factor = white_noise_factor(dt, cutoff_hz)
    if not isinstance(factor, (int, np.integer)) or factor < 1:
        raise DataError(f"decimation factor {factor!r}: give a whole number ≥ 1")
    nyquist = 0.5 / (factor * dt)
    if not 0.0 < cutoff_hz <= nyquist * (1.0 + 1e-9):
        raise DataError(f"maneuver {maneuver.name!r}: cutoff {cutoff_hz!r} Hz must lie between "
                        f"0 and the decimated records' Nyquist frequency {nyquist:.4g} Hz "
                        f"(1/(2·{factor}·{dt:.4g} s)); lower the cutoff or the factor")
    correlation = noise_correlation(dt, factor, cutoff_hz)
    if correlation > NOISE_CORRELATION_LIMIT:
        better = white_noise_factor(dt, cutoff_hz)
        fix = (f"keep every {ordinal(better)} sample (rotorid.resampling.white_noise_factor: "
               f"Nyquist frequency {0.5 / (better * dt):.3g} Hz, correlation "
               f"{noise_correlation(dt, better, cutoff_hz):.2f})" if better != factor else
               f"raise the cutoff to the kept samples' Nyquist frequency {nyquist:.3g} Hz")
        warnings.warn(DataWarning(
            f"white measurement noise low-passed at {cutoff_hz:g} Hz and kept at every "
            f"{ordinal(factor)} sample is correlated {correlation:.2f} from one kept sample "
            f"to the next; the estimators take it as white, so their Cramér-Rao bounds come "
            f"out too small: {fix}"), stacklevel=2)
    return _filtered(maneuver, dt, cutoff_hz, int(factor))


def _filtered(maneuver: Maneuver, dt: float, cutoff_hz: float, factor: int) -> Maneuver:
    """``maneuver`` low-passed at ``cutoff_hz`` (checked by the caller), every ``factor``-th
    sample kept."""
    time = maneuver.time
    sections = _sections(dt, cutoff_hz)
    padding = 3 * (2 * len(sections) + 1)          # sosfiltfilt's default edge padding
    if time.size <= padding:
        raise DataError(f"maneuver {maneuver.name!r}: {time.size} samples are too few to "
                        f"filter (more than {padding} needed)")
    kept = slice(None, None, factor)
    done = (f"zero-phase low-pass at {cutoff_hz:g} Hz"
            + (f", every {ordinal(factor)} sample kept" if factor > 1 else ""))
    earlier = maneuver.metadata.get("low_passed")
    return attrs.evolve(
        maneuver, time=time[kept], inputs=_low_pass(maneuver.inputs, sections)[kept],
        outputs=_low_pass(maneuver.outputs, sections)[kept],
        extra_channels={name: _low_pass(values, sections)[kept]
                        for name, values in maneuver.extra_channels.items()},
        metadata={**maneuver.metadata,
                  "low_passed": done if earlier is None else f"{earlier}; then {done}"})


def decimated(maneuvers: ManeuverSet, factor: int | None, cutoff_hz: float) -> ManeuverSet:
    """Every record of ``maneuvers`` through :func:`decimated_maneuver` (same hold).

    Choose the hold deliberately: the low-passed inputs are smooth, and held constant over
    the longer kept interval they lag by half of it, which the fitted derivatives absorb as a
    delay. On doublet data of a known linear model at 3 Hz, every 8th sample, that made M_q
    45 % off, where the first-order hold came within 3 % of the undecimated fit. On the
    helicopter truth model the same half-interval stands in for the actuator and rotor lags a
    structure without delays lacks, and the first-order hold without delays got other
    derivatives wrong (docs/estimation.md, the hover key derivatives)."""
    return attrs.evolve(maneuvers, maneuvers=[decimated_maneuver(m, factor, cutoff_hz)
                                              for m in maneuvers])


def low_passed(maneuvers: ManeuverSet, cutoff_hz: float) -> ManeuverSet:
    """Every record of ``maneuvers`` low-passed at ``cutoff_hz`` (Hz) as
    :func:`decimated_maneuver` does it, every sample kept: for the filter-error estimator's
    ``update_every`` (its innovations formed at every N-th sample only, N the white-noise
    factor, so their sensor noise stays white while the model steps through every sample with
    its recorded input). Output error weighs every sample, whose noise is then correlated:
    give it :func:`decimated` records instead."""
    filtered = []
    for maneuver in maneuvers:
        dt = float(np.mean(np.diff(maneuver.time)))
        if not 0.0 < cutoff_hz < 0.5 / dt:
            raise DataError(f"maneuver {maneuver.name!r}: cutoff {cutoff_hz!r} Hz must lie "
                            f"between 0 and the records' Nyquist frequency {0.5 / dt:.4g} Hz")
        filtered.append(_filtered(maneuver, dt, cutoff_hz, 1))
    return attrs.evolve(maneuvers, maneuvers=filtered)
