"""A plugin package written from docs/plugins.md alone runs through the whole command line.

``tests/thirdparty/rotorid_example_plugin`` provides a data source, an envelope of each kind
(bounds and cost), a reduction criterion and an estimator. It is "installed" for these tests
the way pip leaves a package: a ``*.dist-info`` folder with an ``entry_points.txt`` on the
path, so that ``importlib.metadata`` finds its entry point; the command-line runs get the
same ``PYTHONPATH``.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import rotorid
from rotorid.plugin.manager import using
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import Study

THIRDPARTY = Path(__file__).parent / "thirdparty"
ENVELOPES = ("example-flat", "example-gain-cost")
CASE = """
name = "example"

[data]
source = "example-simulated"
seed = 3

[verification]
pairs = ["q/long", "p/lat"]
envelopes = ["example-flat", "example-gain-cost"]

[structure]
populate = "none"

[derivatives]
M_q = {}
M_long = {}
L_p = {}
L_lat = {}
M_lat = {}
L_long = {}

[estimator]
name = "example-output-error"
horizons = []

[reduction]
criteria = [{ name = "example-largest-bound", threshold = 25.0 }]
continue_to_zero = false

[delays]
derivatives = ["L_lat"]
"""
#: The identified model: the derivatives of the example source's truth, at hover.
MODEL = """
units = "flight-test"
condition = { airspeed_kt = 0.0 }
structure = { populate = "none" }
derivatives = { M_q = {}, M_long = {}, L_p = {}, L_lat = {} }
"""


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """A folder holding the package's dist-info, as an installation would leave it."""
    site = tmp_path_factory.mktemp("site")
    info = site / "rotorid_example_plugin-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: rotorid-example-plugin\n"
                                   "Version: 0.1\n", encoding="utf-8")
    (info / "entry_points.txt").write_text("[rotorid]\nexample = rotorid_example_plugin.plugin\n",
                                           encoding="utf-8")
    return site


def rotorid_cli(site: Path, *arguments: str) -> subprocess.CompletedProcess:
    """``rotorid ARGUMENTS`` in a fresh interpreter with the package installed."""
    path = os.pathsep.join([str(site), str(THIRDPARTY), os.environ.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, "-m", "rotorid.cli.main", *arguments],
                          capture_output=True, text=True, env={**os.environ, "PYTHONPATH": path})


def test_the_plugins_are_listed_with_their_provider(site):
    listing = rotorid_cli(site, "plugins")
    assert listing.returncode == 0, listing.stderr
    for name in ("example-simulated", *ENVELOPES, "example-largest-bound",
                 "example-output-error"):
        line = next(line for line in listing.stdout.splitlines() if name in line)
        assert "example" in line.split(name, 1)[1], line     # [example], the plugin name


def test_rotorid_study_runs_a_case_made_of_third_party_components(site, tmp_path):
    case = tmp_path / "example.toml"
    case.write_text(CASE, encoding="utf-8")
    run = rotorid_cli(site, "study", str(case), "--out", str(tmp_path / "out"), "--no-figures")
    assert run.returncode == 0, run.stderr
    result = json.loads((tmp_path / "out" / "example" / "result.json").read_text())
    assert {e["estimator"] for e in result["estimates"].values()} == {"example-output-error"}
    removals = [s for s in result["reduction"]["steps"] if s["removed"] is not None]
    assert {s["removed"] for s in removals} == {"M_lat", "L_long"}
    assert {s["criterion"] for s in removals} == {"example-largest-bound"}
    checks = [check for model in result["frequency_verification"].values()
              for pair in model["pairs"] for check in pair["checks"].values()]
    assert {c["envelope"] for c in checks} == set(ENVELOPES)
    assert all(c["cost"] is not None for c in checks if c["envelope"] == "example-gain-cost")
    assert all(c["passed"] for c in checks), checks


@pytest.fixture(scope="module")
def files(site, tmp_path_factory) -> Path:
    """The example source's maneuvers written as CSV files, and a model file."""
    from rotorid_files.formats import write_maneuver

    sys.path.insert(0, str(THIRDPARTY))
    try:
        from rotorid_example_plugin.components import SimulatedSource
    finally:
        sys.path.remove(str(THIRDPARTY))
    root = tmp_path_factory.mktemp("files")
    data = SimulatedSource().case_data({"seed": 5}, root)
    for maneuver in (*data.identification, *data.verification):
        write_maneuver(maneuver, root / f"{maneuver.name}.csv")
    (root / "model.toml").write_text(MODEL, encoding="utf-8")
    return root


