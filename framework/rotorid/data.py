"""Maneuver time histories.

A :class:`Maneuver` is one record: uniformly sampled time, the control inputs and the measured
outputs, all perturbations from trim, plus metadata. A :class:`ManeuverSet` is what
estimators, simulators and verification consume: several maneuvers (lengths and sample times
may differ) and the hold of the inputs between samples.

The default layout is the six-dof helicopter's: inputs :data:`INPUT_CHANNELS`, outputs
:data:`OUTPUT_CHANNELS`. A record may hold fewer of them (``input_names``, ``output_names``,
in that order), e.g. the longitudinal channels only; models pick what they use by name and a
channel a model uses but the record lacks is named when it is asked for.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import attrs
import numpy as np

from rotorid.errors import DataError
from rotorid.frozen import readonly_array
from rotorid.ingestion import Ingestion, prepare_columns
from rotorid.model.structure import CONTROLS, OUTPUTS, STATES
from rotorid.notebook import (
    maneuver_html,
    maneuver_set_html,
    maneuver_set_summary,
    maneuver_summary,
)
from rotorid.units import CHANNEL_KINDS, unit_system

INPUT_CHANNELS = CONTROLS
OUTPUT_CHANNELS = OUTPUTS
ALL_CHANNELS = ("time",) + INPUT_CHANNELS + OUTPUT_CHANNELS
#: The gusts a record may carry as extra channels: the air's velocity (u, v, w) and rotation
#: (p, q, r) in body axes, named as filter error names its gust states (``g_<state>``).
GUST_CHANNELS = ("g_u", "g_v", "g_w", "g_p", "g_q", "g_r")
HOLDS = ("zoh", "foh")
#: Relative tolerance on sample-interval uniformity.
UNIFORM_TOLERANCE = 1e-6


def check_time(time: np.ndarray, where: str) -> float:
    """Validate a time vector (finite, increasing, uniform); return the sample time in s."""
    if time.ndim != 1 or time.size < 2:
        raise DataError(f"{where}: time must be a 1-D array with at least 2 samples")
    bad = np.flatnonzero(~np.isfinite(time))
    if bad.size:
        raise DataError(f"{where}: channel 'time' is not finite at row {bad[0]}")
    steps = np.diff(time)
    if np.any(steps <= 0):
        row = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise DataError(f"{where}: channel 'time' does not increase at row {row} "
                        f"({time[row - 1]} → {time[row]})")
    dt = (time[-1] - time[0]) / (time.size - 1)
    # differences of large clock times (epoch seconds: 1.8e9 s) carry their round-off
    rounding = 8.0 * np.finfo(float).eps * float(np.max(np.abs(time)))
    off = np.abs(steps - dt) > UNIFORM_TOLERANCE * max(dt, 1e-12) + 1e-9 + rounding
    if np.any(off):
        # The first interval that differs from the typical (median) one: a single jump makes
        # every interval differ from the mean.
        typical = float(np.median(steps))
        far = np.abs(steps - typical) > UNIFORM_TOLERANCE * typical + 1e-9 + rounding
        row = int(np.flatnonzero(far if far.any() else off)[0]) + 1
        raise DataError(f"{where}: channel 'time' is not uniformly sampled at row {row} "
                        f"(step {steps[row - 1]:.6g} s, expected {typical:.6g} s); resample "
                        f"first (the files source's resample option, rotorid identify "
                        f"--resample linear)")
    return float(dt)


def _check_layout(names: tuple[str, ...], layout: tuple[str, ...], role: str,
                  where: str) -> None:
    """``names`` must be distinct identifiers; a record of helicopter channels only holds them
    in the ``layout``'s order (a model's own layout may order them as it likes)."""
    bad = [c for c in names if not c.isidentifier() or c == "time"]
    helicopter = all(c in layout for c in names)
    if (len(set(names)) != len(names) or bad
            or (helicopter and list(names) != [c for c in layout if c in names])):
        raise DataError(f"{where}: {role} channels {', '.join(names)} must be distinct names "
                        f"(not 'time'); the helicopter's ({', '.join(layout)}) in that order")


def _check_block(block: np.ndarray, channels, rows: int, where: str) -> None:
    if block.shape != (rows, len(channels)):
        raise DataError(f"{where}: expected shape ({rows}, {len(channels)}) for channels "
                        f"{', '.join(channels)}, got {block.shape}")
    bad = np.argwhere(~np.isfinite(block))
    if bad.size:
        row, col = bad[0]
        raise DataError(f"{where}: channel '{channels[col]}' is NaN or infinite at row {row}")


@attrs.frozen(eq=False)
class Maneuver:
    """One maneuver: time (N,), inputs (N, m) and outputs (N, p), perturbations from trim.

    ``input_names`` and ``output_names`` name the columns (default the six-dof helicopter's
    four controls and eight outputs; a subset of them, in that order, for records without the
    others). ``initial_state`` gives the record's initial perturbation state: one value per
    state of ``state_names`` (default the six-dof helicopter's ``u w q theta v p phi r``); a
    model simulating the record starts each of its own states from the value of that name, or
    from trim (zero) when the record names none (:meth:`initial_values`).

    Units are those of ``units`` (flight-test by default: ft/s², deg/s, deg, % of travel).
    ``metadata`` holds free-form descriptors such as ``condition`` (``"hover"``), ``kind``
    (``"3211"``, ``"2311"``, ``"sweep"``), ``axis`` (``"long"``) and ``direction`` (+1/−1).
    ``extra_channels`` maps further channel names to (N,) time histories beyond the fixed
    layout (e.g. ``V`` or ``alpha`` of an aeroplane), in whatever unit a channel map declares
    for them; models of one's own read them by name (docs/models.md).
    Arrays are copied and made read-only, so a maneuver never aliases the caller's data.
    """

    name: str
    time: np.ndarray = attrs.field(converter=readonly_array)
    inputs: np.ndarray = attrs.field(converter=readonly_array)
    outputs: np.ndarray = attrs.field(converter=readonly_array)
    metadata: Mapping = attrs.field(factory=dict, converter=lambda m: dict(m))
    units: str = attrs.field(default="flight-test", converter=lambda u: unit_system(u).name)
    initial_state: np.ndarray | None = attrs.field(
        default=None, converter=lambda x: None if x is None else readonly_array(x))
    extra_channels: Mapping[str, np.ndarray] = attrs.field(
        factory=dict, converter=lambda m: {str(k): readonly_array(v) for k, v in dict(m).items()})
    input_names: tuple[str, ...] = attrs.field(default=INPUT_CHANNELS, converter=tuple)
    output_names: tuple[str, ...] = attrs.field(default=OUTPUT_CHANNELS, converter=tuple)
    state_names: tuple[str, ...] = attrs.field(
        default=STATES, converter=lambda names: STATES if names is None else tuple(names))

    def __attrs_post_init__(self):
        where = f"maneuver {self.name!r}"
        check_time(self.time, where)
        _check_layout(self.input_names, INPUT_CHANNELS, "input", where)
        _check_layout(self.output_names, OUTPUT_CHANNELS, "output", where)
        both = sorted(set(self.input_names) & set(self.output_names))
        if both:
            raise DataError(f"{where}: channel {both[0]!r} is both an input and an output")
        _check_block(self.inputs, self.input_names, self.time.size, where)
        _check_block(self.outputs, self.output_names, self.time.size, where)
        for name, values in self.extra_channels.items():
            if name in self.channel_names:
                raise DataError(f"{where}: extra channel {name!r} repeats an input or output "
                                "channel; give it another name")
            _check_block(values.reshape(-1, 1) if values.ndim <= 1 else values, (name,),
                         self.time.size, where)
        if self.initial_state is not None and self.initial_state.ndim != 1:
            raise DataError(f"{where}: initial_state must be a vector of states, "
                            f"got shape {self.initial_state.shape}")
        if len(set(self.state_names)) != len(self.state_names):
            raise DataError(f"{where}: state_names {' '.join(self.state_names)} repeat a name")
        if self.initial_state is not None and self.initial_state.size != len(self.state_names):
            raise DataError(f"{where}: initial_state has {self.initial_state.size} values for "
                            f"the {len(self.state_names)} states {' '.join(self.state_names)}; "
                            f"give one value per state and name them (state_names)")

    @classmethod
    def from_columns(cls, name: str, columns: Mapping[str, np.ndarray], *,
                     units: str = "flight-test", metadata: Mapping | None = None,
                     initial_state=None, state_names=None,
                     ingestion: Ingestion | Mapping | None = None) -> "Maneuver":
        """A maneuver from named columns: ``time`` (s), the controls and outputs it has (at
        least one of each, unless it holds columns the ingestion keeps for a model of one's
        own), and any further columns as :attr:`extra_channels`; prepared first as ``ingestion``
        says (units per channel, resampling, trim removal; :mod:`rotorid.ingestion`), each
        step stated in the metadata."""
        where = f"maneuver {name!r}"
        columns, ingestion = Ingestion.coerce(ingestion).mapped(columns, where)
        signals = ingestion.signals
        input_layout = INPUT_CHANNELS if signals is None else signals.inputs.names
        output_layout = OUTPUT_CHANNELS if signals is None else signals.outputs.names
        inputs = tuple(c for c in input_layout if c in columns)
        outputs = tuple(c for c in output_layout if c in columns)
        kept = [c for c in ingestion.keep_columns if c in columns]
        missing = [label for label, present in (("time", "time" in columns),
                                                ("every input", inputs or kept),
                                                ("every output", outputs or kept))
                   if not present]
        if missing:
            raise DataError(f"{where}: missing column(s) {', '.join(missing)}; a maneuver "
                            f"needs time, at least one input ({', '.join(input_layout)}) and "
                            f"at least one output ({', '.join(output_layout)}); link the "
                            f"file's own column names in a channel map")
        prepared, notes = prepare_columns(columns, unit_system(units).name, ingestion, where)
        rows = prepared["time"].size

        def block(names):
            """The columns ``names`` side by side, shape (N, len(names)); (N, 0) for none."""
            return np.array([prepared[c] for c in names]).T.reshape(rows, len(names))

        return cls(name, prepared["time"], block(inputs), block(outputs),
                   metadata={**dict(metadata or {}), **notes}, units=units,
                   initial_state=initial_state, state_names=state_names,
                   extra_channels={k: v for k, v in prepared.items()
                                   if k not in ("time",) + inputs + outputs},
                   input_names=inputs, output_names=outputs)

    @classmethod
    def from_dataframe(cls, frame, name: str, **options) -> "Maneuver":
        """A maneuver from a table with ``columns`` and ``frame[column]`` (a pandas
        DataFrame, a dict of arrays …; pandas is not needed); ``options`` as
        :meth:`from_columns`."""
        try:
            names = list(frame.columns)
        except AttributeError:
            names = list(frame)
        return cls.from_columns(name, {str(c): np.asarray(frame[c], dtype=float)
                                       for c in names}, **options)

    def __repr__(self) -> str:
        return maneuver_summary(self)

    def _repr_html_(self) -> str:
        return maneuver_html(self, self.channel_names)

    def initial_values(self, states) -> np.ndarray:
        """The record's initial state of the model states called ``states``, shape (n,): the
        value it gives for each (:attr:`state_names`), trim (zero) for the others and for all
        when it gives none."""
        given = ({} if self.initial_state is None
                 else dict(zip(self.state_names, self.initial_state)))
        return np.array([given.get(name, 0.0) for name in states], dtype=float)

    @property
    def dt(self) -> float:
        """Sample time in s."""
        return float((self.time[-1] - self.time[0]) / (self.time.size - 1))

    @property
    def n_samples(self) -> int:
        return int(self.time.size)

    @property
    def duration(self) -> float:
        return float(self.time[-1] - self.time[0])

    def channel(self, name: str) -> np.ndarray:
        """Time history of one channel by name (``time``, an input, an output or an extra)."""
        if name == "time":
            return self.time
        if name in self.input_names:
            return self.inputs[:, self.input_names.index(name)]
        if name in self.output_names:
            return self.outputs[:, self.output_names.index(name)]
        if name in self.extra_channels:
            return self.extra_channels[name]
        if name in ALL_CHANNELS or name in CHANNEL_KINDS:
            raise DataError(f"maneuver {self.name!r} has no channel {name!r}, which the model "
                            f"uses; give the record a {name!r} column (a channel map entry), "
                            f"leave the output out of the fit (--outputs, the estimator's "
                            f"outputs), remove the derivatives of the control, or choose a "
                            f"model without it (a structure template such as longitudinal or "
                            f"lateral); the record's channels: "
                            f"{', '.join(self.channel_names + tuple(self.extra_channels))}")
        raise DataError(f"unknown channel {name!r}; channels: "
                        f"{', '.join(self.channel_names + tuple(self.extra_channels))}")

    @property
    def channel_names(self) -> tuple[str, ...]:
        """``time``, the inputs and the outputs the record holds (extras apart)."""
        return ("time",) + self.input_names + self.output_names

    def columns(self, names) -> np.ndarray:
        """The channels called ``names`` side by side, shape (N, len(names))."""
        if not names:
            return np.zeros((self.n_samples, 0))
        return np.column_stack([self.channel(name) for name in names])

    def with_outputs(self, outputs, name: str | None = None,
                     output_names: tuple[str, ...] | None = None) -> "Maneuver":
        """A copy with other outputs (e.g. a simulation, ``output_names`` its channels; by
        default the record's own), same time and inputs; the metadata's note of the replaced
        outputs' unit conversions (``converted_units``) goes with them."""
        metadata = dict(self.metadata)
        converted = {channel: unit for channel, unit in metadata.pop("converted_units", {}).items()
                     if channel not in self.output_names}
        if converted:
            metadata["converted_units"] = converted
        return attrs.evolve(self, outputs=outputs, name=name or self.name,
                            output_names=self.output_names if output_names is None
                            else output_names, metadata=metadata)

    def head(self, duration: float) -> "Maneuver":
        """The first ``duration`` seconds (at least two samples)."""
        return self.samples(0, max(2, int(np.floor(duration / self.dt + 1e-9)) + 1))

    def samples(self, start: int, stop: int) -> "Maneuver":
        """Samples ``start`` to ``stop`` (exclusive) of every channel, extras included."""
        rows = slice(start, stop)
        return attrs.evolve(self, time=self.time[rows], inputs=self.inputs[rows],
                            outputs=self.outputs[rows],
                            extra_channels={k: v[rows] for k, v in self.extra_channels.items()})


def _check_hold(instance, attribute, value):
    if value not in HOLDS:
        raise DataError(f"unknown input hold {value!r}; use 'zoh' (zero-order, default) "
                        f"or 'foh' (first-order, for continuously sampled sticks)")


@attrs.frozen(eq=False)
class ManeuverSet:
    """Several maneuvers analysed together, and the hold of their inputs between samples."""

    maneuvers: tuple[Maneuver, ...] = attrs.field(converter=tuple)
    hold: str = attrs.field(default="zoh", validator=_check_hold)

    def __attrs_post_init__(self):
        if not self.maneuvers:
            raise DataError("a maneuver set needs at least one maneuver")
        names = [m.name for m in self.maneuvers]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise DataError(f"duplicate maneuver name(s) in the set: {', '.join(dupes)}")
        units = {m.units for m in self.maneuvers}
        if len(units) > 1:
            raise DataError(f"maneuvers mix unit systems {sorted(units)}; convert them first")
        layouts = {(m.input_names, m.output_names): m.name for m in self.maneuvers}
        if len(layouts) > 1:
            (first, one), (second, other) = list(layouts.items())[:2]
            raise DataError(f"maneuvers {one!r} and {other!r} hold different channels "
                            f"({' '.join(first[0] + first[1])} against "
                            f"{' '.join(second[0] + second[1])}); give every record of a set "
                            f"the same channels")

    def __repr__(self) -> str:
        return maneuver_set_summary(self)

    def _repr_html_(self) -> str:
        return maneuver_set_html(self)

    def __len__(self) -> int:
        return len(self.maneuvers)

    def __iter__(self):
        return iter(self.maneuvers)

    def __getitem__(self, key):
        if isinstance(key, str):
            for m in self.maneuvers:
                if m.name == key:
                    return m
            raise DataError(f"no maneuver named {key!r}; have: "
                            f"{', '.join(m.name for m in self.maneuvers)}")
        return self.maneuvers[key]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(m.name for m in self.maneuvers)

    @property
    def units(self) -> str:
        return self.maneuvers[0].units

    @property
    def input_names(self) -> tuple[str, ...]:
        """The inputs every maneuver of the set holds."""
        return self.maneuvers[0].input_names

    @property
    def output_names(self) -> tuple[str, ...]:
        """The outputs every maneuver of the set holds."""
        return self.maneuvers[0].output_names

    @property
    def n_samples(self) -> int:
        """Total number of samples over all maneuvers."""
        return sum(m.n_samples for m in self.maneuvers)

    def select(self, predicate=None, **metadata) -> "ManeuverSet":
        """Maneuvers whose metadata match every keyword (and ``predicate(m)`` if given)."""
        chosen = [m for m in self.maneuvers
                  if all(m.metadata.get(k) == v for k, v in metadata.items())
                  and (predicate is None or predicate(m))]
        if not chosen:
            raise DataError(f"no maneuver matches {metadata or predicate}")
        return attrs.evolve(self, maneuvers=chosen)

    def merged(self, other: Iterable[Maneuver]) -> "ManeuverSet":
        """This set plus more maneuvers."""
        return attrs.evolve(self, maneuvers=[*self.maneuvers, *other])
