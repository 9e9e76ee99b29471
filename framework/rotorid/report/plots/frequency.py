"""Figures of the frequency-domain verification (matplotlib; safe under the Agg backend).

* :func:`plot_error`: the paper's error plots (figs. 4, 5, 12, 14): magnitude (dB) and phase
  (deg) of ``ε = H_model/H_truth`` against the envelope bounds, with the coherence, for one
  or several models side by side (e.g. "no delays" and "with delays");
* :func:`plot_bode`: Bode overlay of truth, simulated-model and analytic-model responses with
  the coherence.

Points with γ² ≥ 0.8 are drawn as filled markers, 0.6 ≤ γ² < 0.8 as open markers, lower
coherence is hidden. Every function returns its :class:`matplotlib.figure.Figure`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rotorid.plugin.contracts import ValidationEnvelope
from rotorid.verification.compare import COHERENCE_THRESHOLD, PairVerification
from rotorid.verification.envelopes import error_db_deg
from rotorid.verification.frequency import unwrapped_phase_deg

#: Coherence below which points are hidden.
RELAXED_THRESHOLD = 0.6
_MARKERS = ("o", "s", "^", "D", "v")
#: How the model's single-input response was formed (``PairVerification.model_source``).
_SOURCES = {"simulated": "simulated sweeps", "apparent": "apparent response"}


def _figure(n_rows: int, title: str):
    from matplotlib.figure import Figure

    figure = Figure(figsize=(7.5, 2.4 * n_rows + 0.8), layout="constrained")
    axes = figure.subplots(n_rows, 1, sharex=True, squeeze=False)[:, 0]
    figure.suptitle(title)
    return figure, axes


def _scatter(axis, omega, values, coherence, color, marker, label):
    """Filled markers for γ² ≥ 0.8, open for 0.6–0.8, nothing below."""
    with np.errstate(invalid="ignore"):
        strong = coherence >= COHERENCE_THRESHOLD
        weak = (coherence >= RELAXED_THRESHOLD) & ~strong
    axis.plot(omega[strong], values[strong], marker, color=color, markersize=3.5,
              linestyle="none", label=label)
    axis.plot(omega[weak], values[weak], marker, color=color, markersize=3.5,
              markerfacecolor="none", linestyle="none")


def plot_error(errors: Mapping[str, PairVerification] | PairVerification,
               envelopes: Mapping[str, ValidationEnvelope] | Sequence[ValidationEnvelope] = (),
               analytic: bool = False, title: str | None = None):
    """Magnitude and phase of ``ε`` against envelope bounds, with coherence.

    Args:
        errors: one :class:`PairVerification`, or label → verification of the same pair for
            several models drawn side by side (e.g. ``{"no delays": a, "with delays": b}``).
        envelopes: envelopes whose bounds are drawn dashed (unavailable ones are only named
            in the legend; unverified ones are labelled so).
        analytic: draw ``ε`` of the analytic model response against the truth's conditioned
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
        3, title or f"{first.pair}: error ε = H_model/H_truth ({kind})")
    omega = first.omega
    dense = np.geomspace(omega.min(), omega.max(), 300)
    styles = ("--", ":", "-.")
    for envelope, style in zip(envelopes, styles * 3):
        bounds = envelope.bounds(dense)
        if not bounds.available:
            mag_axis.plot([], [], " ", label=f"{envelope.name}: not available")
            continue
        shown = np.where(bounds.extrapolated, np.nan, 1.0)
        label = f"{envelope.name} bounds" + ("" if envelope.verified else " (unverified)")
        for axis, low, high in ((mag_axis, bounds.mag_lower_db, bounds.mag_upper_db),
                                (phase_axis, bounds.phase_lower_deg, bounds.phase_upper_deg)):
            axis.semilogx(dense, high * shown, style, color="k", linewidth=1.0, label=label)
            axis.semilogx(dense, low * shown, style, color="k", linewidth=1.0)
    for index, (label, item) in enumerate(errors.items()):
        error = item.analytic_error if analytic else item.error
        if error is None:
            raise ValueError(f"{label}: no analytic response was evaluated")
        coherence = item.analytic_coherence if analytic else item.coherence
        magnitude, phase = error_db_deg(error)
        color, marker = f"C{index}", _MARKERS[index % len(_MARKERS)]
        _scatter(mag_axis, item.omega, magnitude, coherence, color, marker, label)
        _scatter(phase_axis, item.omega, phase, coherence, color, marker, label)
        coh_axis.semilogx(item.omega, coherence, color=color, label=label)
    coh_axis.axhline(COHERENCE_THRESHOLD, color="grey", linestyle=":",
                     label=f"γ² = {COHERENCE_THRESHOLD}")
    mag_axis.set_ylabel("|ε| [dB]")
    phase_axis.set_ylabel("∠ε [deg]")
    coh_axis.set_ylabel(("partial γ²" if analytic else "γ²") + " (truth) [-]")
    coh_axis.set_ylim(0.0, 1.05)
    coh_axis.set_xlabel("frequency ω [rad/s]")
    for axis in (mag_axis, phase_axis, coh_axis):
        axis.set_xscale("log")
        axis.grid(True, which="both", alpha=0.3)
    mag_axis.legend(fontsize="small", loc="best")
    coh_axis.legend(fontsize="small", loc="lower left")
    return figure