def test_rotorid_identify_and_verify_use_the_third_party_components(site, files):
    estimate = files / "estimate.json"
    identify = rotorid_cli(site, "identify", str(files / "model.toml"),
                           str(files / "doublet_*.csv"), "--estimator", "example-output-error",
                           "--out", str(estimate))
    assert identify.returncode == 0, identify.stderr
    assert "iteration" in identify.stderr                 # progress through the hook
    record = json.loads(estimate.read_text())
    assert record["estimator"] == "example-output-error"
    assert record["parameters"]["L_p"]["value"] == pytest.approx(-6.0, rel=0.05)
    verify = rotorid_cli(site, "verify", str(estimate), str(files / "chirp_*.csv"),
                         "--pairs", "q/long,p/lat", "--envelopes", ",".join(ENVELOPES),
                         "--out", str(files / "verify"), "--no-figures")
    assert verify.returncode == 0, verify.stderr
    summary = json.loads((files / "verify" / "verification.json").read_text())
    checks = [check for pair in summary["pairs"] for check in pair["checks"].values()]
    assert sorted({c["envelope"] for c in checks}) == sorted(ENVELOPES)
    assert all(c["passed"] for c in checks), checks


def test_a_study_takes_its_plugins_from_the_manager_it_is_given(site, files, tmp_path,
                                                                monkeypatch):
    """In process: a manager built after installation has the plugin (the process-wide one,
    built earlier, need not); the study reports to that manager's observers."""
    monkeypatch.syspath_prepend(str(THIRDPARTY))
    monkeypatch.syspath_prepend(str(site))
    seen = []

    class Observer:
        @rotorid.hookimpl
        def rotorid_case_finished(self, case, result):
            seen.append((case.name, result.estimates["with delays"].estimator))

    manager = rotorid.new_plugin_manager()
    rotorid.register_plugin(Observer(), manager)
    case_file = tmp_path / "example.toml"
    case_file.write_text(CASE.replace("L_long = {}", ""), encoding="utf-8")
    with using(manager):
        case = FlightCase.load(case_file)
    Study([case], tmp_path / "out", progress=None, manager=manager).run()
    assert seen == [("example", "example-output-error")]


def test_a_case_whose_condition_is_not_the_sources_trim_is_refused(site, tmp_path,
                                                                   monkeypatch):
    """The example source gives its trim (hover); a case stating 80 kt as well is refused with
    both trims and the fix, where one stating the same hover trim runs on."""
    import tomllib

    from rotorid.errors import DataError
    from rotorid.study.pipeline import load_data

    monkeypatch.syspath_prepend(str(THIRDPARTY))
    monkeypatch.syspath_prepend(str(site))
    table = tomllib.loads(CASE)
    with using(rotorid.new_plugin_manager()):
        stated = FlightCase.from_mapping({**table, "condition": {
            "airspeed_kt": 80.0, "theta0_deg": 5.0}}, "example.toml")
        with pytest.raises(DataError, match=r"\[condition\] \(80.0 kt, Θ0 = 5.00°.*is not "
                                            r"the trim.*\(0.0 kt.*remove the \[condition\]"):
            load_data(stated, tmp_path)
        same = FlightCase.from_mapping({**table, "condition": {"airspeed_kt": 0.0}},
                                       "example.toml")
        assert load_data(same, tmp_path)[1].airspeed_kt == 0.0


def test_an_entry_point_that_cannot_be_imported_is_named_in_one_line(site, tmp_path):
    """A broken installed plugin (its module missing): every command says which entry point
    and distribution fail, in one line without a traceback, and exits with 3."""
    broken = tmp_path / "broken"
    info = broken / "acme_broken-1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: acme-broken\nVersion: 1.0\n",
                                   encoding="utf-8")
    (info / "entry_points.txt").write_text("[rotorid]\nbroken = acme_missing.plugin\n",
                                           encoding="utf-8")
    run = rotorid_cli(broken, "plugins")
    assert run.returncode == 3
    assert run.stderr.strip() == (
        "rotorid: error: plugin 'broken' (acme_missing.plugin, from acme-broken) cannot be "
        "imported: ModuleNotFoundError: No module named 'acme_missing'; fix it or uninstall "
        "it (pip uninstall acme-broken)")


def test_a_bug_in_a_case_names_where_it_was_raised(tmp_path, monkeypatch, capsys):
    """An error rotorid does not raise on purpose fails the case with the file, line and
    function it came from; ROTORID_TRACEBACK=1 prints the traceback as well."""
    from rotorid.errors import StudyError
    from rotorid.study import pipeline

    def broken(*args, **kwargs):
        raise ValueError("a plugin's bug")

    monkeypatch.setattr(pipeline, "run_case", broken)
    case = FlightCase.load("hover")
    with pytest.raises(StudyError, match=r"ValueError: a plugin's bug \(raised in .*"
                                         r"test_thirdparty_plugin.py:\d+, broken; "
                                         r"ROTORID_TRACEBACK=1 prints the traceback\)"):
        pipeline.run_case_task(case, progress=None, out_dir=tmp_path)
    assert "Traceback" not in capsys.readouterr().err
    monkeypatch.setenv("ROTORID_TRACEBACK", "1")
    with pytest.raises(StudyError):
        pipeline.run_case_task(case, progress=None, out_dir=tmp_path)
    assert "Traceback" in capsys.readouterr().err
