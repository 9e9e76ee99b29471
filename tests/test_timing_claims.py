"""One timing figure for the quick hover run: README, `rotorid study --help` and docs/index.md
state the same measured number."""

import re
from pathlib import Path

import pytest
from rotorid.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
FIGURE = re.compile(r"about (\d+) s on 2 cores")


def _figures(text: str) -> set[str]:
    return set(FIGURE.findall(" ".join(text.split())))


def test_readme_help_and_docs_state_one_quick_run_time(capsys):
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    before_command = readme[:readme.index("<!-- main-command -->")].strip()
    with pytest.raises(SystemExit):
        main(["study", "--help"])
    index = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    stated = [_figures(before_command.rsplit("\n\n", 1)[-1]),
              _figures(capsys.readouterr().out), _figures(index)]
    assert all(len(figures) == 1 for figures in stated), stated
    assert stated[0] == stated[1] == stated[2]
