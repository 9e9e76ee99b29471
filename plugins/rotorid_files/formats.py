"""The ``files`` data source: maneuver files in CSV, NumPy ``.npz`` and MATLAB ``.mat`` format.

One file holds one maneuver; the format follows the suffix. Every writer is atomic. See
:mod:`rotorid_files.csvfile` and :mod:`rotorid_files.arrays` for the layouts.

In a flight case (:meth:`FileSource.case_data`) the ``[data]`` settings are
``identification`` and optionally ``verification`` (each a file, a directory, a glob or a list
of them; relative ones are read from the case file's folder), ``hold``, ``units`` and the
ingestion settings ``trim``, ``resample``, ``sample_time`` and ``channel_units``
(:mod:`rotorid.ingestion`). Flight data carry no trim condition and no truth model: the case's
``[condition]`` table gives the trim.
"""

from __future__ import annotations

import glob
import os
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import ClassVar

import attrs
from rotorid.data import HOLDS, Maneuver, ManeuverSet
from rotorid.errors import DataError, DataFileError, MissingFileError, RotoridError
from rotorid.ingestion import Ingestion
from rotorid.io import atomic_write, require_file
from rotorid.plugin.contracts import CaseData
from rotorid.units import channel_kind, channel_scale, unit_system

from . import arrays, csvfile

#: Suffix → (reader(path), writer(maneuver, binary handle)).
FORMATS = {
    ".csv": (csvfile.read, csvfile.write),
    ".npz": (arrays.read_npz, arrays.write_npz),
    ".mat": (arrays.read_mat, arrays.write_mat),
}
_SAFE_NAME = re.compile(r"[A-Za-z0-9_+-][A-Za-z0-9_.+-]*")


def _format(path: Path):
    try:
        return FORMATS[path.suffix.lower()]
    except KeyError:
        raise DataFileError(f"{path}: unknown maneuver file format {path.suffix!r}; "
                            f"use {', '.join(FORMATS)}") from None


def read_maneuver(path: str | os.PathLike, ingestion: Ingestion | None = None) -> Maneuver:
    """Read the maneuver stored in ``path`` (``.csv``, ``.npz`` or ``.mat``), prepared as
    ``ingestion`` says (default: as recorded)."""
    path = Path(path)
    reader = _format(path)[0]
    require_file(path, "maneuver file")
    try:
        return reader(path, ingestion or Ingestion())
    except RotoridError:
        raise
    except Exception as error:      # the reader library's own failure on a malformed file
        raise DataFileError(f"{path}: cannot read it as a {path.suffix} maneuver file "
                            f"({type(error).__name__}: {error}); check that the file is "
                            f"complete and of that format") from None


def write_maneuver(maneuver: Maneuver, path: str | os.PathLike) -> Path:
    """Write ``maneuver`` to ``path`` atomically, in the format of the suffix; return the path."""
    path = Path(path)
    writer = _format(path)[1]
    return atomic_write(path, lambda handle: writer(maneuver, handle))


def convert_units(maneuver: Maneuver, units, kinds=None) -> Maneuver:
    """``maneuver`` expressed in the unit system ``units`` (controls keep their unit);
    ``kinds`` (name → kind, optional) gives the kinds of a model's own signals."""
    source, target = unit_system(maneuver.units), unit_system(units)
    if source == target:
        return maneuver
    state = None
    if maneuver.initial_state is not None:
        state = maneuver.initial_state * channel_scale(maneuver.state_names, target, source,
                                                       kinds)
    return attrs.evolve(maneuver, outputs=maneuver.outputs * channel_scale(
        maneuver.output_names, target, source, kinds), units=target.name, initial_state=state,
        extra_channels={name: values * (channel_scale((name,), target, source, kinds)[0]
                                        if channel_kind(name, kinds) else 1.0)
                        for name, values in maneuver.extra_channels.items()})


def _expand(location) -> list[Path]:
    if isinstance(location, (list, tuple)):
        return [path for item in location for path in _expand(item)]
    path = Path(location)
    if path.is_file():
        return [path]
    if path.is_dir():
        found = sorted(p for p in path.iterdir() if p.suffix.lower() in FORMATS and p.is_file())
        if not found:
            raise DataFileError(f"{path}: no maneuver files ({', '.join(FORMATS)}) in this "
                                f"directory")
        return found
    if glob.has_magic(str(location)):
        found = sorted(Path(p) for p in glob.glob(str(location)) if Path(p).is_file())
        if not found:
            raise MissingFileError(f"no file matches {location}")
        return found
    if path.exists():
        raise DataFileError(f"{path} is neither a regular file nor a directory; name maneuver "
                            f"files, a directory or a glob pattern")
    raise MissingFileError(f"{location}: no such file or directory")


