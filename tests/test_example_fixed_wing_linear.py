"""docs/examples/fixed_wing_linear.toml: an aeroplane's longitudinal model declared in TOML
(states V α q θ; inputs elevator and thrust; outputs V α q θ q̇ ax az) identifies through
``rotorid identify`` from CSV files with the test range's column names and units.

The data are the test's own and independent of rotorid's simulator: the model's A, B, C, D
written out by hand below, discretised exactly for held inputs (scipy's ZOH), with white noise;
columns in deg, deg/s, g and N as the ``[channels]`` table of the example declares them.
"""

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.signal
from rotorid import load_result
from rotorid.cli.main import main
from rotorid.model.modelfile import load_model

EXAMPLE = Path(__file__).parents[1] / "docs" / "examples" / "fixed_wing_linear.toml"
G, U0, DT = 9.80665, 50.0, 0.02
TRUTH = {"X_V": -0.03, "X_alpha": 4.0, "X_thrust": 0.0002, "Z_V": -0.004, "Z_alpha": -1.6,
         "Z_elevator": -0.003, "M_alpha": -8.0, "M_q": -2.2, "M_elevator": -0.2}
#: Noise standard deviations of V α q θ q̇ ax az in the file's units (m/s, deg, deg/s, deg,
#: rad/s², g, m/s²).
NOISE = np.array([0.05, 0.05, 0.1, 0.05, 0.01, 0.002, 0.05])
COLUMNS = ("VTAS_mps", "AOA_deg", "Q_degps", "PITCH_deg", "QDOT_radps2", "AX_g", "AZ_mps2")


def hand_model():
    """A, B, C, D of the example's model at :data:`TRUTH`, from its equations (SI, rad)."""
    t = TRUTH
    a = np.array([[t["X_V"], t["X_alpha"], 0.0, -G],
                  [t["Z_V"], t["Z_alpha"], 1.0, 0.0],
                  [0.0, t["M_alpha"], t["M_q"], 0.0],
                  [0.0, 0.0, 1.0, 0.0]])
    b = np.array([[0.0, t["X_thrust"]], [t["Z_elevator"], 0.0], [t["M_elevator"], 0.0],
                  [0.0, 0.0]])
    # ax = V̇ + g·θ = ΣX; az = U0·(α̇ − q) = U0·ΣZ; q̇ = ΣM.
    sums = np.vstack([a[2], a[0] + [0, 0, 0, G], U0 * (a[1] - [0, 0, 1, 0])])
    c = np.vstack([np.eye(4), sums])
    d = np.vstack([np.zeros((4, 2)), b[2], b[0], U0 * b[1]])
    return a, b, c, d


def _records():
    time = np.arange(0.0, 15.0, DT)
    def pulse(start, length, amplitude):
        return np.where((time >= start) & (time < start + length), amplitude, 0.0)
    elevator_3211 = (pulse(1, 1.5, 2.0) - pulse(2.5, 1.0, 2.0) + pulse(3.5, 0.5, 2.0)
                     - pulse(4.0, 0.5, 2.0))                                  # deg
    thrust_step = pulse(6.0, 4.0, 800.0) - pulse(10.0, 3.0, 400.0)            # N
    doublet = pulse(1.0, 1.0, -1.5) + pulse(2.0, 1.0, 1.5)
    return {"elevator3211": (elevator_3211, 0.0 * time), "thrust": (0.0 * time, thrust_step),
            "mixed": (doublet, pulse(4.0, 5.0, 500.0))}, time


def write_records(directory: Path, seed: int = 3, elevator_in_rad: bool = False) -> None:
    """One CSV per record with the file's own column names and units (the elevator in deg,
    or in rad with ``elevator_in_rad``)."""
    rng = np.random.default_rng(seed)
    system = scipy.signal.cont2discrete(hand_model(), DT, method="zoh")
    records, time = _records()
    to_file = np.array([1.0, 180 / math.pi, 180 / math.pi, 180 / math.pi, 1.0, 1 / G, 1.0])
    for name, (elevator_deg, thrust) in records.items():
        # The model's B takes the elevator in the file's unit (deg): controls are not converted.
        u = np.column_stack([elevator_deg, thrust])
        _, y, _ = scipy.signal.dlsim(system[:4] + (DT,), u, time)
        y = y * to_file + rng.normal(0.0, NOISE, y.shape)
        elevator = np.radians(elevator_deg) if elevator_in_rad else elevator_deg
        header = ",".join(("time", "DELE_deg", "THRUST_N") + COLUMNS)
        table = np.column_stack([time, elevator, thrust, y])
        np.savetxt(directory / f"{name}.csv", table, delimiter=",", header=header, comments="")


