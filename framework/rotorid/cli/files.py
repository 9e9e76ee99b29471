"""Command-line rules for the files a command reads and writes."""

from __future__ import annotations

from pathlib import Path

from rotorid.errors import DataFileError, OverwriteError


def refuse_overwrite(path, force: bool) -> Path:
    """``path``, after checking that it does not exist yet unless ``force`` (``--force``)."""
    path = Path(path)
    if path.exists() and not force:
        raise OverwriteError(f"{path} exists already; give --force to overwrite it")
    return path


def load_maneuvers(locations, hold: str = "zoh", units: str | None = None, ingestion=None):
    """The maneuvers of files, directories or glob patterns (the ``files`` data source) as one
    set with input ``hold``, converted to the unit system ``units`` (None: as the files
    declare) after the ``ingestion`` steps (:class:`rotorid.ingestion.Ingestion` or its
    settings, e.g. a model file's channel map); a maneuver name used twice is an error."""
    from rotorid.data import ManeuverSet
    from rotorid.plugin.manager import create

    source = create("data-sources", "files", hold=hold, units=units, ingestion=ingestion)
    maneuvers = []
    for location in locations:
        maneuvers.extend(source.load(location))
    names = [m.name for m in maneuvers]
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise DataFileError(f"maneuver name(s) {', '.join(repeated)} appear in more than one "
                            f"input; each maneuver must have a unique name")
    return ManeuverSet(maneuvers, hold=hold)