def _check_hold(instance, attribute, value):
    if value not in HOLDS:
        raise DataError(f"unknown input hold {value!r}; use one of {', '.join(HOLDS)}")


def _optional_units(value):
    return None if value is None else unit_system(value).name


@attrs.frozen
class FileSource:
    """Loads and saves maneuver files.

    Attributes:
        hold: input hold of the loaded set, ``"zoh"`` or ``"foh"``.
        units: convert loaded maneuvers to this unit system (``"flight-test"`` or ``"si"``);
            ``None`` keeps the units the files declare (then they must all agree).
        ingestion: how every file is prepared (:class:`rotorid.ingestion.Ingestion` or a
            mapping of its settings: trim removal ``"first-second"`` or stated values,
            resampling ``"linear"`` or ``"decimate"`` onto a uniform grid, the unit each
            channel was recorded in); a file's own ``channel_units`` header adds to these.
    """

    hold: str = attrs.field(default="zoh", validator=_check_hold)
    units: str | None = attrs.field(default=None, converter=_optional_units)
    ingestion: Ingestion = attrs.field(factory=Ingestion, converter=Ingestion.coerce)
    #: Case settings that name files: the study reads relative ones from the case's folder.
    path_settings: ClassVar[tuple[str, ...]] = ("identification", "verification")
    #: Case settings that are attributes of the source, and those of its ingestion.
    options: ClassVar[tuple[str, ...]] = ("hold", "units")
    ingestion_settings: ClassVar[tuple[str, ...]] = tuple(
        k for k in attrs.fields_dict(Ingestion) if k != "trim_units")

    def load(self, location) -> ManeuverSet:
        """Every maneuver in ``location``: one file, a directory (its ``.csv``, ``.npz`` and
        ``.mat`` files, sorted by name), a glob pattern such as ``"data/hover_*.csv"``, or a
        list of these."""
        maneuvers, origin = [], {}
        ingestion = (self.ingestion if self.units is None or self.ingestion.trim_units
                     else attrs.evolve(self.ingestion, trim_units=self.units))
        for path in _expand(location):
            maneuver = read_maneuver(path, ingestion)
            if maneuver.name in origin:
                raise DataFileError(f"maneuver name {maneuver.name!r} is used by both "
                                    f"{origin[maneuver.name]} and {path}; rename one")
            origin[maneuver.name] = path
            maneuvers.append(maneuver if self.units is None
                             else convert_units(maneuver, self.units, self.ingestion.kind))
        units = {m.units for m in maneuvers}
        if len(units) > 1:
            raise DataFileError(f"{location}: files mix unit systems {sorted(units)}; load with "
                                f"FileSource(units='flight-test') to convert them")
        return ManeuverSet(maneuvers, hold=self.hold)

    def case_data(self, settings: Mapping, directory) -> CaseData:
        """A flight case's maneuvers from the files its settings name (``directory`` is not
        used: the files stay where they are)."""
        known = (*self.path_settings, *self.options, *self.ingestion_settings)
        unknown = sorted(set(settings) - set(known))
        if unknown:
            raise DataFileError(f"files data: unknown [data] setting(s) {unknown}; known: "
                                f"{', '.join(known)} (a seed or an airspeed only applies to "
                                f"generated data)")
        if "identification" not in settings:
            raise DataFileError("files data: [data] needs identification (files, a directory "
                                "or a glob)")
        reader = attrs.evolve(
            self, **{k: settings[k] for k in self.options if k in settings},
            ingestion=attrs.evolve(self.ingestion, **{k: settings[k] for k in
                                                      self.ingestion_settings if k in settings}))
        verification = settings.get("verification")
        return CaseData(reader.load(settings["identification"]),
                        None if verification is None else reader.load(verification),
                        None, None)

    def save(self, maneuvers: ManeuverSet | Iterable[Maneuver], directory: str | os.PathLike,
             format: str = "csv") -> tuple[Path, ...]:
        """Write each maneuver to ``directory/<name>.<format>`` (created if needed); return
        the paths. ``format`` is ``"csv"``, ``"npz"`` or ``"mat"``."""
        suffix = f".{format.lower()}"
        if suffix not in FORMATS:
            raise DataFileError(f"unknown maneuver file format {format!r}; use "
                                f"{', '.join(s[1:] for s in FORMATS)}")
        maneuvers = list(maneuvers)
        names = [m.name for m in maneuvers]
        for name in names:
            if not _SAFE_NAME.fullmatch(name):
                raise DataFileError(f"maneuver name {name!r} cannot be a file name; use letters, "
                                    f"digits and _ . + - only")
            if names.count(name) > 1:
                raise DataFileError(f"two maneuvers are named {name!r}; names must be unique")
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        return tuple(write_maneuver(m, directory / f"{m.name}{suffix}") for m in maneuvers)