def test_the_declared_aeroplane_model_identifies_from_its_own_columns(tmp_path, capsys):
    model = tmp_path / "fixed_wing_linear.toml"
    shutil.copy(EXAMPLE, model)
    data = tmp_path / "records"
    data.mkdir()
    write_records(data)
    out = tmp_path / "result.json"
    status = main(["identify", str(model), str(data), "--out", str(out), "--quiet"])
    assert status == 0, capsys.readouterr().err
    identified = load_result(out)
    assert identified.structure.outputs == ("V", "alpha", "q", "theta", "q_dot", "ax", "az")
    estimate = identified.estimate
    for name, truth in TRUTH.items():
        row = estimate[name]
        assert abs(row.value - truth) <= max(4 * row.cramer_rao, 0.02 * abs(truth)), (name, row)
    report = capsys.readouterr().out
    assert "M_elevator" in report


def test_a_control_recorded_in_another_unit_is_converted_into_the_declared_one(tmp_path,
                                                                               capsys):
    model = tmp_path / "model.toml"
    model.write_text(EXAMPLE.read_text().replace(
        'DELE_deg = { signal = "elevator", unit = "deg" }',
        'DELE_deg = { signal = "elevator", unit = "rad" }'))
    data = tmp_path / "records"
    data.mkdir()
    write_records(data, elevator_in_rad=True)
    out = tmp_path / "result.json"
    assert main(["identify", str(model), str(data), "--out", str(out), "--quiet"]) == 0
    estimate = load_result(out).estimate
    assert estimate["M_elevator"].value == pytest.approx(TRUTH["M_elevator"], rel=0.02)
    assert estimate.parameter_units["M_elevator"] == "rad/s² per deg"


def test_the_declaration_round_trips_through_a_saved_model_file(tmp_path):
    from rotorid.model.modelfile import save_model

    structure = load_model(EXAMPLE)
    assert structure.outputs == ("V", "alpha", "q", "theta", "q_dot", "ax", "az")
    saved = save_model(structure, tmp_path / "saved.toml")
    assert load_model(saved) == structure


def test_the_structure_equals_the_hand_written_model():
    structure = load_model(EXAMPLE)
    a, b, c, d = structure.matrices(TRUTH)
    for mine, hand in zip((a, b, c, d), hand_model()):
        np.testing.assert_allclose(mine, hand, atol=1e-12)


@pytest.mark.parametrize("edit, fragment", [
    (('alpha = { q = 1.0 }', 'alpha = { qq = 1.0 }'), "'qq' is not a state"),
    (('equations = { X = "V"', 'equations = { X = "U"'), "X drives 'U', which is not a state"),
    (('az = { "d(alpha)" = 50.0, q = -50.0 }', ''), "output az has no output equation"),
    (('q = "rate", theta', 'q = "spin", theta'), "unknown signal kind 'spin'"),
    (('elevator = "deg"', 'elevator = "m/s"'), "controls.elevator = 'm/s'"),
    (('[derivatives.M_q]', '[derivatives.M_beta]'), "M_beta does not fit"),
    (('AOA_deg = { signal = "alpha", unit = "deg" }', 'AOA_deg = { signal = "alpha", unit = "m/s" }'),
     "does not fit"),
])
def test_bad_declarations_are_one_line_errors_naming_the_file(tmp_path, capsys, edit, fragment):
    model = tmp_path / "model.toml"
    model.write_text(EXAMPLE.read_text().replace(*edit))
    data = tmp_path / "records"
    data.mkdir()
    write_records(data)
    status = main(["identify", str(model), str(data), "--out", str(tmp_path / "r.json")])
    error = capsys.readouterr().err
    assert status != 0
    assert fragment in error and "model.toml" in error
    assert len(error.strip().splitlines()) == 1
    assert "Traceback" not in error


