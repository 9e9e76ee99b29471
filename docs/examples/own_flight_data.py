"""Identify a helicopter model from your own flight data in CSV files.

A walk-through for a flight-test engineer: from exported maneuver files to a reduced model
with delays, verified against frequency sweeps. The steps:

1. **Export one CSV file per maneuver** (format below): the multisteps (3211, 2311, doublets)
   you identify from in one folder, the frequency sweeps you verify with in another.
2. **Check the files**: load them with rotorid's ``files`` data source and look at the
   inventory (name, kind, axis, length, sample time, input amplitude). Loading stops at the
   first bad value with the file, line, row and channel.
3. **Write a case file** (TOML) naming the files, the trim condition and the pipeline options
   (or build the same settings as a mapping: ``FlightCase.from_mapping({...})``).
4. **Run the case**: from Python (``Study`` / ``run_case``, as here) or with the command
   ``rotorid study my-hover.toml --out results``.
5. **Read the results**: ``OUT/my-hover/result.json`` (``results/own-data/my-hover/`` with the
   command below), ``OUT/report.html`` and the printed summary (reduction path, selected
   structure, delays, key derivatives, verification per sweep pair).

CSV format (details in docs/conventions.md, "Maneuver files")::

    # name: hover_3211_long_pos
    # kind: "3211"
    # axis: long
    # direction: 1
    time,long,lat,coll,ped,ax,az,q,theta,ay,p,phi,r
    0.0,0.0,0.0,0.0,0.0,0.012,-0.031,0.05,0.01,-0.02,0.11,-0.03,0.02
    0.02,0.0,0.0,0.0,0.0,...

* columns: ``time`` in s, uniformly sampled (resample first), then the controls ``long lat
  coll ped`` in % of full travel (stick forward, stick right, collective up, right pedal
  positive) and the outputs ``ax az q theta ay p phi r``: body-axis specific forces in ft/s²,
  rates in deg/s, attitudes in deg. ``# units: si`` declares m/s², rad/s and rad instead;
* every channel is a **perturbation from trim**: subtract the trim values (for example the
  mean over the steady second before the input) before exporting; the trim itself goes into
  the case file's ``[condition]`` table (airspeed, pitch and bank attitude);
* header lines ``# key: value``: ``kind`` (quote ``"3211"`` so that it stays text) and ``axis``
  (the excited control) describe the maneuver; ``axis`` tells the verification which input a
  sweep excites. Any other key (flight number, pilot, gross weight …) is kept as metadata.

Without your own files the script first writes demonstration files: the built-in nonlinear
truth model (the ``helisim`` data source) trimmed in hover and flown with multisteps and
sweeps, saved exactly in the format above, so every step runs as it would on flight data.

Run it from the repository root with the Python that has rotorid installed (README's
``.venv/bin/python``, or ``python`` with that environment active)::

    # demonstration data, reduced run (about 90 s on 2 cores, figures included; measured
    # 2026-11-28, 64 s through `rotorid study` on the case file it writes)
    .venv/bin/python docs/examples/own_flight_data.py results/own-data --quick
    # your files
    .venv/bin/python docs/examples/own_flight_data.py results/flight-042 \\
        --identification 'flight042/multisteps/*.csv' --verification 'flight042/sweeps/*.csv' \\
        --airspeed-kt 0 --theta0-deg 2.1 --phi0-deg -2.8

``--quick`` (or ``ROTORID_QUICK=1``) makes the demonstration data shorter (one direction per
multistep, records at 60 %) and stops the reduction with the criteria; without it the
reduction continues to zero parameters for the full RMSE-versus-removals curve, as in the
paper. ``--no-figures`` skips the figures and the HTML report (``OUT/report.html``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import rotorid
from rotorid.data import INPUT_CHANNELS, OUTPUT_CHANNELS
from rotorid.io import atomic_write
from rotorid.study.case import FlightCase
from rotorid.study.result import CaseResult

sys.path.insert(0, str(Path(__file__).resolve().parent))

from study_hover import print_summary, quick_requested, run_study  # noqa: E402

CASE_NAME = "my-hover"
COLUMNS = ("time", *INPUT_CHANNELS, *OUTPUT_CHANNELS)
#: What a test engineer notes per run; the truth model's other metadata is left out.
KEPT_METADATA = ("kind", "axis", "direction")


# ----------------------------------------------------------------- step 1: the files
def write_csv(path: Path, maneuver, header: dict) -> Path:
    """One maneuver as a CSV file: ``# key: value`` header lines, channel row, samples."""
    lines = [f"# name: {maneuver.name}"]
    # Values as JSON: "3211" stays text, 1 a number.
    lines += [f"# {key}: {json.dumps(value)}" for key, value in header.items()]
    lines.append(",".join(COLUMNS))
    table = np.column_stack([maneuver.channel(name) for name in COLUMNS])
    lines += [",".join(f"{v:.7g}" for v in row) for row in table]
    return atomic_write(path, "\n".join(lines) + "\n")


