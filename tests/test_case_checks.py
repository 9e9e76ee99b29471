"""Case files are checked before any data exist: each bad setting is one line naming the case
file, the table and key, and the fix; a Study checks every case before running any."""

import numpy as np
import pytest
from rotorid.errors import DataFileError
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import Study, load_data, run_case
from rotorid.study.reference import ReferenceValue
from rotorid.verification.band import VerificationBand

FILES = {"source": "files", "identification": "flight/*.csv"}


def case_file(tmp_path, text: str):
    path = tmp_path / "case.toml"
    path.write_text(f'name = "own"\n[data]\nsource = "files"\nidentification = "f.csv"\n{text}')
    return path


@pytest.mark.parametrize("text, message", [
    ('[derivatives]\nL_pp = {}\n', r"L_pp"),
    ('[structure]\nremove = ["X_q"]\npopulate = "none"\n', r"\[structure\] remove"),
    ('[verification]\npairs = ["q/lng"]\n', r"\[verification\] pairs.*'q/lng'.*OUTPUT/INPUT"),
    ('[verification]\nenvelopes = ["muda"]\n',
     r"\[verification\] envelopes 'muda' is not registered in the validation-envelopes "
     r"family; use .*muad"),
    ('[reduction]\ncriteria = ["cramer_rao"]\n',
     r"\[reduction\] criteria 'cramer_rao' is not registered.*use one of cramer-rao"),
    ('[reduction]\ncriteria = [{ name = "cramer-rao", treshold = 5.0 }]\n',
     r"\[reduction\] criteria: reduction criterion 'cramer-rao' has no option 'treshold'; "
     r"its options: .*threshold"),
    ('[reduction]\nrule = "best"\n', r"\[reduction\] rule 'best' is unknown"),
    ('[reduction]\nwarm_start = "yes"\n', r"\[reduction\] warm_start must be true or false"),
    ('[estimator]\nname = "least-squares"\n', r"\[estimator\] name 'least-squares'"),
    ('[estimator]\nname = "filter-error"\ngust = ["w"]\n',
     r"\[estimator\]: estimator 'filter-error' has no option 'gust'; its options: .*gusts"),
    ('[estimator]\nprocess_noise = ["w"]\n',
     r"\[estimator\]: estimator 'output-error' has no option 'process_noise'"),
    ('[estimator]\nname = "filter-error"\ngusts = ["w", "w"]\n',
     r"\[estimator\]: gusts must name distinct states"),
    ('[structure]\ntemplate = "longitudinal"\n[estimator]\nname = "filter-error"\n'
     'disturbances = ["u", "v", "q"]\n',
     r"\[estimator\]: disturbances names v, not states of the structure \(u, w, q, theta\)"),
    ('[delays]\nderivatives = ["L_lt"]\n', r"\[delays\] derivatives L_lt are not in the case"),
    ('[delays]\nupper = -0.1\n', r"\[delays\] upper must be a positive time"),
    ('[delays]\nupper = 0.2\ninitial = 0.5\n', r"\[delays\] initial must lie in \[0, upper"),
    ('[delays]\nthreshold = 0\n', r"\[delays\] threshold must be a positive percentage"),
    ('[delays]\nstarts = "four"\n', r"\[delays\] starts must be an integer"),
    ('[delays]\nderivatives = "L_p"\n', r"\[delays\] derivatives must be a list"),
    ('[condition]\nairspeed = 3\n', r"\[condition\].*unknown key"),
    ('[structure]\npopulate = "none"\n[derivatives]\nM_q = { fixed = -1.0 }\n'
     '[delays]\nderivatives = []\n', r"no free derivative to estimate"),
    ('[identification]\nkinds = ["3211"]\n', r"unknown key\(s\) \['identification'\]"),
    ('[verification]\ncoherence = 1.5\n', r"\[verification\].*coherence must be a γ² in "
                                           r"\(0, 1\]"),
    ('[verification]\ncoherence = "high"\n', r"\[verification\]: coherence must be a number"),
    ('[verification]\nomega_min = 12.0\n', r"\[verification\].*0 < omega_min < omega_max"),
    ('[reference]\nM_qq = -3.9\n', r"\[reference\] M_qq are not derivatives of the case's "
                                    r"structure"),
    ('[reference]\nM_q = "-3.9"\n', r"\[reference\] M_q must be a finite number"),
    ('[reference]\nM_q = { value = -3.9, sigma = 1 }\n',
     r"\[reference\] M_q: give a number or a table with value"),
    ('[reference]\nM_q = { value = -3.9, uncertainty = -1 }\n',
     r"\[reference\] M_q.uncertainty must be a positive number"),
    ('channels = { Q_g = { signal = "q", unit = "g" } }\n',
     r"\[data\] channels: column 'Q_g' has unit g, which does not fit 'q' \(rate\); give one "
     r"of"),
    ('channels = { Q1 = { signal = "q", unit = "deg/s" }, Q2 = { signal = "q", unit = "rad/s" } }'
     '\n', r"\[data\] channels: signal 'q' is linked to several columns \(Q1, Q2\)"),
    ('channels = { P = { signal = "p", unit = "deg/s" } }\n[structure]\n'
     'template = "longitudinal"\n[delays]\nderivatives = ["M_q"]\n',
     r"\[data\] channels: column 'P' is linked to 'p', which is not a signal of the case's "
     r"structure \(u, w, q, theta"),
    ('channels = { Time_s = { signal = "time", unit = "deg" } }\n',
     r"\[data\] channels: column 'Time_s' has unit deg, which does not fit 'time' \(time\); "
     r"give one of s, ms"),
    ('[structure]\ntemplate = "longitudinal"\n[delays]\nderivatives = ["M_q"]\n'
     '[verification]\npairs = ["p/lat"]\n',
     r"\[verification\] pairs: unknown response pair 'p/lat'; write OUTPUT/INPUT with OUTPUT "
     r"one of ax, az, q, theta and INPUT one of long, coll"),
])
def test_a_bad_setting_names_the_file_and_the_key(tmp_path, text, message):
    path = case_file(tmp_path, text)
    with pytest.raises(DataFileError, match=message) as caught:
        FlightCase.load(path)
    assert str(caught.value).startswith(str(path)) and "\n" not in str(caught.value)


