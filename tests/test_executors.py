"""Studies through executors: the same numbers serially, in a process pool and on a Dask
cluster; failures named with their case and step; speed sweeps; executor errors."""

import json
from pathlib import Path

import attrs
import numpy as np
import pytest
from rotorid import Derivative, ModelStructure
from rotorid.cli.main import main
from rotorid.errors import DataError, ExitStatus, PluginError, StudyError
from rotorid.executors import connect_dask, open_executor
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import Study
from rotorid.study.result import MODELS
from rotorid.study.sweep import case_name, parse_speeds, speed_sweep
from test_output_error import doublet_maneuvers, with_outputs
from test_reduction_study import HOVER, TRUE, files_case

TINY = Path(__file__).parent / "cases" / "tiny.toml"


def tiny_sweep():
    """Two small generated cases: the tiny case at 0 and 60 kt."""
    return speed_sweep([0, 60], FlightCase.load(TINY))


def run_study(out, executor=None, cases=None):
    return Study(cases or tiny_sweep(), out, executor=executor,
                 progress=None).run()


def numbers(results) -> dict:
    """Every estimated number of a study's results, by case, model and reduction step."""
    table = {}
    for name, result in results.items():
        for label in MODELS:
            estimate = result.estimates[label]
            table[name, label] = (estimate.parameter_names, estimate.values,
                                  estimate.cramer_rao, estimate.noise_covariance,
                                  result.time_metrics[label].rmse)
        for step in result.path.steps:
            table[name, step.index] = (step.structure.names, step.estimate.values)
        table[name, "truth"] = tuple(sorted(result.truth_derivatives.items()))
    return table


def assert_identical(first, second):
    a, b = numbers(first), numbers(second)
    assert list(a) == list(b)
    for key in a:
        for x, y in zip(a[key], b[key]):
            assert np.array_equal(np.asarray(x), np.asarray(y)), key


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    return run_study(tmp_path_factory.mktemp("serial"))


def test_process_pool_gives_the_serial_numbers_bit_for_bit(serial, tmp_path):
    pooled = run_study(tmp_path, executor="process")
    assert_identical(serial, pooled)
    assert set(pooled) == {"speed-000kt", "speed-060kt"}
    assert pooled["speed-060kt"].condition.airspeed_kt == pytest.approx(60.0)