def write_demo_flight_data(directory: Path, quick: bool, seed: int = 0) -> dict:
    """Fly the truth model in hover and export its maneuvers as flight-test CSV files.

    Returns the file patterns and the trim condition a test engineer would have noted:
    ``{"identification": glob, "verification": glob, "condition": {...}}``.
    """
    settings = {"condition": "hover", "seed": seed}
    if quick:
        settings.update(duration_scale=0.6, directions=[1])
    flown = rotorid.create("data-sources", "helisim").generate(settings)
    folders = {"3211": "multisteps", "2311": "multisteps", "sweep": "sweeps"}
    for maneuver in flown:
        folder = directory / folders[maneuver.metadata["kind"]]
        folder.mkdir(parents=True, exist_ok=True)
        header = {key: maneuver.metadata[key] for key in KEPT_METADATA}
        write_csv(folder / f"{maneuver.name}.csv", maneuver, header)
    trim = flown[0].metadata
    return {"identification": str(directory / "multisteps" / "*.csv"),
            "verification": str(directory / "sweeps" / "*.csv"),
            "condition": {"airspeed_kt": trim["airspeed_kt"],
                          "theta0_deg": round(trim["trim_theta_deg"], 2),
                          "phi0_deg": round(trim["trim_phi_deg"], 2)}}


# ----------------------------------------------------------------- step 2: check them
def inventory(location: str) -> str:
    """Load the files of one pattern and list them: the first check of new data."""
    maneuvers = rotorid.create("data-sources", "files").load(location)
    lines = [f"{location}: {len(maneuvers)} maneuvers",
             f"  {'name':<24}{'kind':>6}{'axis':>6}{'length s':>10}{'dt s':>7}"
             f"{'peak input %':>14}"]
    for m in maneuvers:
        axis = m.metadata.get("axis", "?")
        peak = (np.abs(m.channel(axis)).max() if axis in INPUT_CHANNELS
                else np.abs(m.inputs).max())
        lines.append(f"  {m.name:<24}{m.metadata.get('kind', '?'):>6}{axis:>6}"
                     f"{m.duration:>10.1f}{m.dt:>7.3f}{peak:>14.2f}")
    return "\n".join(lines)


