"""Preparing recorded columns for a :class:`~rotorid.data.Maneuver`: units per channel,
resampling onto a uniform grid, trim removal.

Flight data rarely arrive as rotorid wants them (uniform time, perturbations from trim, one
unit system). An :class:`Ingestion` says what to do about it; :func:`prepare_columns` does it
to one record's columns, in this order:

1. **channel units**: a channel recorded in another unit than its unit system's
   (``{"q": "rad/s"}`` in flight-test data) is converted into the system's unit;
2. **resampling** (only when asked): ``"linear"`` interpolates every channel onto a uniform
   grid (the median step, or ``sample_time``); ``"decimate"`` low-passes with a zero-phase FIR
   filter and keeps every k-th sample, so that ``sample_time`` carries no aliased content.
   Steps longer than :data:`GAP_FACTOR` median steps are time gaps, and NaN samples are
   dropouts: both are warned about (:class:`~rotorid.errors.DataWarning`) and interpolated
   across;
3. **trim removal**: ``"first-second"`` subtracts each channel's mean over the first second;
   a mapping subtracts stated values, given in the unit system ``trim_units`` (the model's,
   as a file source sets it) or else in the record's own (after step 1).

Each step taken is stated in the returned notes (``converted_units``, ``resampled``,
``trim_removed``), which become the maneuver's metadata.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping

import attrs
import numpy as np

from rotorid.errors import DataError, DataWarning, SignalError
from rotorid.model.signals import ChannelMap, ModelSignals
from rotorid.units import (
    CHANNEL_KINDS,
    canonical_unit,
    conversion_factor,
    unit_fits_kind,
    unit_system,
    units_of_kind,
)

RESAMPLE_METHODS = ("linear", "decimate")
#: A step longer than this many median steps is a time gap.
GAP_FACTOR = 3.0
#: Seconds at the start whose mean is the trim under ``trim="first-second"``.
TRIM_WINDOW = 1.0


def _check_trim(instance, attribute, value):
    if value is None or value == "first-second":
        return
    if not isinstance(value, Mapping) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value.values()):
        raise DataError(f"trim {value!r} is neither 'first-second' nor channel = value pairs; "
                        f"give trim = \"first-second\" or e.g. {{theta = 5.0, az = -32.17}}")


def _check_resample(instance, attribute, value):
    if value is not None and value not in RESAMPLE_METHODS:
        raise DataError(f"unknown resampling method {value!r}; use one of "
                        f"{', '.join(RESAMPLE_METHODS)}")


def _optional_positive(value):
    if value is None:
        return None
    value = float(value)
    if not value > 0:
        raise DataError(f"sample_time must be a positive number of seconds, got {value!r}")
    return value


def _units(value) -> dict[str, str]:
    if not isinstance(value, Mapping):
        raise DataError(f"channel_units must map channel names to units, e.g. "
                        f"{{q = \"rad/s\"}}, got {value!r}")
    return {str(k): canonical_unit(v) for k, v in value.items()}


def _channel_map(value) -> ChannelMap:
    if isinstance(value, ChannelMap):
        return value
    if not isinstance(value, Mapping):
        raise DataError(f"channels must be a table COLUMN = {{ signal = ..., unit = ... }}, "
                        f"got {value!r}")
    return ChannelMap.from_mapping(value)


@attrs.frozen
class Ingestion:
    """What to do to recorded columns before they become a maneuver.

    Attributes:
        trim: ``None`` (the data are perturbations already), ``"first-second"`` or a mapping
            channel → trim value to subtract.
        resample: ``None`` (non-uniform time is refused), ``"linear"`` or ``"decimate"``.
        sample_time: the grid's interval in s (default: the median step); ``"decimate"``
            needs one longer than the record's step.
        channel_units: channel → the unit it was recorded in, when that differs from its unit
            system's (outputs and extra channels only; controls keep their unit).
        channels: a :class:`~rotorid.model.signals.ChannelMap` (or a ``[channels]`` table)
            linking the record's own column names to channels, with unit, scale and offset;
            applied first, by :meth:`mapped`.
        signals: the model's signals (optional): their kinds decide unit conversions, and a
            maneuver built with them takes the model's controls and outputs as its inputs
            and outputs (e.g. ``elevator`` and ``alpha`` of an aeroplane).
        keep_columns: further columns kept as recorded, as extra channels: those a model of
            one's own reads through its own channel map
            (:attr:`rotorid.estimation.integrated.IntegratedModel.columns`); a record holding
            them needs none of the inputs and outputs.
        trim_units: the unit system stated trim values are in (``"flight-test"``, ``"si"``;
            the model's), converted per channel kind into the record's; ``None``: the
            record's own. Controls are in the model's unit after the channel map already.
    """

    trim: str | Mapping[str, float] | None = attrs.field(default=None, validator=_check_trim)
    resample: str | None = attrs.field(default=None, validator=_check_resample)
    sample_time: float | None = attrs.field(default=None, converter=_optional_positive)
    channel_units: Mapping[str, str] = attrs.field(factory=dict, converter=_units)
    channels: ChannelMap = attrs.field(factory=ChannelMap, converter=_channel_map)
    signals: ModelSignals | None = None
    keep_columns: tuple[str, ...] = attrs.field(default=(), converter=tuple)
    trim_units: str | None = None

    def _control_factor(self, link) -> float:
        """Factor from a control column's unit into the unit the model states for that control
        (1 where it states none: controls keep the data's unit)."""
        if self.signals is None or link.signal not in self.signals.inputs:
            return 1.0
        stated = self.signals.inputs[link.signal].unit
        if stated == link.unit or stated == "%":
            return 1.0
        try:
            return conversion_factor(link.unit, stated)
        except SignalError:
            raise DataError(f"{self.channels.source}: column {link.column!r} is in {link.unit}, "
                            f"which does not convert into {link.signal!r}'s {stated}; give the "
                            f"column's unit in a {stated}-like unit") from None

    def kind(self, channel: str) -> str | None:
        """Physical kind of ``channel``: the model's signal's when :attr:`signals` declares
        it, else the shipped channel's, else ``None`` (read as recorded)."""
        if self.signals is not None and channel in self.signals.all:
            return self.signals.all[channel].kind
        return CHANNEL_KINDS.get(channel)

    def __attrs_post_init__(self):
        if self.resample == "decimate" and self.sample_time is None:
            raise DataError("resample = 'decimate' needs a sample_time (the interval after "
                            "decimation, s)")
        linked = {link.column: link.signal for link in self.channels.links}
        columns = [name for name in (self.trim if isinstance(self.trim, Mapping) else ())
                   if name in linked and name != linked[name]]
        if columns:
            raise DataError(f"trim value for column {columns[0]!r}, which {self.channels.source} "
                            f"links to {linked[columns[0]]!r}: give the trim of "
                            f"{linked[columns[0]]!r} instead, in the model's units")
        if self.signals is not None:
            targets = set(self.signals.all.names) | set(CHANNEL_KINDS) | set(self.keep_columns)
            strange = [link for link in self.channels.links if link.signal not in targets]
            if strange:
                raise DataError(
                    f"{self.channels.source}: column {strange[0].column!r} is linked to "
                    f"{strange[0].signal!r}, which is no signal of the model; its signals are "
                    f"{', '.join(self.signals.all.names)} (and time); correct the signal name")

    def mapped(self, columns: Mapping[str, np.ndarray], where: str
               ) -> tuple[dict[str, np.ndarray], "Ingestion"]:
        """``columns`` with each column the map links read as its channel (``scale · column
        + offset`` under the channel's name), and this ingestion without the map and with
        the linked outputs' units added to ``channel_units`` (controls keep the data's
        unit). A record that holds none of the linked columns, its channels under their own
        names (as ``rotorid simulate`` writes them), is read as it is. ``where`` names the
        record in errors."""
        links = self.channels.links
        if not links:
            return dict(columns), self
        source = self.channels.source
        linked = {link.column for link in links}
        result = {k: v for k, v in columns.items() if k not in linked}
        units = dict(self.channel_units)
        # a record holding none of the linked columns but the channels under their own names
        # is in rotorid's naming already (rotorid simulate's files): read as it is
        own_naming = not any(link.column in columns for link in links)
        for link in links:
            if link.column not in columns and own_naming and link.signal in columns:
                continue
            if link.column not in columns:
                raise DataError(f"{where} has no column {link.column!r} (linked to "
                                f"{link.signal!r} in {source}); columns: "
                                f"{', '.join(columns)}; correct the column name in {source}")
            if link.signal in result:
                raise DataError(f"{where}: column {link.signal!r} and column {link.column!r} "
                                f"(linked to it in {source}) both give {link.signal!r}; keep "
                                f"one")
            kind = self.kind(link.signal)
            if kind is not None and not unit_fits_kind(link.unit, kind):
                raise DataError(f"{source}: column {link.column!r} has unit {link.unit}, which "
                                f"does not fit {link.signal!r} ({kind}); give one of "
                                f"{', '.join(units_of_kind(kind))}")
            result[link.signal] = (link.scale * np.asarray(columns[link.column], dtype=float)
                                   + link.offset) * self._control_factor(link)
            if kind not in (None, "control"):
                units[link.signal] = link.unit
        return result, attrs.evolve(self, channels=ChannelMap(), channel_units=units)

    @classmethod
    def coerce(cls, value) -> "Ingestion":
        """An :class:`Ingestion` from itself, ``None`` or a mapping of its attributes."""
        if isinstance(value, cls):
            return value
        return cls(**dict(value or {}))


def _convert_units(columns: dict, ingestion: "Ingestion", units: str, where: str) -> dict:
    system = unit_system(units)
    for channel, unit in ingestion.channel_units.items():
        if channel not in columns:
            continue
        kind = ingestion.kind(channel)
        if kind is None or kind == "control":
            raise DataError(f"{where}: channel {channel!r} cannot be given a unit ({unit}): "
                            f"units convert outputs and extra channels, controls keep theirs")
        target = canonical_unit(system.unit_of(kind))
        try:
            factor = conversion_factor(unit, target)
        except SignalError as error:
            raise DataError(f"{where}: channel {channel!r}: {error}") from None
        columns[channel] = columns[channel] * factor
    return columns


def _uniform_grid(time: np.ndarray, step: float) -> np.ndarray:
    count = int(np.floor((time[-1] - time[0]) / step + 1e-9)) + 1
    return time[0] + step * np.arange(count)


def _warn_gaps(time: np.ndarray, step: float, where: str) -> None:
    """One warning naming the time gaps (steps over :data:`GAP_FACTOR` grid steps)."""
    steps = np.diff(time)
    gaps = np.flatnonzero(steps > GAP_FACTOR * step)
    if gaps.size:
        row = gaps[np.argmax(steps[gaps])]
        warnings.warn(f"{where}: {gaps.size} time gap(s) longer than {GAP_FACTOR:g} steps of "
                      f"{step:.4g} s, the longest {steps[row]:.4g} s after t = "
                      f"{time[row]:.6g} s; resampling interpolates across them, cut the record "
                      f"there if the aircraft moved in between", DataWarning, stacklevel=5)


def _fill_nan_gaps(columns: dict, where: str) -> tuple[dict, int]:
    """Every channel with NaN samples (dropouts) interpolated across them, with one
    :class:`~rotorid.errors.DataWarning` per channel naming the gaps; and how many samples
    were filled."""
    time = columns["time"]
    filled, count = dict(columns), 0
    for name, values in columns.items():
        missing = np.isnan(values)
        if name == "time" or not missing.any():
            continue
        if missing.all():
            raise DataError(f"{where}: channel {name!r} holds no number at all")
        starts = np.flatnonzero(np.diff(np.concatenate([[0], missing.astype(int)])) == 1)
        warnings.warn(f"{where}: channel {name!r} has {starts.size} NaN gap(s), "
                      f"{int(missing.sum())} samples, the first at {moment_text(time, starts[0])} "
                      f"(a dropout); resampling interpolates across them",
                      DataWarning, stacklevel=5)
        filled[name] = np.interp(time, time[~missing], values[~missing])
        count += int(missing.sum())
    return filled, count


def _resample(columns: dict, ingestion: Ingestion, where: str) -> tuple[dict, str | None]:
    time = columns["time"]
    steps = np.diff(time)
    if time.size < 2 or np.any(steps <= 0) or not np.all(np.isfinite(time)):
        raise DataError(f"{where}: channel 'time' must be finite and increasing to be resampled")
    columns, filled = _fill_nan_gaps(columns, where)
    median = float(np.median(steps))
    uniform = np.allclose(steps, median, rtol=1e-6, atol=1e-9)
    if uniform and ingestion.sample_time in (None, median):
        return columns, (f"linear interpolation across {filled} NaN samples on the recorded "
                         f"{median:.6g} s grid" if filled else None)
    _warn_gaps(time, max(median, ingestion.sample_time or 0.0), where)
    if ingestion.resample == "linear":
        step = ingestion.sample_time or median
        grid = _uniform_grid(time, step)
        note = (f"linear interpolation onto a uniform {step:.6g} s grid (recorded steps "
                f"{steps.min():.6g}–{steps.max():.6g} s, median {median:.6g} s)")
        return {k: (grid if k == "time" else np.interp(grid, time, v))
                for k, v in columns.items()}, note
    from scipy.signal import firwin, resample_poly

    factor = int(round(ingestion.sample_time / median))
    if factor < 2:
        raise DataError(f"{where}: decimation to {ingestion.sample_time:g} s needs a record "
                        f"sampled at least twice as fast (median step {median:.6g} s); use "
                        f"resample = 'linear'")
    fine = _uniform_grid(time, ingestion.sample_time / factor)
    n = (fine.size - 1) // factor * factor + 1
    fine = fine[:n]
    resampled = {"time": fine[::factor]}
    # the FIR of scipy.signal.decimate (Hamming, 20·factor + 1 taps), run with its delay
    # compensated (zero phase) over the record extended by the straight line through its ends,
    # not by zeros, which would pull the first and last samples of a record towards zero (and
    # a trim offset with them)
    window = firwin(20 * factor + 1, 1.0 / factor, window="hamming")
    for name, values in columns.items():
        if name != "time":
            resampled[name] = resample_poly(np.interp(fine, time, values), 1, factor,
                                            window=window, padtype="line")
    note = (f"anti-aliased decimation by {factor} (zero-phase FIR low-pass, after linear "
            f"interpolation onto a {ingestion.sample_time / factor:.6g} s grid) to "
            f"{ingestion.sample_time:.6g} s (recorded median step {median:.6g} s)")
    return resampled, note


def _remove_trim(columns: dict, ingestion: "Ingestion", units: str, where: str
                 ) -> tuple[dict, dict]:
    """``columns`` (in the unit system ``units``) less their trim, and the trim removed per
    channel, stated in ``ingestion.trim_units`` when set (else in ``units``)."""
    trim = ingestion.trim
    factors = {k: _trim_factor(ingestion, k, units) for k in columns if k != "time"}
    if trim == "first-second":
        time = columns["time"]
        window = time <= time[0] + TRIM_WINDOW + 1e-9
        values = {k: float(np.mean(v[window])) for k, v in columns.items() if k != "time"}
    else:
        unknown = sorted(set(trim) - set(columns) - {"time"})
        if unknown or "time" in trim:
            raise DataError(f"{where}: trim value for unknown channel "
                            f"{(unknown or ['time'])[0]!r}; channels: "
                            f"{', '.join(c for c in columns if c != 'time')}")
        values = {k: float(v) * factors[k] for k, v in trim.items()}
    removed = {k: v / factors[k] for k, v in values.items()}
    return {k: v - values.get(k, 0.0) for k, v in columns.items()}, removed


def _trim_factor(ingestion: "Ingestion", channel: str, units: str) -> float:
    """Factor from ``channel``'s unit in ``ingestion.trim_units`` into its unit in ``units``
    (1 for controls, channels of no known kind, or no ``trim_units``)."""
    kind = ingestion.kind(channel)
    if ingestion.trim_units is None or kind in (None, "control"):
        return 1.0
    return conversion_factor(unit_system(ingestion.trim_units).unit_of(kind),
                             unit_system(units).unit_of(kind))


def prepare_columns(columns: Mapping[str, np.ndarray], units: str,
                    ingestion: Ingestion | Mapping | None, where: str
                    ) -> tuple[dict[str, np.ndarray], dict]:
    """One record's ``columns`` (name → (N,) values, including ``time`` in s) after the
    steps of ``ingestion`` (see the module docstring), in the unit system ``units``; and the
    notes stating each step taken, for the maneuver's metadata. ``where`` names the record in
    errors and warnings."""
    ingestion = Ingestion.coerce(ingestion)
    prepared = {k: np.asarray(v, dtype=float).reshape(-1) for k, v in columns.items()}
    notes: dict = {}
    if ingestion.channel_units:
        prepared = _convert_units(prepared, ingestion, units, where)
        notes["converted_units"] = {k: v for k, v in ingestion.channel_units.items()
                                  if k in prepared}
    if ingestion.resample is not None:
        prepared, note = _resample(prepared, ingestion, where)
        if note:
            notes["resampled"] = note
    if ingestion.trim is not None:
        prepared, notes["trim_removed"] = _remove_trim(prepared, ingestion, units, where)
        notes["trim_units"] = unit_system(ingestion.trim_units or units).name
    return prepared, notes


def moment_text(time: np.ndarray, index: int) -> str:
    """When sample ``index`` of a record with ``time`` (s) lies: ``t = 12.34 s``, or for a
    record that does not start at zero (a clock) the time into it with the recorded value
    beside it (``12.34 s into the record (t = 15863542.34 s)``)."""
    into = float(time[index] - time[0])
    if time[0] == 0:
        return f"t = {into:.4g} s"
    return f"{into:.4g} s into the record (t = {float(time[index]):.12g} s)"
