"""Figures of a study (matplotlib; safe under the Agg backend; each function returns its figure).

* :func:`plot_rmse_path`: RMSE against the number of removed parameters, zoomed on the region
  the selection rules look at, with the tolerance band and where each rule lands (the paper's
  figs. 1 and 6);
* :func:`plot_time_histories`: one maneuver's measured outputs (thin, grey) behind the outputs
  of one or several identified models, the recorded inputs, and a zoom on the input window
  (figs. 2, 3, 7, 8, …);
* :func:`save_figure`: PNG and SVG files of a figure, written atomically.

Legends sit outside the axes, so they never cover data.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from rotorid.data import Maneuver
from rotorid.estimation.estimate import rmse_unit
from rotorid.estimation.reduction import ReductionPath
from rotorid.io import atomic_write
from rotorid.model.signals import ModelSignals, Signal, SignalSet
from rotorid.units import CHANNEL_KINDS, unit_system

#: Output names as engineers write them.
OUTPUT_TITLES = {"ax": "a_x", "az": "a_z", "q": "q", "theta": "θ", "ay": "a_y", "p": "p",
                 "phi": "φ", "r": "r"}
#: Outputs shown in the zoom panels, by the control axis a maneuver excites: the on-axis
#: response and the coupled one the delays act on (the roll-rate lag after a longitudinal
#: input, the paper's point).
ZOOM_OUTPUTS = {"long": ("q", "p"), "lat": ("p", "q"), "coll": ("az", "r"), "ped": ("r", "p")}
#: Colour and width of measured data, drawn behind the models.
MEASURED_STYLE = {"color": "0.6", "linewidth": 0.7, "zorder": 1}
_STYLES = ("-", "--", "-.", ":")
#: Headroom of the RMSE axis above the lowest RMSE, relative (the region selection looks at).
RMSE_VIEW = 0.15


def save_figure(figure, stem: str | Path, formats: tuple[str, ...] = ("png", "svg"),
                dpi: int = 110) -> list[Path]:
    """Write ``figure`` as ``<stem>.<format>`` for each of ``formats``, atomically; returns the
    paths. The same figure gives the same bytes: SVGs carry no date and fixed element ids.

    The layout engine's result of the first format is kept for the others (the figure's
    layout engine is then off), which saves a constrained layout per further format."""
    paths = []
    for fmt in formats:
        paths.append(atomic_write(Path(f"{stem}.{fmt}"),
                                  lambda handle, fmt=fmt: _save(figure, handle, fmt, dpi)))
        figure.set_layout_engine("none")
    return paths


def _save(figure, handle, fmt: str, dpi: int) -> None:
    import matplotlib

    with matplotlib.rc_context({"svg.hashsalt": "rotorid"}):
        figure.savefig(handle, format=fmt, dpi=dpi,
                       metadata={"Date": None} if fmt == "svg" else None)


def rule_marks(path: ReductionPath) -> dict[str, int]:
    """Step index where the selection rules land (:meth:`ReductionPath.selections`), one
    entry per step, naming the rules that land there; the path's own rule's step first and
    labelled "selected" (label → step index)."""
    selections = path.selections()
    by_step: dict[int, list[str]] = {}
    for rule in [path.rule, *(r for r in selections if r != path.rule)]:
        by_step.setdefault(selections[rule], []).append(rule)
    marks = {}
    for index, rules in by_step.items():
        text = ", ".join(rules) + ("" if rules == ["lowest-rmse"]
                                   else f", tolerance {path.rmse_tolerance:.0%}")
        marks[f"selected ({text})" if path.rule in rules else text] = index
    return marks


def plot_rmse_path(path: ReductionPath, title: str = "Model reduction"):
    """RMSE (the paper's eq. 18) against the number of removed parameters.

    The y-axis spans the lowest RMSE to ``RMSE_VIEW`` above it (steps beyond are drawn at the
    top edge as open triangles), the tolerance band above the lowest RMSE is shaded, and the
    step each rule of :func:`rule_marks` picks is marked. The parameter removed to reach each
    step labels the top axis.
    """
    from matplotlib.figure import Figure

    removed, rmse = path.rmse_curve()
    figure = Figure(figsize=(10.0, 5.2), layout="constrained")
    axis = figure.subplots()
    lowest = float(np.nanmin(rmse))
    top = lowest * (1.0 + max(RMSE_VIEW, 3.0 * path.rmse_tolerance))
    bottom = lowest * (1.0 - 0.25 * max(RMSE_VIEW, 3.0 * path.rmse_tolerance))
    axis.axhspan(lowest, lowest * (1.0 + path.rmse_tolerance), facecolor="C1", alpha=0.3,
                 edgecolor="C1", linewidth=1.0,
                 label=f"lowest RMSE + tolerance ({path.rmse_tolerance:.0%})")
    axis.plot(removed, np.where(rmse <= top, rmse, np.nan), "o-", color="C0", markersize=4,
              label="converged fit")
    above = rmse > top
    if above.any():
        axis.plot(removed[above], np.full(int(above.sum()), top), "^", color="C0",
                  markerfacecolor="none", markersize=6, clip_on=False,
                  label="RMSE above the axis (off scale)")
    for (label, index), (marker, color) in zip(rule_marks(path).items(),
                                                (("*", "C3"), ("D", "C2"), ("s", "C4"))):
        step = path.steps[index]
        axis.plot(index, min(rmse[index], top), marker, color=color, markersize=13,
                  markerfacecolor="none" if marker != "*" else color, markeredgewidth=1.8,
                  label=f"{label}: step {index}, {step.n_parameters} parameters, "
                        f"RMSE {rmse[index]:.4f}", zorder=4)
    axis.set_ylim(bottom, top)
    axis.set_xlim(-0.5, removed[-1] + 0.5)
    axis.set_xlabel("number of removed parameters [-]")
    axis.set_ylabel(f"RMSE (eq. 18) [{rmse_unit(path.steps[0].estimate.output_units)}]")
    names = axis.secondary_xaxis("top")
    names.set_xticks(removed[1:], [s.removal.parameter for s in path.steps[1:]], rotation=90,
                     fontsize=7 if len(removed) < 45 else 6)
    names.set_xlabel("parameter removed at that step")
    axis.grid(True, alpha=0.3)
    figure.suptitle(title)
    figure.legend(loc="outside lower center", ncols=2, fontsize="small")
    return figure


def input_window(maneuver: Maneuver, margin: float = 1.5) -> tuple[float, float]:
    """Start and end (s) of the input window: from ``margin``/3 s before the first to
    ``margin`` s after the last step of the primary input (a sample-to-sample change above
    20 % of its excursion); for inputs without steps, the span where it deviates from its
    first value by more than 5 % of its excursion."""
    time = maneuver.time
    control = maneuver.channel(_primary_axis(maneuver))
    excursion = float(np.ptp(control))
    if excursion == 0.0:
        return float(time[0]), float(time[-1])
    changing = np.abs(np.diff(control)) > 0.2 * excursion
    if changing.any():
        first, last = np.flatnonzero(changing)[[0, -1]] + (0, 1)
    else:
        first, last = np.flatnonzero(np.abs(control - control[0]) > 0.05 * excursion)[[0, -1]]
    return (float(max(time[0], time[first] - margin / 3)),
            float(min(time[-1], time[last] + margin)))


def _primary_axis(maneuver: Maneuver) -> str:
    axis = maneuver.metadata.get("axis")
    if axis in maneuver.input_names:
        return axis
    excursion = np.ptp(maneuver.inputs, axis=0)
    return maneuver.input_names[int(np.argmax(excursion))]


def _zoomed(axis: str, outputs: tuple[str, ...], rates: tuple[str, ...], control: np.ndarray,
            response: np.ndarray | None) -> tuple[str, ...]:
    """The outputs of the zoom row: :data:`ZOOM_OUTPUTS` of the axis that the model has.

    For another axis (an aeroplane's rudder, say) the angular rates among ``outputs``
    (``rates``: those of kind ``rate``) whose change follows the input most closely, as in
    :data:`ZOOM_OUTPUTS` the on-axis rate and the coupled one (r and p for a rudder): largest
    |correlation| of the model's simulated ``response`` (N, ny) differentiated against
    ``control`` (N,), the excited input over the same samples. Fewer than two rates are
    completed by the other outputs in the same order; without a response, or with a constant
    input, the first two outputs."""
    chosen = tuple(o for o in ZOOM_OUTPUTS.get(axis, ()) if o in outputs)
    if chosen or response is None or len(control) < 3 or np.ptp(control) == 0.0:
        return chosen or outputs[:2]
    change = np.gradient(response, axis=0)
    change, input_change = change - change.mean(axis=0), control - control.mean()
    spread = np.linalg.norm(change, axis=0) * np.linalg.norm(input_change)
    with np.errstate(invalid="ignore", divide="ignore"):
        following = np.where(spread > 0.0, np.abs(input_change @ change) / spread, 0.0)
    order = sorted(range(len(outputs)), key=lambda k: (outputs[k] not in rates, -following[k]))
    return tuple(outputs[k] for k in order[:2])


def _title(signal) -> str:
    """``a_x [ft/s²]``: a signal's name as engineers write it, and its unit."""
    return f"{OUTPUT_TITLES.get(signal.name, signal.name)} [{signal.unit}]"


def _outputs_panel(axis, time: np.ndarray, measured: np.ndarray,
                   simulated: Mapping[str, np.ndarray], ylabel: str) -> None:
    """One output: measured (N,) behind each model's simulation (N,) over ``time`` (N,)."""
    axis.plot(time, measured, label="measured", **MEASURED_STYLE)
    for index, (label, values) in enumerate(simulated.items()):
        axis.plot(time, values, _STYLES[index % len(_STYLES)], color=f"C{index}",
                  linewidth=1.4, label=label, zorder=3)
    axis.set_ylabel(ylabel)
    axis.grid(True, alpha=0.3)


def _default_signals(maneuver: Maneuver) -> ModelSignals:
    """The maneuver's own inputs and outputs as signals in its unit system's units."""
    units = unit_system(maneuver.units)

    def signal_set(names):
        return SignalSet(Signal(n, units.label(n), CHANNEL_KINDS[n]) for n in names)

    return ModelSignals(signal_set(()), signal_set(maneuver.input_names),
                        signal_set(maneuver.output_names))


def plot_time_histories(maneuver: Maneuver, simulated: Mapping[str, np.ndarray],
                        title: str | None = None, signals: ModelSignals | None = None):
    """Measured outputs of ``maneuver`` against the simulated outputs of each model.

    The first rows: the model's outputs, two per row (measured thin and grey behind the
    models; the input window shaded); then the inputs (two panels); last the on-axis and the
    main coupled output zoomed on the input window (:data:`ZOOM_OUTPUTS`; for other controls
    the two outputs the input drives most directly, :func:`_zoomed`). Axes are labelled
    with the signals' names and units.

    Args:
        maneuver: the record (its channels of the outputs' names are drawn as "measured").
        simulated: label → simulated outputs, shape (N, ny), columns ``signals.outputs``.
        signals: the model's signals (e.g. ``structure.signals``); default the maneuver's own
            inputs and outputs in its unit system.
    """
    from matplotlib.figure import Figure

    signals = _default_signals(maneuver) if signals is None else signals
    outputs, inputs = signals.outputs, signals.inputs
    simulated = {label: np.asarray(values) for label, values in simulated.items()}
    for label, values in simulated.items():
        if values.shape != (maneuver.n_samples, len(outputs)):
            raise ValueError(f"{label}: simulated outputs have shape {values.shape}, expected "
                             f"({maneuver.n_samples}, {len(outputs)}) for outputs "
                             f"{', '.join(outputs.names)}")
    measured = maneuver.columns(outputs.names)
    rows = (len(outputs) + 1) // 2
    figure = Figure(figsize=(10.0, 3.0 + 2.5 * rows), layout="constrained")
    grid = figure.add_gridspec(rows + 2, 2, height_ratios=(1,) * rows + (0.9, 1.3))
    first = figure.add_subplot(grid[0, 0])
    axes = [first] + [figure.add_subplot(grid[k // 2, k % 2], sharex=first)
                      for k in range(1, len(outputs))]
    origin = float(maneuver.time[0])        # a range's clock (IRIG seconds of day) starts late
    start, end = (t - origin for t in input_window(maneuver))
    time = maneuver.time - origin
    time_label = ("time t [s]" if origin == 0.0
                  else f"time from the record's start at t = {origin:.12g} s [s]")
    for column, signal in enumerate(outputs):
        _outputs_panel(axes[column], time, measured[:, column],
                       {label: values[:, column] for label, values in simulated.items()},
                       _title(signal))
        axes[column].axvspan(start, end, color="C8", alpha=0.08, zorder=0)
        axes[column].tick_params(labelbottom=False)
    half = (len(inputs) + 1) // 2
    for offset, group in enumerate((inputs.signals[:half], inputs.signals[half:])):
        axis = figure.add_subplot(grid[rows, offset], sharex=first)
        for k, signal in enumerate(group):
            axis.plot(time, maneuver.channel(signal.name), _STYLES[k % len(_STYLES)],
                      color=f"C{4 + 2 * offset + k}", label=f"δ_{signal.name} [{signal.unit}]")
        axis.set_ylabel("inputs" if len({s.unit for s in group}) != 1
                        else f"input [{group[0].unit}]")
        axis.set_xlabel(time_label)
        if group:
            axis.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.0, 1.0))
        axis.grid(True, alpha=0.3)
    mask = (time >= start) & (time <= end)
    axis_name = _primary_axis(maneuver)
    response = next(iter(simulated.values()), None)
    rates = tuple(signal.name for signal in outputs if signal.kind == "rate")
    zoomed = _zoomed(axis_name, outputs.names, rates, maneuver.channel(axis_name)[mask],
                     None if response is None else response[mask])
    for k, name in enumerate(zoomed):
        zoom = figure.add_subplot(grid[rows + 1, k])
        column = outputs.index(name)
        _outputs_panel(zoom, time[mask], measured[mask, column],
                       {label: values[mask, column] for label, values in simulated.items()},
                       _title(outputs[column]))
        zoom.set_title(f"zoom: {OUTPUT_TITLES.get(name, name)} over the input window "
                       f"{start:.1f}–{end:.1f} s", fontsize="medium")
        zoom.set_xlabel(time_label)
        zoom.set_facecolor((0.97, 0.97, 1.0))
    handles, labels = axes[0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="outside lower center", ncols=len(labels),
                  fontsize="small")
    figure.suptitle(title or f"{maneuver.name}: measured and identified models")
    return figure
