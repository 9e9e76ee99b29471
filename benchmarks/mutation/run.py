"""Mutation testing: does the fast suite notice a wrong line in the core?

Every mutant in ``mutants.toml`` names a file, an original text that must occur exactly once
in it, its replacement and what the change breaks. The runner copies the repository's
``framework``, ``plugins``, ``tests``, ``docs`` and ``pyproject.toml`` into a scratch
directory (the working tree is never touched), then for each mutant writes the replacement
into the copy, runs pytest there with ``PYTHONPATH`` pointing at the copy's packages (they take
precedence over the editable install), and restores the file. A mutant is *killed* when the
tests fail (or time out) and *survives* when they pass. Each mutant runs the tests its
``tests`` entry lists (pytest node ids or files), by default the whole fast suite; before the
mutants, the union of the selected tests must pass on the unmutated copy.

    .venv/bin/python benchmarks/mutation/run.py                  # every mutant, its own tests
    .venv/bin/python benchmarks/mutation/run.py zoh-direct-lag   # some mutants by id
    .venv/bin/python benchmarks/mutation/run.py --full-suite     # the whole fast suite each
    .venv/bin/python benchmarks/mutation/run.py --check          # only check the list

Prints one line per mutant (killed/survived/timeout, seconds, the first failing test), the
survivors and the score killed / total. Exit status 0 when every mutant was killed, 1
otherwise, 2 when the list does not match the code or the unmutated tests fail.
"""

from __future__ import annotations

import argparse
import datetime
import os
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MUTANTS = Path(__file__).with_name("mutants.toml")
COPIED = ("framework", "plugins", "tests", "docs", "pyproject.toml")
FULL_SUITE = ("tests",)
FIELDS = {"id", "file", "original", "replacement", "breaks"}


class ListError(Exception):
    """The mutant list does not match the code."""


def load_mutants(path: Path = MUTANTS) -> list[dict]:
    """The mutants of ``path``, each checked against the repository's files."""
    mutants = tomllib.loads(path.read_text(encoding="utf-8"))["mutant"]
    seen = set()
    for mutant in mutants:
        missing = FIELDS - set(mutant)
        if missing:
            raise ListError(f"mutant {mutant.get('id', '?')}: missing {sorted(missing)}")
        if mutant["id"] in seen:
            raise ListError(f"mutant id {mutant['id']} appears twice")
        seen.add(mutant["id"])
        source = ROOT / mutant["file"]
        if not source.is_file():
            raise ListError(f"mutant {mutant['id']}: no file {mutant['file']}")
        count = source.read_text(encoding="utf-8").count(mutant["original"])
        if count != 1:
            raise ListError(f"mutant {mutant['id']}: its original text occurs {count} times in "
                            f"{mutant['file']} (must be once); update mutants.toml")
        if mutant["original"] == mutant["replacement"]:
            raise ListError(f"mutant {mutant['id']}: the replacement equals the original")
    return mutants


def scratch_copy(directory: Path) -> Path:
    """Copy the parts of the repository the tests need into ``directory``."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", ".pytest_cache")
    for name in COPIED:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, directory / name, ignore=ignore)
        else:
            shutil.copy2(source, directory / name)
    return directory


def run_tests(copy: Path, tests, timeout: float) -> tuple[str, float, str]:
    """Run pytest on ``tests`` inside ``copy``: ("passed" | "failed" | "timeout", seconds,
    the first failing test's id or "")."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(copy / "framework"), str(copy / "plugins")]), PYTHONDONTWRITEBYTECODE="1",
               MPLBACKEND="Agg")
    command = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *tests]
    start = time.perf_counter()
    try:
        result = subprocess.run(command, cwd=copy, env=env, capture_output=True, text=True,
                                timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", time.perf_counter() - start, ""
    elapsed = time.perf_counter() - start
    if result.returncode == 0:
        return "passed", elapsed, ""
    if result.returncode == 1:
        failed = [line.split()[1] for line in result.stdout.splitlines()
                  if line.startswith("FAILED ")]
        return "failed", elapsed, failed[0] if failed else ""
    raise ListError(f"pytest could not run {' '.join(tests)} (exit {result.returncode}):\n"
                    f"{result.stdout[-2000:]}{result.stderr[-2000:]}")


def selected_tests(mutant: dict, full_suite: bool) -> tuple[str, ...]:
    return FULL_SUITE if full_suite else tuple(mutant.get("tests", FULL_SUITE))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("ids", nargs="*", help="mutant ids to run (default: all)")
    parser.add_argument("--full-suite", action="store_true",
                        help="run the whole fast suite for every mutant")
    parser.add_argument("--timeout", type=float, default=900.0,
                        help="seconds per test run; a mutant that exceeds it counts as killed")
    parser.add_argument("--check", action="store_true",
                        help="only check that every original text occurs once")
    parser.add_argument("--no-baseline", action="store_true",
                        help="skip running the selected tests on the unmutated copy")
    args = parser.parse_args(argv)
    try:
        mutants = load_mutants()
        unknown = set(args.ids) - {m["id"] for m in mutants}
        if unknown:
            raise ListError(f"unknown mutant id(s) {sorted(unknown)}")
        chosen = [m for m in mutants if not args.ids or m["id"] in args.ids]
        print(f"{len(mutants)} mutants listed, {len(chosen)} chosen")
        if args.check:
            return 0
        with tempfile.TemporaryDirectory(prefix="rotorid-mutation-") as scratch:
            copy = scratch_copy(Path(scratch))
            if not args.no_baseline:
                union = sorted({t for m in chosen for t in selected_tests(m, args.full_suite)})
                outcome, seconds, _ = run_tests(copy, union, args.timeout)
                print(f"baseline (unmutated): {outcome} in {seconds:.0f} s")
                if outcome != "passed":
                    raise ListError("the selected tests do not pass on the unmutated code")
            results = []
            for mutant in chosen:
                target = copy / mutant["file"]
                original = target.read_text(encoding="utf-8")
                target.write_text(original.replace(mutant["original"], mutant["replacement"]),
                                  encoding="utf-8")
                try:
                    outcome, seconds, failed = run_tests(
                        copy, selected_tests(mutant, args.full_suite), args.timeout)
                finally:
                    target.write_text(original, encoding="utf-8")
                status = "survived" if outcome == "passed" else (
                    "killed" if outcome == "failed" else "killed (timeout)")
                results.append((mutant, status))
                print(f"{mutant['id']:<36} {status:<17} {seconds:6.1f} s  {failed}", flush=True)
    except ListError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    survivors = [m for m, status in results if status == "survived"]
    killed = len(results) - len(survivors)
    for mutant in survivors:
        print(f"survived: {mutant['id']} ({mutant['file']}): {mutant['breaks']}")
    print(f"score {killed}/{len(results)} = {100.0 * killed / max(len(results), 1):.1f} % "
          f"on {datetime.date.today().isoformat()}")
    return 0 if not survivors else 1


if __name__ == "__main__":
    sys.exit(main())
