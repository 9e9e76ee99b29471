"""Wall time of saving one report figure as PNG and SVG, against a layout per format.

The figure: a case report's time history (``plot_time_histories``: ten panels, two models
beside the measured outputs) of one of ``tests/hover_reference.py``'s 15 s records at 50 Hz.

In the same run, in turns, each on a freshly built figure (building not timed):

* rotorid: ``save_figure``, which keeps the first format's constrained layout for the others;
* baseline: the same two files, each format laid out again (matplotlib's default when a
  constrained-layout figure is saved twice).

Printed: the medians of ``--repeats`` and their ratio. Target: rotorid ≤ 0.9 of the baseline.

    .venv/bin/python benchmarks/bench_figures.py [--repeats 9]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from hover_reference import closed_loop_maneuvers, true_structure  # noqa: E402
from rotorid.io import atomic_write  # noqa: E402
from rotorid.report.plots.case import _save, plot_time_histories, save_figure  # noqa: E402

#: rotorid's time over the baseline's must not exceed this.
TARGET_RATIO = 0.9
FORMATS = ("png", "svg")


def _figure(maneuver):
    simulated = {"no delays": maneuver.outputs * 1.01, "with delays": maneuver.outputs * 0.99}
    return plot_time_histories(maneuver, simulated, title="hover: 3211 input on long")


def _layout_per_format(figure, stem: Path) -> None:
    for fmt in FORMATS:
        atomic_write(Path(f"{stem}.{fmt}"), lambda handle, fmt=fmt: _save(figure, handle, fmt,
                                                                          110))


def _timed(saves, maneuver, directory: Path, repeats: int) -> list[float]:
    """The median time of each of ``saves``, taken in turns (one of each per repeat), so
    that the machine's drift falls on both alike."""
    times = [[] for _ in saves]
    for repeat in range(repeats):
        for save, taken in zip(saves, times):
            figure = _figure(maneuver)
            started = time.perf_counter()
            save(figure, directory / f"figure_{repeat}")
            taken.append(time.perf_counter() - started)
    return [statistics.median(taken) for taken in times]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9)
    args = parser.parse_args(argv)
    structure, values = true_structure()
    maneuver = closed_loop_maneuvers(structure, values)[0]
    with tempfile.TemporaryDirectory() as directory:
        directory = Path(directory)
        _timed([save_figure], maneuver, directory, 1)                    # warm-up
        rotorid, baseline = _timed([save_figure, _layout_per_format], maneuver, directory,
                                   args.repeats)
    ratio = rotorid / baseline
    print(f"load average {os.getloadavg()[0]:.2f}; median of {args.repeats}: rotorid "
          f"{rotorid:.3f} s, layout per format {baseline:.3f} s, ratio {ratio:.2f} "
          f"(target ≤ {TARGET_RATIO}: {'met' if ratio <= TARGET_RATIO else 'missed'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
