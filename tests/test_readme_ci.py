"""README commands, the CI script that runs them, and the README's API example."""

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
CI = ROOT / ".ci" / "run"


def block(marker: str) -> str:
    """The fenced block between ``<!-- marker -->`` and ``<!-- /marker -->`` in README.md."""
    match = re.search(rf"^<!-- {marker} -->\n```\w*\n(.*?)\n```\n<!-- /{marker} -->$", README,
                      flags=re.MULTILINE | re.DOTALL)
    assert match, f"README.md has no fenced block between <!-- {marker} --> markers"
    return match[1]


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
    assert test.endswith("&& .venv/bin/python -m pytest -q") and "'.[test]'" in test
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
