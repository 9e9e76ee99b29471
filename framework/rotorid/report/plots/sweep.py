"""Summary figure of a speed sweep (matplotlib; safe under the Agg backend).

:func:`plot_speed_sweep` draws, per selected derivative and delay, the identified value
against airspeed with ±k·Cramér-Rao error bars beside the truth model's linearisation at the
same trims. A derivative removed by the reduction (or a delay dropped as undetermined) at
some airspeed is drawn as a grey cross at zero there. Returns the
:class:`matplotlib.figure.Figure`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rotorid.model.derivatives import delay_parameter, delayed_derivative, parameter_label
from rotorid.study.sweep import SweepPoint

#: Derivatives drawn by default: the main damping, control and coupling terms.
DEFAULT_DERIVATIVES = ("X_u", "Z_w", "Z_coll", "M_u", "M_q", "M_long",
                       "L_v", "L_p", "L_lat", "N_v", "N_r", "N_ped")
#: Delays drawn by default (those the built-in cases add).
DEFAULT_DELAYS = ("L_p", "L_lat", "M_q", "M_long")
_COLUMNS = 4


def plot_speed_sweep(points: Sequence[SweepPoint],
                     derivatives: Sequence[str] = DEFAULT_DERIVATIVES,
                     delays: Sequence[str] = DEFAULT_DELAYS, bound: float = 1.0,
                     title: str = "Identified derivatives and delays versus airspeed"):
    """Identified derivatives/delays versus airspeed with ±``bound``·CR bars and the truth.

    Args:
        points: one :class:`~rotorid.study.sweep.SweepPoint` per airspeed.
        derivatives: derivative names, one panel each (units of the points).
        delays: derivatives whose delay ``tau_<name>`` (s) gets a panel.
        bound: error-bar half-width in Cramér-Rao bounds.
    """
    from matplotlib.figure import Figure

    names = [*derivatives, *(delay_parameter(d) for d in delays)]
    rows = max(1, math.ceil(len(names) / _COLUMNS))
    figure = Figure(figsize=(3.0 * _COLUMNS, 2.3 * rows + 0.7), layout="constrained")
    axes = figure.subplots(rows, _COLUMNS, sharex=True, squeeze=False).ravel()
    speed = np.array([p.airspeed_kt for p in points], dtype=float)
    for axis, name in zip(axes, names):
        _panel(axis, name, points, speed, bound)
    for axis in axes[len(names):]:
        axis.set_visible(False)
    for axis in axes[len(names) - _COLUMNS:len(names)]:
        axis.set_xlabel("airspeed (kt)")
    handles, labels = axes[0].get_legend_handles_labels()
    for axis in axes[1:len(names)]:
        for handle, label in zip(*axis.get_legend_handles_labels()):
            if label not in labels:
                handles.append(handle)
                labels.append(label)
    figure.legend(handles, labels, loc="outside lower center", ncols=len(labels),
                  fontsize="small")
    figure.suptitle(title)
    return figure


def _panel(axis, name: str, points, speed: np.ndarray, bound: float) -> None:
    value = np.array([p.values.get(name, np.nan) for p in points])
    bar = np.array([p.cramer_rao.get(name, np.nan) for p in points]) * bound
    truth = np.array([p.truth.get(name, np.nan) for p in points])
    if np.any(np.isfinite(truth)):
        axis.plot(speed, truth, "-", color="0.35", linewidth=1.2, label="truth linearisation")
    shown = np.isfinite(value)
    finite_bar = np.where(np.isfinite(bar), bar, 0.0)
    axis.errorbar(speed[shown], value[shown], yerr=finite_bar[shown], fmt="o", markersize=3.5,
                  capsize=2.5, color="C0", label=f"identified ±{bound:g} CR")
    if np.any(~shown):
        axis.plot(speed[~shown], np.zeros(int((~shown).sum())), "x", color="0.6",
                  label="removed / dropped")
    axis.axhline(0.0, color="0.85", linewidth=0.8, zorder=0)
    label = parameter_label(name)
    axis.set_title(f"{label} (s)" if delayed_derivative(name) else label, fontsize="medium")
    axis.grid(True, alpha=0.3)
