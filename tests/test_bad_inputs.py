"""Bad inputs: each is refused with one line naming the offending item, the right exit status,
no traceback, nothing written outside ``--out`` and no half-written file (issue 15).

Every case builds its own tiny input in ``tmp_path`` and runs ``rotorid`` in this process with
``tmp_path/work`` as the working directory. Resume state, the data-set store and figures are
checked through the functions the commands call, so that no case flies or fits.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
import types
import zipfile
from pathlib import Path

import attrs
import numpy as np
import pytest
import rotorid
from rotorid.cli.main import MESSAGE_LIMIT, main, one_line
from rotorid.data import OUTPUT_CHANNELS
from rotorid.errors import (
    DataFileError,
    DataWarning,
    EstimationError,
    ExitStatus,
    SimulationDivergedError,
)
from rotorid.estimation.models import LinearModel
from rotorid.io import parse_number
from rotorid.model.modelfile import load_model
from rotorid.study.case import FlightCase
from rotorid.study.persistence import load_delays, load_steps, prepare_directory
from rotorid_files.formats import write_maneuver
from rotorid_helisim import store
from rotorid_output_error.levenberg_marquardt import Problem, Settings, run
from test_cli_simulate import MODEL, VALUES

HEADER = "time,long,lat,coll,ped,ax,az,q,theta,ay,p,phi,r"


def _csv_rows(value: str = "0.5", times=None, header: str = HEADER) -> str:
    """A 40-row CSV maneuver with ``value`` in channel long at row 5."""
    times = [f"{0.02 * k:.2f}" for k in range(40)] if times is None else times
    rows = [",".join([t] + ["0"] * 12) for t in times]
    rows[5] = ",".join([times[5], value] + ["0"] * 11)
    return "\n".join([header, *rows]) + "\n"


def _maneuver(name: str = "m0", samples: int = 50) -> rotorid.Maneuver:
    time = np.arange(samples) * 0.02
    return rotorid.Maneuver(name, time, np.zeros((samples, 4)), np.zeros((samples, 8)))


def _good_npz(directory: Path) -> Path:
    return write_maneuver(_maneuver(), directory / "good.npz")


# ----------------------------------------------------------------- the inputs
def _csv_with(value):
    def make(tmp_path):
        path = tmp_path / "bad.csv"
        path.write_text(_csv_rows(value))
        return path
    return make


def _csv_text(text):
    def make(tmp_path):
        path = tmp_path / "bad.csv"
        path.write_text(text)
        return path
    return make


def _times(change):
    times = [0.02 * k for k in range(40)]
    change(times)
    return [f"{t:.4f}" for t in times]


def _jump_at_row_20(times):
    times[20:] = [t + 0.5 for t in times[20:]]


def _back_at_row_7(times):
    times[7] = times[6]


def _bytes(name, content):
    def make(tmp_path):
        path = tmp_path / name
        path.write_bytes(content)
        return path
    return make


def _truncated_npz(tmp_path):
    whole = _good_npz(tmp_path).read_bytes()
    path = tmp_path / "cut.npz"
    path.write_bytes(whole[: len(whole) // 2])
    return path


def _cut(suffix, keep):
    """A good maneuver file of ``suffix`` cut to ``keep`` bytes (a fraction if below 1)."""
    def make(tmp_path):
        whole = write_maneuver(_maneuver("whole", 200), tmp_path / f"whole{suffix}").read_bytes()
        size = int(len(whole) * keep) if keep < 1 else keep
        path = tmp_path / f"cut{suffix}"
        path.write_bytes(whole[:size])
        return path
    return make


def _fifo(tmp_path):
    path = tmp_path / "pipe.csv"
    os.mkfifo(path)
    return path


def _empty_directory(tmp_path):
    path = tmp_path / "nothing"
    path.mkdir()
    return path


def _directory_named_csv(tmp_path):
    path = tmp_path / "folder.csv"
    path.mkdir()
    return path


#: Data files given to ``rotorid simulate``: (id, maker, words the one-line message contains).
DATA_FILES = [
    ("underscore-digits", _csv_with("1_000"), ["bad.csv", "'long'", "'1_000' is not a number"]),
    ("hex-number", _csv_with("0x10"), ["bad.csv", "'0x10' is not a number"]),
    ("word", _csv_with("fast"), ["bad.csv", "'fast' is not a number"]),
    *[(f"number-{text}", _csv_with(text), ["bad.csv", "'long'", f"{text!r} is not a number"])
      for text in ("1e", "--1", "+-1", "1.2.3", "½", "١", "0b1", "1j", "true", "e3", "1__0",
                   "0o7", "Infinity5", "1 000")],
    *[(f"number-{text}", _csv_with(text), ["bad.csv", "'long'", f"{text!r} is not a number"])
      for text in ("1e+", ".", "-", "+", "1e1.5", "0x1p3", "1d3", "1.0f", "5%", "∞")],
    *[(f"non-finite-{text}", _csv_with(text), ["bad.csv", "'long'", "NaN or infinite"])
      for text in ("nan", "NaN", "inf", "-inf", "1e999", "-1e400", "+inf", "INF", "-nan",
                   "infinity", "1e309")],
    *[(f"cut-{suffix[1:]}-{keep}", _cut(suffix, keep), [f"cut{suffix}"])
      for suffix in (".npz", ".mat") for keep in (1, 12, 126, 127, 300, 0.5, 0.9)],
    *[(f"cut-csv-{keep}", _cut(".csv", keep), ["cut.csv"])
      for keep in (1, 2, 40, 100, 0.5, 0.93)],
    ("time-jump-at-row-20", _csv_text(_csv_rows(times=_times(_jump_at_row_20))),
     ["bad.csv", "not uniformly sampled at row 20"]),
    ("time-back-at-row-7", _csv_text(_csv_rows(times=_times(_back_at_row_7))),
     ["bad.csv", "does not increase at row 7"]),
    ("duplicated-channel", _csv_text(_csv_rows(header=HEADER.replace(",r", ",q"))),
     ["bad.csv", "'q' appears twice"]),
    ("short-row", _csv_text(_csv_rows() + "1.0,2.0\n"), ["bad.csv", "expected 13 values"]),
    ("empty-field", _csv_with(""), ["bad.csv", "'long'", "empty, NaN or infinite",
                                    "--resample linear"]),
    ("semicolons", _csv_text(HEADER + "\n" + ";".join(["0,0"] * 13) + "\n"),
     ["bad.csv", "expected 13 values", "semicolons", "comma-separated"]),
    ("semicolons-throughout", _csv_text(HEADER.replace(",", ";") + "\n"
                                        + ";".join(["0.5"] * 13) + "\n"),
     ["bad.csv", "is not a number", "semicolons", "comma-separated"]),
    ("units-row", _csv_text(HEADER + "\ns,%,%,%,%,ft/s2,ft/s2,deg/s,deg,ft/s2,deg/s,deg,deg/s\n"
                            + _csv_rows().split("\n", 1)[1]),
     ["bad.csv", "'s' is not a number", "row of units", "channel map"]),
    ("comments-only", _csv_text("# name: x\n# kind: 3211\n"), ["bad.csv", "no header row"]),
    ("binary-csv", _bytes("junk.csv", bytes(range(256)) * 4), ["junk.csv"]),
    ("empty-csv", _bytes("empty.csv", b""), ["empty.csv"]),
    ("12-byte-mat", _bytes("tiny.mat", b"MATLAB 5.0 M"), ["tiny.mat", "cannot read"]),
    ("126-byte-mat", _bytes("short.mat", b"MATLAB 5.0 MAT-file" + b" " * 107),
     ["short.mat"]),
    ("truncated-npz", _truncated_npz, ["cut.npz"]),
    ("zero-npz", _bytes("zero.npz", b"\0" * 64), ["zero.npz"]),
    ("unknown-suffix", _bytes("data.xlsx", b"PK"), ["data.xlsx", "unknown maneuver file format"]),
    ("fifo", _fifo, ["pipe.csv", "neither a regular file nor a directory"]),
    *[(f"device-{device}", lambda tmp_path, device=device: Path(f"/dev/{device}"),
       [f"/dev/{device}", "neither a regular file nor a directory"])
      for device in ("null", "zero")],
    ("empty-directory", _empty_directory, ["nothing", "no maneuver files"]),
    ("directory-named-csv", _directory_named_csv, ["folder.csv", "no maneuver files"]),
    ("missing", lambda tmp_path: tmp_path / "absent.csv", ["absent.csv", "no such file"]),
    ("no-glob-match", lambda tmp_path: tmp_path / "runs" / "*.csv", ["no file matches"]),
]


def _simulate_inputs(make, values=VALUES, model_text=MODEL):
    def command(tmp_path):
        model = tmp_path / "model.toml"
        model.write_text(model_text)
        (tmp_path / "values.json").write_text(json.dumps(values))
        values_path = tmp_path / "values.json"
        return ["simulate", str(model), str(make(tmp_path)), "--values", str(values_path),
                "--out", str(tmp_path / "out")]
    return command


def _identify(change=lambda outputs: outputs, model=MODEL, samples=200, dt=0.02,
              units="flight-test", every=True):
    """``rotorid identify`` of two noise records whose outputs ``change`` edits (in the
    first record only unless ``every``)."""
    def command(tmp_path):
        (tmp_path / "model.toml").write_text(model)
        data = tmp_path / "flight"
        data.mkdir()
        rng = np.random.default_rng(3)
        for k in range(2):
            maneuver = attrs.evolve(_maneuver(f"m{k}", samples), time=np.arange(samples) * dt,
                                    units=units)
            outputs = rng.normal(size=(samples, 8))
            write_maneuver(maneuver.with_outputs(change(outputs) if k == 0 or every else outputs),
                           data / f"m{k}.csv")
        (tmp_path / "out").mkdir()
        return ["identify", str(tmp_path / "model.toml"), str(data), "--quiet",
                "--out", str(tmp_path / "out" / "result.json")]
    return command


def _set_column(index, value):
    def change(outputs):
        outputs[:, index] = value
        return outputs
    return change


def _copy_column(source, target):
    def change(outputs):
        outputs[:, target] = outputs[:, source]
        return outputs
    return change


def _model_with(old, new):
    return _simulate_inputs(_good_csv, model_text=MODEL.replace(old, new))


NO_FREE_PARAMETER = MODEL.split("[structure]")[0] + '[structure]\npopulate = "none"\n'
TEN_SECOND_DELAY = MODEL.replace("delay = 0.0", "delay = { initial = 10.0, fixed = true }")


def _good_csv(tmp_path):
    return write_maneuver(_maneuver("m0", 200), tmp_path / "m0.csv")


def _study_case(text):
    """``rotorid study`` of a case file holding ``text``."""
    def command(tmp_path):
        (tmp_path / "case.toml").write_text(text)
        return ["study", str(tmp_path / "case.toml"), "--out", str(tmp_path / "out")]
    return command


def _files_case(name="own", data='source = "files"\nidentification = "f.csv"', extra=""):
    return _study_case(f'name = "{name}"\n[data]\n{data}\n{extra}')


#: Paths that are not regular files: (label, maker of the path in tmp_path).
NOT_FILES = [("directory", lambda tmp_path: _empty_directory(tmp_path)),
             ("fifo", _fifo), ("dev-null", lambda tmp_path: Path("/dev/null"))]


def _not_a_file(what, command):
    """``command(tmp_path, path)`` with a path of each kind in :data:`NOT_FILES`, expecting
    ``what`` named as not a regular file."""
    return [(f"{what.replace(' ', '-')}-is-{label}",
             lambda tmp_path, make=make: command(tmp_path, str(make(tmp_path))),
             ExitStatus.ERROR, [what, "is not a regular file (a directory, device or pipe)"])
            for label, make in NOT_FILES]


def _plain(*args):
    return lambda tmp_path: [a.format(tmp=tmp_path) for a in args]


def _regular_file(tmp_path):
    (tmp_path / "taken").write_text("not a directory")
    return str(tmp_path / "taken")


def _with_out(command, make_out):
    return lambda tmp_path: [*command, "--out", make_out(tmp_path)]


#: Command lines: (id, command maker, exit status, words the one-line message contains).
COMMANDS = [
    *[(f"data-{name}", _simulate_inputs(make), ExitStatus.ERROR, words)
      for name, make, words in DATA_FILES],
    # identification data and model
    ("identify-zero-output", _identify(_set_column(2, 0.0)), ExitStatus.ERROR,
     ["output 'q' is constant", "--outputs"]),
    ("identify-constant-output", _identify(_set_column(0, 1.0)), ExitStatus.ERROR,
     ["output 'ax' is constant", "value 1"]),
    ("identify-all-outputs-constant", _identify(lambda y: y * 0 + 1.0), ExitStatus.ERROR,
     ["maneuver m0", "every fitted output is constant"]),
    ("identify-duplicated-output", _identify(_copy_column(2, 5)), ExitStatus.ERROR,
     ["outputs 'q' and 'p' hold the same record"]),
    ("identify-too-few-samples", _identify(samples=3, dt=0.5), ExitStatus.ERROR,
     ["48 output samples cannot determine"]),
    *[(f"identify-{n}-sample-records", _identify(samples=n), ExitStatus.ERROR,
       ["maneuver m0", f"({n} samples)", "shorter than the 1 s"]) for n in (2, 5, 20)],
    ("identify-time-in-minutes", _identify(dt=0.02 / 60, samples=300), ExitStatus.ERROR,
     ["maneuver m0", "lasts 0.09967 s", "in minutes"]),
    ("identify-time-in-ms-at-5-khz", _identify(dt=0.2, samples=20000), ExitStatus.ERROR,
     ["maneuver m0", "lasts 4000 s", "longer than any identification maneuver", "in ms"]),
    ("identify-unknown-output", lambda tmp_path: [*_identify()(tmp_path), "--outputs", "q,zz"],
     ExitStatus.USAGE, ["argument --outputs: 'zz' is no output of ", "its outputs are ax, az"]),
    *[(f"identify-zero-{name}", _identify(_set_column(k, 0.0)), ExitStatus.ERROR,
       [f"output {name!r} is constant", "--outputs"])
      for k, name in enumerate(OUTPUT_CHANNELS) if name != "q"],
    *[(f"identify-{first}-equals-{second}", _identify(_copy_column(i, j)), ExitStatus.ERROR,
       [f"outputs {first!r} and {second!r} hold the same record"])
      for i, j, first, second in ((0, 4, "ax", "ay"), (3, 6, "theta", "phi"),
                                  (5, 7, "p", "r"))],
    ("identify-unknown-estimator", lambda tmp_path: [*_identify()(tmp_path), "--estimator",
                                                     "magic"],
     ExitStatus.USAGE, ["argument --estimator: no estimator named 'magic'", "rotorid plugins"]),
    ("identify-unknown-noise", lambda tmp_path: [*_identify()(tmp_path), "--noise", "pink"],
     ExitStatus.USAGE, ["argument --noise", "'pink'"]),
    ("identify-fixed-delay-longer-than-records", _identify(model=TEN_SECOND_DELAY),
     ExitStatus.ERROR, ["delay tau_L_lat = 10 s", "record m0 (3.98 s)"]),
    ("simulate-delay-longer-than-records", _simulate_inputs(_good_csv, {"tau_L_lat": 100.0}),
     ExitStatus.ERROR, ["delay tau_L_lat = 100 s", "record m0"]),
    *[(f"model-airspeed-{text}", _simulate_inputs(
        _good_csv, model_text=MODEL.replace("airspeed_kt = 60.0", f"airspeed_kt = {text}")),
       ExitStatus.ERROR, ["model.toml", words])
      for text, words in (("1e6", "1e+06 kt is beyond any rotorcraft"),
                          ("-5.0", "≥ 0 kt"), ("nan", "finite"), ('"70"', "airspeed_kt"))],
    ("model-not-toml", _model_with("[structure]", "[[[structure"), ExitStatus.ERROR,
     ["model.toml", "not a valid TOML file", "line"]),
    ("model-unknown-derivative", _simulate_inputs(
        _good_csv, model_text=MODEL + "\n[derivatives.X_zz]\ninitial = 1.0\n"),
     ExitStatus.ERROR, ["model.toml", "X_zz", "does not fit the six-dof template"]),
    ("model-unknown-template", _model_with('populate = "all"', 'template = "tandem"'),
     ExitStatus.ERROR, ["model.toml", "template = 'tandem'", "'six-dof'"]),
    ("model-negative-delay", _model_with("delay = 0.0", "delay = -0.1"), ExitStatus.ERROR,
     ["model.toml", "negative", "-0.1 s"]),
    ("model-unknown-units", _model_with('units = "flight-test"', 'units = "imperial"'),
     ExitStatus.ERROR, ["model.toml", "'imperial'", "'flight-test'"]),
    ("model-unknown-condition-key", _model_with("theta0_deg", "pitch_deg"), ExitStatus.ERROR,
     ["model.toml", "'pitch_deg'"]),
    *[(f"model-{key}-{value}", _model_with("theta0_deg = 2.0", f"{key}_deg = {value}"),
       ExitStatus.ERROR, ["model.toml", f"{key} = {value:g}°", "not within ±90°", "unit"])
      for key, value in (("theta0", 400.0), ("theta0", -90.0), ("phi0", 180.0))],
    ("model-missing", lambda tmp_path: ["simulate", str(tmp_path / "none.toml"),
                                        str(_good_csv(tmp_path)), "--out", str(tmp_path / "out")],
     ExitStatus.ERROR, ["none.toml", "does not exist"]),
    ("values-unknown-parameter", _simulate_inputs(_good_csv, {"X_zz": 1.0}), ExitStatus.ERROR,
     ["unknown or non-free parameter(s) ['X_zz']"]),
    ("values-not-a-number", _simulate_inputs(_good_csv, {"X_u": "fast"}), ExitStatus.ERROR,
     ["values.json", "X_u must be numbers"]),
    ("values-not-an-object", _simulate_inputs(_good_csv, [1, 2]), ExitStatus.ERROR,
     ["values.json", "must hold a JSON object"]),
    ("model-body-velocity-in-wrong-unit", _simulate_inputs(
        _good_csv, model_text=MODEL.replace("airspeed_kt = 60.0", "u0_fps = 5000.0")),
     ExitStatus.ERROR, ["model.toml", "beyond any rotorcraft"]),
    ("identify-trim-not-pairs",
     lambda tmp_path: [*_identify()(tmp_path), "--trim", "theta:5"], ExitStatus.USAGE,
     ["argument --trim", "CHANNEL=VALUE"]),
    ("identify-trim-unknown-channel",
     lambda tmp_path: [*_identify()(tmp_path), "--trim", "pitch=5"], ExitStatus.ERROR,
     ["trim value for unknown channel 'pitch'"]),
    ("identify-sample-time-without-resample",
     lambda tmp_path: [*_identify()(tmp_path), "--sample-time", "0.05"], ExitStatus.USAGE,
     ["--sample-time needs --resample"]),
    ("identify-decimate-without-sample-time",
     lambda tmp_path: [*_identify()(tmp_path), "--resample", "decimate"], ExitStatus.ERROR,
     ["'decimate' needs a sample_time"]),
    ("identify-time-in-ms", _identify(dt=20.0), ExitStatus.ERROR,
     ["maneuver m0", "sample interval 20 s", "in ms"]),
    ("identify-roll-in-deg-declared-rad", _identify(
        lambda y: _set_column(6, 5.0 * (-1) ** np.arange(200))(0.01 * y), units="si"),
     ExitStatus.ERROR, ["output 'phi'", "286.5° from trim", "deg declared as rad"]),
    ("identify-yaw-rate-in-deg-per-s-declared-rad-per-s", _identify(
        lambda y: _set_column(7, 20.0 * (-1) ** np.arange(200))(0.01 * y), units="si"),
     ExitStatus.ERROR, ["output 'r'", "1146°/s from trim", "rates in deg/s declared as rad/s"]),
    ("identify-one-flat-maneuver-among-good-ones", _identify(lambda y: y * 0.0, every=False),
     ExitStatus.ERROR, ["maneuver m0", "every fitted output is constant"]),
    ("identify-values-times-1e300", _identify(lambda y: y * 1e300), ExitStatus.ERROR,
     ["maneuver m0", "output 'theta' reaches 3.332e+300°", "unit and scale"]),
    ("identify-acceleration-times-1000", _identify(_set_column(1, 1000.0)), ExitStatus.ERROR,
     ["output 'az'", "31.08 g", "beyond 30 g"]),
    ("identify-rate-in-wrong-unit", _identify(
        lambda y: _set_column(5, 2000.0 * (-1) ** np.arange(200))(0.01 * y)),
     ExitStatus.ERROR, ["output 'p'", "2000°/s", "beyond 1000°/s"]),
    ("identify-no-free-parameter", _identify(model=NO_FREE_PARAMETER), ExitStatus.ERROR,
     ["model.toml", "no free parameter"]),
    # seeds
    ("generate-negative-seed", _plain("generate", "hover", "--seed", "-1", "--out", "{tmp}/out"),
     ExitStatus.USAGE, ["--seed", "≥ 0", "'-1'"]),
    ("generate-fractional-seed", _plain("generate", "hover", "--seed", "1.5", "--out",
                                        "{tmp}/out"), ExitStatus.USAGE, ["--seed", "'1.5'"]),
    ("study-negative-seed", _plain("study", "hover", "--seed", "-5", "--out", "{tmp}/out"),
     ExitStatus.USAGE, ["--seed", "'-5'"]),
    ("study-word-seed", _plain("study", "hover", "--seed", "x", "--out", "{tmp}/out"),
     ExitStatus.USAGE, ["--seed", "'x'"]),
    ("montecarlo-negative-seed", _plain("montecarlo", "hover", "--runs", "3", "--seed", "-1",
                                        "--out", "{tmp}/out"), ExitStatus.USAGE, ["--seed"]),
    *[(f"montecarlo-runs-{runs}", _plain("montecarlo", "hover", "--runs", runs, "--out",
                                         "{tmp}/out"), ExitStatus.USAGE,
       ["argument --runs", "≥ 2", repr(runs)]) for runs in ("1", "0", "-3", "x", "1.5")],
    *[(f"{command}-seed-{text}", _plain(command, "hover", "--seed", text, "--out", "{tmp}/out"),
       ExitStatus.USAGE, ["--seed", repr(text)])
      for command, text in (("generate", "1e3"), ("study", " "), ("generate", "0x1"))],
    # executors
    ("generate-unknown-case", _plain("generate", "cruise", "--out", "{tmp}/out"),
     ExitStatus.USAGE, ["invalid choice: 'cruise'"]),
    ("study-unknown-executor", _plain("study", "hover", "--executor", "gpu", "--out",
                                      "{tmp}/out"), ExitStatus.USAGE, ["--executor", "'gpu'"]),
    ("study-scheduler-without-dask", _plain("study", "hover", "--scheduler", "tcp://x:1",
                                            "--out", "{tmp}/out"), ExitStatus.ERROR,
     ["--scheduler only applies to --executor dask"]),
    ("study-dask-without-scheduler", _plain("study", "hover", "--executor", "dask", "--out",
                                            "{tmp}/out"), ExitStatus.ERROR,
     ["--executor dask needs --scheduler"]),
    ("verify-without-result", _plain("verify", "model.toml", "--out", "{tmp}/out"),
     ExitStatus.USAGE, ["RESULT.json"]),
    ("verify-missing-result", _plain("verify", "{tmp}/r.json", "{tmp}/sweeps", "--out",
                                     "{tmp}/out"), ExitStatus.ERROR, ["r.json", "does not exist"]),
    ("verify-band-not-three-numbers", _plain("verify", "{tmp}/r.json", "{tmp}/sweeps", "--band",
                                             "0.8,1", "--out", "{tmp}/out"),
     ExitStatus.USAGE, ["--band needs COHERENCE,OMEGA_MIN,OMEGA_MAX", "'0.8,1'"]),
    ("verify-band-coherence-above-one", _plain("verify", "{tmp}/r.json", "{tmp}/sweeps",
                                               "--band", "1.5,0.1,10", "--out", "{tmp}/out"),
     ExitStatus.USAGE, ["--band: verification band: coherence must be a γ² in (0, 1]"]),
    # --out of the wrong kind
    *[(f"{command[0]}-out-is-a-file", _with_out(command, _regular_file), ExitStatus.USAGE,
       ["--out", "taken", "not a directory"])
      for command in (["study", "hover"], ["generate", "hover"],
                      ["montecarlo", "hover", "--runs", "3"],
                      ["simulate", "model.toml", "inputs.csv"], ["verify", "result.json"])],
    ("identify-out-is-a-directory", _plain("identify", "model.toml", "data", "--out", "{tmp}"),
     ExitStatus.USAGE, ["--out", "is not a regular file"]),
    ("identify-out-is-dev-null", _plain("identify", "model.toml", "data", "--out", "/dev/null"),
     ExitStatus.USAGE, ["--out", "/dev/null", "is not a regular file"]),
    ("identify-out-below-a-file", lambda tmp_path: [
        "identify", "model.toml", "data", "--out", str(Path(_regular_file(tmp_path)) / "r.json")],
     ExitStatus.USAGE, ["--out", "cannot write into", "taken"]),
    ("frequency-out-is-a-directory", _plain("frequency", "sweeps", "--out", "{tmp}"),
     ExitStatus.USAGE, ["--out", "is not a regular file"]),
    ("study-out-is-dev-null", _plain("study", "hover", "--out", "/dev/null"), ExitStatus.USAGE,
     ["--out", "/dev/null", "not a directory"]),
    ("generate-out-below-a-file", lambda tmp_path: [
        "generate", "hover", "--out", str(Path(_regular_file(tmp_path)) / "sub")],
     ExitStatus.USAGE, ["--out", "cannot write into", "taken"]),
    # airspeeds
    ("trim-huge-airspeed", _plain("trim", "--airspeed-kt", "1e300"), ExitStatus.ERROR,
     ["airspeed_kt", "200 kt", "1e+300"]),
    ("trim-above-envelope", _plain("trim", "--airspeed-kt", "250"), ExitStatus.ERROR,
     ["airspeed_kt", "200 kt"]),
    ("trim-negative-airspeed", _plain("trim", "--airspeed-kt", "-5"), ExitStatus.ERROR,
     ["airspeed_kt", "≥ 0"]),
    ("trim-nan-airspeed", _plain("trim", "--airspeed-kt", "nan"), ExitStatus.ERROR,
     ["airspeed_kt", "finite"]),
    *[(f"trim-airspeed-{text}", _plain("trim", f"--airspeed-kt={text}"), ExitStatus.ERROR,
       ["airspeed_kt", words]) for text, words in (("inf", "finite"), ("-inf", "finite"),
                                                   ("200.5", "200 kt"), ("1e400", "finite"))],
    ("trim-word-airspeed", _plain("trim", "--airspeed-kt", "fast"), ExitStatus.USAGE,
     ["--airspeed-kt", "'fast'"]),
    ("speeds-too-many", _plain("study", "speed-sweep", "--speeds", "0:200:0.001", "--out",
                               "{tmp}/out"), ExitStatus.ERROR, ["0:200:0.001", "200001", "201"]),
    ("speeds-zero-step", _plain("study", "speed-sweep", "--speeds", "0:200:5e-324", "--out",
                                "{tmp}/out"), ExitStatus.ERROR, ["0:200:5e-324", "at most 201"]),
    ("speeds-same-name", _plain("study", "speed-sweep", "--speeds", "0:1:0.05", "--out",
                                "{tmp}/out"), ExitStatus.ERROR, ["0.05", "0.1 kt apart"]),
    ("speeds-underscore", _plain("study", "speed-sweep", "--speeds", "1_000", "--out",
                                 "{tmp}/out"), ExitStatus.ERROR, ["'1_000'", "cannot read"]),
    ("speeds-infinite", _plain("study", "speed-sweep", "--speeds", "0:inf:10", "--out",
                               "{tmp}/out"), ExitStatus.ERROR, ["'0:inf:10'"]),
    ("speeds-out-of-range", _plain("study", "speed-sweep", "--speeds", "0,250", "--out",
                                   "{tmp}/out"), ExitStatus.ERROR, ["0–200 kt", "250"]),
    ("speeds-without-sweep", _plain("study", "hover", "--speeds", "0,10", "--out", "{tmp}/out"),
     ExitStatus.USAGE, ["--speeds", "speed-sweep"]),
    # case files
    *[(f"case-name-{label}", _files_case(name), ExitStatus.ERROR,
       ["case.toml", repr(name), "cannot name a results directory"])
      for label, name in (("up-twice", "../../X"), ("absolute", "/tmp/abs"), ("nested", "a/b"),
                          ("parent", ".."), ("hidden", ".hidden"), ("empty", ""))],
    ("case-unknown-source", _files_case(data='source = "renamed-csv"'), ExitStatus.ERROR,
     ["case.toml", "'renamed-csv'"]),
    ("case-not-toml", _study_case("name = \n"), ExitStatus.ERROR, ["case.toml", "TOML"]),
    ("case-unknown-table", _files_case(extra="[flight]\nx = 1\n"), ExitStatus.ERROR,
     ["case.toml", "flight"]),
    # paths that are not regular files
    *_not_a_file("model file", lambda tmp_path, path: [
        "simulate", path, str(_good_csv(tmp_path)), "--out", str(tmp_path / "out")]),
    *_not_a_file("values file", lambda tmp_path, path: [
        "simulate", str(_simulate_inputs(_good_csv)(tmp_path)[1]), str(_good_csv(tmp_path)),
        "--values", path, "--out", str(tmp_path / "out")]),
    *_not_a_file("result file", lambda tmp_path, path: [
        "export", path, "--format", "json", "--out", str(tmp_path / "out")]),
    *_not_a_file("case file", lambda tmp_path, path: [
        "study", path, "--out", str(tmp_path / "out")]),
    ("unknown-command", _plain("fly"), ExitStatus.USAGE, ["invalid choice: 'fly'"]),
    ("unknown-case", _plain("study", "cruise", "--out", "{tmp}/out"), ExitStatus.ERROR,
     ["cruise"]),
]


def _files_under(root: Path) -> set[Path]:
    return {p for p in root.rglob("*") if not p.is_dir()}


def _run(argv) -> int:
    try:
        return main(argv)
    except SystemExit as stop:          # argparse's errors
        return stop.code


@pytest.mark.parametrize("command, status, words", [c[1:] for c in COMMANDS],
                         ids=[c[0] for c in COMMANDS])
def test_a_bad_input_is_one_line_naming_it_and_writes_nothing(command, status, words, tmp_path,
                                                              capsys, monkeypatch):
    argv = command(tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    before = _files_under(tmp_path)
    assert _run(argv) == status
    error = capsys.readouterr().err
    lines = error.splitlines()
    assert len(lines) == 1, error
    assert lines[0].startswith(f"rotorid {argv[0]}: error: ") or argv[0] == "fly", error
    assert "Traceback" not in error
    for word in words:
        assert word in lines[0], (word, lines[0])
    written = _files_under(tmp_path) - before
    assert not [p for p in written if tmp_path / "out" not in p.parents], written
    assert not [p for p in written if p.name.endswith(".tmp")], written


def test_an_unwritable_out_is_refused_before_any_work(tmp_path, capsys):
    if os.geteuid() == 0:
        pytest.skip("root may write into any directory")
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    assert _run(["generate", "hover", "--out", str(locked / "data")]) == ExitStatus.USAGE
    assert "cannot write into" in capsys.readouterr().err


# ----------------------------------------------------------------- numerics
def _doublets(tmp_path, count=4, n=300, scale=1.0):
    """The model file's structure and ``count`` maneuvers of doublets, one axis each."""
    (tmp_path / "model.toml").write_text(MODEL)
    t = np.arange(n) * 0.02
    maneuvers = []
    for i in range(count):
        u = np.zeros((n, 4))
        u[(t > 0.5) & (t < 1.5), i] = 2.0 * scale
        u[(t >= 1.5) & (t < 2.5), i] = -2.0 * scale
        maneuvers.append(rotorid.Maneuver(f"m{i}", t, u, np.zeros((n, 8))))
    return load_model(tmp_path / "model.toml"), rotorid.ManeuverSet(maneuvers)