def _sweep(directory: Path, seed: int = 5) -> None:
    """A 60 s elevator sweep (0.05–2.5 Hz) in the files' own columns and units."""
    rng = np.random.default_rng(seed)
    time = np.arange(0.0, 60.0, DT)
    frequency = 2 * np.pi * (0.05 + (2.5 - 0.05) * time / 60.0)
    elevator_deg = 1.5 * np.sin(np.cumsum(frequency) * DT)
    system = scipy.signal.cont2discrete(hand_model(), DT, method="zoh")
    _, y, _ = scipy.signal.dlsim(system[:4] + (DT,),
                                 np.column_stack([elevator_deg, 0.0 * time]), time)
    to_file = np.array([1.0, 180 / math.pi, 180 / math.pi, 180 / math.pi, 1.0, 1 / G, 1.0])
    y = y * to_file + rng.normal(0.0, NOISE, y.shape)
    header = ",".join(("time", "DELE_deg", "THRUST_N") + COLUMNS)
    np.savetxt(directory / "elevator_sweep.csv",
               np.column_stack([time, elevator_deg, 0.0 * time, y]), delimiter=",",
               header=header, comments="")


def _case_text() -> str:
    """A files case holding the example's structure and channel map."""
    text = EXAMPLE.read_text()
    structure = text[text.index("[structure]"):text.index("[channels]")]
    links = [line.split("#")[0].strip() for line in
             text[text.index("[channels]") + len("[channels]"):].splitlines()]
    channels = "{ " + ", ".join(link for link in links if link) + " }"
    return (f'name = "aeroplane"\ndescription = "fixed-wing longitudinal from flight-test files"'
            f'\n\n[data]\nsource = "files"\nunits = "si"\nidentification = "ident/*.csv"\n'
            f'verification = "sweeps/*.csv"\nchannels = {channels}\n\n[condition]\n'
            f'u0_mps = 50.0\n\n{structure}')


def test_a_study_of_the_aeroplane_speaks_about_the_aeroplane(tmp_path, capsys):
    (tmp_path / "ident").mkdir()
    (tmp_path / "sweeps").mkdir()
    write_records(tmp_path / "ident")
    _sweep(tmp_path / "sweeps")
    case = tmp_path / "case.toml"
    case.write_text(_case_text())
    status = main(["study", str(case), "--out", str(tmp_path / "out")])
    printed = capsys.readouterr()
    assert status == 0, printed.err
    identified = load_result(tmp_path / "out" / "aeroplane" / "result.json", "no delays")
    assert identified.structure.outputs == ("V", "alpha", "q", "theta", "q_dot", "ax", "az")
    assert not identified.structure.free_delays                # no rotor, no default delays
    report = (tmp_path / "out" / "aeroplane" / "report.html").read_text()
    for absent in ("Bo-105", "paper's claims", "truth", "Appendix B", " kt"):
        assert absent not in report
    assert "rad/s per m/s" in report and "q/elevator" in report       # Z_V
    assert "Trim: 50.0 m/s" in report and "RMSE values (eq. 18) are pure numbers" in report
    assert "RMSE [-]" in report and "RMSE [mixed units]" not in report      # pure numbers
    assert "[%]" not in report.split('id="time-histories"')[1].split('id="verification"')[0]
    # no delays declared: one model, not the same model twice as "no delays" and "with delays"
    assert "none declared" in report and "identified model: value" in report
    assert "delays: value" not in report and "without delays" not in report
    assert report.count("time-domain RMSE ≤ 1.0 to 2.0 (identified model") == 1
    summary = next(line for line in printed.out.splitlines() if line.startswith("aeroplane:"))
    assert "RMSE" in summary and "delays" not in summary
    # the study's result verifies on the range's files through the case's own channel map
    status = main(["verify", str(tmp_path / "out" / "aeroplane" / "result.json"),
                   str(tmp_path / "sweeps"), "--out", str(tmp_path / "verified"),
                   "--no-figures"])
    assert status == 0, capsys.readouterr().err


def test_a_case_without_sweeps_says_it_was_not_verified(tmp_path, capsys):
    (tmp_path / "ident").mkdir()
    write_records(tmp_path / "ident")
    case = tmp_path / "case.toml"
    case.write_text(_case_text().replace('verification = "sweeps/*.csv"\n', ""))
    assert main(["study", str(case), "--out", str(tmp_path / "out")]) == 0, \
        capsys.readouterr().err
    report = (tmp_path / "out" / "aeroplane" / "report.html").read_text()
    assert ("Frequency-domain verification: not done, the case gives no sweeps ([data] "
            "verification).") in report
    assert "checked pairs inside MUAD" not in report


def test_a_declared_structure_in_a_case_needs_its_unit_system(tmp_path, capsys):
    case = tmp_path / "case.toml"
    case.write_text(_case_text().replace('units = "si"\n', ""))
    assert main(["study", str(case), "--out", str(tmp_path / "out")]) != 0
    error = capsys.readouterr().err
    assert "[data] units" in error and len(error.strip().splitlines()) == 1
