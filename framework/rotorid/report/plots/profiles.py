"""Delay profiles (:mod:`rotorid.estimation.profiles`) as one figure.

:func:`plot_delay_profiles`: for each delay, the RMSE with the delay fixed on its grid and
everything else refitted, relative to the free fit's RMSE (%), with the free fit's delay
marked; refits that did not converge are crosses, not joined to the line. A deep, narrow
curve is a delay the data determine; a flat one is not. The y-axis is
linear within ±1 % and logarithmic beyond, so shallow profiles of a few tenths of a percent
and steep ones of tens of percent both read.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rotorid.estimation.profiles import DelayProfile


def plot_delay_profiles(profiles: Sequence[DelayProfile], title: str = "Delay profiles"):
    """One line per delay: RMSE increase over the free fit (%) against the fixed delay (s);
    the free fit's delay as a marker at 0 %. Legend outside the axes."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import FuncFormatter

    figure = Figure(figsize=(8.0, 4.2), layout="constrained")
    axis = figure.subplots()
    for index, profile in enumerate(profiles):
        color = f"C{index % 10}"
        percent = 100.0 * profile.relative_rmse
        axis.plot(profile.grid, np.where(profile.converged, percent, np.nan), "o-",
                  color=color, markersize=3.5,
                  label=f"{profile.delay} (free {profile.free_value:.3f} s)")
        axis.plot([profile.free_value], [0.0], "*", color=color, markersize=10)
        failed = ~profile.converged
        if failed.any():
            axis.plot(profile.grid[failed], percent[failed], "x", color=color, markersize=6)
    if any((~p.converged).any() for p in profiles):
        axis.plot([], [], "x", color="0.3", label="refit did not converge (not joined)")
    axis.set_yscale("symlog", linthresh=1.0)
    axis.yaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.axhspan(-1.0, 1.0, color="0.94", zorder=0)
    axis.set_xlabel("delay fixed at [s]")
    axis.set_ylabel("RMSE above the free fit [%] (linear within ±1 %, shaded)")
    axis.set_title(title)
    axis.grid(True, alpha=0.3)
    if profiles:
        axis.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    return figure
