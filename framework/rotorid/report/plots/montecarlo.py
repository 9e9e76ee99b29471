"""Figure of a Monte Carlo check of the Cramér-Rao bounds (matplotlib; safe under Agg).

:func:`plot_monte_carlo` draws per parameter, top: the sample standard deviation over the
mean Cramér-Rao bound (1 for honest bounds, with the band a sample of N honest runs stays in
about 95 % of the time; on a log scale when a ratio lies beyond :data:`LOG_SCALE_ABOVE`);
bottom: the coverage of the ±2·CR interval around the sample mean (filled) and around the
truth where known (open), against the nominal 95.4 % and its binomial band. Returns the
:class:`matplotlib.figure.Figure`.
"""

from __future__ import annotations

import numpy as np

from rotorid.model.derivatives import parameter_label
from rotorid.study.montecarlo import NOMINAL_COVERAGE, MonteCarloResult

#: The std/CR axis turns logarithmic when a ratio lies beyond this factor of 1 either way.
LOG_SCALE_ABOVE = 5.0
#: The lowest ratio the log axis shows; smaller ones are marked at its edge.
LOG_SCALE_FLOOR = 0.05


def plot_monte_carlo(result: MonteCarloResult, title: str | None = None):
    """std/CR ratio and ±2·CR coverage per parameter of ``result``."""
    from matplotlib.figure import Figure

    names = result.parameter_names
    x = np.arange(len(names))
    figure = Figure(figsize=(max(7.0, 0.2 * len(names) + 2.5), 6.0), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True)
    ratio = result.ratio
    top.axhspan(1 - result.ratio_band, 1 + result.ratio_band, color="0.9",
                label=f"honest bounds, {result.runs} runs (±2 s.e.)")
    top.axhline(1.0, color="0.4", linewidth=1.0)
    top.plot(x, ratio, "o", color="C0", markersize=4, label="std / mean CR")
    finite = ratio[np.isfinite(ratio) & (ratio > 0)]
    if finite.size and (finite.max() > LOG_SCALE_ABOVE or finite.min() < 1 / LOG_SCALE_ABOVE):
        # one far-off parameter (a noise variance 90 times its bound) would flatten the rest
        low = max(min(0.5, finite.min() / 1.5), LOG_SCALE_FLOOR)
        top.set_yscale("log")
        top.set_ylim(low, max(2.0, finite.max() * 1.5))
        top.set_ylabel("sample std / mean CR (log)")
        below = np.isfinite(ratio) & (ratio < low)
        if np.any(below):
            top.plot(x[below], np.full(int(below.sum()), low * 1.15), "v", color="C0",
                     markersize=5, label=f"below {low:g} (bound far above the spread)")
    else:
        top.set_ylim(0.0, max(2.0, float(finite.max(initial=0.0)) * 1.1))
        top.set_ylabel("sample std / mean CR")
    top.legend(loc="upper left", fontsize="small")
    bottom.axhspan(NOMINAL_COVERAGE - result.coverage_band,
                   min(1.0, NOMINAL_COVERAGE + result.coverage_band), color="0.9")
    bottom.axhline(NOMINAL_COVERAGE, color="0.4", linewidth=1.0,
                   label=f"nominal {NOMINAL_COVERAGE:.1%}")
    bottom.plot(x, result.coverage("mean"), "o", color="C0", markersize=4,
                label="around the sample mean")
    truth = result.coverage("truth")
    if np.any(np.isfinite(truth)):
        bottom.plot(x, truth, "o", color="C3", markerfacecolor="none", markersize=4,
                    label="around the truth")
    bottom.set_ylabel("coverage of ±2 CR")
    bottom.set_ylim(-0.02, 1.02)
    bottom.legend(loc="lower left", fontsize="small")
    bottom.set_xticks(x, [parameter_label(n) for n in names], rotation=90, fontsize="small")
    for axis in (top, bottom):
        axis.grid(True, axis="y", alpha=0.3)
    figure.suptitle(title or f"Monte Carlo check of the Cramér-Rao bounds\ncase "
                             f"{result.case}, {result.runs} runs")
    return figure
