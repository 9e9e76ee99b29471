"""Figures of a study (matplotlib; safe under the Agg backend; each function returns its figure).

* :func:`plot_rmse_path`: RMSE against the number of removed parameters, the selected structure
  marked (the paper's figs. 1 and 6);
* :func:`plot_time_histories`: one maneuver's recorded (truth) outputs beside the outputs of
  one or several identified models, with the recorded inputs (figs. 2, 3, 7, 8, …);
* :func:`save_figure`: PNG and SVG files of a figure, written atomically.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from rotorid.data import INPUT_CHANNELS, OUTPUT_CHANNELS, Maneuver
from rotorid.estimation.reduction import ReductionPath
from rotorid.io import atomic_write
from rotorid.units import unit_system

#: Output names as engineers write them.
OUTPUT_TITLES = {"ax": "a_x", "az": "a_z", "q": "q", "theta": "θ", "ay": "a_y", "p": "p",
                 "phi": "φ", "r": "r"}
_STYLES = ("-", "--", "-.", ":")


def save_figure(figure, stem: str | Path, formats: tuple[str, ...] = ("png", "svg"),
                dpi: int = 110) -> list[Path]:
    """Write ``figure`` as ``<stem>.<format>`` for each of ``formats``, atomically; returns the
    paths. The same figure gives the same bytes: SVGs carry no date and fixed element ids."""
    return [atomic_write(Path(f"{stem}.{fmt}"),
                         lambda handle, fmt=fmt: _save(figure, handle, fmt, dpi))
            for fmt in formats]


def _save(figure, handle, fmt: str, dpi: int) -> None:
    import matplotlib

    with matplotlib.rc_context({"svg.hashsalt": "rotorid"}):
        figure.savefig(handle, format=fmt, dpi=dpi,
                       metadata={"Date": None} if fmt == "svg" else None)


def plot_rmse_path(path: ReductionPath, title: str = "Model reduction"):
    """RMSE (the paper's eq. 18) against the number of removed parameters.

    Each point is labelled with the parameter removed to reach it; the structure the
    selection rule picked is marked, and the tolerance band of the rule is shaded.
    """
    from matplotlib.figure import Figure

    removed, rmse = path.rmse_curve()
    figure = Figure(figsize=(9.0, 4.6), layout="constrained")
    axis = figure.subplots()
    axis.plot(removed, rmse, "o-", color="C0", markersize=3.5, label="converged fit")
    selected = path.selected_index
    axis.plot(removed[selected], rmse[selected], "*", color="C3", markersize=14,
              label=f"selected: {path.selected.n_parameters} parameters "
                    f"({path.rule}, tolerance {path.rmse_tolerance:.0%})")
    if path.rule == "lowest-rmse":
        axis.axhspan(rmse.min(), rmse.min() * (1 + path.rmse_tolerance), color="C3",
                     alpha=0.12, label="lowest RMSE + tolerance")
    for step in path.steps[1:]:
        axis.annotate(step.removal.parameter, (step.index, step.rmse), textcoords="offset points",
                      xytext=(0, 6), rotation=90, fontsize=6, ha="center", va="bottom",
                      color="0.35")
    axis.set_xlabel("number of removed parameters [-]")
    axis.set_ylabel("RMSE (eq. 18) [mixed units]")
    axis.set_title(title)
    finite = rmse[np.isfinite(rmse)]
    if finite.size:
        axis.set_ylim(0.0, finite.max() * 1.6)   # headroom: labels and legend
    axis.grid(True, alpha=0.3)
    axis.legend(loc="upper left", fontsize="small")
    return figure


def plot_time_histories(maneuver: Maneuver, simulated: Mapping[str, np.ndarray],
                        title: str | None = None):
    """Recorded outputs of ``maneuver`` against the simulated outputs of each model.

    Args:
        maneuver: the record (its outputs are drawn as "truth").
        simulated: label → simulated outputs, shape (N, 8) in ``OUTPUT_CHANNELS`` order.
    """
    from matplotlib.figure import Figure

    units = unit_system(maneuver.units)
    figure = Figure(figsize=(10.0, 10.5), layout="constrained")
    axes = figure.subplots(5, 2, sharex=True).ravel()
    time = maneuver.time
    for column, name in enumerate(OUTPUT_CHANNELS):
        axis = axes[column]
        axis.plot(time, maneuver.outputs[:, column], color="k", linewidth=1.3, label="truth")
        for index, (label, outputs) in enumerate(simulated.items()):
            outputs = np.asarray(outputs)
            if outputs.shape != maneuver.outputs.shape:
                raise ValueError(f"{label}: simulated outputs have shape {outputs.shape}, the "
                                 f"maneuver {maneuver.outputs.shape}")
            axis.plot(time, outputs[:, column], _STYLES[index % len(_STYLES)],
                      color=f"C{index + 1}", linewidth=1.1, label=label)
        axis.set_ylabel(f"{OUTPUT_TITLES[name]} [{units.label(name)}]")
        axis.grid(True, alpha=0.3)
    for offset, (axis, pair) in enumerate(zip(axes[8:], (INPUT_CHANNELS[:2],
                                                          INPUT_CHANNELS[2:]))):
        for k, name in enumerate(pair):
            column = INPUT_CHANNELS.index(name)
            axis.plot(time, maneuver.inputs[:, column], color=f"C{5 + 2 * offset + k}",
                      label=f"δ_{name}")
        axis.set_ylabel("control [% of travel]")
        axis.set_xlabel("time t [s]")
        axis.legend(fontsize="small", loc="upper right")
        axis.grid(True, alpha=0.3)
    axes[0].legend(fontsize="small", loc="best")
    figure.suptitle(title or f"{maneuver.name}: truth and identified models")
    return figure
