"""``rotorid verify`` of a declared, non-helicopter structure: the fixed-wing model of
docs/examples/fixed_wing_linear.toml, identified and verified on sweeps with the test range's
own column names, read through its ``[channels]`` table.

The records and sweeps are the test's own, from the hand-written model of
``test_example_fixed_wing_linear`` (scipy's exact ZOH discretisation, independent of rotorid).
"""

import json
import math
import shutil

import numpy as np
import scipy.signal
from rotorid.cli.main import main
from rotorid.verification.pairs import default_pairs
from sweeps import log_sweep
from test_example_fixed_wing_linear import (
    COLUMNS,
    DT,
    EXAMPLE,
    NOISE,
    G,
    hand_model,
    write_records,
)

OUTPUTS = ("V", "alpha", "q", "theta", "q_dot", "ax", "az")


def _write_sweeps(directory) -> None:
    """An elevator sweep (±2 deg) and a thrust sweep (±500 N) of the hand-written model."""
    directory.mkdir()
    system = scipy.signal.cont2discrete(hand_model(), DT, method="zoh")
    sweep = log_sweep(duration=60.0, omega_min=0.3, omega_max=12.0)
    time = np.arange(sweep.size) * DT
    to_file = np.array([1.0, 180 / math.pi, 180 / math.pi, 180 / math.pi, 1.0, 1 / G, 1.0])
    rng = np.random.default_rng(1)
    zero = np.zeros_like(sweep)
    for name, inputs in (("sweep_elevator", (2.0 * sweep, zero)),
                         ("sweep_thrust", (zero, 500.0 * sweep))):
        u = np.column_stack(inputs)
        _, y, _ = scipy.signal.dlsim(system[:4] + (DT,), u, time)
        y = y * to_file + rng.normal(0.0, NOISE, y.shape)
        np.savetxt(directory / f"{name}.csv", np.column_stack([time, u, y]), delimiter=",",
                   header=",".join(("time", "DELE_deg", "THRUST_N") + COLUMNS), comments="")


def _identified(tmp_path, capsys, *options, recorded=None):
    """The example's model file and records in ``tmp_path`` (``recorded(directory)`` changes
    the records first), identified with ``options``; the result's path."""
    model = tmp_path / "fixed_wing_linear.toml"
    shutil.copy(EXAMPLE, model)
    (tmp_path / "records").mkdir()
    write_records(tmp_path / "records")
    if recorded is not None:
        recorded(tmp_path / "records")
    result = tmp_path / "result.json"
    assert main(["identify", str(model), str(tmp_path / "records"), "--out", str(result),
                 "--quiet", *options]) == 0, capsys.readouterr().err
    return result


def test_verify_checks_every_pair_of_the_aeroplane_on_its_own_columns(tmp_path, capsys):
    result = _identified(tmp_path, capsys)
    _write_sweeps(tmp_path / "sweeps")
    out = tmp_path / "verification"
    status = main(["verify", str(result), str(tmp_path / "sweeps"), "--out", str(out),
                   "--no-figures"])
    printed = capsys.readouterr()
    assert status == 0, printed.err
    summary = json.loads((out / "verification.json").read_text(encoding="utf-8"))
    pairs = [p["pair"] for p in summary["pairs"]]
    # none of the paper's pairs: every output over every input
    assert pairs == list(default_pairs(OUTPUTS, ("elevator", "thrust")))
    assert len(pairs) == 14 and summary["skipped_pairs"] == []
    muad = {p["pair"]: p["checks"]["muad"]["passed"] for p in summary["pairs"]}
    for pair in ("V/elevator", "alpha/elevator", "q/elevator", "theta/elevator", "V/thrust"):
        assert muad[pair], pair
    assert list(summary["time_domain"]["rmse_per_output"]) == list(OUTPUTS)
    assert not [n for n in summary["notes"] if "step input" in n]      # sweeps are sweeps