UNSTABLE_ROLL = {**VALUES, "L_p": 40.0}


def test_a_divergence_names_the_maneuver_the_state_and_when(tmp_path):
    structure, maneuvers = _doublets(tmp_path)
    with pytest.raises(SimulationDivergedError) as caught:
        rotorid.simulate(structure, UNSTABLE_ROLL, maneuvers)
    message = str(caught.value)
    found = re.fullmatch(r"simulation diverged: maneuver (m\d), state (\w+) reaches (\S+) "
                         r"\(beyond 1e\+07\) at t = (\S+) s; .*", message)
    assert found, message
    name, state, size, when = found.groups()
    assert (name, state) == ("m1", "p") and float(size) > 1e7     # the roll doublet, roll rate
    # when: the record up to the sample before stays below the limit, one sample more does not
    maneuver = maneuvers[1]
    rotorid.simulate(structure, UNSTABLE_ROLL, rotorid.ManeuverSet([maneuver.head(
        float(when) - maneuver.dt)]))
    with pytest.raises(SimulationDivergedError):
        rotorid.simulate(structure, UNSTABLE_ROLL, rotorid.ManeuverSet([maneuver.head(
            float(when))]))


def _problem(structure, maneuvers, measured):
    model = LinearModel(structure)
    return model, Problem(model, maneuvers, measured, np.ones(8), Settings())


