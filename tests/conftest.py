"""Session fixtures shared by the test modules: the truth model's trims and linearisations, and
one quick run of the built-in study that every test of a quick study result reads.

The Padfield hover matrices live once, in ``rotorid_helisim.linear_plant`` (``HOVER_A``,
``HOVER_B``); tests import them from there.
"""

from __future__ import annotations

import contextlib
import fcntl
import io
import json
import os
from pathlib import Path

import attrs
import pytest
from rotorid.cli.main import main
from rotorid_helisim.linearize import linearize
from rotorid_helisim.model import Bo105Model
from rotorid_helisim.trim import trim


@pytest.fixture(scope="session")
def truth_model():
    """The nonlinear Bo-105 truth model with its default configuration."""
    return Bo105Model()


@pytest.fixture(scope="session")
def hover_trim(truth_model):
    """The truth model trimmed in hover."""
    return trim(truth_model, 0.0)


@pytest.fixture(scope="session")
def trim_70kt(truth_model):
    """The truth model trimmed in level flight at 70 kt."""
    return trim(truth_model, 70.0)


@pytest.fixture(scope="session")
def hover_linear(truth_model, hover_trim):
    """Residualised 6-DoF linearisation in hover, SI units."""
    return linearize(truth_model, hover_trim)


@pytest.fixture(scope="session")
def linear_70kt(truth_model, trim_70kt):
    """Residualised 6-DoF linearisation at 70 kt, SI units."""
    return linearize(truth_model, trim_70kt)


@attrs.frozen
class QuickStudy:
    """One ``rotorid study all --quick`` run: its exit status, what it printed on stdout, and
    its results directory (``out/hover``, ``out/forward``, ``out/report.html``)."""

    status: int
    printed: str
    out: Path


@pytest.fixture(scope="session")
def quick_study(tmp_path_factory) -> QuickStudy:
    """The README's main command for both built-in cases, run once per test session (about
    40 s of each core). Tests read its files and must not write into ``out``; a test that runs
    on from these results copies the case directory first.

    Under pytest-xdist (``-n``) the workers share one run: the first to need it runs it while
    holding a lock in the session's common temporary directory, the others wait for it and
    read its status and printed text from ``run.json``."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent                       # the directory every worker's temp lies in
    shared = root / "quick-study"
    record = shared / "run.json"
    shared.mkdir(exist_ok=True)
    with open(root / "quick-study.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not record.exists():
            printed = io.StringIO()
            with contextlib.redirect_stdout(printed):
                status = main(["study", "all", "--quick", "--out", str(shared / "results")])
            record.write_text(json.dumps({"status": status, "printed": printed.getvalue()}))
        run = json.loads(record.read_text())
    return QuickStudy(run["status"], run["printed"], shared / "results")