def test_a_files_case_reads_its_records_through_a_linked_time_column(tmp_path):
    """A range's time column (in ms here) linked in the case's channel map, as in a model
    file's: the case passes its checks and its records read on a time axis in s."""
    time_ms = np.arange(0.0, 2000.0, 20.0)
    columns = {"T_ms": time_ms, "Q_rps": 0.01 * np.sin(time_ms / 300.0),
               **{name: np.zeros_like(time_ms) for name in ("long", "lat", "coll", "ped", "ax",
                                                            "az", "theta", "ay", "p", "phi",
                                                            "r")}}
    np.savetxt(tmp_path / "f.csv", np.column_stack(list(columns.values())), delimiter=",",
               header=",".join(columns), comments="")
    path = case_file(tmp_path, 'channels = { T_ms = { signal = "time", unit = "ms" }, '
                               'Q_rps = { signal = "q", unit = "rad/s" } }\n'
                               '[condition]\nairspeed_kt = 0.0\n')
    case = FlightCase.load(path)
    data, _ = load_data(case, tmp_path / "store")
    record = data.identification[0]
    assert record.time[-1] == pytest.approx(1.98)
    assert np.degrees(0.01) * np.sin(1.98 / 0.3) == pytest.approx(record.channel("q")[-1])


@pytest.mark.parametrize("name", ["../../X", "/tmp/abs", "a/b", "..", ".hidden", ""])
def test_a_case_name_is_never_a_path(tmp_path, name):
    path = tmp_path / "case.toml"
    path.write_text(f'name = "{name}"\n[data]\nsource = "files"\nidentification = "f.csv"\n')
    with pytest.raises(DataFileError, match="cannot name a results directory"):
        FlightCase.load(path)


def test_an_unknown_data_source_is_named_before_anything_runs(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text('name = "own"\n[data]\nsource = "renamed-csv"\n')
    with pytest.raises(DataFileError, match=r"\[data\] source 'renamed-csv' is not "
                                            r"registered.*use one of files, helisim"):
        FlightCase.load(path)


def test_a_study_checks_every_case_before_running_any(tmp_path):
    good = FlightCase(name="good", data=FILES)
    misspelt = FlightCase(name="misspelt", data=FILES, delay_derivatives=("M_lon",))
    with pytest.raises(DataFileError, match=r"case misspelt: \[delays\] derivatives M_lon"):
        Study([good, misspelt], tmp_path / "out")
    with pytest.raises(DataFileError, match=r"case sourceless: \[data\] needs a source"):
        Study([FlightCase(name="sourceless")], tmp_path / "out")
    with pytest.raises(DataFileError, match="case name.* good used twice"):
        Study([good, good], tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_the_builtin_cases_pass_their_checks():
    for name in ("hover", "forward"):
        case = FlightCase.load(name)
        assert case.delay_threshold == 20.0 and case.data_source == "helisim"


def test_run_case_refuses_a_name_that_leaves_the_results_directory(tmp_path):
    escaping = FlightCase(name="../../escaped", data=FILES)
    with pytest.raises(DataFileError, match="cannot name a results directory"):
        run_case(escaping, tmp_path / "a" / "b" / "out")
    assert not any(tmp_path.rglob("escaped*")) and not (tmp_path / "a").exists()


def test_the_verification_band_is_read_from_the_case_file(tmp_path):
    path = case_file(tmp_path, "[verification]\ncoherence = 0.6\nomega_max = 20\n")
    band = FlightCase.load(path).band
    assert (band.coherence, band.omega_min, band.omega_max) == (0.6, 0.1, 20.0)
    assert FlightCase.load(case_file(tmp_path, "")).band == VerificationBand(0.8, 0.1, 10.0)


def test_reference_values_are_read_from_the_case_file(tmp_path):
    path = case_file(tmp_path, '[reference]\nsource = "previous model"\nM_q = -3.9\n'
                               'L_v = { value = -0.41, uncertainty = 0.05, source = "tunnel" }\n')
    assert FlightCase.load(path).reference == {
        "M_q": ReferenceValue(-3.9, None, "previous model"),
        "L_v": ReferenceValue(-0.41, 0.05, "tunnel")}
    assert FlightCase.load(case_file(tmp_path, "")).reference == {}


def test_reference_rows_state_the_units_the_estimate_states():
    """A control of one's own (an aileron in deg) is in the estimate's own unit, as in the
    identified-parameters table; a helicopter derivative without a stated unit keeps its
    flight-test unit."""
    import types

    from rotorid.study.reference import compare_with_reference

    item = types.SimpleNamespace(value=0.3, cramer_rao=0.01)
    estimate = type("Estimate", (), {"units": "si", "parameter_units": {"L_aileron": "rad/s² per deg"},
                              "__contains__": lambda self, name: True,
                              "__getitem__": lambda self, name: item})()
    rows = compare_with_reference(estimate, {"L_aileron": ReferenceValue(0.29),
                                             "M_q": ReferenceValue(-3.9)})
    assert [row.unit for row in rows] == ["rad/s² per deg", "1/s"]
