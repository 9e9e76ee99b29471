"""``rotorid frequency``: frequency responses of sweeps as data.

Usage::

    rotorid frequency SWEEPS... [--model MODEL.toml] [--pairs q/long,p/lat] [--conditioned]
                      [--handling-qualities] --out responses.json [--force]

SWEEPS are maneuver files, directories or glob patterns (only ``kind = sweep`` maneuvers when
the files say their kind). Each pair's composite response (:mod:`rotorid.verification.frequency`)
comes from the sweeps whose axis is its input, on the default log grid of the verification
(:func:`rotorid.verification.compare.default_omega`). With ``--model`` the files are read
through a model file's signals and ``[channels]`` table (an aeroplane's channels, a test
range's column names and units) and converted to its unit system. The file's suffix picks the
format:

* ``.json``: ``{"sweeps", "units", "pairs": [{"pair", "input", "output", "conditioned_on",
  "windows_s", "omega_rad_s", "magnitude_db", "phase_deg", "real", "imag", "coherence",
  "random_error"}]}`` (NaN where no window covers a frequency written as null);
* ``.csv``: one row per pair and frequency with those columns;
* ``.mat``: one struct per pair named ``<output>_<input>`` with the same fields and ``H``
  (complex).

Frequencies in rad/s, magnitudes in dB of output unit per input unit, phases in deg
(unwrapped), coherence γ² (partial with ``--conditioned``), random error normalised.

``--handling-qualities`` adds the attitude pairs ``theta/long``, ``phi/lat`` and ``r/ped`` (the
heading's) that the sweeps hold and excite, prints their ADS-33 bandwidth and phase delay
(:mod:`rotorid.verification.handling_qualities`) and writes them as ``handling_qualities``
to a JSON or MAT file.
"""

from __future__ import annotations

from pathlib import Path

from rotorid.cli.arguments import output_file

NAME = "frequency"
HELP = ("frequency responses of sweeps as data: ω, H (dB, deg, complex), coherence and "
        "random error per pair, to JSON, CSV or MAT")
FORMATS = (".json", ".csv", ".mat")
COLUMNS = ("omega_rad_s", "magnitude_db", "phase_deg", "real", "imag", "coherence",
           "random_error")


def add_arguments(parser) -> None:
    parser.add_argument("sweeps", nargs="+", metavar="SWEEPS",
                        help="sweep files, directories or glob patterns")
    parser.add_argument("--model", default=None, metavar="MODEL.toml",
                        help="read the sweeps through this model file's signals and [channels] "
                             "table, in its unit system (for channels other than the "
                             "helicopter's, or a test range's column names)")
    parser.add_argument("--pairs", default=None,
                        help="comma-separated OUTPUT/INPUT pairs of the sweeps' channels "
                             "(default: the paper's pairs they hold, else every output over "
                             "every input, limited to the inputs the sweeps excite)")
    parser.add_argument("--conditioned", action="store_true",
                        help="condition each response on the other inputs that moved in its "
                             "sweeps (partial coherence)")
    parser.add_argument("--handling-qualities", action="store_true",
                        help="add the attitude pairs theta/long, phi/lat and r/ped the sweeps "
                             "hold and excite, and report their ADS-33 bandwidth and phase "
                             "delay")
    parser.add_argument("--out", required=True, metavar="FILE", type=output_file,
                        help="responses.json, responses.csv or responses.mat")
    parser.add_argument("--force", action="store_true", help="overwrite FILE if it exists")


def response_columns(response) -> dict:
    """One response's arrays by column name, each shape (M,)."""
    return {"omega_rad_s": response.omega, "magnitude_db": response.magnitude_db,
            "phase_deg": response.phase_deg, "real": response.response.real,
            "imag": response.response.imag, "coherence": response.coherence,
            "random_error": response.random_error}


def _json(responses, sweeps, qualities) -> str:
    import json

    from rotorid.io import jsonable

    pairs = [{"pair": r.pair, "input": r.input, "output": r.output,
              "conditioned_on": list(r.conditioned_on), "windows_s": list(r.windows),
              **{k: v.tolist() for k, v in response_columns(r).items()}} for r in responses]
    record = {"sweeps": list(sweeps.names), "units": sweeps.units, "pairs": pairs}
    if qualities is not None:
        record["handling_qualities"] = [q.as_dict() for q in qualities]
    return json.dumps(jsonable(record), indent=1)


