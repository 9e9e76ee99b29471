"""README commands, the CI script that runs them, and the examples of README and docs/."""

import re
import shutil
import subprocess
import tomllib
import types
from pathlib import Path

import numpy as np
import pytest
from rotorid.model.modelfile import parse_model
from rotorid.plugin.manager import create, new_plugin_manager
from rotorid_files.formats import read_maneuver

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
CI = ROOT / ".ci" / "run"


def block(marker: str, text: str = README) -> str:
    """The fenced block between ``<!-- marker -->`` and ``<!-- /marker -->`` in ``text``."""
    match = re.search(rf"^<!-- {marker} -->\n```\w*\n(.*?)\n```\n<!-- /{marker} -->$", text,
                      flags=re.MULTILINE | re.DOTALL)
    assert match, f"no fenced block between <!-- {marker} --> markers"
    return match[1]


def fenced(path: Path, language: str) -> list[str]:
    """Every fenced ``language`` block of a Markdown file."""
    return re.findall(rf"^```{language}\n(.*?)^```$", path.read_text(),
                      flags=re.MULTILINE | re.DOTALL)


def ci(*arguments, cwd=ROOT):
    return subprocess.run(["bash", str(cwd / ".ci" / "run"), *arguments], capture_output=True,
                          text=True, timeout=60)


def test_ci_runs_exactly_the_readme_test_command():
    result = ci("--print")
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == block("test-command")


def test_readme_commands_install_into_a_fresh_venv_and_run():
    test, main = block("test-command"), block("main-command")
    for command in (test, main):
        assert "\n" not in command
        assert command.startswith("python3 -m venv .venv && .venv/bin/pip install -q -e ")
    assert test.endswith("&& .venv/bin/python -m pytest -q -n auto") and "'.[test]'" in test
    assert main.endswith("&& .venv/bin/rotorid study hover --quick --out results")


def test_ci_script_is_strict_bash():
    lines = CI.read_text().splitlines()
    assert lines[0] == "#!/usr/bin/env bash"
    assert "set -euo pipefail" in lines


@pytest.fixture
def copy_of_project(tmp_path):
    (tmp_path / ".ci").mkdir()
    shutil.copy(CI, tmp_path / ".ci" / "run")
    shutil.copy(ROOT / "README.md", tmp_path / "README.md")
    return tmp_path


def test_ci_refuses_a_venv_that_is_not_fresh(copy_of_project):
    (copy_of_project / ".venv").mkdir()
    result = ci(cwd=copy_of_project)
    assert result.returncode == 2
    assert ".venv already exists" in result.stderr and "fresh clone" in result.stderr


def test_ci_fails_without_the_markers(copy_of_project):
    (copy_of_project / "README.md").write_text("# rotorid\n")
    result = ci("--print", cwd=copy_of_project)
    assert result.returncode == 2
    assert "exactly one command line between <!-- test-command -->" in result.stderr


def test_readme_api_example_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(block("api-example"), "README.md", "exec"), namespace)
    assert (tmp_path / "hover.toml").is_file()
    assert "('tau_L_lat', 'tau_M_long')" in capsys.readouterr().out
    assert type(namespace["files"]).__name__ == "FileSource"


def test_readme_links_exist():
    for link in re.findall(r"\]\(([^)#]+)\)", README):
        if "://" not in link:
            assert (ROOT / link).is_file(), f"README.md links to missing {link}"


def test_plugin_guide_example_registers_and_builds_its_signal():
    module = types.ModuleType("rotorid_chirp_example")
    exec(compile(block("plugin-example", (ROOT / "docs" / "plugins.md").read_text()),
                 "docs/plugins.md", "exec"), module.__dict__)
    manager = new_plugin_manager([module], load_entry_points=False)
    chirp = create("input-signals", "linear-chirp", manager, amplitude=2.0, duration=10.0)
    time = np.array([-1.0, 0.0, 1.25, 11.0])
    expected_phase = 2 * np.pi * (0.1 * 1.25 + 1.9 * 1.25**2 / 20.0)
    np.testing.assert_allclose(chirp(time), [0.0, 0.0, 2.0 * np.sin(expected_phase), 0.0])
    assert chirp.duration == 10.0


def test_conventions_csv_example_reads(tmp_path):
    (example,) = [b for b in fenced(ROOT / "docs" / "conventions.md", "") if b.startswith("# name")]
    path = tmp_path / "example.csv"
    path.write_text(example)
    maneuver = read_maneuver(path)
    assert maneuver.metadata == {"condition": "hover", "kind": "3211", "axis": "long",
                                 "direction": 1}
    assert maneuver.n_samples == 2 and maneuver.channel("q")[1] == 0.3


def test_conventions_model_file_examples_parse():
    template, declared = [b for b in fenced(ROOT / "docs" / "conventions.md", "toml")
                          if b.startswith("units")]
    structure = parse_model(tomllib.loads(template), "docs/conventions.md")
    assert len(structure.names) == 58 and structure.derivative("M_w").fixed
    aeroplane = parse_model(tomllib.loads(declared + '[derivatives.M_elevator]\n'),
                            "docs/conventions.md")
    assert aeroplane.outputs == ("V", "alpha", "q", "theta", "q_dot", "ax", "az")
    assert aeroplane.names == ("M_elevator",)