# ----------------------------------------------------------------- step 3: the case file
def case_text(identification: str, verification: str | None, condition: dict,
              quick: bool) -> str:
    """A case TOML for flight data; every table but [data] and [condition] is optional."""
    verification_line = "" if verification is None else f"verification = {verification!r}\n"
    return f"""\
# Identification of my own hover flight data (see docs/examples/own_flight_data.py)
name = "{CASE_NAME}"
description = "Hover flight data from CSV files"

[data]
source = "files"                       # maneuver files (.csv, .npz, .mat)
identification = {identification!r}    # a file, a folder or a glob
{verification_line}
[condition]                            # the trim point the perturbations are taken from
airspeed_kt = {condition['airspeed_kt']}
theta0_deg = {condition['theta0_deg']}
phi0_deg = {condition['phi0_deg']}

[verification]                         # output/input pairs checked on the sweeps
pairs = ["q/long", "p/long", "q/lat", "p/lat", "r/coll", "az/coll", "r/ped", "ay/ped"]

[reduction]                            # the paper's criteria and selection rule
criteria = [{{ name = "insensitivity", threshold = 10.0 }},
            {{ name = "cramer-rao", threshold = 20.0 }}]
# true: keep removing to zero parameters for the RMSE-versus-removals curve (the paper)
continue_to_zero = {str(not quick).lower()}
# true: restart each step from the previous values (faster); false: from zero (the paper)
warm_start = {str(quick).lower()}

[delays]                               # added after selection, to those still in the model
derivatives = ["L_p", "L_q", "L_long", "L_lat", "M_p", "M_q", "M_long", "M_lat"]
upper = 0.3
"""


def write_case_file(path: Path, text: str) -> FlightCase:
    """Write the case file and read it back (reading checks every key)."""
    atomic_write(path, text)
    return FlightCase.load(path)


# ----------------------------------------------------------------- steps 4 and 5
def parse_arguments(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description="Identify a model from CSV flight data.")
    parser.add_argument("out", nargs="?", default="results/own-flight-data",
                        help="results directory (default: %(default)s)")
    parser.add_argument("--identification", metavar="GLOB",
                        help="multistep files (file, folder or glob); default: write "
                             "demonstration files from the truth model into OUT/flight-data")
    parser.add_argument("--verification", metavar="GLOB", help="sweep files")
    parser.add_argument("--airspeed-kt", type=float, default=0.0, help="trim airspeed")
    parser.add_argument("--theta0-deg", type=float, default=0.0, help="trim pitch attitude")
    parser.add_argument("--phi0-deg", type=float, default=0.0, help="trim bank angle")
    parser.add_argument("--quick", action="store_true",
                        help="short demonstration data, criteria-stopped reduction "
                             "(also: ROTORID_QUICK=1)")
    parser.add_argument("--seed", type=int, default=0, help="noise seed of the demo data")
    parser.add_argument("--no-figures", dest="figures", action="store_false",
                        help="skip the figures and the HTML report")
    return parser.parse_args(argv)


def main(argv=None) -> CaseResult:
    args = parse_arguments(argv)
    quick = quick_requested(args.quick)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.identification:
        # Paths in a case file are read from the current directory: store absolute ones.
        files = {"identification": str(Path(args.identification).absolute()),
                 "verification": (None if args.verification is None
                                  else str(Path(args.verification).absolute())),
                 "condition": {"airspeed_kt": args.airspeed_kt,
                               "theta0_deg": args.theta0_deg, "phi0_deg": args.phi0_deg}}
    else:
        print(f"Writing demonstration flight data to {out / 'flight-data'} …")
        files = write_demo_flight_data((out / "flight-data").resolve(), quick, args.seed)

    print("\n1-2. The files\n")
    for key in ("identification", "verification"):
        if files[key]:
            print(inventory(files[key]))

    case_path = out / f"{CASE_NAME}.toml"
    text = case_text(files["identification"], files["verification"], files["condition"], quick)
    case = write_case_file(case_path, text)
    print(f"\n3. The case file {case_path}\n\n{text}")

    command = f"rotorid study {case_path} --out {out}" + ("" if args.figures else " --no-figures")
    print(f"4. Running it (the same as: {command})\n")
    result = run_study(case, out, figures=args.figures)
    print("\n5. The results\n")
    print_summary(result)
    print(f"\nResults: {out / CASE_NAME / 'result.json'}"
          + (f"; report: {out / 'report.html'}" if args.figures else ""))
    return result


if __name__ == "__main__":
    main()