def test_a_start_without_finite_cost_says_what_diverged_before_suggesting_a_start(tmp_path):
    structure, maneuvers = _doublets(tmp_path)
    measured = rotorid.simulate(structure, VALUES, maneuvers)
    model, problem = _problem(structure, maneuvers, measured)
    start = structure.as_vector(UNSTABLE_ROLL)
    with pytest.raises(SimulationDivergedError) as caught:
        run(problem, start, model.bounds())
    message = str(caught.value)
    assert message.startswith("the start values give no finite cost: simulation diverged: "
                              "maneuver m1, state p reaches"), message
    assert message.index("at t = ") < message.index("start closer to a stable model")


def test_a_start_whose_noise_covariance_is_singular_names_the_exact_outputs(tmp_path):
    structure, maneuvers = _doublets(tmp_path, scale=1e-60)      # outputs of about 1e-60
    measured = rotorid.simulate(structure, VALUES, maneuvers)
    model, problem = _problem(structure, maneuvers, measured)
    with pytest.raises(SimulationDivergedError) as caught:
        run(problem, structure.as_vector(VALUES), model.bounds())
    assert ("the noise covariance R is singular: the outputs ax, az, q, theta, ay, p, phi, r "
            "are reproduced exactly (noise-free data?); use --noise diagonal") in str(caught.value)


