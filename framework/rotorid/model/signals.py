"""Named signals with units, ordered sets of them, and maps from data columns to signals.

A model declares its states, inputs and outputs as :class:`Signal` values collected in
:class:`SignalSet` s (together a :class:`ModelSignals`); arrays follow the set's order and are
picked by name. A :class:`ChannelMap` says which data column holds which signal, how it is
scaled and in which unit, so data with the test range's column names (``Q_degps``, ``DELV``)
and units are read without renaming. Units and their factors live in :mod:`rotorid.units`; values are converted
once, when a column is read.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import attrs
import numpy as np

from rotorid.errors import SignalError
from rotorid.units import (
    canonical_unit,
    conversion_factor,
    same_dimension,
    unit_fits_kind,
    units_like,
    units_of_kind,
)


def _identifier(instance, attribute, value):
    if not isinstance(value, str) or not value.isidentifier():
        raise SignalError(f"{attribute.name} {value!r} is not a valid name; use letters, digits "
                          "and underscores, not starting with a digit (e.g. 'alpha', 'q_dot')")


@attrs.frozen
class Signal:
    """One named signal of a model.

    Attributes:
        name: identifier such as ``"q"`` or ``"alpha"``.
        unit: a :data:`rotorid.units.UNITS` label, e.g. ``"rad/s"``; the unit the model computes in.
        kind: physical kind (:data:`rotorid.units.KIND_DIMENSIONS`): ``velocity``, ``angle``,
            ``rate``, ``acceleration``, ``angular-acceleration`` or ``control``.
        description: free text for reports.
    """

    name: str = attrs.field(validator=_identifier)
    unit: str = attrs.field(converter=canonical_unit)
    kind: str
    description: str = ""

    def __attrs_post_init__(self):
        if not unit_fits_kind(self.unit, self.kind):
            raise SignalError(f"signal {self.name!r}: unit {self.unit} does not fit kind "
                              f"{self.kind!r}; use one of {', '.join(units_of_kind(self.kind))}")


def _unique_signals(instance, attribute, value):
    for item in value:
        if not isinstance(item, Signal):
            raise SignalError(f"a signal set holds Signal values, got {item!r}")
    names = [s.name for s in value]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise SignalError(f"duplicate signal {duplicates[0]!r} in a signal set; give every "
                          "signal its own name")


@attrs.frozen
class SignalSet:
    """Signals in a fixed order (the order of the model's arrays), unique by name."""

    signals: tuple[Signal, ...] = attrs.field(converter=tuple, validator=_unique_signals)

    def __len__(self) -> int:
        return len(self.signals)

    def __iter__(self):
        return iter(self.signals)

    def __contains__(self, name) -> bool:
        return name in self.names

    def __getitem__(self, key: str | int) -> Signal:
        """The signal called ``key`` (a name) or at position ``key``."""
        if isinstance(key, str):
            return self.signals[self.index(key)]
        return self.signals[key]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.signals)

    @property
    def units(self) -> tuple[str, ...]:
        return tuple(s.unit for s in self.signals)

    def index(self, name: str) -> int:
        """Position of the signal called ``name``; an unknown name raises, listing the known."""
        try:
            return self.names.index(name)
        except ValueError:
            raise SignalError(f"unknown signal {name!r}; signals: {', '.join(self.names)}") from None

    def indices(self, names: Iterable[str]) -> list[int]:
        """Positions of several signals, in the order given."""
        return [self.index(n) for n in names]


@attrs.frozen
class ModelSignals:
    """The states (n), inputs (m) and outputs (ny) of a model, in the order of its arrays.

    A name used in several roles (a state that is also measured, such as ``q``) must carry the
    same unit and kind in each; :attr:`all` is then the set of distinct signals.
    """

    states: SignalSet
    inputs: SignalSet
    outputs: SignalSet

    def __attrs_post_init__(self):
        seen = {}
        for role, signals in (("state", self.states), ("input", self.inputs),
                              ("output", self.outputs)):
            for signal in signals:
                first_role, first = seen.setdefault(signal.name, (role, signal))
                if (first.unit, first.kind) != (signal.unit, signal.kind):
                    raise SignalError(
                        f"signal {signal.name!r} is a {first_role} in {first.unit} "
                        f"({first.kind}) and an {role} in {signal.unit} ({signal.kind}); "
                        "declare one unit and kind for it or give the two different names")
                if "input" in (first_role, role) and first_role != role:
                    raise SignalError(f"signal {signal.name!r} is both a {first_role} and "
                                         f"an {role}; an input cannot be a state or an output")

    @property
    def all(self) -> SignalSet:
        """Every distinct signal: states, then inputs, then outputs not named before."""
        distinct = {}
        for signal in (*self.states, *self.inputs, *self.outputs):
            distinct.setdefault(signal.name, signal)
        return SignalSet(distinct.values())


@attrs.frozen
class ChannelLink:
    """One data column read as one signal: ``value [unit] = scale · column + offset``.

    The value is then converted from ``unit`` into the signal's own unit.

    Attributes:
        column: the column's name in the data, e.g. ``"Q_degps"``.
        signal: the signal's name in the model, e.g. ``"q"``.
        unit: the unit of ``scale · column + offset`` (a :data:`rotorid.units.UNITS` label).
        scale, offset: linear calibration of the raw column (sign flips, gearing, zero shifts).
    """

    column: str
    signal: str
    unit: str = attrs.field(converter=canonical_unit)
    scale: float = attrs.field(default=1.0, converter=float)
    offset: float = attrs.field(default=0.0, converter=float)

    def read(self, raw: np.ndarray, target_unit: str) -> np.ndarray:
        """The column's values ``raw`` as the signal in ``target_unit``."""
        factor = conversion_factor(self.unit, target_unit)
        return (self.scale * np.asarray(raw, dtype=float) + self.offset) * factor


