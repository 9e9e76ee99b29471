"""``rotorid frequency``: responses of sweep files written as JSON, CSV and MAT."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from rotorid.cli.main import main
from rotorid.simulation.transfer import frequency_response
from rotorid.verification.handling_qualities import bandwidth_phase_delay
from rotorid_files.formats import read_maneuver, write_maneuver

sys.path.insert(0, str(Path(__file__).parent))
from test_frequency_response_estimator import TRUTH, _structure, _sweeps  # noqa: E402


@pytest.fixture(scope="module")
def sweep_dir(tmp_path_factory):
    directory = tmp_path_factory.mktemp("sweeps")
    for maneuver in _sweeps(_structure(), TRUTH, noise=0.0, seed=0):
        write_maneuver(maneuver, directory / f"{maneuver.name}.npz")
    return directory


def test_json_holds_the_response_that_matches_the_model(sweep_dir, tmp_path, capsys):
    out = tmp_path / "responses.json"
    assert main(["frequency", str(sweep_dir), "--pairs", "q/long,p/lat", "--out",
                 str(out)]) == 0
    assert "wrote 2 responses" in capsys.readouterr().out
    record = json.loads(out.read_text())
    assert [p["pair"] for p in record["pairs"]] == ["q/long", "p/lat"]
    pair = record["pairs"][0]
    omega = np.array(pair["omega_rad_s"])
    measured = np.array(pair["real"]) + 1j * np.array(pair["imag"])
    coherent = (np.array(pair["coherence"]) > 0.99) & (omega < 10.0)
    model = frequency_response(_structure(), TRUTH, omega)[:, 2, 0]        # q / long
    hold = (1 - np.exp(-1j * omega * 0.02)) / (1j * omega * 0.02)           # zero-order hold
    ratio = measured[coherent] / (model * hold)[coherent]
    assert np.all(np.abs(20 * np.log10(np.abs(ratio))) < 0.5)             # dB
    assert np.all(np.abs(np.degrees(np.angle(ratio))) < 5.0)
    np.testing.assert_allclose(pair["magnitude_db"], 20 * np.log10(np.abs(measured)))


def test_csv_and_mat_carry_the_same_numbers(sweep_dir, tmp_path):
    csv, mat = tmp_path / "r.csv", tmp_path / "r.mat"
    assert main(["frequency", str(sweep_dir), "--pairs", "theta/long", "--conditioned",
                 "--out", str(csv)]) == 0
    assert main(["frequency", str(sweep_dir), "--pairs", "theta/long", "--conditioned",
                 "--out", str(mat)]) == 0
    table = np.genfromtxt(csv, delimiter=",", names=True, dtype=None, encoding="utf-8")
    struct = scipy.io.loadmat(mat, simplify_cells=True)["theta_long"]
    np.testing.assert_allclose(table["omega_rad_s"], struct["omega_rad_s"], rtol=1e-9)
    np.testing.assert_allclose(table["real"] + 1j * table["imag"], struct["H"], rtol=1e-8)


def test_unknown_suffix_is_a_usage_error(sweep_dir, tmp_path, capsys):
    assert main(["frequency", str(sweep_dir), "--out", str(tmp_path / "r.txt")]) == 2
    assert "give a file ending in .json, .csv, .mat" in capsys.readouterr().err


def test_handling_qualities_of_the_measured_attitude_responses_match_the_models(
        sweep_dir, tmp_path, capsys):
    """--handling-qualities adds theta/long and phi/lat (and r/ped where swept), prints the
    ADS-33 numbers and writes them; each matches the numbers of the model's own analytic
    response times the records' zero-order hold on the same coherent frequencies, within 8 %
    (near −135° the composite estimate's phase lies about 2° above the model's and the phase
    falls by about 2.5° per 0.1 rad/s there)."""
    out, mat = tmp_path / "hq.json", tmp_path / "hq.mat"
    assert main(["frequency", str(sweep_dir), "--pairs", "q/long", "--handling-qualities",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    record = json.loads(out.read_text())
    pairs = [p["pair"] for p in record["pairs"]]
    assert pairs[0] == "q/long" and {"theta/long", "phi/lat"} <= set(pairs)
    qualities = {q["pair"]: q for q in record["handling_qualities"]}
    assert {"theta/long", "phi/lat"} <= set(qualities)
    for pair in ("theta/long", "phi/lat"):
        measured = next(p for p in record["pairs"] if p["pair"] == pair)
        omega = np.array(measured["omega_rad_s"])
        keep = np.array([c is not None and c >= 0.6 for c in measured["coherence"]])
        output, control = pair.split("/")
        model = frequency_response(_structure(), TRUTH, omega[keep])[
            :, _structure().outputs.index(output), _structure().controls.index(control)]
        hold = (1 - np.exp(-1j * omega[keep] * 0.02)) / (1j * omega[keep] * 0.02)
        expected = bandwidth_phase_delay(omega[keep], model * hold, pair)
        assert qualities[pair]["bandwidth"] == pytest.approx(expected.bandwidth, rel=0.08)
        assert qualities[pair]["omega_180"] == pytest.approx(expected.omega_180, rel=0.08)
        assert qualities[pair]["phase_delay"] == pytest.approx(expected.phase_delay, abs=0.01)
        assert f"{pair:<12} ADS-33 bandwidth" in printed
    assert main(["frequency", str(sweep_dir), "--handling-qualities", "--out", str(mat)]) == 0
    struct = scipy.io.loadmat(mat, simplify_cells=True)["handling_qualities"]
    assert struct["theta_long"]["bandwidth"] == pytest.approx(
        qualities["theta/long"]["bandwidth"])


def test_a_model_file_reads_sweeps_in_a_test_ranges_names(sweep_dir, tmp_path, capsys):
    """The same sweeps with the range's column names (pitch rate in rad/s, stick as DLONG):
    without a model the columns are unknown channels, through the model file's [channels]
    table the response is the one of the files in rotorid's names."""
    renamed = tmp_path / "range"
    renamed.mkdir()
    for path in sorted(sweep_dir.glob("*.npz")):
        csv = renamed / f"{path.stem}.csv"
        write_maneuver(read_maneuver(path), csv)
        lines = csv.read_text().splitlines()
        header = next(k for k, line in enumerate(lines) if not line.startswith("#"))
        columns = lines[header].split(",")
        q, long = columns.index("q"), columns.index("long")
        columns[q], columns[long] = "Q_radps", "DLONG"
        rows = [line.split(",") for line in lines[header + 1:]]
        for row in rows:
            row[q] = repr(float(np.radians(float(row[q]))))
        csv.write_text("\n".join(lines[:header] + [",".join(columns)]
                                 + [",".join(row) for row in rows]) + "\n")
    model = tmp_path / "model.toml"
    model.write_text('[condition]\nairspeed_kt = 0.0\n[structure]\ntemplate = "six-dof"\n'
                     '[channels]\nQ_radps = { signal = "q", unit = "rad/s" }\n'
                     'DLONG = { signal = "long", unit = "%" }\n', encoding="utf-8")
    plain, mapped = tmp_path / "plain.json", tmp_path / "mapped.json"
    assert main(["frequency", str(sweep_dir), "--pairs", "q/long", "--out", str(plain)]) == 0
    assert main(["frequency", str(renamed), "--pairs", "q/long", "--out",
                 str(tmp_path / "x.json")]) == 3
    assert "--model" in capsys.readouterr().err
    assert main(["frequency", str(renamed), "--model", str(model), "--pairs", "q/long",
                 "--out", str(mapped)]) == 0
    first, second = (json.loads(p.read_text())["pairs"][0] for p in (plain, mapped))
    np.testing.assert_allclose(second["real"], first["real"], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(second["coherence"], first["coherence"], rtol=1e-6, atol=1e-9)


def test_an_existing_out_file_is_kept_without_force(sweep_dir, tmp_path, capsys):
    out = tmp_path / "r.json"
    out.write_text("earlier responses", encoding="utf-8")
    assert main(["frequency", str(sweep_dir), "--pairs", "q/long", "--out", str(out)]) != 0
    assert "exists already; give --force" in capsys.readouterr().err
    assert out.read_text(encoding="utf-8") == "earlier responses"
    assert main(["frequency", str(sweep_dir), "--pairs", "q/long", "--out", str(out),
                 "--force"]) == 0
    assert out.read_text(encoding="utf-8").startswith("{")
