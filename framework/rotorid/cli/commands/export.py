"""``rotorid export``: an identified model as A, B, C, D for use outside rotorid.

Usage::

    rotorid export RESULT.json --format mat|csv|json|python-control --out PATH
                   [--model "with delays"|"no delays"] [--structure MODEL.toml] [--pade N]
                   [--force]

``RESULT.json`` is a ``rotorid identify`` result or a study's ``result.json`` (``--model``
chooses which of its two models; default the one with delays). The system keeps the controls
that drive the model, the states they reach and the outputs that respond
(:mod:`rotorid.model.statespace`); ``--pade N`` realises the delays by N-th order Padé
approximations among the states, otherwise the matrices ignore them and the delays are listed
beside them. The formats: :mod:`rotorid.model.statespace_files` and docs/export.md.
"""

from __future__ import annotations

from collections.abc import Mapping

NAME = "export"
HELP = ("write an identified model's A, B, C, D with signal names, units and delays as MATLAB, "
        "CSV, JSON or a python-control script")


def add_arguments(parser) -> None:
    from rotorid.estimation.result_file import STUDY_MODELS
    from rotorid.model.statespace_files import FORMATS

    parser.add_argument("result", metavar="RESULT.json",
                        help="a `rotorid identify` result or a study's result.json")
    parser.add_argument("--format", required=True, choices=FORMATS,
                        help="mat (MATLAB), csv (a directory of tables), json, or "
                             "python-control (a Python file defining system())")
    parser.add_argument("--out", required=True, metavar="PATH",
                        help="file to write (a directory for csv)")
    parser.add_argument("--model", choices=STUDY_MODELS, default=None,
                        help="which model of a study result (default: with delays)")
    parser.add_argument("--structure", metavar="MODEL.toml", default=None,
                        help="model file the estimate belongs to, when the result names none")
    parser.add_argument("--pade", type=int, default=0, metavar="N",
                        help="realise each delay by an N-th order Padé approximation among the "
                             "states (default 0: the matrices ignore the delays, which are "
                             "listed beside them)")
    parser.add_argument("--force", action="store_true", help="overwrite PATH if it exists")


def run(args) -> int:
    from rotorid.cli.files import refuse_overwrite
    from rotorid.errors import ExitStatus, UsageError
    from rotorid.estimation.result_file import load_result
    from rotorid.model.modelfile import load_model
    from rotorid.model.statespace_files import write_state_space

    if args.pade < 0:
        raise UsageError(f"--pade must be 0 (delays listed only) or a positive order, got "
                         f"{args.pade}")
    out = refuse_overwrite(args.out, args.force)
    structure = None if args.structure is None else load_model(args.structure)
    identified = load_result(args.result, args.model, structure)
    trim = identified.ingestion.get("trim")
    system = identified.state_space(args.pade).with_channels(
        _channel_map(args, identified), trim if isinstance(trim, Mapping) else None)
    source = args.result + (f", model {identified.model!r}" if identified.model else "")
    write_state_space(system, out, args.format, source)
    print(f"{system!r} written to {out}")
    if isinstance(trim, Mapping):
        print(f"the channels' offsets take off the identification's stated trim "
              f"({', '.join(f'{k}={v:g}' for k, v in trim.items())}): they give the model's "
              f"perturbations")
    elif trim == "first-second":
        print("note: the identification records' trim was each record's mean over its first "
              "second; take that mean off each channel's signal before driving the model, "
              "which is in perturbations from trim")
    return ExitStatus.OK


def _channel_map(args, identified):
    """The channel map the identification records were read with: the model file's
    (``--structure``, else the one the result names), else a study case's ``[data]
    channels``; empty when there is none."""
    from rotorid.estimation.result_file import named_model_file
    from rotorid.model.modelfile import load_channel_map
    from rotorid.model.signals import ChannelMap

    model_file = args.structure or named_model_file(args.result)
    if model_file is not None:
        return load_channel_map(model_file)
    recorded = identified.ingestion.get("channels")
    return ChannelMap.from_mapping(recorded) if recorded else ChannelMap()