def test_residuals_dependent_to_working_precision_name_their_outputs(tmp_path):
    """A fit whose residuals become linearly dependent (an output equation reproduced exactly
    on noise-free data) stops with the outputs named and the fix, not a bare linear-algebra
    failure."""
    structure, maneuvers = _doublets(tmp_path)
    measured = rotorid.simulate(structure, VALUES, maneuvers)
    model, problem = _problem(structure, maneuvers, measured)
    # residuals far above the outputs, so that R's floor (a fraction of the outputs' power)
    # leaves the dependence at working precision
    residuals = [1e4 * np.random.default_rng(3).normal(size=z.shape) for z in measured]
    for e in residuals:
        e[:, 7] = e[:, 5] - 2.0 * e[:, 6]                       # r's from p's and phi's
    with pytest.raises(EstimationError) as caught:
        problem.gauss_newton(structure.as_vector(VALUES), problem.noise(residuals), residuals)
    assert str(caught.value) == (
        "the noise covariance R became singular to working precision: the residuals of the "
        "outputs p, phi, r are linearly dependent, the fit reproducing them almost exactly "
        "(noise-free data?); use --noise diagonal or leave such outputs out with --outputs")


def test_the_advice_on_exact_outputs_suits_the_noise_setting():
    """Some outputs exact: leave them out (or, with a full R, make it diagonal); all exact:
    the records are noise-free, and nothing is to be left out."""
    from rotorid_output_error.estimator import _warn_exact_outputs

    measured = [np.column_stack([np.sin(np.arange(50.0)), np.cos(np.arange(50.0))])]
    result = types.SimpleNamespace(noise_covariance=np.diag([1e-20, 0.1]))
    for noise, fix in (("full", "; use --noise diagonal or leave them out with --outputs"),
                       ("diagonal", "; leave them out with --outputs")):
        with pytest.warns(DataWarning) as caught:
            _warn_exact_outputs(result, measured, np.ones(2), ["q", "theta"], noise)
        assert str(caught[0].message).startswith("the fit reproduces the outputs 'q' exactly")
        assert str(caught[0].message).endswith("bounds mean nothing" + fix)


