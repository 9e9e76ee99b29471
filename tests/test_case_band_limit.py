"""A case's ``[resampling] cutoff_hz``: the identification records are low-passed and
decimated before every fit of the study (and of its Monte Carlo), the setting is checked
when the case is read, and it is recorded in result.json only when set."""

import json
from pathlib import Path

import attrs
import numpy as np
import pytest
from rotorid.cli.main import main
from rotorid.errors import DataFileError
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import run_case
from test_reduction_study import TRUE, data, files_case  # noqa: F401  (data: fixture)

CASE = {"name": "banded", "data": {"source": "helisim", "condition": "hover"}}


def test_the_setting_is_read_and_recorded_only_when_set():
    case = FlightCase.from_mapping({**CASE, "resampling": {"cutoff_hz": 3.0,
                                                               "decimate": 8, "hold": "foh"}})
    assert (case.cutoff_hz, case.decimate, case.identification_hold) == (3.0, 8, "foh")
    assert {k: case.as_dict()[k] for k in ("cutoff_hz", "decimate", "identification_hold")} \
        == {"cutoff_hz": 3.0, "decimate": 8, "identification_hold": "foh"}
    plain = FlightCase.from_mapping(CASE).as_dict()
    assert not {"cutoff_hz", "decimate", "identification_hold"} & set(plain)


@pytest.mark.parametrize("table, message", [
    ({"cutoff_hz": -1.0}, r"\[resampling\] cutoff_hz must be a frequency > 0 Hz"),
    ({"cutoff_hz": float("nan")}, r"cutoff_hz must be a frequency > 0 Hz"),
    ({"decimate": 4}, r"\[resampling\] decimate needs cutoff_hz"),
    ({"cutoff_hz": 3.0, "decimate": 0}, r"decimate must be a whole number ≥ 1"),
    ({"cutoff": 3.0}, r"\[resampling\] unknown key\(s\) \['cutoff'\]"),
    ({"hold": "linear"}, r"\[resampling\] hold must be \"zoh\" .* got 'linear'"),
])
def test_bad_settings_are_refused_when_the_case_is_read(table, message):
    with pytest.raises(DataFileError, match=message):
        FlightCase.from_mapping({**CASE, "resampling": table}, "case.toml")


def test_the_study_fits_the_band_limited_records(tmp_path, data):  # noqa: F811
    case = attrs.evolve(files_case(tmp_path, data), cutoff_hz=8.0, identification_hold="foh")
    messages = []
    result = run_case(case, tmp_path / "out", progress=lambda c, m: messages.append(m))
    assert "identification records low-passed at 8 Hz, sample time 0.02 → 0.06 s" in messages
    assert result.identification[0].dt == pytest.approx(0.06)     # every 3rd sample kept
    record = json.loads((tmp_path / "out" / "own" / "result.json").read_text())
    assert record["case"]["cutoff_hz"] == 8.0
    # the doublets' dynamics lie below 8 Hz: the band keeps the true model (with the
    # first-order hold the case asks for; held constant over 0.1 s at 5 Hz, M_q came out
    # 24 % off)
    assert result.identification.hold == "foh"
    # the sweeps share the records' hold (unchanged without one), and a model read back from
    # the result has it
    assert case.verification_records(result.identification).hold == "foh"
    plain = attrs.evolve(case, identification_hold=None)
    assert plain.verification_records(attrs.evolve(result.identification, hold="zoh")).hold \
        == "zoh"
    assert case.verification_records(None) is None
    from rotorid.estimation.result_file import load_result
    assert load_result(tmp_path / "out" / "own" / "result.json").hold == "foh"
    estimate = result.estimates["with delays"]
    values = dict(zip(estimate.parameter_names, estimate.values))
    assert set(values) >= set(TRUE)
    for name in ("M_q", "M_long", "L_p", "L_lat"):
        assert values[name] == pytest.approx(TRUE[name], rel=0.1), name
    assert np.all(np.isfinite(estimate.cramer_rao))


EXAMPLE = (Path(__file__).resolve().parents[1] / "docs" / "examples"
           / "turbulence_longitudinal.toml")


def test_the_turbulence_case_file_reads():
    case = FlightCase.load(EXAMPLE)
    assert (case.cutoff_hz, case.decimate, case.estimator) == (3.0, None, "filter-error")
    assert case.data_settings["turbulence"] == "moderate"


@pytest.mark.slow
def test_rotorid_montecarlo_runs_the_turbulence_case_file(tmp_path, capsys):
    """docs/estimation.md has 30 runs of it (about 2 minutes); four here."""
    assert main(["montecarlo", str(EXAMPLE), "--runs", "4", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    record = json.loads((tmp_path / "hover-turbulence-longitudinal" / "montecarlo.json")
                        .read_text())
    assert record["converged"] == 4 and record["failed"] == 0
    study = json.loads((tmp_path / "hover-turbulence-longitudinal" / "result.json").read_text())
    assert study["case"]["cutoff_hz"] == 3.0


FILTER_EVERY = {"name": "filter-error", "update_every": 6}


def test_with_update_every_the_records_keep_every_sample():
    """With the filter-error estimator's update_every the low-passed records are not
    decimated (the filter steps through every sample and updates once per six)."""
    from test_filter_error import noisy_data

    case = FlightCase.from_mapping({**CASE, "estimator": FILTER_EVERY,
                                    "resampling": {"cutoff_hz": 4.0}})
    raw = noisy_data({})
    records = case.identification_records(raw)
    assert [m.n_samples for m in records] == [m.n_samples for m in raw]
    assert records[0].dt == raw[0].dt
    assert not np.allclose(records[0].outputs, raw[0].outputs)
    decimated_case = FlightCase.from_mapping({**CASE, "resampling": {"cutoff_hz": 4.0}})
    assert decimated_case.identification_records(raw)[0].dt == pytest.approx(6 * raw[0].dt)


def test_decimate_and_update_every_together_are_refused():
    with pytest.raises(DataFileError, match=r"give \[resampling\] decimate or \[estimator\] "
                                            r"update_every, not both"):
        FlightCase.from_mapping({**CASE, "estimator": FILTER_EVERY,
                                 "resampling": {"cutoff_hz": 4.0, "decimate": 6}}, "case.toml")


def test_the_run_is_labelled_by_what_the_source_gives():
    """Generated data come as a quick or a full set; recorded files are what they are (only a
    [quick] table makes a quick run of them)."""
    generated = FlightCase.from_mapping(CASE)
    assert generated.run_label == "full set"
    assert attrs.evolve(generated, is_quick=True).run_label == "quick set"
    files = FlightCase.from_mapping({"name": "own", "data": {"source": "files",
                                                             "identification": "f/*.csv"}})
    assert files.run_label == "" and attrs.evolve(files, is_quick=True).run_label == "quick run"