@attrs.frozen
class ChannelMap:
    """Links from data columns to signals; ``source`` (the file it came from) is named in errors.

    A signal without a link is read from the column of the same name, in that column's own unit
    when the data know it (:meth:`read`'s ``column_units``), else in the signal's unit. A signal
    the model does not use needs no column.
    """

    links: tuple[ChannelLink, ...] = attrs.field(default=(), converter=tuple)
    source: str = "the channel map"

    def __attrs_post_init__(self):
        signals = [link.signal for link in self.links]
        duplicates = sorted({s for s in signals if signals.count(s) > 1})
        if duplicates:
            columns = [link.column for link in self.links if link.signal == duplicates[0]]
            raise SignalError(f"{self.source}: signal {duplicates[0]!r} is linked to several "
                              f"columns ({', '.join(columns)}); keep one link per signal")

    @classmethod
    def from_mapping(cls, table: Mapping, source: str = "the channel map") -> "ChannelMap":
        """Build from a ``[channels]`` table: ``COLUMN = {signal = "q", unit = "deg/s",
        scale = 1.0, offset = 0.0}`` (scale and offset optional)."""
        links = []
        for column, entry in table.items():
            if not isinstance(entry, Mapping) or "signal" not in entry or "unit" not in entry:
                raise SignalError(f"{source}: channel {column!r} needs a table with 'signal' and "
                                  f"'unit', e.g. {column} = {{ signal = \"q\", unit = \"deg/s\" }}")
            unknown = sorted(set(entry) - {"signal", "unit", "scale", "offset"})
            if unknown:
                raise SignalError(f"{source}: channel {column!r} has unknown key {unknown[0]!r}; "
                                  "keys: signal, unit, scale, offset")
            try:
                links.append(ChannelLink(column, **entry))
            except (SignalError, TypeError, ValueError) as error:
                raise SignalError(f"{source}: channel {column!r}: {error}") from None
        return cls(links, source)

    def signal_of(self, column: str) -> str:
        """The signal ``column`` is linked to, else the column's own name."""
        return next((link.signal for link in self.links if link.column == column), column)

    def time_links(self) -> "ChannelMap":
        """This map's links of the records' time column only (for a file reader)."""
        return ChannelMap([link for link in self.links if link.signal == "time"], self.source)

    def link(self, signal: str) -> ChannelLink | None:
        """The link of ``signal``, or None when it is read from its own column name."""
        return next((link for link in self.links if link.signal == signal), None)

    def check(self, signals: SignalSet) -> None:
        """Every link names a signal of ``signals`` (or the records' ``time``) with a unit
        that fits its kind."""
        for link in self.links:
            if link.signal == "time":
                if not unit_fits_kind(link.unit, "time"):
                    raise SignalError(f"{self.source}: column {link.column!r} is linked to time "
                                      f"in {link.unit}; give unit = \"s\" or \"ms\"")
                continue
            if link.signal not in signals:
                raise SignalError(f"{self.source}: column {link.column!r} is linked to unknown "
                                  f"signal {link.signal!r}; signals: {', '.join(signals.names)}")
            signal = signals[link.signal]
            if not same_dimension(link.unit, signal.unit):
                raise SignalError(f"{self.source}: column {link.column!r} has unit {link.unit}, "
                                  f"which does not fit signal {signal.name!r} ({signal.kind} in "
                                  f"{signal.unit}); give the column's unit as one of "
                                  f"{', '.join(units_like(signal.unit))}")

    def read(self, columns: Mapping[str, np.ndarray], signals: SignalSet, names: Sequence[str],
             where: str, column_units: Mapping[str, str] | None = None) -> np.ndarray:
        """The signals called ``names`` from a record's ``columns``, in the signals' units.

        Args:
            columns: column name → (N,) values of one record (a file or a maneuver).
            signals: the model's signals the names refer to.
            names: the signals wanted, in the order of the result's columns.
            where: the record, named in errors (e.g. ``"file 'run1.csv'"``).
            column_units: units the record declares for its own columns, used by signals
                without a link.
        Returns:
            (N, len(names)) array.
        """
        self.check(signals)
        units = column_units or {}
        result = []
        for name in names:
            signal = signals[name]
            link = self.link(name)
            if link is None:
                if name not in columns:
                    raise SignalError(
                        f"{where} has no column {name!r} for signal {name!r}; link the column "
                        f"that holds it in {self.source} (column, signal, unit, scale, offset)")
                link = ChannelLink(name, name, units.get(name, signal.unit))
                if not same_dimension(link.unit, signal.unit):
                    raise SignalError(
                        f"{where}: column {name!r} is in {link.unit}, which does not fit signal "
                        f"{name!r} ({signal.kind} in {signal.unit}); link the column that holds "
                        f"it in {self.source}")
            elif link.column not in columns:
                raise SignalError(
                    f"{where} has no column {link.column!r} (linked to signal {name!r} in "
                    f"{self.source}); columns: {', '.join(columns)}; correct the column name "
                    f"in {self.source}")
            result.append(link.read(columns[link.column], signal.unit))
        if not result:
            return np.zeros((len(next(iter(columns.values()), ())), 0))
        return np.stack(result, axis=1)