def test_noise_free_outputs_are_a_warning_naming_them(tmp_path, capsys):
    structure, maneuvers = _doublets(tmp_path)
    data = tmp_path / "flight"
    data.mkdir()
    for maneuver, y in zip(maneuvers, rotorid.simulate(structure, VALUES, maneuvers)):
        write_maneuver(maneuver.with_outputs(y), data / f"{maneuver.name}.csv")
    assert _run(["identify", str(tmp_path / "model.toml"), str(data), "--quiet",
                 "--out", str(tmp_path / "result.json")]) == ExitStatus.OK
    warnings = [line for line in capsys.readouterr().err.splitlines() if "exactly" in line]
    assert len(warnings) == 1, warnings
    assert warnings[0].startswith("rotorid identify: warning: the fit reproduces the outputs "
                                  "'ax', 'az', 'q', 'theta', 'ay', 'p', 'phi', 'r' exactly "
                                  "(residual RMS at most ")
    assert warnings[0].endswith("the Cramér-Rao bounds mean nothing; the values are the "
                                "model's that generated the records; bounds need noisy records")


# ----------------------------------------------------------------- strict numbers, short errors
@pytest.mark.parametrize("text, value", [("1", 1.0), ("-1.5", -1.5), (" 2e-3 ", 2e-3),
                                         (".5", 0.5), ("5.", 5.0), ("+1E+2", 100.0)])
