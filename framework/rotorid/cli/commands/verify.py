"""``rotorid verify``: frequency-domain verification of an identified model on sweeps.

Usage::

    rotorid verify [MODEL.toml] RESULT.json SWEEPS... [--pairs q/long,p/long] [--out DIR]
                   [--force] [--trim first-second|CH=VALUE,...] [--hold zoh|foh]

``RESULT.json`` is an estimate written by ``rotorid identify`` or a study's ``result.json``
(its model with delays, or the one ``--model`` names), read by
:func:`rotorid.estimation.result_file.load_result`: ``parameters`` and ``delays``
(``{"L_lat": {"value": 0.05}}``), ``fixed`` values and ``structure`` (the model file's path,
relative to the result file, or an embedded model-file mapping). ``MODEL.toml`` overrides
the structure (the estimate JSON of ``Estimate.as_dict`` names none, so give it). Free
derivatives of the structure that the result does not list were removed by the reduction and
are dropped; output biases and initial states of the identification records are ignored.
SWEEPS are maneuver files, directories or glob patterns, read through the model file's
``[channels]`` map (a study's result: its case's ``[data] channels``) and converted to its unit
system, with the trim removal and resampling the identification records had (the result's
``ingestion``; ``--trim`` states another trim) and simulated with their input hold (the
result's ``hold``; ``--hold`` states another). When the maneuvers carry ``kind`` metadata
only the ``sweep`` ones are used; without it, a maneuver whose input reverses only a few
times (a multistep or doublet) gets a note, since its frequency responses rest on few
frequencies (:func:`rotorid.verification.pairs.step_input_notes`). They need only the channels
the model uses (a ``longitudinal`` model verifies on sweeps without lateral columns); a sweep
of a control the model lacks (``axis`` metadata, or none of the model's controls moving in
it) is left out with a line saying so, so a directory holding every axis's sweeps can be
given. A result identified with the actuators' lag (``actuator_lag_s``,
:mod:`rotorid.actuators`) has the sweeps' inputs put through the same lag. A result of a
model of one's own (``model``: ``file.py:Name``) is verified through its simulation of the
sweeps, read through its own channel map (:mod:`rotorid.verification.integrated`).

Pairs are ``OUTPUT/INPUT`` names of the model's signals; by default the paper's pairs the model
has (q/long and az/coll for the ``longitudinal`` template), else every output over every input
(:func:`rotorid.verification.pairs.default_pairs`), limited to the inputs the sweeps excite.
A pair the model or the sweeps cannot produce (the model lacks its signals, no sweep excites
its input, the model's output does not respond to that input, the measured output never
moves) is skipped with the reason
(:mod:`rotorid.verification.producible`). Writes ``verification.json`` (every check, J_ave,
time-domain metrics, the skipped pairs, and per pair the frequency responses it was judged
on) and, per pair, ``error_<output>_<input>.png`` and ``bode_<output>_<input>.png`` into
``--out``. Progress (stderr): a line per pair compared and per pair drawn, with a bar and the
time left (:class:`rotorid.progress.Countdown`).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

from rotorid.data import HOLDS
from rotorid.cli.arguments import names, output_directory, trim

NAME = "verify"
HELP = ("verify an identified model on frequency sweeps: ε = H_model/H_measured against the "
        "MUAD/AEE envelopes and the mismatch cost J, with figures and a JSON of the checks")
DEFAULT_ENVELOPES = "muad,aee,mismatch-cost"


def add_arguments(parser) -> None:
    from rotorid.estimation.result_file import STUDY_MODELS

    parser.add_argument("files", nargs="+", metavar="FILE",
                        help="[MODEL.toml] RESULT.json SWEEPS...: optional model file, the "
                             "estimate JSON, then sweep files, directories or glob patterns")
    parser.add_argument("--pairs", default=None,
                        help="comma-separated OUTPUT/INPUT pairs of the model's outputs and "
                             "inputs (default: the paper's q/long,p/long,q/lat,p/lat,r/coll,"
                             "az/coll,r/ped,ay/ped that the model has, else every pair of the "
                             "model; limited to the axes the sweeps excite)")
    parser.add_argument("--model", choices=STUDY_MODELS, default=None,
                        help="which model of a study's result.json (default: with delays)")
    parser.add_argument("--trim", type=trim, default=None,
                        metavar="first-second|CH=VALUE,...",
                        help="remove the trim from every sweep: each channel's mean over the "
                             "first second, or stated values in the model's units (default: "
                             "as the result's identification records were)")
    parser.add_argument("--hold", choices=HOLDS, default=None,
                        help="the sweeps' input hold between samples (default: the "
                             "identification records', as the result records it)")
    parser.add_argument("--envelopes", default=DEFAULT_ENVELOPES,
                        help=f"comma-separated envelope names ({DEFAULT_ENVELOPES})")
    parser.add_argument("--band", default=None, metavar="COHERENCE,OMEGA_MIN,OMEGA_MAX",
                        help="the verification band every check counts points in: γ² "
                             "threshold and frequency range in rad/s (default 0.8,0.1,10)")
    parser.add_argument("--out", default="verification", metavar="DIR", type=output_directory,
                        help="output directory (created if needed; default ./verification)")
    parser.add_argument("--force", action="store_true",
                        help="overwrite an earlier verification in DIR")
    parser.add_argument("--no-figures", action="store_true",
                        help="write only verification.json (faster)")
    parser.add_argument("--strict", action="store_true",
                        help="exit with status 1 when a verified envelope check fails")


def parse_band(text: str | None):
    """The :class:`~rotorid.verification.band.VerificationBand` of ``--band`` (default when
    None)."""
    from rotorid.errors import UsageError, VerificationError
    from rotorid.verification.band import DEFAULT_BAND, VerificationBand

    if text is None:
        return DEFAULT_BAND
    try:
        values = [float(part) for part in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3:
        raise UsageError(f"--band needs COHERENCE,OMEGA_MIN,OMEGA_MAX, e.g. 0.8,0.1,10; got "
                         f"{text!r}")
    try:
        return VerificationBand(*values)
    except VerificationError as error:
        raise UsageError(f"--band: {error}") from None


def _split(files: list[str]):
    from rotorid.errors import UsageError

    model = files[0] if files[0].lower().endswith(".toml") else None
    rest = files[1:] if model else files
    if len(rest) < 2 or not rest[0].lower().endswith(".json"):
        raise UsageError("give [MODEL.toml] RESULT.json SWEEPS...: the estimate JSON and at "
                         "least one sweep file, directory or pattern")
    return model, Path(rest[0]), rest[1:]


def load_sweeps(locations, units: str | None = None, ingestion=None, convert=None,
                hold: str = "zoh"):
    """(sweeps, left out): the maneuvers of files, directories or patterns
    (:func:`rotorid.cli.files.load_maneuvers`, with input ``hold``), only the ``sweep`` ones
    when the maneuvers carry
    ``kind`` metadata, without those that sweep none of the model's controls
    (:func:`_not_sweeping`: a lateral sweep in a directory read for a longitudinal model);
    left out: name → reason. Raises VerificationError when no sweep is left."""
    from rotorid.cli.files import load_maneuvers
    from rotorid.errors import VerificationError

    sweeps = load_maneuvers(locations, hold, units=units, ingestion=ingestion)
    if convert is not None:                  # into a model of one's own's signals
        sweeps = convert(sweeps)
    if any("kind" in m.metadata for m in sweeps):
        sweeps = sweeps.select(kind="sweep")
    left_out = {m.name: reason for m in sweeps if (reason := _not_sweeping(m)) is not None}
    if left_out and len(left_out) == len(sweeps):
        raise VerificationError("no sweep excites a control of the model: " + "; ".join(
            f"{name}: {reason}" for name, reason in left_out.items()))
    return sweeps.select(lambda m: m.name not in left_out), left_out


def _data_warnings(sweeps, structure) -> list[str]:
    """What the sanity checks of identification data (:func:`rotorid.estimation.sanity.
    check_data`: 1 g in az, absolute attitudes, rates in rad/s, kinematic consistency) find in
    the sweeps as read: a trim left in makes every verdict on them meaningless."""
    import warnings

    from rotorid.errors import DataWarning
    from rotorid.estimation.sanity import check_data, checks_report

    with warnings.catch_warnings(record=True) as caught, checks_report(shown=False):
        warnings.simplefilter("always", DataWarning)
        check_data(sweeps, structure.condition, structure.signals)
    return [str(w.message) for w in caught if issubclass(w.category, DataWarning)]


def _not_sweeping(sweep) -> str | None:
    """Why ``sweep``, read with a model's controls, sweeps none of them; None when it does."""
    import numpy as np

    controls = ", ".join(sweep.input_names)
    axis = sweep.metadata.get("axis")
    if axis is not None and axis not in sweep.input_names:
        return (f"it sweeps {axis!r}, not a control of the model ({controls}); name one of "
                f"them (or the column the channel map links to it) as the file's axis")
    if not np.any(np.ptp(sweep.inputs, axis=0) > 0):
        return f"none of the model's controls ({controls}) moves in it"
    return None


