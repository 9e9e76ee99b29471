"""The ``rotorid`` command: version, plugin listing and one-line errors."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import rotorid
from rotorid.cli import main as cli
from rotorid.cli.commands import plugins as plugins_command
from rotorid.errors import DataFileError, ExitStatus, UsageError

SCRIPT = shutil.which("rotorid", path=str(Path(sys.executable).parent))


def run(*arguments):
    return subprocess.run([SCRIPT, *arguments], capture_output=True, text=True, timeout=120)


def test_the_console_script_is_installed_next_to_python():
    assert SCRIPT is not None, "the rotorid console script is missing; pip install -e ."


def test_version():
    result = run("--version")
    assert result.returncode == 0
    assert result.stdout.strip() == f"rotorid {rotorid.__version__}"
    assert rotorid.__version__ != "0.0.0+unknown"


def test_plugins_lists_every_family_and_the_built_in_files_source():
    result = run("plugins")
    assert result.returncode == 0, result.stderr
    for family in ("estimators:", "reduction-criteria:", "validation-envelopes:",
                   "data-sources:", "input-signals:"):
        assert family in result.stdout.splitlines()
    line = next(l for l in result.stdout.splitlines() if l.strip().startswith("files "))
    assert "CSV" in line and line.endswith("[files]")


def test_plugins_of_one_family():
    result = run("plugins", "--family", "data-sources")
    assert result.returncode == 0
    assert result.stdout.splitlines()[0] == "data-sources:"
    assert "estimators:" not in result.stdout


def test_a_rotorid_error_is_one_line_on_stderr():
    result = run("plugins", "--family", "estimator")
    assert result.returncode == ExitStatus.ERROR == 3
    assert result.stdout == ""
    assert result.stderr.splitlines() == [
        "rotorid plugins: error: unknown plugin family 'estimator'; families: estimators, "
        "reduction-criteria, validation-envelopes, data-sources, input-signals, commands"]


def test_usage_errors_exit_non_zero_without_traceback():
    result = run("no-such-command")
    assert result.returncode == ExitStatus.USAGE == 2
    assert "invalid choice: 'no-such-command'" in result.stderr
    assert "Traceback" not in result.stderr


def test_no_command_prints_help_and_fails(capsys):
    assert cli.main([]) == ExitStatus.USAGE
    assert "usage: rotorid" in capsys.readouterr().out


@pytest.mark.parametrize("error, status", [
    (DataFileError("data/x.csv, line 7 (row 5), channel 'q': 'abc' is not a number"),
     ExitStatus.ERROR),
    (FileNotFoundError(2, "No such file or directory", "results/x"), ExitStatus.ERROR),
    (UsageError("--max-iterations must be at least 1, got 0"), ExitStatus.USAGE),
    (KeyboardInterrupt(), ExitStatus.INTERRUPTED),
])
def test_errors_inside_a_command_become_one_line(monkeypatch, capsys, error, status):
    def failing(args):
        raise error

    monkeypatch.setattr(plugins_command, "run", failing)
    assert cli.main(["plugins"]) == status
    captured = capsys.readouterr()
    assert len(captured.err.splitlines()) == 1
    assert captured.err.startswith("rotorid plugins: ")