def test_plain_numbers_are_read(text, value):
    assert parse_number(text) == value


@pytest.mark.parametrize("text", ["1_000", "0x10", "1e", "--1", "1,5", "", "e3", "1.2.3",
                                  "½", "１"])
def test_other_number_spellings_are_refused(text):
    with pytest.raises(ValueError, match="not a plain decimal number"):
        parse_number(text)


def test_a_long_message_loses_its_middle_with_a_count_of_what_is_left_out(tmp_path, capsys):
    speeds = ",".join(str(v) for v in range(300, 500))
    assert _run(["study", "speed-sweep", "--speeds", speeds, "--out",
                 str(tmp_path / "out")]) == ExitStatus.ERROR
    (line,) = capsys.readouterr().err.splitlines()
    full = f"airspeeds must lie in 0–200 kt, got {[float(v) for v in range(300, 500)]}"
    kept = MESSAGE_LIMIT - MESSAGE_LIMIT // 3
    # the start and the end (where a message puts its fix) kept, the middle counted
    assert f"{full[:kept]} … ({len(full) - MESSAGE_LIMIT} characters left out) … " in line
    assert line.endswith(full[-(MESSAGE_LIMIT // 3):])
    assert len(line) < MESSAGE_LIMIT + 120
    assert one_line("a\n  b\tc") == "a b c"


# ----------------------------------------------------------------- resume state
def _case_directory(tmp_path) -> Path:
    directory = tmp_path / "out" / "tiny"
    prepare_directory(directory, FlightCase(name="tiny", data={"source": "files"}), resume=True)
    return directory


@pytest.mark.parametrize("content, cause", [
    ('{"index": 0, "removal": null, "estim', "not valid JSON"),
    ("{}", "no 'removal'"),
    ("[]", "must hold a JSON object"),
    ('{"index": 0, "removal": null, "estimate": {}}', "cannot resume"),
    ('{"index": 0, "removal": {"parameter": "M_q"}, "estimate": {}}', "cannot resume"),
    ("", "not valid JSON"),
])
def test_a_damaged_step_file_is_named_with_the_fix(tmp_path, content, cause):
    directory = _case_directory(tmp_path)
    step = directory / "steps" / "step_000.json"
    step.write_text(content)
    with pytest.raises(DataFileError) as caught:
        load_steps(directory, rotorid.ModelStructure.six_dof(rotorid.FlightCondition()))
    message = str(caught.value)
    assert str(step) in message and cause in message and "delete that file" in message
    assert "\n" not in message


@pytest.mark.parametrize("content", ["{", '{"selected_step": 3}', "[1]", ""])
def test_a_damaged_delay_file_is_named_with_the_fix(tmp_path, content):
    directory = _case_directory(tmp_path)
    (directory / "delays.json").write_text(content)
    with pytest.raises(DataFileError, match="delays.json.*delete that file"):
        load_delays(directory, selected_step=3)


def test_a_delay_file_of_another_step_is_recomputed(tmp_path):
    directory = _case_directory(tmp_path)
    for content in ("{}", '{"selected_step": 2, "dropped": []}'):
        (directory / "delays.json").write_text(content)
        assert load_delays(directory, selected_step=3) is None


def test_opening_a_case_directory_removes_stale_temporary_files(tmp_path):
    directory = _case_directory(tmp_path)
    stale = [directory / ".result.json.0f1e.tmp", directory / "steps" / ".step_004.json.9a.tmp"]
    kept = [directory / "steps" / "step_000.json", directory / "notes.tmp"]
    for path in stale + kept:
        path.write_text("x")
    prepare_directory(directory, FlightCase(name="tiny", data={"source": "files"}), resume=True)
    assert not any(p.exists() for p in stale) and all(p.exists() for p in kept)


# ----------------------------------------------------------------- the data-set store
def test_a_new_data_set_deletes_only_the_files_the_store_wrote(tmp_path):
    directory = tmp_path / "data"
    directory.mkdir()
    own = write_maneuver(_maneuver("old_run"), directory / "old_run.npz")
    foreign_npz = directory / "foreign.npz"
    with zipfile.ZipFile(foreign_npz, "w") as archive:
        archive.writestr("weights.npy", b"")
    precious = directory / "precious.txt"
    outside = tmp_path / "outside.npz"
    write_maneuver(_maneuver("outside"), outside)
    for path in (precious,):
        path.write_text("keep me")
    (directory / store.MANIFEST).write_text(json.dumps({"files": [
        own.name, foreign_npz.name, precious.name, "../outside.npz", str(outside),
        "missing.npz"]}))
    store.save(rotorid.ManeuverSet([_maneuver("new_run")]), directory, "digest", {})
    assert not own.exists()
    assert foreign_npz.exists() and precious.exists() and outside.exists()
    assert json.loads((directory / store.MANIFEST).read_text())["files"] == ["new_run.npz"]


# ----------------------------------------------------------------- deterministic records
def test_the_same_figure_gives_the_same_svg_and_png_bytes(tmp_path):
    from matplotlib.figure import Figure
    from rotorid.report.plots.case import save_figure

    def figure():
        drawn = Figure()
        axis = drawn.subplots()
        axis.fill_between([0, 1, 2], [0, 1, 0], [1, 2, 1], alpha=0.3)
        axis.plot([0, 1, 2], [1, 0, 1], label="x")
        axis.legend()
        return drawn

    first, second = save_figure(figure(), tmp_path / "a"), save_figure(figure(), tmp_path / "b")
    for a, b in zip(first, second):
        assert a.read_bytes() == b.read_bytes(), a.suffix
    assert b"<dc:date>" not in first[1].read_bytes()


# ----------------------------------------------------------------- orphaned workers
@pytest.mark.slow
def test_pool_workers_end_when_the_parent_is_killed_and_write_nothing_after(tmp_path):
    """A process pool's parent is SIGKILLed while its tasks sleep before writing a file; the
    workers end with it and the files never appear."""
    written = [tmp_path / f"late_{k}.txt" for k in range(2)]
    script = f"""
import os, signal, threading
from rotorid.executors import run_tasks
code = "import time, pathlib; time.sleep(2.0); pathlib.Path({{!r}}).write_text('late')"
tasks = {{k: ((code.format(path),), {{}}) for k, path in enumerate({[str(p) for p in written]})}}
threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGKILL)).start()
run_tasks(exec, tasks, "process")
"""
    parent = subprocess.run([sys.executable, "-c", script], timeout=60)
    assert parent.returncode == -signal.SIGKILL
    time.sleep(2.5)
    assert not any(p.exists() for p in written)


@pytest.mark.slow
def test_dask_workers_write_nothing_after_the_study_is_killed(tmp_path):
    """`rotorid study` on a Dask cluster whose scheduler and worker are not its children,
    SIGKILLed once its first reduction step is written: the worker goes on computing the case
    but refuses every later write (the run's lease, rotorid.lease), so nothing in --out
    changes after the kill."""
    pytest.importorskip("distributed")
    dask = Path(sys.executable).with_name("dask")
    address_file = tmp_path / "scheduler.json"
    logs = {name: (tmp_path / f"{name}.log").open("w") for name in ("scheduler", "worker")}
    cluster = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0",
                                 "--no-dashboard", "--scheduler-file", address_file],
                                stderr=logs["scheduler"])]
    try:
        cluster.append(subprocess.Popen(
            [dask, "worker", "--scheduler-file", address_file, "--nworkers", "1",
             "--nthreads", "1", "--no-dashboard"], stderr=logs["worker"]))
        deadline = time.monotonic() + 60
        while not address_file.is_file() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(address_file.read_text())["address"]
        case = tmp_path / "long.toml"            # the tiny case, reduced to its last parameter
        case.write_text((Path(__file__).parent / "cases" / "tiny.toml").read_text().replace(
            "continue_to_zero = false", "continue_to_zero = true"))
        out = tmp_path / "out"
        killed = subprocess.Popen([sys.executable, "-m", "rotorid.cli.main", "study", str(case),
                                   "--no-figures", "--executor", "dask", "--scheduler", address,
                                   "--out", str(out)], stderr=subprocess.DEVNULL)
        first_step = out / "tiny" / "steps" / "step_000.json"
        deadline = time.monotonic() + 120
        while not first_step.exists() and killed.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        killed.kill()
        assert killed.wait() == -signal.SIGKILL, "the run ended before it could be killed"
        at_kill = {p: p.stat().st_mtime_ns for p in _files_under(out / "tiny")}
        deadline = time.monotonic() + 60
        while "not writing" not in (tmp_path / "worker.log").read_text() \
                and time.monotonic() < deadline:
            time.sleep(0.2)
        time.sleep(2.0)
        assert "not writing" in (tmp_path / "worker.log").read_text()
        assert {p: p.stat().st_mtime_ns for p in _files_under(out / "tiny")} == at_kill
    finally:
        for process in reversed(cluster):
            process.terminate()
            process.wait(timeout=30)


