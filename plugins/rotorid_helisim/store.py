"""The data-set cache: maneuver files plus a manifest keyed by the configuration hash.

A generated data set lives in one directory: one ``<maneuver>.npz`` file per maneuver (the
``files`` plugin's NumPy layout: channels ``time long lat coll ped ax az q theta ay p phi r``
and a JSON header with the metadata) and ``manifest.json`` holding the configuration, its
SHA-256 digest and the file list. A later request with the same digest reads the files back
instead of flying again; any change of configuration, seed or plant changes the digest and
the set is regenerated: its files replace those the old manifest listed (only maneuver files
the store itself wrote are ever deleted).
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

from rotorid.data import ManeuverSet
from rotorid.errors import DataFileError
from rotorid.io import atomic_write
from rotorid.lease import check_owner_alive

MANIFEST = "manifest.json"


def _manifest(directory) -> dict:
    """The manifest in ``directory`` ({} when missing or unreadable)."""
    path = Path(directory) / MANIFEST
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return manifest if isinstance(manifest, dict) else {}


def load_cached(directory, digest: str) -> ManeuverSet | None:
    """The set stored in ``directory`` if its manifest matches ``digest``, else ``None``."""
    from rotorid_files.formats import read_maneuver

    manifest = _manifest(directory)
    if manifest.get("digest") != digest:
        return None
    files = [Path(directory) / name for name in manifest.get("files", [])]
    if not files or not all(f.is_file() for f in files):
        return None
    return ManeuverSet([read_maneuver(f) for f in files])


def _is_own_file(directory: Path, name: str) -> bool:
    """Whether ``directory/name`` is a maneuver file this store wrote: a plain ``.npz`` file
    directly in ``directory`` holding the ``files`` plugin's header. A manifest may list
    anything; only such files are ever deleted."""
    from rotorid_files.arrays import HEADER_KEY

    path = directory / name
    if path.parent != directory or path.suffix != ".npz" or not path.is_file():
        return False
    try:
        with zipfile.ZipFile(path) as archive:
            return f"{HEADER_KEY}.npy" in archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return False


def save(maneuvers: ManeuverSet, directory, digest: str, settings: dict) -> Path:
    """Write the maneuver files, then the manifest (last, so a crash leaves no stale match).

    Returns the manifest path.
    """
    from rotorid_files.formats import FileSource

    directory = Path(directory)
    check_owner_alive(directory)
    directory.mkdir(parents=True, exist_ok=True)
    manifest = directory / MANIFEST
    previous = _manifest(directory).get("files", [])
    if manifest.exists():
        manifest.unlink()
    paths = FileSource().save(maneuvers, directory, format="npz")
    written = {p.name for p in paths}
    for name in previous:
        if str(name) not in written and _is_own_file(directory, str(name)):
            (directory / str(name)).unlink()
    text = json.dumps({"digest": digest, "settings": settings,
                       "files": [p.name for p in paths]}, indent=2, sort_keys=True)
    try:
        return atomic_write(manifest, text)
    except OSError as error:
        raise DataFileError(f"cannot write the data-set manifest {manifest}: {error}") from None