def chosen_pairs(option: str | None, sweeps, outputs, inputs) -> list[str]:
    """The ``--pairs`` option's pairs, each checked against the ``outputs`` and ``inputs`` (a
    model's, or the sweeps' own); by default the
    :func:`~rotorid.verification.pairs.default_pairs` of those signals whose input the sweeps
    excite."""
    from rotorid.verification.pairs import default_pairs, parse_pair, primary_axis

    if option:
        pairs = names(option)
        for pair in pairs:
            parse_pair(pair, outputs, inputs)
        return pairs
    axes = {primary_axis(m) for m in sweeps}
    return [p for p in default_pairs(outputs, inputs) if p.split("/")[1] in axes]


def _model_file(model: str | None, result_path: Path):
    """The model file whose ``[channels]`` the sweeps are read with: ``MODEL.toml`` if given,
    else the one the result names (None for a study result)."""
    from rotorid.estimation.result_file import named_model_file

    return Path(model) if model is not None else named_model_file(result_path)


def _db_deg(response) -> dict:
    from rotorid.verification.envelopes import error_db_deg

    magnitude, phase = error_db_deg(response)
    return {"magnitude_db": magnitude.tolist(), "phase_deg": phase.tolist()}


def response_arrays(item) -> dict:
    """The frequency responses a pair was judged on: ω (rad/s), the truth's coherence, the
    measured and the model's response and ε = model/measured, each as magnitude (dB) and phase
    (deg, wrapped to (−180, 180]); with the analytic model, the conditioned measured response
    and its partial coherence too. NaN marks points no window covered."""
    arrays = {"omega_rad_s": item.omega.tolist(), "coherence": item.coherence.tolist(),
              "measured": _db_deg(item.truth.response), "model": _db_deg(item.model.response),
              "error": _db_deg(item.error)}
    if item.analytic_error is not None:
        arrays["analytic"] = {"coherence": item.analytic_coherence.tolist(),
                              "measured": _db_deg(item.conditioned.response),
                              "model": _db_deg(item.analytic),
                              "error": _db_deg(item.analytic_error)}
    return arrays