def test_dask_local_cluster_gives_the_serial_numbers_bit_for_bit(serial, tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        results = run_study(tmp_path / "api", executor=client.get_executor())
        # The command line connects its own client to the scheduler's address.
        status = main(["study", "speed-sweep", "--template", str(TINY), "--speeds", "0,60",
                       "--executor", "dask", "--scheduler", cluster.scheduler_address,
                       "--no-figures", "--out", str(tmp_path / "cli")])
    assert_identical(serial, results)
    assert (tmp_path / "api" / "speed-060kt" / "result.json").is_file()
    assert status == 0
    points = json.loads((tmp_path / "cli" / "speed-sweep.json").read_text())["points"]
    for point in points:
        assert point["values"] == serial[point["case"]].estimates["with delays"].as_mapping()


def fail_at_second_step(case, message):
    if case == "bad" and message.startswith("reduction step 1"):
        raise RuntimeError("simulated failure")


def test_a_failed_case_is_named_with_its_step_and_the_finished_cases_are_kept(tmp_path):
    structure = ModelStructure(HOVER, [Derivative(n) for n in TRUE])
    data = with_outputs(structure, structure.as_vector(TRUE), doublet_maneuvers(n=300),
                        noise=0.05, seed=2)
    good = files_case(tmp_path, data)
    bad = attrs.evolve(good, name="bad")
    missing = attrs.evolve(good, name="missing", data={
        "source": "files", "identification": str(tmp_path / "nowhere")})
    with pytest.raises(StudyError) as caught:
        Study([good, bad], tmp_path / "out", progress=fail_at_second_step).run()
    error = caught.value
    assert list(error.results) == ["own"] and list(error.failures) == ["bad"]
    assert "case bad failed after “reduction step 1" in str(error)
    assert "RuntimeError: simulated failure" in str(error)
    assert (tmp_path / "out" / "own" / "result.json").is_file()

    with pytest.raises(StudyError) as caught:
        Study([good, missing], tmp_path / "pool", executor="process",
              progress=None).run()
    assert list(caught.value.results) == ["own"]
    assert "case missing failed after “data: files" in caught.value.failures["missing"]


def test_executor_choices_are_checked_and_named(tmp_path):
    with pytest.raises(PluginError, match="get_executor"):
        Study(["hover"], tmp_path, executor="dask")
    with pytest.raises(PluginError, match="needs --scheduler"):
        with open_executor("dask"):
            pass
    with pytest.raises(PluginError, match="only applies to --executor dask"):
        with open_executor("process", "tcp://127.0.0.1:8786"):
            pass
    with open_executor("serial") as executor:
        assert executor is None


def test_an_unreachable_scheduler_is_reported():
    pytest.importorskip("dask.distributed")
    with pytest.raises(PluginError, match="cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'"):
        connect_dask("tcp://127.0.0.1:9", timeout=1.0)
    assert main(["study", "hover", "--out", "unused", "--executor", "dask"]) == ExitStatus.ERROR


def test_speed_lists_and_case_names():
    assert parse_speeds("0:120:10") == tuple(float(v) for v in range(0, 121, 10))
    assert parse_speeds("80, 0,40,40") == (0.0, 40.0, 80.0)
    assert parse_speeds("0:1:0.5") == (0.0, 0.5, 1.0)
    for bad in ("0-120", "0:120", "10:0:5", "0:10:0", "", "fast"):
        with pytest.raises(DataError, match="comma list"):
            parse_speeds(bad)
    with pytest.raises(DataError, match="0–200 kt"):
        parse_speeds("0,250")
    assert case_name(70) == "speed-070kt" and case_name(12.5) == "speed-012.5kt"
    cases = speed_sweep("0,70")
    assert [c.name for c in cases] == ["speed-000kt", "speed-070kt"]
    assert cases[1].data["airspeed_kt"] == 70.0 and cases[1].data["condition"] == "speed-070kt"
    assert cases[1].structure == FlightCase.load("hover").structure


def test_a_speed_sweep_needs_generated_data(tmp_path):
    template = FlightCase(name="flight", data={"source": "files", "identification": "x"})
    with pytest.raises(DataError, match="needs generated data flown at"):
        speed_sweep([0, 10], template)
    assert main(["study", "hover", "--speeds", "0,10", "--out", str(tmp_path)]) == ExitStatus.USAGE


def test_speed_sweep_command_writes_the_summary(tmp_path, capsys):
    out = tmp_path / "sweep"
    status = main(["study", "speed-sweep", "--template", str(TINY), "--speeds", "0,60",
                   "--executor", "serial", "--no-figures", "--out", str(out)])
    assert status == 0, capsys.readouterr().err
    record = json.loads((out / "speed-sweep.json").read_text())
    points = record["points"]
    assert [p["airspeed_kt"] for p in points] == [0.0, 60.0]
    assert set(points[1]["values"]) >= {"M_q", "L_p", "tau_M_long"}
    assert points[1]["truth"]["M_q"] < 0 and points[1]["cramer_rao"]["M_q"] > 0
    assert (out / "speed-sweep.png").stat().st_size > 0 and (out / "speed-sweep.svg").is_file()


def test_montecarlo_command_repeats_the_final_estimation(tmp_path, capsys):
    out = tmp_path / "mc"
    status = main(["montecarlo", str(TINY), "--runs", "3", "--executor", "serial",
                   "--out", str(out)])
    assert status == 0, capsys.readouterr().err
    record = json.loads((out / "tiny" / "montecarlo.json").read_text())
    study = json.loads((out / "tiny" / "result.json").read_text())
    final = study["estimates"]["with delays"]
    assert record["seeds"] == [0, 1, 2] and record["parameter_names"] == final["parameter_names"]
    # Run 0 uses the case's own seed: regenerated data and the same start give the study's
    # final estimate exactly.
    assert record["estimates"][0] == [final["parameters"].get(n, final["delays"].get(
        n[4:], {})).get("value") for n in final["parameter_names"]]
    assert record["estimates"][1] != record["estimates"][0]
    assert "std/CR" in capsys.readouterr().out
    assert (out / "tiny" / "montecarlo.png").is_file()


def test_sweep_figure_marks_removed_derivatives_and_round_trips(tmp_path):
    from rotorid.report.plots.sweep import plot_speed_sweep
    from rotorid.study.sweep import SweepPoint, load_sweep_summary, write_sweep_summary

    points = [SweepPoint("speed-000kt", 0.0, {"M_q": -2.4, "tau_M_q": 0.15},
                         {"M_q": 0.01, "tau_M_q": float("inf")}, {"M_q": -3.5}),
              SweepPoint("speed-060kt", 60.0, {"tau_M_q": 0.17}, {"tau_M_q": 0.002},
                         {"M_q": -3.7})]
    figure = plot_speed_sweep(points, derivatives=["M_q"], delays=["M_q"], bound=2.0)
    visible = [axis for axis in figure.axes if axis.get_visible()]
    assert [axis.get_title() for axis in visible] == ["M_q", "τ M_q (s)"]
    labels = [line.get_label() for line in visible[0].get_lines()]
    assert "truth linearisation" in labels and "removed / dropped" in labels
    write_sweep_summary(points, tmp_path)
    again = load_sweep_summary(tmp_path / "speed-sweep.json")
    assert again == points
