"""Figures of the frequency-domain verification (matplotlib; safe under the Agg backend).

* :func:`plot_error`: the paper's error plots (figs. 4, 5, 12, 14): magnitude (dB) and phase
  (deg, principal value) of ``ε = H_model/H_measured`` against the envelope bounds, with
  the measured response's coherence, for one or several models side by side (e.g. "no delays" and "with
  delays"); each model's legend entry counts its points inside/outside each envelope;
* :func:`plot_bode`: Bode overlay of the measured response, the model's simulated or
  apparent response, the measured response conditioned on the other inputs and the model's analytic
  response, all phases on one branch (no 360° jumps between curves), with the coherences.

Points of the pair's verification band (:class:`~rotorid.verification.band.VerificationBand`,
by default γ² ≥ 0.8 over 0.1–10 rad/s) are drawn as filled markers (they are checked), other
points with γ² ≥ 0.6 as open markers (shown, not checked), lower coherence is hidden; the
frequencies outside the band's range are shaded and its threshold is drawn on the coherence
panel. The y-limits come from the checked points (and the envelope bounds, the analytic
response), so outliers of low coherence never squash the plot; open markers beyond them are
cut off. The
frequency axis is labelled at 1, 2 and 5 of every decade. Legends sit outside the axes.
Every function returns its :class:`matplotlib.figure.Figure`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rotorid.plugin.contracts import ValidationEnvelope
from rotorid.verification.band import VerificationBand
from rotorid.verification.compare import PairVerification
from rotorid.verification.envelopes import error_db_deg, wrap180
from rotorid.verification.frequency import unwrapped_phase_deg

#: Coherence below which points are hidden (or the band's threshold, if lower).
RELAXED_THRESHOLD = 0.6
_MARKERS = ("o", "s", "^", "D", "v")
#: How the model's single-input response was formed (``PairVerification.model_source``).
_SOURCES = {"simulated": "simulated sweeps", "apparent": "apparent response"}


def _figure(n_rows: int, title: str):
    from matplotlib.figure import Figure

    figure = Figure(figsize=(8.0, 2.4 * n_rows + 1.4), layout="constrained")
    axes = figure.subplots(n_rows, 1, sharex=True, squeeze=False)[:, 0]
    figure.suptitle(title)
    return figure, axes


def _shown(band: VerificationBand, omega: np.ndarray, coherence: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    """(checked, shown) masks: the band's points, and the others with γ² ≥ 0.6."""
    checked = band.selects(omega, coherence)
    with np.errstate(invalid="ignore"):
        shown = (coherence >= min(RELAXED_THRESHOLD, band.coherence)) & ~checked
    return checked, shown


def _scatter(axis, band, omega, values, coherence, color, marker, label):
    """Filled markers for the band's points, open for the other points with γ² ≥ 0.6."""
    strong, weak = _shown(band, omega, coherence)
    axis.plot(omega[strong], values[strong], marker, color=color, markersize=3.5,
              linestyle="none", label=label)
    axis.plot(omega[weak], values[weak], marker, color=color, markersize=3.5,
              markerfacecolor="none", linestyle="none")


def limits(values: Sequence[np.ndarray], pad: float = 0.08, least: float = 1.0
           ) -> tuple[float, float]:
    """Axis limits holding every finite value of ``values`` with ``pad`` (relative) each
    side and a span of at least ``least``."""
    finite = np.concatenate([np.asarray(v, float).ravel() for v in values] or [np.zeros(0)])
    finite = finite[np.isfinite(finite)]
    if finite.size == 0:
        return -least, least
    low, high = float(finite.min()), float(finite.max())
    if high - low < least:
        middle = 0.5 * (low + high)
        low, high = middle - least / 2, middle + least / 2
    span = high - low
    return low - pad * span, high + pad * span


