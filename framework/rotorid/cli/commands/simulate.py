"""``rotorid simulate``: outputs of a linear model driven by recorded inputs.

Usage::

    rotorid simulate MODEL.toml INPUTS... --values VALUES.json --out DIR [--format csv|npz|mat]
                     [--hold zoh|foh] [--trim first-second|CH=VALUE,...]
                     [--resample linear|decimate] [--sample-time S]

``MODEL.toml`` is a model file (:mod:`rotorid.model.modelfile`). INPUTS are maneuver files,
directories or glob patterns (the ``files`` data source); their inputs drive the model and
their outputs are replaced by the simulation. ``VALUES.json`` holds the parameter values:

* a flat mapping ``{"L_p": -4.1, "tau_L_lat": 0.05}`` (free derivatives by name, delays as
  ``tau_<derivative>``; parameters not listed keep the model file's initial values), or
* an estimate written by ``rotorid identify`` (``{"parameters": {"L_p": {"value": …}},
  "delays": {"L_lat": {"value": …}}, "fixed": {…}}``): free derivatives it does not list were
  removed by the reduction, and its delays are added to the model.

The inputs are read as the estimate's identification records were (its ``ingestion``: trim
removal, resampling; its ``hold``), or as ``--trim``, ``--resample``, ``--sample-time`` and
``--hold`` say, which take precedence: a model of perturbations is driven by perturbations, and a record with dropouts
needs resampling. Without ``--values`` the model file's initial values are simulated. Each
maneuver is written
atomically to ``DIR/<name>.<format>`` with the inputs and metadata of its source file. A model
that diverges stops the command with a one-line error.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

from rotorid.cli.arguments import (add_ingestion_arguments, ingestion_settings, ingestion_text,
                                   output_directory)

NAME = "simulate"
HELP = ("simulate a linear model over recorded inputs and write the simulated outputs as "
        "maneuver files")


def add_arguments(parser) -> None:
    parser.add_argument("model", metavar="MODEL.toml", help="model file")
    parser.add_argument("inputs", nargs="+", metavar="INPUTS",
                        help="maneuver files, directories or glob patterns")
    parser.add_argument("--values", metavar="VALUES.json",
                        help="parameter values: a flat name→value JSON mapping or an estimate "
                             "written by `rotorid identify` (default: the model's initial "
                             "values)")
    parser.add_argument("--out", required=True, metavar="DIR", type=output_directory,
                        help="output directory (created if needed)")
    parser.add_argument("--format", choices=("csv", "npz", "mat"), default="csv",
                        help="format of the written maneuver files (default csv)")
    parser.add_argument("--hold", choices=("zoh", "foh"), default=None,
                        help="input hold between samples (default: the estimate's "
                             "identification records', else zoh)")
    add_ingestion_arguments(parser, "input file")


def read_values(path: Path, structure):
    """The structure, the parameter vector and the recorded ingestion settings (none for a
    flat mapping) that ``path`` (a values JSON file) describes."""
    from rotorid.errors import DataFileError
    from rotorid.estimation.result_file import load_result
    from rotorid.io import read_json_object

    content = read_json_object(path, "values file", "name → value, or an estimate with a "
                                                    "'parameters' table")
    if isinstance(content.get("parameters"), Mapping):
        identified = load_result(path, structure=structure)
        return (identified.structure, identified.structure.as_vector(identified.values),
                dict(identified.ingestion), identified.hold)
    bad = [name for name, value in content.items()
           if not isinstance(value, (int, float)) or isinstance(value, bool)]
    if bad:
        raise DataFileError(f"values file {path}: {', '.join(sorted(bad))} must be numbers; "
                            f"give a flat name → value mapping or an estimate with a "
                            f"'parameters' table")
    return structure, structure.as_vector(content), {}, None


def run(args) -> int:
    from rotorid.cli.files import load_maneuvers
    from rotorid.estimation.data_checks import check_delays
    from rotorid.model.modelfile import load_channel_map, load_model
    from rotorid.plugin.manager import create
    from rotorid.simulation.simulator import simulated_maneuvers

    structure = load_model(args.model)
    values, recorded, recorded_hold = None, {}, None
    if args.values is not None:
        structure, values, recorded, recorded_hold = read_values(Path(args.values), structure)
    ingestion = {**recorded, **ingestion_settings(args)}
    if ingestion:
        print(f"inputs read with {ingestion_text(ingestion)}")
    hold = args.hold or recorded_hold or "zoh"
    if args.hold is None and recorded_hold == "foh":
        print("inputs held as the identification records were: foh")
    maneuvers = load_maneuvers(args.inputs, hold, structure.units.name,
                               {**ingestion, "signals": structure.signals,
                                "channels": load_channel_map(args.model)})
    check_delays(structure, maneuvers, values)
    simulated = simulated_maneuvers(structure, values, maneuvers)
    paths = create("data-sources", "files", hold=hold).save(simulated, args.out, format=args.format)
    print(f"simulated {len(paths)} maneuver(s) with {structure.n_parameters} parameters; "
          f"wrote {Path(args.out)}")
    return 0
