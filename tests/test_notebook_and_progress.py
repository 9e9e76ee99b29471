"""Notebook use: short reprs and HTML tables; progress through logging; no silent overwrite."""

import json
import logging
from pathlib import Path

import numpy as np
import pytest
import rotorid
from rotorid.cli.main import main
from rotorid.errors import ExitStatus
from rotorid.estimation.estimate import Estimate
from rotorid.executors import run_tasks
from rotorid.notebook import case_result_html, case_result_summary
from rotorid.progress import Countdown, duration_text
from rotorid.study.pipeline import log_progress

TINY = Path(__file__).parent / "cases" / "tiny.toml"


def _maneuver(name="doublet_long", n=501):
    time = np.arange(n) * 0.02
    inputs = np.zeros((n, 4))
    inputs[25:75, 0] = 4.0
    outputs = np.zeros((n, 8))
    outputs[:, 2] = np.linspace(-3.0, 5.0, n)
    return rotorid.Maneuver(name, time, inputs, outputs,
                            metadata={"kind": "doublet", "axis": "long", "signal": {"a": 1}})


def _estimate(n=60):
    names = [f"M_{v}" for v in ("u", "w", "q", "p")] * (n // 4)
    names = [f"{name}{i}" for i, name in enumerate(names)][:n - 1] + ["tau_M_q"]
    return Estimate(estimator="output-error", parameter_names=names,
                    values=np.linspace(-1.0, 1.0, n), start=np.zeros(n),
                    cramer_rao=np.full(n, 0.01), insensitivity=np.full(n, 0.005),
                    correlation=np.eye(n), information=np.eye(n), noise_covariance=np.eye(8),
                    output_names=rotorid.OUTPUTS, cost=1.5e-10, rmse=0.0652,
                    cost_history=[1.0, 0.5], rmse_history=[0.1, 0.0652], iterations=7,
                    converged=True, stop_reason="cost change below tolerance", n_samples=1000)


def test_an_estimate_shows_one_line_and_its_parameter_table():
    estimate = _estimate()
    text = repr(estimate)
    assert text == ("Estimate(output-error, 60 parameters incl. 1 delay, converged after 7 "
                    "iterations, RMSE 0.0652, det R 1.5e-10)")
    page = estimate._repr_html_()
    assert page.count("<tr>") == 61                       # header and one row per parameter
    assert "<td>tau_M_q</td><td>1</td>" in page
    assert "array" not in page and "[" not in page


def test_a_maneuver_and_a_set_show_one_line_and_a_small_table():
    maneuver = _maneuver()
    assert repr(maneuver) == ("Maneuver('doublet_long', 10 s, 501 samples at 50 Hz, "
                              "flight-test units, kind=doublet, axis=long)")
    page = maneuver._repr_html_()
    assert "<td>q</td><td>deg/s</td><td>-3</td><td>5</td>" in page
    assert page.count("<tr>") == 14                       # header, time and 12 channels
    maneuvers = rotorid.ManeuverSet([_maneuver(f"m{i}") for i in range(6)])
    assert repr(maneuvers) == ("ManeuverSet(6 maneuvers: m0, m1, m2, m3, …; 3006 samples, "
                               "zoh hold, flight-test units)")
    assert maneuvers._repr_html_().count("<td>doublet</td>") == 6


def test_a_case_result_shows_its_models(tmp_path):
    from rotorid.study.case import FlightCase
    from rotorid.study.pipeline import Study

    result = Study([FlightCase.load(TINY)], tmp_path, progress=None).run()["tiny"]
    text = repr(result)
    assert text == case_result_summary(result)
    assert text.startswith("CaseResult('tiny', 8 parameters at step 0 of 0; RMSE no delays ")
    assert len(text) < 120
    assert "<td>with delays</td><td>9</td><td>1</td>" in case_result_html(result)


def test_progress_goes_through_the_rotorid_logger(caplog):
    with caplog.at_level(logging.INFO, logger="rotorid"):
        log_progress("hover", "reduction step 3")
        run_tasks(pow, {k: ((k, 2), {}) for k in range(3)}, label=lambda k: f"run {k}")
    messages = [r.getMessage() for r in caplog.records]
    assert messages[0] == "[hover] reduction step 3"
    assert messages[1].startswith("run 0 done [#######             ] 1/3, about ")
    assert messages[3] == "run 2 done [####################] 3/3, about 0 s left"


def fake_clock(*readings):
    """A clock that returns ``readings`` in turn (s)."""
    values = iter(readings)
    return lambda: next(values)


def test_a_countdown_shows_a_bar_and_the_time_left_from_the_mean_step():
    countdown = Countdown(4, clock=fake_clock(100.0, 110.0, 130.0))
    assert countdown.step() == "[#####               ] 1/4, about 30 s left"     # 10 s × 3
    assert countdown.step() == "[##########          ] 2/4, about 30 s left"     # 15 s × 2


def test_a_resumed_reduction_counts_reused_steps_but_times_only_its_own():
    countdown = Countdown(10, done=2, at_most=True, clock=fake_clock(0.0, 20.0))
    assert countdown.step() == ("[######              ] 3 of at most 10, at most about "
                                "2 min left")                                  # 20 s × 7


def test_durations_are_rounded_to_seconds_or_minutes():
    assert [duration_text(s) for s in (0.2, 99.4, 100.0, 3600.0)] == [
        "0 s", "99 s", "2 min", "60 min"]


def test_the_command_shows_progress_on_stderr_and_leaves_logging_as_it_was(tmp_path, capsys):
    logger = logging.getLogger("rotorid")
    handlers, level = list(logger.handlers), logger.level
    (tmp_path / "tiny.toml").write_text(TINY.read_text(encoding="utf-8"), encoding="utf-8")
    assert main(["study", str(tmp_path / "tiny.toml"), "--out", str(tmp_path / "out"),
                 "--no-figures"]) == ExitStatus.OK
    err = capsys.readouterr().err
    assert "[tiny] reduction step 0: full structure" in err
    assert "iter [##                  ] 1 of at most 9, at most about " in err
    assert logger.handlers == handlers and logger.level == level


def test_montecarlo_refuses_to_overwrite_before_any_run(tmp_path, capsys):
    previous = tmp_path / "tiny" / "montecarlo.json"
    previous.parent.mkdir()
    previous.write_text(json.dumps({"runs": 100}), encoding="utf-8")
    assert main(["montecarlo", str(TINY), "--runs", "2", "--out", str(tmp_path)]) == (
        ExitStatus.ERROR)
    assert capsys.readouterr().err.strip() == (
        f"rotorid montecarlo: error: {previous} exists already; give --force to overwrite it")
    assert json.loads(previous.read_text(encoding="utf-8")) == {"runs": 100}
    assert not (tmp_path / "tiny" / "result.json").exists()


def test_identify_refuses_to_overwrite_its_result(tmp_path, capsys):
    out = tmp_path / "result.json"
    out.write_text("{}", encoding="utf-8")
    model = tmp_path / "model.toml"
    model.write_text('units = "flight-test"\n[condition]\nairspeed_kt = 0.0\n'
                     '[structure]\npopulate = "none"\n[derivatives.M_q]\n', encoding="utf-8")
    assert main(["identify", str(model), str(tmp_path / "data"), "--out", str(out)]) == (
        ExitStatus.ERROR)
    assert "give --force to overwrite it" in capsys.readouterr().err
    assert out.read_text(encoding="utf-8") == "{}"


@pytest.mark.parametrize("obj", [_maneuver(), _estimate(8)])
def test_reprs_are_one_short_line(obj):
    assert "\n" not in repr(obj) and len(repr(obj)) < 160
