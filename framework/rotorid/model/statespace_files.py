"""Files of a named state-space system, for use outside rotorid (``rotorid export``).

Every format holds A, B, C, D, the state, input and output names with their units, the delayed
terms and the order of their Padé realisation (0: the matrices ignore the delays):

- ``json``: :meth:`NamedStateSpace.as_dict` plus ``source``;
- ``mat``: a MATLAB file with ``A B C D``, ``StateName InputName OutputName`` and
  ``StateUnit InputUnit OutputUnit`` (cell arrays, as MATLAB's ``ss`` names them),
  ``DelayDerivative DelayEquation DelaySource`` (cell arrays), ``DelaySeconds``, ``PadeOrder``,
  ``UnitSystem``, ``Source`` and the recorded channels, ``ChannelSignal ChannelColumn``
  (cell arrays), ``ChannelFactor ChannelOffset`` (signal = factor · column + offset);
- ``csv``: a directory with ``A.csv B.csv C.csv D.csv`` (row and column names in the first
  column and row), ``signals.csv`` (role, name, unit), ``delays.csv`` and ``channels.csv``;
- ``python-control``: a Python file defining the matrices and names and ``system()``, which
  returns ``control.ss(A, B, C, D, states=..., inputs=..., outputs=...)``.

Writers are atomic, per file.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import attrs
import numpy as np

from rotorid.io import atomic_write
from rotorid.model.statespace import NamedStateSpace

FORMATS = ("json", "mat", "csv", "python-control")


def write_state_space(system: NamedStateSpace, path, file_format: str, source: str) -> Path:
    """Write ``system`` to ``path`` (a directory for ``csv``) in ``file_format`` (one of
    :data:`FORMATS`); ``source`` says where the model comes from (e.g. ``"result.json, model
    'with delays'"``)."""
    writers = {"json": _write_json, "mat": _write_mat, "csv": _write_csv,
               "python-control": _write_python}
    path = Path(path)
    writers[file_format](system, path, source)
    return path


def _write_json(system: NamedStateSpace, path: Path, source: str) -> None:
    atomic_write(path, json.dumps({"source": source, **system.as_dict()}, indent=1))


def _cell(strings) -> np.ndarray:
    """A MATLAB cell array (1 × n) of strings."""
    cell = np.empty((1, len(strings)), dtype=object)
    for i, text in enumerate(strings):
        cell[0, i] = text
    return cell


def _write_mat(system: NamedStateSpace, path: Path, source: str) -> None:
    from scipy.io import savemat

    content = {
        "A": system.a, "B": system.b, "C": system.c, "D": system.d,
        "StateName": _cell(system.states), "InputName": _cell(system.inputs),
        "OutputName": _cell(system.outputs),
        "StateUnit": _cell([system.units[n] for n in system.states]),
        "InputUnit": _cell([system.units[n] for n in system.inputs]),
        "OutputUnit": _cell([system.units[n] for n in system.outputs]),
        "DelayDerivative": _cell([t.derivative for t in system.delays]),
        "DelayEquation": _cell([t.equation for t in system.delays]),
        "DelaySource": _cell([t.source for t in system.delays]),
        "DelaySeconds": np.array([[t.seconds for t in system.delays]]),
        "PadeOrder": float(system.pade_order), "UnitSystem": system.unit_system,
        "Source": source,
        "ChannelSignal": _cell([c.signal for c in system.channels]),
        "ChannelColumn": _cell([c.column for c in system.channels]),
        "ChannelFactor": np.array([[c.factor for c in system.channels]]),
        "ChannelOffset": np.array([[c.offset for c in system.channels]]),
    }
    atomic_write(path, lambda handle: savemat(handle, content, oned_as="row"))


def _csv_text(rows) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    return buffer.getvalue()


def _matrix_rows(matrix: np.ndarray, rows, columns) -> list[list]:
    return [["", *columns], *([name, *map(repr, values)]
                              for name, values in zip(rows, matrix.tolist()))]


def _write_csv(system: NamedStateSpace, path: Path, source: str) -> None:
    path.mkdir(parents=True, exist_ok=True)
    blocks = {"A": (system.a, system.states, system.states),
              "B": (system.b, system.states, system.inputs),
              "C": (system.c, system.outputs, system.states),
              "D": (system.d, system.outputs, system.inputs)}
    for name, (matrix, rows, columns) in blocks.items():
        atomic_write(path / f"{name}.csv", _csv_text(_matrix_rows(matrix, rows, columns)))
    signals = [["role", "name", "unit"]] + [
        [role, name, system.units[name]]
        for role, names in (("state", system.states), ("input", system.inputs),
                            ("output", system.outputs)) for name in names]
    atomic_write(path / "signals.csv", _csv_text(signals))
    delays = [["derivative", "equation", "source", "seconds", "pade_order"]] + [
        [t.derivative, t.equation, t.source, repr(t.seconds), system.pade_order]
        for t in system.delays]
    atomic_write(path / "delays.csv", _csv_text(delays))
    channels = [["signal", "column", "factor", "offset"]] + [
        [c.signal, c.column, repr(c.factor), repr(c.offset)] for c in system.channels]
    atomic_write(path / "channels.csv", _csv_text(channels))


_PYTHON = '''"""State-space model exported by rotorid from {source}.

{unit_system} units; states, inputs and outputs with their units in UNITS. DELAYS lists the
delayed derivative terms (s); {delays_note} CHANNELS says how a signal is read from the
recorded data: signal = factor · column + offset, in the signal's unit.

    import runpy
    system = runpy.run_path("{name}")["system"]()    # needs python-control
"""

STATES = {states!r}
INPUTS = {inputs!r}
OUTPUTS = {outputs!r}
UNITS = {units!r}
DELAYS = {delays!r}
PADE_ORDER = {pade_order!r}
CHANNELS = {channels!r}

A = {a!r}
B = {b!r}
C = {c!r}
D = {d!r}


def system(name={system_name!r}):
    """The model as a python-control state-space system with named signals."""
    import control

    return control.ss(A, B, C, D, states=STATES, inputs=INPUTS, outputs=OUTPUTS, name=name)
'''


def _write_python(system: NamedStateSpace, path: Path, source: str) -> None:
    note = (f"they are realised by Padé approximations of order {system.pade_order} among "
            f"the states." if system.pade_order and system.delays else
            "A, B, C, D ignore them (export with a Padé order to realise them)."
            if system.delays else "there are none.")
    text = _PYTHON.format(
        source=source, unit_system=system.unit_system, delays_note=note, name=path.name,
        states=list(system.states), inputs=list(system.inputs), outputs=list(system.outputs),
        units={n: system.units[n] for n in system.states + system.inputs + system.outputs},
        delays=[attrs.asdict(t) for t in system.delays], pade_order=system.pade_order,
        channels={c.signal: {"column": c.column, "factor": c.factor, "offset": c.offset}
                  for c in system.channels},
        a=system.a.tolist(), b=system.b.tolist(), c=system.c.tolist(), d=system.d.tolist(),
        system_name=path.stem)
    atomic_write(path, text)


__all__ = ["FORMATS", "write_state_space"]