def _csv(responses) -> str:
    import numpy as np

    lines = [",".join(("pair", *COLUMNS))]
    for r in responses:
        table = np.column_stack(list(response_columns(r).values()))
        lines.extend(f"{r.pair}," + ",".join(f"{x:.10g}" for x in row) for row in table)
    return "\n".join(lines) + "\n"


def _mat(responses, qualities):
    import numpy as np
    import scipy.io

    structs = {r.pair.replace("/", "_"): {**response_columns(r), "H": r.response,
                                          "input": r.input, "output": r.output}
               for r in responses}
    if qualities is not None:       # MATLAB has no null: NaN where a crossing is missing
        structs["handling_qualities"] = {
            q.pair.replace("/", "_"): {k: np.nan if v is None else v
                                       for k, v in q.as_dict().items()} for q in qualities}
    return lambda handle: scipy.io.savemat(handle, structs)


def _print_qualities(qualities) -> None:
    def number(value, unit):
        return "–" if value is None else f"{value:.3g} {unit}"

    if not qualities:
        print("handling qualities: the sweeps hold and excite none of theta/long, phi/lat, "
              "r/ped")
    for q in qualities:
        print(f"{q.pair:<12} ADS-33 bandwidth {number(q.bandwidth, 'rad/s')} (phase "
              f"{number(q.phase_bandwidth, 'rad/s')}, gain {number(q.gain_bandwidth, 'rad/s')}),"
              f" ω180 {number(q.omega_180, 'rad/s')}, phase delay "
              f"{number(q.phase_delay, 's')}")


def run(args) -> int:
    from rotorid.cli.commands.verify import chosen_pairs, load_sweeps
    from rotorid.cli.files import refuse_overwrite
    from rotorid.errors import UsageError
    from rotorid.io import atomic_write
    from rotorid.verification.compare import default_omega
    from rotorid.verification.frequency import moving_inputs, response_from_maneuvers
    from rotorid.verification.handling_qualities import (
        measured_handling_qualities,
        sweep_attitude_pairs,
    )
    from rotorid.verification.pairs import parse_pair, step_input_notes, sweeps_exciting

    out = Path(args.out)
    if out.suffix.lower() not in FORMATS:
        raise UsageError(f"--out {out}: give a file ending in {', '.join(FORMATS)}")
    refuse_overwrite(out, args.force)
    units, ingestion = None, None
    if args.model is not None:
        from rotorid.model.modelfile import load_channel_map, load_model

        structure = load_model(args.model)
        units = structure.units.name
        ingestion = {"signals": structure.signals, "channels": load_channel_map(args.model)}
    sweeps, _ = load_sweeps(args.sweeps, units, ingestion)
    for note in step_input_notes(sweeps):
        print(f"warning: {note}")
    omega = default_omega(sweeps)
    responses = []
    pairs = chosen_pairs(args.pairs, sweeps, sweeps.output_names, sweeps.input_names)
    if args.handling_qualities:
        pairs = list(dict.fromkeys([*pairs, *sweep_attitude_pairs(sweeps)]))
    for pair in pairs:
        output, control = parse_pair(pair, sweeps.output_names, sweeps.input_names)
        subset = sweeps_exciting(sweeps, control, pair, UsageError)
        others = moving_inputs(subset, control) if args.conditioned else ()
        responses.append(response_from_maneuvers(subset, control, output, omega,
                                                 conditioned_on=others))
    if out.parent != Path(""):
        out.parent.mkdir(parents=True, exist_ok=True)
    qualities = (measured_handling_qualities(responses) if args.handling_qualities else None)
    suffix = out.suffix.lower()
    atomic_write(out, _json(responses, sweeps, qualities) if suffix == ".json"
                 else _csv(responses) if suffix == ".csv" else _mat(responses, qualities))
    for r in responses:
        coherent = r.omega[r.coherence >= 0.6]
        band = (f"γ² ≥ 0.6 over {coherent.min():.2f}–{coherent.max():.2f} rad/s"
                if coherent.size else "no frequency with γ² ≥ 0.6")
        print(f"{r.pair:<12} {band}")
    if qualities is not None:
        _print_qualities(qualities)
    print(f"wrote {len(responses)} responses to {out}")
    return 0