def run(args) -> int:
    import matplotlib

    matplotlib.use("Agg")

    from rotorid.cli.files import refuse_overwrite
    from rotorid.estimation.result_file import named_model_reference
    from rotorid.verification.compare import envelopes_by_name

    model, result_path, locations = _split(args.files)
    band = parse_band(args.band)
    refuse_overwrite(Path(args.out) / "verification.json", args.force)
    envelopes = envelopes_by_name(names(args.envelopes), band=band)
    reference = None if model is not None else named_model_reference(result_path)
    if reference is not None:
        verification, signals, sweeps, skipped = _verify_own_model(
            args, reference, result_path, locations, band, envelopes)
    else:
        verification, signals, sweeps, skipped = _verify_structure(
            args, model, result_path, locations, band, envelopes)
    return _write(args, verification, signals, sweeps, skipped, result_path, envelopes)


def _read_sweeps(args, locations, units, ingestion, warnings_of, convert=None,
                 recorded_hold: str = "zoh"):
    """The sweeps as :func:`load_sweeps` reads them with ``ingestion`` (``--trim`` in place of
    the recorded trim) and the identification's ``recorded_hold`` (``--hold`` in its place),
    with a line for each trim, hold other than zoh, left-out sweep and data warning
    (``warnings_of(sweeps)``)."""
    from rotorid.cli.arguments import trim_text

    if args.trim is not None:
        ingestion["trim"] = args.trim
    if ingestion.get("trim") is not None:
        how = "--trim" if args.trim is not None else "the identification records' trim removal"
        print(f"sweeps read with {how}: {trim_text(ingestion['trim'])}")
    hold = args.hold or recorded_hold
    if hold != "zoh":
        how = "--hold" if args.hold is not None else "the identification records' hold"
        print(f"sweeps simulated with {how}: {hold}")
    sweeps, left_out = load_sweeps(locations, units, ingestion, convert, hold)
    for name, reason in left_out.items():
        print(f"left out {name}: {reason}")
    for warning in warnings_of(sweeps):
        print(f"warning: {warning}")
    return sweeps