def test_verify_on_multisteps_says_they_are_not_sweeps(tmp_path, capsys):
    """The identification records (3211 and doublets, no kind metadata) given as sweeps:
    verified, with a note per record that it is a step input."""
    result = _identified(tmp_path, capsys)
    out = tmp_path / "verification"
    status = main(["verify", str(result), str(tmp_path / "records"), "--out", str(out),
                   "--no-figures"])
    printed = capsys.readouterr()
    assert status == 0, printed.err
    notes = json.loads((out / "verification.json").read_text(encoding="utf-8"))["notes"]
    stepped = [n for n in notes if "a step input (multistep, doublet), not a frequency sweep" in n]
    records = sorted(p.stem for p in (tmp_path / "records").glob("*.csv"))
    assert sorted(n.split(":")[0] for n in stepped) == records
    assert all(f"note: {n}" in printed.out for n in stepped)


def _offset_records(directory, offsets: dict) -> None:
    """Every CSV of ``directory`` with ``offsets`` (column → value) added: the trim a flight
    test records on top of the perturbations."""
    for path in directory.glob("*.csv"):
        header = path.read_text().splitlines()[0]
        table = np.loadtxt(path, delimiter=",", skiprows=1)
        for column, value in offsets.items():
            table[:, header.split(",").index(column)] += value
        np.savetxt(path, table, delimiter=",", header=header, comments="")


def test_verify_reads_the_sweeps_with_the_identifications_trim_removal(tmp_path, capsys):
    """Records and sweeps on top of a trim (40 m/s true airspeed, 4 deg pitch, 1.5 deg
    elevator): identified with --trim first-second, which the result records, the sweeps are
    read the same way; stating a trim that removes nothing (--trim theta=0) leaves the offsets
    in, and the average mismatch cost J_ave grows more than fivefold (1090 against 93)."""
    _write_sweeps(tmp_path / "sweeps")
    trim = {"VTAS_mps": 40.0, "PITCH_deg": 4.0, "DELE_deg": 1.5}
    result = _identified(tmp_path, capsys, "--trim", "first-second",
                         recorded=lambda records: _offset_records(records, trim))
    _offset_records(tmp_path / "sweeps", trim)
    assert json.loads(result.read_text())["ingestion"] == {"trim": "first-second"}
    capsys.readouterr()
    costs = {}
    for label, extra in (("recorded", []), ("nothing removed", ["--trim", "theta=0"])):
        out = tmp_path / label
        assert main(["verify", str(result), str(tmp_path / "sweeps"), "--out", str(out),
                     "--no-figures", *extra]) == 0
        printed = capsys.readouterr().out
        summary = json.loads((out / "verification.json").read_text(encoding="utf-8"))
        costs[label] = summary["average_cost"]
        muad = {p["pair"]: p["checks"]["muad"]["passed"] for p in summary["pairs"]}
        if label == "recorded":
            assert "sweeps read with the identification records' trim removal: first-second" \
                in printed
            assert muad["q/elevator"] and muad["theta/elevator"]
            assert "warning:" not in printed
        else:
            assert "sweeps read with --trim: theta=0" in printed
            # the data checks of identification records, run on the sweeps, name the offset
            assert ("warning: output 'V' starts away from zero in 2 of 2 maneuvers: 40 m/s"
                    in printed)
    assert costs["nothing removed"] > 5 * costs["recorded"]


def test_verify_simulates_the_sweeps_with_the_identifications_hold(tmp_path, capsys):
    """Identified with --hold foh, the result records the hold and verify simulates the sweeps
    with it (a line says so); --hold zoh states another. The sweeps here are the held inputs
    of scipy's exact ZOH discretisation, so the zero-order hold fits them better: the sweeps'
    time-domain RMSE in q is lower with it, which shows the hold reached the simulation."""
    _write_sweeps(tmp_path / "sweeps")
    result = _identified(tmp_path, capsys, "--hold", "foh")
    assert json.loads(result.read_text())["hold"] == "foh"
    capsys.readouterr()
    rmse = {}
    for label, extra in (("recorded", []), ("stated", ["--hold", "zoh"])):
        out = tmp_path / label
        assert main(["verify", str(result), str(tmp_path / "sweeps"), "--out", str(out),
                     "--no-figures", "--pairs", "q/elevator", *extra]) == 0
        printed = capsys.readouterr().out
        assert ("sweeps simulated with the identification records' hold: foh" in printed) == (
            label == "recorded")
        summary = json.loads((out / "verification.json").read_text(encoding="utf-8"))
        rmse[label] = summary["time_domain"]["rmse_per_output"]["q"]
    assert rmse["stated"] < rmse["recorded"], rmse
