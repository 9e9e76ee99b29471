"""``rotorid verify``: frequency-domain verification of an identified model on sweeps.

Usage::

    rotorid verify [MODEL.toml] RESULT.json SWEEPS... [--pairs q/long,p/long] [--out DIR]

``RESULT.json`` is an estimate written by ``rotorid identify``: ``parameters`` and ``delays``
(``{"L_lat": {"value": 0.05}}``), ``fixed`` values and ``structure`` (the model file's path,
relative to the result file, or an embedded model-file mapping). ``MODEL.toml`` overrides the
structure (the estimate JSON of ``Estimate.as_dict`` names none, so give it). Free derivatives
of the structure that the result does not list were removed by the reduction and are dropped;
output biases of the identification records are ignored. SWEEPS are maneuver files,
directories or glob patterns; when the maneuvers carry ``kind`` metadata only the ``sweep``
ones are used.

Writes ``verification.json`` (every check, J_ave, time-domain metrics) and, per pair,
``error_<output>_<input>.png`` and ``bode_<output>_<input>.png`` into ``--out``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path

NAME = "verify"
HELP = ("verify an identified model on frequency sweeps: ε = H_model/H_truth against the "
        "MUAD/AEE envelopes and the mismatch cost J, with figures and a JSON of the checks")
DEFAULT_ENVELOPES = "muad,aee,mismatch-cost"


def add_arguments(parser) -> None:
    parser.add_argument("files", nargs="+", metavar="FILE",
                        help="[MODEL.toml] RESULT.json SWEEPS...: optional model file, the "
                             "estimate JSON, then sweep files, directories or glob patterns")
    parser.add_argument("--pairs", default=None,
                        help="comma-separated OUTPUT/INPUT pairs (default: the paper's "
                             "q/long,p/long,q/lat,p/lat,r/coll,az/coll,r/ped,ay/ped, limited "
                             "to the axes the sweeps excite)")
    parser.add_argument("--envelopes", default=DEFAULT_ENVELOPES,
                        help=f"comma-separated envelope names ({DEFAULT_ENVELOPES})")
    parser.add_argument("--out", default="verification", metavar="DIR",
                        help="output directory (created if needed; default ./verification)")
    parser.add_argument("--no-figures", action="store_true",
                        help="write only verification.json (faster)")
    parser.add_argument("--strict", action="store_true",
                        help="exit with status 1 when a verified envelope check fails")


def _split(files: list[str]):
    from rotorid.errors import UsageError

    model = files[0] if files[0].lower().endswith(".toml") else None
    rest = files[1:] if model else files
    if len(rest) < 2 or not rest[0].lower().endswith(".json"):
        raise UsageError("give [MODEL.toml] RESULT.json SWEEPS...: the estimate JSON and at "
                         "least one sweep file, directory or pattern")
    return model, Path(rest[0]), rest[1:]


def _read_result(path: Path) -> dict:
    from rotorid.errors import DataFileError, MissingFileError

    if not path.is_file():
        raise MissingFileError(f"estimate file {path} does not exist")
    try:
        result = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise DataFileError(f"estimate file {path} is not valid JSON: {error}") from None
    if not isinstance(result, Mapping) or not isinstance(result.get("parameters"), Mapping):
        raise DataFileError(f"estimate file {path} has no 'parameters' table")
    return dict(result)


def _structure(model: str | None, result: dict, result_path: Path):
    from rotorid.errors import DataFileError
    from rotorid.model.modelfile import load_model, parse_model

    if model is not None:
        return load_model(model)
    described = result.get("structure")
    if isinstance(described, str):
        path = Path(described)
        return load_model(path if path.is_absolute() else result_path.parent / path)
    if isinstance(described, Mapping):
        return parse_model(described, f"{result_path} (embedded structure)")
    raise DataFileError(f"{result_path}: the result names no model structure; run "
                        f"`rotorid verify MODEL.toml {result_path} SWEEPS...`")


def _value(entry, name: str, path: Path) -> float:
    from rotorid.errors import DataFileError

    value = entry.get("value") if isinstance(entry, Mapping) else entry
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise DataFileError(f"{path}: {name} has no numeric value ({entry!r})")
    return float(value)


def model_from_result(structure, result: Mapping, path: Path):
    """The identified structure and its parameter values from an estimate mapping.

    Output biases (``bias_<maneuver>_<output>``) belong to the identification records, not
    to the model, and are ignored.
    """
    parameters = {n: _value(e, n, path) for n, e in result["parameters"].items()
                  if not n.startswith("bias_")}
    for name, value in dict(result.get("fixed") or {}).items():
        if name in structure.names:
            structure = structure.fixing(name, _value(value, name, path))
    delays = {n: _value(e, n, path) for n, e in dict(result.get("delays") or {}).items()}
    removed = [d.name for d in structure.free_derivatives if d.name not in parameters]
    structure = structure.without(*removed)
    structure = structure.with_delays([n for n in delays if structure.derivative(n).delay
                                       is None], missing="error")
    values = dict(parameters)
    values.update({f"tau_{n}": v for n, v in delays.items()})
    return structure, structure.as_mapping(values)


def load_sweeps(locations):
    """The maneuvers of files, directories or patterns; only the ``sweep`` ones when the
    maneuvers carry ``kind`` metadata."""
    from rotorid.plugin.manager import create

    source = create("data-sources", "files")
    sweeps = source.load(locations[0])
    for location in locations[1:]:
        sweeps = sweeps.merged(source.load(location))
    if any("kind" in m.metadata for m in sweeps):
        sweeps = sweeps.select(kind="sweep")
    return sweeps


def chosen_pairs(option: str | None, sweeps) -> list[str]:
    """The ``--pairs`` option's pairs, or the paper's pairs whose input the sweeps excite."""
    from rotorid.verification.compare import PAPER_PAIRS, primary_axis

    if option:
        return [p.strip() for p in option.split(",") if p.strip()]
    axes = {primary_axis(m) for m in sweeps}
    return [p for p in PAPER_PAIRS if p.split("/")[1] in axes]


def _check_units(structure, result: Mapping, sweeps, path: Path) -> None:
    from rotorid.errors import DataFileError
    from rotorid.units import unit_system

    expected = structure.units.name
    declared = result.get("units")
    if declared is not None and unit_system(declared).name != expected:
        raise DataFileError(f"{path}: the estimate is in {declared!r} units but the model "
                            f"structure in {expected!r}; use the model file it was estimated "
                            f"with")
    if unit_system(sweeps.units).name != expected:
        raise DataFileError(f"the sweeps are in {sweeps.units!r} units but the model in "
                            f"{expected!r}; convert the sweep files first")


def run(args) -> int:
    import matplotlib

    matplotlib.use("Agg")

    from rotorid.io import atomic_write
    from rotorid.report.plots.case import save_figure
    from rotorid.report.plots.frequency import plot_bode, plot_error
    from rotorid.verification.compare import envelopes_by_name, verify_model

    model, result_path, locations = _split(args.files)
    result = _read_result(result_path)
    structure, values = model_from_result(_structure(model, result, result_path), result,
                                          result_path)
    sweeps = load_sweeps(locations)
    _check_units(structure, result, sweeps, result_path)
    pairs = chosen_pairs(args.pairs, sweeps)
    envelopes = envelopes_by_name([e.strip() for e in args.envelopes.split(",") if e.strip()])
    verification = verify_model(structure, values, sweeps, pairs, envelopes)

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    shown = [e for e in envelopes.values() if e.kind == "bounds"]
    for item in () if args.no_figures else verification.pairs:
        stem = item.pair.replace("/", "_")
        save_figure(plot_error(item, shown), out / f"error_{stem}", formats=("png",))
        save_figure(plot_bode(item, structure.units.label(item.truth.output)),
                    out / f"bode_{stem}", formats=("png",))
    summary = verification.summary()
    summary["result"] = str(result_path)
    summary["sweeps"] = list(sweeps.names)
    atomic_write(out / "verification.json", json.dumps(summary, indent=2, allow_nan=False))
    print(verification.report())
    print(f"{'verification.json' if args.no_figures else 'figures and verification.json'} "
          f"written to {out}")
    failed = [c for p in verification.pairs for c in p.checks.values()
              if c.verified and c.passed is False]
    return 1 if args.strict and failed else 0