def _verify_structure(args, model, result_path, locations, band, envelopes):
    """(verification, signals, sweeps, skipped pairs) of a linear structure's result."""
    from rotorid.actuators import lagged_inputs
    from rotorid.errors import VerificationError
    from rotorid.estimation.result_file import load_result
    from rotorid.model.modelfile import load_channel_map, load_model
    from rotorid.progress import Countdown
    from rotorid.verification.producible import producible_pairs
    from rotorid.verification.verify import verify_model

    identified = load_result(result_path, args.model,
                             None if model is None else load_model(model))
    structure, values = identified.structure, identified.values
    model_file = _model_file(model, result_path)
    ingestion = {"signals": structure.signals, **identified.ingestion}
    if model_file is not None:
        ingestion["channels"] = load_channel_map(model_file)
    sweeps = _read_sweeps(args, locations, structure.units.name, ingestion,
                          lambda read: _data_warnings(read, structure),
                          recorded_hold=identified.hold)
    if identified.actuator_lag_s is not None:
        sweeps = lagged_inputs(sweeps, identified.actuator_lag_s, identified.actuator_inputs)
        print(f"sweep inputs through the identification's {identified.actuator_lag_s:g} s "
              f"actuator lag")
    selection = producible_pairs(structure, values, sweeps,
                                 chosen_pairs(args.pairs, sweeps, structure.outputs,
                                              structure.controls))
    if not selection.pairs:
        raise VerificationError("no pair can be verified: " + "; ".join(
            f"{pair}: {reason}" for pair, reason in selection.skipped.items()))
    log = logging.getLogger("rotorid.verify")
    log.info("verifying %s on %d sweep(s)", ", ".join(selection.pairs), len(sweeps))
    compared = Countdown(len(selection.pairs))
    verification = verify_model(
        structure, values, sweeps, selection.pairs, envelopes, band=band,
        on_pair=lambda item: log.info("%s compared %s", item.pair, compared.step()))
    return verification, structure.signals, sweeps, selection.skipped


def _verify_own_model(args, reference, result_path, locations, band, envelopes):
    """(verification, signals, sweeps, no skipped pairs) of a model of one's own's result
    (:mod:`rotorid.verification.integrated`)."""
    from rotorid.data import ManeuverSet
    from rotorid.errors import UsageError
    from rotorid.estimation.result_file import checked_hold
    from rotorid.io import read_json_object
    from rotorid.model.reference import load_model_reference
    from rotorid.verification.integrated import signal_sweeps, verify_integrated

    if args.model is not None:
        raise UsageError(f"{result_path} is a `rotorid identify` result holding one model; "
                         f"--model applies to study results only")
    own = load_model_reference(reference)
    record = read_json_object(result_path, "result file")
    values = {name: entry["value"] for name, entry in record.get("parameters", {}).items()
              if isinstance(entry, dict) and "value" in entry}
    settings = record.get("ingestion") if isinstance(record.get("ingestion"), dict) else {}
    ingestion = {**settings, "keep_columns": own.columns, "channels": own.channels.time_links()}
    as_recorded = {}

    def in_signals(read):                   # the sweeps are chosen by the model's inputs
        as_recorded.update({m.name: m for m in read})
        return signal_sweeps(own, read)

    sweeps = _read_sweeps(args, locations, None, ingestion, lambda read: [], in_signals,
                          checked_hold(record.get("hold"), result_path))
    raw = ManeuverSet([as_recorded[m.name] for m in sweeps], hold=sweeps.hold)
    pairs = None if args.pairs is None else names(args.pairs)
    verification = verify_integrated(own, values, raw, pairs, envelopes, band=band)
    return verification, own.signals, sweeps, {}


def _write(args, verification, signals, sweeps, skipped, result_path, envelopes) -> int:
    """Figures, ``verification.json`` and the report of ``verification``; the exit status."""
    from rotorid.errors import ExitStatus
    from rotorid.io import atomic_write, jsonable
    from rotorid.progress import Countdown
    from rotorid.report.plots.case import save_figure
    from rotorid.report.plots.frequency import plot_bode, plot_error

    log = logging.getLogger("rotorid.verify")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    shown = [e for e in envelopes.values() if e.kind == "bounds"]
    drawn = Countdown(len(verification.pairs))
    for item in () if args.no_figures else verification.pairs:
        stem = item.pair.replace("/", "_")
        save_figure(plot_error(item, shown), out / f"error_{stem}", formats=("png",))
        save_figure(plot_bode(item, signals.outputs[item.truth.output].unit,
                              signals.inputs[item.truth.input].unit),
                    out / f"bode_{stem}", formats=("png",))
        log.info("%s figures drawn %s", item.pair, drawn.step())
    summary = verification.summary()
    for entry, item in zip(summary["pairs"], verification.pairs):
        entry["frequency_response"] = response_arrays(item)
    summary["skipped_pairs"] = [{"pair": pair, "reason": reason}
                                for pair, reason in skipped.items()]
    summary["result"] = str(result_path)
    summary["sweeps"] = list(sweeps.names)
    atomic_write(out / "verification.json",
                 json.dumps(jsonable(summary), indent=1, allow_nan=False))
    for pair, reason in skipped.items():
        print(f"skipped {pair}: {reason}")
    print(verification.report())
    print(f"{'verification.json' if args.no_figures else 'figures and verification.json'} "
          f"written to {out}")
    failed = [c for p in verification.pairs for c in p.checks.values()
              if c.verified and c.passed is False]
    return ExitStatus.CHECK_FAILED if args.strict and failed else ExitStatus.OK