def plot_bode(item: PairVerification, output_unit: str = "", input_unit: str = "%",
              title: str | None = None):
    """Bode overlay of truth, simulated model and (if evaluated) analytic model, with γ².

    When the truth's response was conditioned on other inputs, its conditioned estimate (the
    one the analytic response is compared with) is drawn too, with its partial coherence.
    """
    unit = f"{output_unit}/{input_unit}" if output_unit else f"output/{input_unit}"
    figure, (mag_axis, phase_axis, coh_axis) = _figure(
        3, title or f"{item.pair}: frequency responses")
    curves = [("truth (estimated)", item.truth.response, item.truth.coherence, "C0"),
              (f"model ({_SOURCES[item.model_source]})", item.model.response,
               item.truth.coherence, "C1")]
    conditioned = item.conditioned
    if conditioned is not None and conditioned.conditioned_on:
        curves.append((f"truth conditioned on {', '.join(conditioned.conditioned_on)}",
                       conditioned.response, conditioned.coherence, "C3"))
    for label, response, coherence, color in curves:
        with np.errstate(divide="ignore"):
            magnitude = 20.0 * np.log10(np.abs(response))
        _scatter(mag_axis, item.omega, magnitude, coherence, color, "o", label)
        _scatter(phase_axis, item.omega, unwrapped_phase_deg(response), coherence, color, "o",
                 label)
    if item.analytic is not None:
        mag_axis.semilogx(item.omega, 20.0 * np.log10(np.abs(item.analytic)), color="C2",
                          label="model (analytic, exact delays)")
        phase_axis.semilogx(item.omega, unwrapped_phase_deg(item.analytic), color="C2",
                            label="model (analytic, exact delays)")
    coh_axis.semilogx(item.omega, item.truth.coherence, color="C0", label="truth")
    if item.model_source == "simulated":
        coh_axis.semilogx(item.omega, item.model.coherence, color="C1", label="model (simulated)")
    if conditioned is not None and conditioned.conditioned_on:
        coh_axis.semilogx(item.omega, conditioned.coherence, color="C3",
                          label="truth, partial")
    coh_axis.axhline(COHERENCE_THRESHOLD, color="grey", linestyle=":")
    mag_axis.set_ylabel(f"magnitude [dB, {unit}]")
    phase_axis.set_ylabel("phase [deg]")
    coh_axis.set_ylabel("γ² [-]")
    coh_axis.set_ylim(0.0, 1.05)
    coh_axis.set_xlabel("frequency ω [rad/s]")
    for axis in (mag_axis, phase_axis, coh_axis):
        axis.set_xscale("log")
        axis.grid(True, which="both", alpha=0.3)
    mag_axis.legend(fontsize="small", loc="best")
    coh_axis.legend(fontsize="small", loc="lower left")
    return figure