def decade_axis(axis) -> None:
    """Log frequency axis with plain-number labels at 1, 2 and 5 of every decade."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    axis.set_xscale("log")
    axis.xaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    axis.xaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.xaxis.set_minor_locator(LogLocator(base=10.0, subs=np.arange(1.0, 10.0)))
    axis.xaxis.set_minor_formatter(NullFormatter())
    axis.grid(True, which="major", alpha=0.35)
    axis.grid(True, which="minor", alpha=0.12)


def _mark_band(axes, band: VerificationBand, omega: np.ndarray) -> None:
    """Legend proxies explaining the filled and open markers; the frequencies of ``omega``'s
    span outside the band's range shaded on every axis; the band's threshold on the last
    (coherence) axis."""
    axes[0].plot([], [], "o", color="0.3", markersize=4,
                 label=f"filled: in the verification band, {band.describe()} (checked)")
    axes[0].plot([], [], "o", color="0.3", markersize=4, markerfacecolor="none",
                 label=f"open: γ² ≥ {min(RELAXED_THRESHOLD, band.coherence):g} outside the "
                       f"band (shown, not checked)")
    low, high = float(np.min(omega)), float(np.max(omega))
    spans = [(low, band.omega_min), (band.omega_max, high)]
    for axis in axes:
        for start, stop in spans:
            if start < stop:
                axis.axvspan(start, stop, color="0.9", zorder=0, linewidth=0,
                             label="outside the band's frequency range")
    axes[-1].axhline(band.coherence, color="grey", linestyle=":",
                     label=f"γ² = {band.coherence:g} (band threshold)")


def _counts(item: PairVerification, analytic: bool) -> str:
    """``"MUAD 140/150 inside, 10 outside"`` for each available bounds check of ``item``."""
    checks = item.analytic_checks if analytic else item.checks
    parts = [f"{c.envelope} {c.n_inside}/{c.n_used} inside, {c.n_outside} outside"
             for c in checks.values() if c.cost is None and c.status != "not available"]
    return "; ".join(parts)


def plot_error(errors: Mapping[str, PairVerification] | PairVerification,
               envelopes: Mapping[str, ValidationEnvelope] | Sequence[ValidationEnvelope] = (),
               analytic: bool = False, title: str | None = None):
    """Magnitude and phase of ``ε`` against envelope bounds, with the coherence of the measured response.

    Bounds are drawn solid over the envelope's own range (where points are checked) and
    thin dotted where extrapolated over the rest of the points' range (not checked).
    Envelopes without data are left out.

    Args:
        errors: one :class:`PairVerification`, or label → verification of the same pair for
            several models drawn side by side (e.g. ``{"no delays": a, "with delays": b}``).
        envelopes: bounds-kind envelopes to draw.
        analytic: draw ``ε`` of the analytic model response against the conditioned measured
            response (with its partial coherence) instead of the simulated one.
    """
    if isinstance(errors, PairVerification):
        errors = {"model": errors}
    if not errors:
        raise ValueError("plot_error needs at least one verification result")
    if isinstance(envelopes, Mapping):
        envelopes = list(envelopes.values())
    first = next(iter(errors.values()))
    kind = "analytic model" if analytic else _SOURCES[first.model_source]
    figure, (mag_axis, phase_axis, coh_axis) = _figure(
        3, title or f"{first.pair}: error ε = H_model/H_measured ({kind})")
    omega = first.omega
    dense = np.geomspace(omega.min(), omega.max(), 300)
    shown_mag, shown_phase = [], []
    for envelope, color in zip(envelopes, ("k", "0.35", "C7")):
        bounds = envelope.bounds(dense)
        if not bounds.available:
            continue
        inside = np.where(bounds.extrapolated, np.nan, 1.0)
        outside = np.where(bounds.extrapolated, 1.0, np.nan)
        label = f"{envelope.name} bounds" + ("" if envelope.verified else " (unverified)")
        for axis, low, high, shown in (
                (mag_axis, bounds.mag_lower_db, bounds.mag_upper_db, shown_mag),
                (phase_axis, bounds.phase_lower_deg, bounds.phase_upper_deg, shown_phase)):
            axis.semilogx(dense, high * inside, "--", color=color, linewidth=1.2, label=label)
            axis.semilogx(dense, low * inside, "--", color=color, linewidth=1.2)
            axis.semilogx(dense, high * outside, ":", color=color, linewidth=0.9,
                          label=f"{envelope.name} extrapolated (not checked)")
            axis.semilogx(dense, low * outside, ":", color=color, linewidth=0.9)
            shown += [low * inside, high * inside]
    for index, (label, item) in enumerate(errors.items()):
        error = item.analytic_error if analytic else item.error
        if error is None:
            raise ValueError(f"{label}: no analytic response was evaluated")
        coherence = item.analytic_coherence if analytic else item.coherence
        magnitude, phase = error_db_deg(error)
        strong, _ = _shown(item.band, item.omega, coherence)
        shown_mag.append(magnitude[strong])
        shown_phase.append(phase[strong])
        counts = _counts(item, analytic)
        text = f"{label}: {counts}" if counts else label
        color, marker = f"C{index}", _MARKERS[index % len(_MARKERS)]
        _scatter(mag_axis, item.band, item.omega, magnitude, coherence, color, marker, text)
        _scatter(phase_axis, item.band, item.omega, phase, coherence, color, marker, text)
    coherence = first.analytic_coherence if analytic else first.coherence
    coh_axis.semilogx(omega, coherence, color="0.2",
                      label=("partial γ² of the conditioned measured response" if analytic
                             else "γ² of the measured response"))
    _mark_band((mag_axis, phase_axis, coh_axis), first.band, omega)
    mag_axis.set_ylim(*limits(shown_mag, least=2.0))
    phase_axis.set_ylim(*limits(shown_phase, least=10.0))
    mag_axis.set_ylabel("|ε| [dB]")
    phase_axis.set_ylabel("∠ε [deg]")
    return _finish(figure, mag_axis, phase_axis, coh_axis,
                   ("partial γ²" if analytic else "γ²") + " [-]")


def _figure_legend(figure, axes) -> None:
    """One legend below the axes with the entries of ``axes``, each label once."""
    handles, labels = [], []
    for axis in axes:
        for handle, label in zip(*axis.get_legend_handles_labels()):
            if label not in labels:
                handles.append(handle)
                labels.append(label)
    figure.legend(handles, labels, loc="outside lower center", ncols=2, fontsize="small")


def common_branch_phase_deg(response: np.ndarray, reference_deg: np.ndarray) -> np.ndarray:
    """Phase of ``response`` (deg) on the 360° branch nearest ``reference_deg`` point by point,
    so curves compared on one plot never differ by whole turns; shape (M,)."""
    with np.errstate(invalid="ignore"):
        return reference_deg + wrap180(np.angle(response, deg=True) - reference_deg)


def plot_bode(item: PairVerification, output_unit: str = "", input_unit: str = "%",
              title: str | None = None):
    """Bode overlay of the measured response, the model (simulated or apparent) and, when evaluated, the
    analytic model and the measured response conditioned on the other inputs, with their coherences.

    The analytic response (or, without it, the model's) is unwrapped along frequency and
    every other phase is drawn on the branch nearest it (:func:`common_branch_phase_deg`).
    """
    unit = f"{output_unit}/{input_unit}" if output_unit else f"output/{input_unit}"
    figure, (mag_axis, phase_axis, coh_axis) = _figure(
        3, title or f"{item.pair}: frequency responses")
    reference = item.analytic if item.analytic is not None else item.model.response
    reference_deg = _filled(unwrapped_phase_deg(reference))
    curves = [("measured (estimated from the sweeps)", item.truth.response,
               item.truth.coherence, "C0"),
              (f"model ({_SOURCES[item.model_source]})", item.model.response,
               item.truth.coherence, "C1")]
    conditioned = item.conditioned
    if conditioned is not None and conditioned.conditioned_on:
        curves.append((f"measured, conditioned on {', '.join(conditioned.conditioned_on)}",
                       conditioned.response, conditioned.coherence, "C3"))
    shown_mag, shown_phase = [], []
    for label, response, coherence, color in curves:
        with np.errstate(divide="ignore"):
            magnitude = 20.0 * np.log10(np.abs(response))
        phase = common_branch_phase_deg(response, reference_deg)
        strong, _ = _shown(item.band, item.omega, coherence)
        shown_mag.append(magnitude[strong])
        shown_phase.append(phase[strong])
        _scatter(mag_axis, item.band, item.omega, magnitude, coherence, color, "o", label)
        _scatter(phase_axis, item.band, item.omega, phase, coherence, color, "o", label)
    if item.analytic is not None:
        with np.errstate(divide="ignore"):
            magnitude = 20.0 * np.log10(np.abs(item.analytic))
        mag_axis.semilogx(item.omega, magnitude, color="C2",
                          label="model (analytic, exact delays)")
        phase_axis.semilogx(item.omega, reference_deg, color="C2")
        shown_mag.append(magnitude)
        shown_phase.append(reference_deg)
    coh_axis.semilogx(item.omega, item.truth.coherence, color="C0", label="γ², measured")
    if item.model_source == "simulated":
        coh_axis.semilogx(item.omega, item.model.coherence, "--", color="C1",
                          label="γ², model (simulated)")
    if conditioned is not None and conditioned.conditioned_on:
        coh_axis.semilogx(item.omega, conditioned.coherence, color="C3",
                          label="partial γ², measured conditioned")
    _mark_band((mag_axis, phase_axis, coh_axis), item.band, item.omega)
    mag_axis.set_ylim(*limits(shown_mag, least=6.0))
    phase_axis.set_ylim(*limits(shown_phase, least=30.0))
    mag_axis.set_ylabel(f"magnitude [dB, {unit}]")
    phase_axis.set_ylabel("phase [deg]")
    return _finish(figure, mag_axis, phase_axis, coh_axis, "γ² [-]")


def _finish(figure, mag_axis, phase_axis, coh_axis, coherence_label: str):
    """The coherence axis's label and range, decade ticks on the shared frequency axis and
    one legend below the axes; returns ``figure``."""
    coh_axis.set_ylabel(coherence_label)
    coh_axis.set_ylim(0.0, 1.05)
    coh_axis.set_xlabel("frequency ω [rad/s]")
    for axis in (mag_axis, phase_axis, coh_axis):
        decade_axis(axis)
    _figure_legend(figure, (mag_axis, coh_axis))
    return figure


def _filled(phase_deg: np.ndarray) -> np.ndarray:
    """``phase_deg`` with NaN points filled by the nearest finite neighbour in frequency."""
    finite = np.isfinite(phase_deg)
    if finite.all() or not finite.any():
        return phase_deg
    index = np.arange(phase_deg.size)
    return np.interp(index, index[finite], phase_deg[finite])