# ----------------------------------------------------------------- kill and resume
@pytest.mark.slow
@pytest.mark.parametrize("written, figures", [
    ("data/manifest.json", False), ("steps/step_000.json", False),
    ("steps/step_004.json", False), ("result.json", True)],
    ids=["while-fitting-step-0", "after-the-first-step", "mid-reduction", "while-drawing"])
def test_a_killed_study_resumes_to_the_same_files(tmp_path, written, figures):
    """`rotorid study` of the tiny case reduced to its last parameter, SIGKILLed once
    ``written`` appears (during the first fit, after the first step, in the middle of the
    reduction, while the figures are drawn), then resumed: every file equals the uninterrupted
    run's byte for byte (figures included), result.json apart from its timing key and the
    HTML reports apart from the timings they state; no temporary file is left."""
    case = tmp_path / "tiny.toml"
    case.write_text((Path(__file__).parent / "cases" / "tiny.toml").read_text().replace(
        "continue_to_zero = false", "continue_to_zero = true"))
    command = ["study", str(case), "--executor", "serial",
               *(() if figures else ("--no-figures",))]
    assert _run([*command, "--out", str(tmp_path / "whole")]) == ExitStatus.OK
    killed = subprocess.Popen([sys.executable, "-m", "rotorid.cli.main", *command, "--out",
                               str(tmp_path / "killed")], stderr=subprocess.DEVNULL)
    trigger = tmp_path / "killed" / "tiny" / written
    deadline = time.monotonic() + 120
    while not trigger.exists() and killed.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    killed.kill()
    assert killed.wait() == -signal.SIGKILL, "the run ended before it could be killed"
    assert _run([*command, "--out", str(tmp_path / "killed"), "--resume"]) == ExitStatus.OK
    whole, resumed = tmp_path / "whole" / "tiny", tmp_path / "killed" / "tiny"
    names = sorted(p.relative_to(whole) for p in _files_under(whole))
    assert names == sorted(p.relative_to(resumed) for p in _files_under(resumed))
    assert len([n for n in names if n.parts[0] == "steps"]) == 9
    for name in names:
        if name.name == "result.json":
            records = [json.loads((root / name).read_text()) for root in (whole, resumed)]
            assert records[0].pop("timing") != records[1].pop("timing")
            assert records[0] == records[1]
        elif name.name != "report.html":
            assert (whole / name).read_bytes() == (resumed / name).read_bytes(), name
    assert (Path("figures/rmse.svg") in names) == figures
