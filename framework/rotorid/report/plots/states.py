"""The figure of an estimator's state estimates along one maneuver (``rotorid identify
--states``): each state's estimate over time in its unit, in a band of ±2 standard deviations
of its error as the estimator states it, the turbulence's states (disturbances ``d_<state>``,
gusts ``g_<state>``) first; where the record holds a channel of a state's name (a measured
rate, less its estimated bias; a generated record's true gust) it is drawn thin and grey behind
the estimate. The legend sits below the panels.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rotorid.estimation.state_estimates import StateEstimates
from rotorid.report.plots.case import MEASURED_STYLE, OUTPUT_TITLES

#: What the prefix of a noise model's state says, for the panel titles.
NOISE_TITLES = {"g_": "gust", "d_": "disturbance"}
#: Prefixes of the noise model's states, drawn first.
NOISE_PREFIXES = tuple(NOISE_TITLES)


def _label(name: str, unit: str) -> str:
    """``gust w [ft/s]``, ``θ [deg]``: a state as the panel names it."""
    prefix = name[:2]
    if prefix in NOISE_PREFIXES:
        return f"{NOISE_TITLES[prefix]} {OUTPUT_TITLES.get(name[2:], name[2:])} [{unit}]"
    return f"{OUTPUT_TITLES.get(name, name)} [{unit}]"


def recorded_states(maneuver, names, estimate=None
                    ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Name → (time, values) of each of ``names`` that ``maneuver`` records as a channel, less
    the output bias ``estimate`` (an Estimate) holds for it (``bias_<maneuver>_<name>``), so
    that a record with an estimated offset is drawn where the filter sees it."""
    held = set(maneuver.channel_names) | set(maneuver.extra_channels)
    biases = {} if estimate is None else dict(zip(estimate.parameter_names, estimate.values))
    return {name: (maneuver.time,
                   maneuver.channel(name) - biases.get(f"bias_{maneuver.name}_{name}", 0.0))
            for name in names if name in held}


def drawing_order(names) -> list[int]:
    """Indices of ``names``: the noise model's states first, then the aircraft's."""
    noise = [k for k, n in enumerate(names) if n[:2] in NOISE_PREFIXES]
    return noise + [k for k in range(len(names)) if k not in noise]


def plot_state_estimates(estimates: StateEstimates, maneuver: str,
                         known: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
                         title: str | None = None):
    """The state estimates of ``maneuver`` (one of ``estimates.maneuvers``), two panels a row.

    Args:
        known: state name → (time (K,), values (K,)) of the record's channel of that name
            (:func:`recorded_states`), drawn thin and grey behind the estimate.
        title: the figure's title (default the maneuver's name).
    """
    from matplotlib.figure import Figure

    index = estimates.maneuvers.index(maneuver)
    time, values = estimates.time[index], estimates.values[index]
    order = drawing_order(estimates.names)
    known = dict(known or {})
    rows = (len(order) + 1) // 2
    figure = Figure(figsize=(10.0, 1.2 + 2.1 * rows), layout="constrained")
    axes = figure.subplots(rows, 2, sharex=True, squeeze=False).ravel()
    for axis, column in zip(axes, order):
        name, sigma = estimates.names[column], estimates.standard_deviation[column]
        estimate = values[:, column]
        if name in known:
            label = "true (recorded)" if name[:2] in NOISE_PREFIXES else "recorded"
            axis.plot(*known[name], label=label, **MEASURED_STYLE)
        axis.fill_between(time, estimate - 2 * sigma, estimate + 2 * sigma, color="C0",
                          alpha=0.2, linewidth=0, label="±2σ")
        axis.plot(time, estimate, color="C0", linewidth=1.2, label="estimate", zorder=3)
        axis.set_ylabel(_label(name, estimates.units[column]))
        axis.grid(True, alpha=0.3)
    for axis in axes[len(order):]:
        axis.set_visible(False)
    for axis in axes[max(len(order) - 2, 0):len(order)]:     # the lowest panel of each column
        axis.set_xlabel("time t [s]")
        axis.tick_params(labelbottom=True)
    legend = {}
    for axis in axes[:len(order)]:
        for handle, label in zip(*axis.get_legend_handles_labels()):
            legend.setdefault(label, handle)
    figure.legend(legend.values(), legend.keys(), loc="outside lower center", ncols=len(legend))
    figure.suptitle(title or f"{maneuver}: state estimates ({estimates.method})",
                    fontsize="medium")
    return figure
