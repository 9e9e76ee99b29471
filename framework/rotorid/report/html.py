"""Figures, tables and HTML reports of a study, as the paper presents its results.

Per case (``<out>/<case>/``):

* ``figures/``: the figures of :mod:`rotorid.report.figures`, each shown with its caption;
* ``tables/removed.csv``, ``tables/parameters.csv`` (Appendix B), ``tables/key_derivatives.csv``,
  ``tables/verification.csv`` and ``tables/checks.csv`` (the paper's claims, measured, or for a
  case without a truth model the guidelines); with ``[reference]`` values ``tables/reference.csv``; with ``[compare] frequency`` ``tables/comparison_costs.csv``
  and ``tables/comparison_parameters.csv`` (the frequency-domain fit beside the time-domain
  fit); with ``[compare] estimators`` ``tables/estimators.csv`` and
  ``tables/estimator_fits.csv`` (the estimators' fits of the model with delays side by side);
  every column states its unit;
* ``report.html`` linking all of it: a table of contents, a summary (selected structure,
  verdicts, what fails), captions under every figure and one section (anchor
  ``pair-<out>-<in>``) per verified pair.

A case about measured data only (``source = "files"``, no truth model) is reported about
that aircraft alone: no paper claims but the guidelines (RMSE, MUAD on its verified pairs), no
truth or published Bo-105 values; only the reference values its case file gives
(``[reference]``).

Per study: ``<out>/report.html``, a summary of every case linking the case reports.
Every file is written atomically.
"""

from __future__ import annotations

import csv
import html
import io
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from rotorid.estimation.estimate import rmse_counted_units, rmse_unit
from rotorid.io import atomic_write
from rotorid.model.derivatives import delayed_derivative
from rotorid.model.modes import modes
from rotorid.progress import counted as plural
from rotorid.report.figures import (
    ReportFigure,
    case_figures,
    file_stem,
    flight_label,
    rmse_caption,
)
from rotorid.study.claims import (
    PAPER_SOURCES,
    case_claims,
    claims_tally,
    claims_title,
    mean_phase_error,
)
from rotorid.study.expectations import check_signs, derivative_unit
from rotorid.study.hybrid_comparison import FLAP_SHAPED, HYBRID_MODELS, mean_cost
from rotorid.study.result import ONE_MODEL
from rotorid.units import CHANNEL_KINDS, unit_system
from rotorid.verification.band import DEFAULT_BAND
from rotorid.verification.envelopes import MISMATCH_COST_GUIDELINE_TEXT
from rotorid.verification.handling_qualities import HQ_PAIRS

def key_derivative_checks(result):
    """Sign checks of the key derivatives of the model with delays (the final model)."""
    estimate = result.estimates["with delays"]
    identified = {name: (float(estimate.values[i]), float(estimate.cramer_rao[i]))
                  for i, name in enumerate(estimate.parameter_names)}
    return check_signs(result.key_derivative_names(), identified, result.condition.airspeed_kt,
                       estimate.units, result.truth_derivatives,
                       published=result.case.data_source in PAPER_SOURCES)


# ----------------------------------------------------------------- tables
def _number(value, digits: int = 4) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return f"{value:.{digits}g}"


def parameter_unit(name: str, units: str, estimate=None) -> str:
    """Unit of an estimated parameter: the one ``estimate`` states for it (its model's own
    signals), else s for a delay, the state's unit for filter error's process noise
    ``F_<state>`` (per sample), the output's unit squared for its measurement noise
    ``R_<output>``, else the helicopter derivative's unit."""
    if estimate is not None and estimate.parameter_units.get(name):
        return estimate.parameter_units[name]
    if delayed_derivative(name):
        return "s"
    kind, _, signal = name.partition("_")
    if kind in ("F", "R") and signal in CHANNEL_KINDS:
        label = unit_system(units).label(signal)
        return label if kind == "F" else f"({label})²"
    return derivative_unit(name, units)


def rmse_basis_text(estimate) -> str:
    """What the report's RMSE values ("[-]" or "[mixed units]") are: the units ``estimate``'s
    residuals count in (:func:`rotorid.estimation.estimate.rmse_counted_units`)."""
    counted = rmse_counted_units(estimate.output_units)
    if counted:
        return (f"RMSE values (eq. 18) are pure numbers, the residuals counted in "
                f"{', '.join(counted)}")
    return "RMSE values pool the outputs' residuals in their own units"


def removed_rows(result) -> list[list[str]]:
    """Appendix B, removed parameters: step, parameter, criterion, metric, RMSE, iterations."""
    unit = rmse_unit(result.estimates["no delays"].output_units)
    rows = [["step", "removed", "criterion", "metric", "parameters [-]",
             f"RMSE [{unit}]", "iterations [-]", "selected"]]
    selected = result.path.selected_index
    for step in result.path.steps:
        removal = step.removal
        rows.append([str(step.index), "—" if removal is None else removal.parameter,
                     "" if removal is None else removal.criterion,
                     "" if removal is None else removal.metric_text,
                     str(step.n_parameters), f"{step.rmse:.4f}", str(step.estimate.iterations),
                     "yes" if step.index == selected else ""])
    return rows


def parameter_rows(result) -> list[list[str]]:
    """Appendix B, identified parameters of the models shown (both, or the one of a case
    without delays): value, CR bound, CR %, insensitivity %."""
    header = ["parameter", "unit"]
    for label in result.models:
        name = result.model_name(label)
        header += [f"{name}: value", f"{name}: CR", f"{name}: CR [%]", f"{name}: I [%]"]
    names = list(dict.fromkeys(n for label in result.models
                               for n in result.estimates[label].parameter_names))
    rows = [header]
    units = result.estimates["with delays"].units
    for name in names:
        stating = next(result.estimates[label] for label in result.models
                       if name in result.estimates[label].parameter_names)
        row = [name, parameter_unit(name, units, stating)]
        for label in result.models:
            estimate = result.estimates[label]
            if name not in estimate.parameter_names:
                row += ["", "", "", ""]
                continue
            i = estimate.index(name)
            row += [_number(float(estimate.values[i])), _number(float(estimate.cramer_rao[i]), 3),
                    _number(float(estimate.cramer_rao_pct[i]), 3),
                    _number(float(estimate.insensitivity_pct[i]), 3)]
        rows.append(row)
    return rows


def _key_table(result, truth) -> str:
    """The key-derivative table, or a sentence when the selected model kept none of those
    its structure can hold."""
    rows = key_derivative_rows(result)
    if len(rows) == 1:
        return (f"<p>The selected model kept none of the key derivatives "
                f"({html.escape(', '.join(result.key_derivative_names()))}).</p>")
    return _html_table(rows, None if not truth else 8)


def key_derivative_rows(result) -> list[list[str]]:
    if not has_truth_model(result):
        estimate = result.estimates["with delays"]
        rows = [["derivative", "unit", "identified", "CR bound"]]
        for name in result.key_derivative_names():
            if name in estimate:
                item = estimate[name]
                rows.append([name, parameter_unit(name, estimate.units, estimate),
                             _number(item.value), _number(item.cramer_rao, 3)])
        return rows
    rows = [["derivative", "unit", "identified", "CR bound", "truth linearisation",
             "identified / truth [-]", "published reference", "expected sign from", "sign"]]
    for check in key_derivative_checks(result):
        rows.append([check.name, check.unit, _number(check.identified), _number(check.cramer_rao, 3),
                     _number(check.truth_linearisation), _number(check.ratio_to_truth, 3),
                     _number(check.reference, 3), check.basis, check.verdict])
    return rows


def reference_rows(result) -> list[list[str]]:
    """The model with delays beside the case's ``[reference]`` values."""
    rows = [["derivative", "unit", "identified", "CR bound", "reference",
             "reference uncertainty", "identified − reference", "combined bound", "verdict",
             "source"]]
    for row in result.reference_comparison():
        rows.append([row.name, row.unit, _number(row.identified), _number(row.cramer_rao, 3),
                     _number(row.reference.value), _number(row.reference.uncertainty, 3),
                     _number(row.difference, 3), _number(row.combined_bound, 3), row.verdict,
                     row.reference.source])
    return rows


def reference_html(result) -> str:
    """The case report's section on the user's reference values (empty without them)."""
    if not result.case.reference:
        return ""
    return "\n".join([
        '<h2 id="reference">Reference values</h2>',
        f"<p>The {result.final_model_name} beside the reference values the case file gives "
        "(<code>[reference]</code>), in the model's units. The verdict is <em>agrees</em> when "
        "the difference is within two combined bounds √(CR² + uncertainty²), <em>differs</em> "
        "beyond; a reference without uncertainty counts the Cramér-Rao bound only.</p>",
        _html_table(reference_rows(result), 8)])


def verification_rows(result) -> list[list[str]]:
    """Per sweep pair and model: the band, its points, MUAD/AEE status, worst margins, J."""
    rows = [["pair", "model", "verification band", "points in band [-]", "MUAD",
             "worst margin [dB / deg]", "AEE",
             f"J (mismatch; guideline {MISMATCH_COST_GUIDELINE_TEXT}) [-]", "mean |∠ε| [deg]"]]
    for label in result.models:
        verification = result.verification.get(label)
        for item in () if verification is None else verification.pairs:
            muad, aee = item.checks.get("muad"), item.checks.get("aee")
            cost = item.checks.get("mismatch-cost")
            rows.append([item.pair, result.model_name(label), item.band.describe(),
                         str(int(item.checked.sum())),
                         "" if muad is None else muad.status,
                         "" if muad is None else f"{_number(muad.worst_margin_db, 3)} / "
                                                 f"{_number(muad.worst_margin_deg, 3)}",
                         "" if aee is None else aee.status,
                         "" if cost is None else _number(cost.cost, 3),
                         _number(mean_phase_error(item), 3)])
    return rows


def _unavailable_envelopes_html(result) -> str:
    """Why an envelope column reads "not available": its source's first sentence."""
    unavailable = {check.envelope: check.source_sentence
                   for verification in result.verification.values()
                   for item in verification.pairs for check in item.checks.values()
                   if check.status == "not available"}
    return "".join(f"<p>{html.escape(name)}: not available — "
                   f"{html.escape(why[:1].lower() + why[1:])}.</p>"
                   for name, why in unavailable.items())


def comparison_cost_rows(result) -> list[list[str]]:
    """With ``[compare] frequency``: J per pair of the time- and frequency-domain fits of each
    model, their sum, and both fits' RMSE and worst TIC on the identification multisteps, from
    the plain simulation and with each multistep's input biases and output reference shifts
    fitted to the fixed model."""
    rows = [["model", "pair", "time-domain fit", "frequency-domain fit"]]
    for label, comparison in result.frequency_comparison.items():
        costs = comparison.pair_costs
        for pair in costs["time"]:
            rows.append([label, f"J {pair}", _number(costs["time"][pair], 3),
                         _number(costs["frequency"][pair], 3)])
        rows.append([label, "J total", *(_number(sum(costs[m].values()), 4)
                                         for m in ("time", "frequency"))])
        for metrics, how in ((comparison.time_metrics, ""),
                             (comparison.shifted_metrics, ", biases and shifts fitted")):
            rows.append([label, f"multistep RMSE{how}", *(
                "diverges" if metrics[m] is None else _number(metrics[m].rmse, 3)
                for m in ("time", "frequency"))])
            rows.append([label, f"multistep TIC, worst output{how}", *(
                "diverges" if metrics[m] is None else _number(float(np.max(metrics[m].tic)), 3)
                for m in ("time", "frequency"))])
    return rows


def comparison_parameter_rows(result) -> list[list[str]]:
    """With ``[compare] frequency``: each model's parameters, time-domain estimate and
    frequency-domain fit, with their Cramér-Rao bounds."""
    rows = [["model", "parameter", "time: value", "time: CR", "frequency: value",
             "frequency: CR"]]
    for label, comparison in result.frequency_comparison.items():
        fits = (result.estimates[label], comparison.frequency_estimate)
        for name in fits[1].parameter_names:
            row = [label, name]
            for estimate in fits:
                item = estimate[name]
                row += [_number(item.value), _number(item.cramer_rao, 3)]
            rows.append(row)
    return rows


def comparison_html(result) -> str:
    """The case report's section on the frequency-domain fit beside the time-domain fit
    (empty unless the case ran it)."""
    if not result.frequency_comparison:
        return ""
    runs = "; ".join(f"{label}: {c.frequency_estimate.iterations} iterations, "
                     f"{c.frequency_estimate.stop_reason}, {c.seconds:.1f} s"
                     for label, c in result.frequency_comparison.items())
    return "\n".join([
        '<h2 id="comparison">Frequency-domain fit beside the time-domain fit</h2>',
        "<p>Each model's structure fitted to the verification sweeps' frequency responses by "
        "the mismatch cost J (frequency-response estimator, from equation-error start values "
        "and varied ones, the lowest J kept), on the compared pairs and, where the sweeps "
        "and the model have them, the on-axis translational accelerations ax/long and ay/lat, "
        "then judged like the time-domain fit: J per pair "
        "on the same measured responses, RMSE and TIC on the identification multisteps, from "
        "the plain simulation and with each multistep's input biases and output reference "
        "shifts fitted to the fixed model (the verification of frequency-domain practice). "
        f"Fits: {html.escape(runs)}.</p>",
        _html_table(comparison_cost_rows(result)),
        "<h3>Estimates with Cramér-Rao bounds</h3>",
        _html_table(comparison_parameter_rows(result))])


def estimator_rows(result) -> list[list[str]]:
    """With ``[compare] estimators``: every estimator's values and Cramér-Rao bounds of the
    model with delays, side by side (and the truth linearisation when there is one)."""
    comparison = result.estimator_comparison
    estimates = comparison.estimates
    truth = result.truth_derivatives if has_truth_model(result) else None
    units = result.estimates["with delays"].units
    header = ["parameter", "unit"]
    for name in estimates:
        header += [f"{name}: value", f"{name}: CR"]
    rows = [header + ([] if truth is None else ["truth linearisation"])]
    names = list(dict.fromkeys(n for e in estimates.values() for n in e.parameter_names))
    for parameter in names:
        stating = next(e for e in estimates.values() if parameter in e.parameter_names)
        row = [parameter, parameter_unit(parameter, units, stating)]
        for estimate in estimates.values():
            if parameter in estimate:
                item = estimate[parameter]
                row += [_number(item.value), _number(item.cramer_rao, 3)]
            else:
                row += ["", ""]
        if truth is not None:
            row.append(_number(truth.get(parameter)))
        rows.append(row)
    return rows


def estimator_fit_rows(result) -> list[list[str]]:
    """With ``[compare] estimators``: each fit's iterations, its own cost and RMSE, and its
    model's simulation of the identification maneuvers (RMSE, det R), and its time."""
    unit = rmse_unit(result.estimates["with delays"].output_units)
    rows = [["estimator", "iterations [-]", "converged", "own cost [-]",
             f"own RMSE [{unit}]", f"simulation RMSE [{unit}]",
             "simulation det R [mixed units]", "fit time [s]"]]
    comparison = result.estimator_comparison
    for name, estimate in comparison.estimates.items():
        simulation = comparison.simulation[name]
        rows.append([name, str(estimate.iterations), "yes" if estimate.converged else "no",
                     _number(estimate.cost), _number(estimate.rmse),
                     "diverges" if simulation is None else _number(simulation.metrics.rmse),
                     "diverges" if simulation is None else _number(simulation.det_r),
                     "the case's fit" if name == result.case.estimator
                     else f"{comparison.seconds[name]:.1f}"])
    return rows


def estimators_html(result) -> str:
    """The case report's section on the estimators side by side (empty unless the case ran
    them)."""
    if result.estimator_comparison is None:
        return ""
    return "\n".join([
        '<h2 id="estimators">Estimators side by side</h2>',
        f"<p>The model with delays, chosen with <code>{html.escape(result.case.estimator)}"
        "</code>, fitted by each estimator to the same identification maneuvers from that "
        "estimator's values (an estimator's own parameters, such as filter error's process "
        "noise F and measurement noise R, from their defaults). Own cost and RMSE are each "
        "estimator's (filter error: exp(2L/N) and the RMSE of the innovations); the "
        "simulation columns judge every fitted model alike: its simulation of the "
        "identification maneuvers, the RMSE and det R of those residuals.</p>",
        _html_table(estimator_fit_rows(result)),
        "<h3>Estimates with Cramér-Rao bounds</h3>",
        _html_table(estimator_rows(result))])


def hybrid_model_rows(result) -> list[list[str]]:
    """With ``[compare] hybrid``: each of the three models' parameters, simulation RMSE and
    det R on the identification maneuvers, and J per verification pair over 1–20 rad/s."""
    comparison = result.hybrid_comparison
    pairs = list(dict.fromkeys(p for costs in comparison.costs.values() for p in costs))
    unit = rmse_unit(comparison.estimate.output_units)
    rows = [["model", "parameters [-]", f"RMSE [{unit}]", "det R [mixed units]",
             *(f"J {pair} [-]" for pair in pairs), "mean J [-]"]]
    for label in HYBRID_MODELS:
        simulation = comparison.simulation[label]
        costs = comparison.costs.get(label, {})
        rows.append([label, str(comparison.parameters[label]),
                     "diverges" if simulation is None else _number(simulation.metrics.rmse),
                     "diverges" if simulation is None else _number(simulation.det_r),
                     *(_number(costs.get(pair), 3) for pair in pairs),
                     _number(mean_cost(costs), 3)])
    return rows


def mode_rows(result) -> list[list[str]]:
    """Each shown model's modes (:func:`rotorid.model.modes.modes`), slowest first."""
    rows = [["model", "eigenvalue [1/s]", "ω_n [rad/s]", "ζ", "time constant [s]",
             "in words", "states"]]
    for label in result.models:
        structure, estimate = result.structures[label], result.estimates[label]
        values = [estimate[name].value for name in structure.parameter_names]
        for mode in modes(structure, values):
            rows.append([
                result.model_name(label), mode.eigenvalue_text,
                _number(mode.frequency, 3) if mode.oscillatory else "–",
                _number(mode.damping, 3) if mode.oscillatory else "–",
                "–" if mode.oscillatory else _number(mode.time_constant, 3),
                mode.describe(), ", ".join(mode.states)])
    return rows


def modes_html(result) -> str:
    """The case report's section on the identified models' modes."""
    return "\n".join([
        '<h2 id="modes">Modes</h2>',
        "<p>The eigenvalues of each model's A (delays set to zero), slowest first: an "
        "oscillatory pair by its natural frequency ω_n and damping ratio ζ, a real mode by its "
        "time constant −1/λ (a growing one by the time it takes to double). States: those "
        "that carry the mode, largest eigenvector component first (in the model's units), "
        "which name its character: v and r for a Dutch roll, p for a roll subsidence, u and θ "
        "for a phugoid.</p>",
        _html_table(mode_rows(result))])


def fit_notes(result) -> dict[str, list[str]]:
    """The final estimates' notes (residuals, modes, maneuvers that stand out), each once:
    note → the model labels whose fit left it, in the estimates' order."""
    found: dict[str, list[str]] = {}
    for label, estimate in result.estimates.items():
        for note in estimate.notes:
            found.setdefault(note, []).append(label)
    return found


def fit_notes_html(result) -> str:
    """The case report's section on what the final fits noted about the data and the
    structure (empty when they noted nothing)."""
    notes = fit_notes(result)
    if not notes:
        return ""
    return "\n".join([
        '<h2 id="fit-notes">Fit notes</h2>',
        "<p>What the estimator recorded at the final fits: how it got there (horizons, "
        "starts) and what it found in the data and the structure that the numbers above do "
        "not show (the models each note concerns in brackets; docs/estimation.md, "
        "\"The fit report\").</p>",
        "<ul>" + "".join(f"<li>{html.escape(note)} ({html.escape(', '.join(labels))})</li>"
                         for note, labels in notes.items()) + "</ul>"])


def handling_quality_rows(result) -> list[list[str]]:
    """ADS-33 bandwidth and phase delay per attitude pair and source (each model's analytic
    response, and the sweeps' measured one)."""
    rows = [["pair", "source", "ω180 [rad/s]", "ω_BW,phase [rad/s]", "ω_BW,gain [rad/s]",
             "bandwidth ω_BW [rad/s]", "phase delay τ_p [s]"]]
    for source, items in result.handling_qualities.items():
        for item in items:
            rows.append([item.pair, source, _number(item.omega_180, 3),
                         _number(item.phase_bandwidth, 3), _number(item.gain_bandwidth, 3),
                         _number(item.bandwidth, 3), _number(item.phase_delay, 3)])
    rows[1:] = sorted(rows[1:], key=lambda row: HQ_PAIRS.index(row[0]))
    return rows


def handling_qualities_html(result) -> str:
    """The case report's section on ADS-33 bandwidth and phase delay (empty when neither the
    models nor the sweeps have an attitude pair)."""
    if not any(result.handling_qualities.values()):
        return ""
    return "\n".join([
        '<h2 id="handling-qualities">Handling qualities: ADS-33 bandwidth and phase delay</h2>',
        "<p>Per ADS-33E-PRF §3.3–3.4 (small-amplitude attitude changes; an aeroplane's pairs "
        "by the same definitions, MIL-STD-1797A's bandwidth criterion): ω180 where the "
        "attitude's phase reaches −180°, the phase bandwidth at −135°, the gain bandwidth "
        "where the gain is 6 dB above its value at ω180, the bandwidth the lesser, and the "
        "phase delay τ_p = −(Φ(2ω180) + 180°)/(57.3·2ω180). The heading is the integrated yaw "
        "rate. Measured: the sweeps' composite responses over their points with γ² ≥ 0.6; "
        "models: their analytic responses on the same frequencies (over 0.1–100 rad/s for a "
        "case without sweeps), so that the crossings are those of the band the data show, not "
        "of slow modes below it. – where the response does not reach the crossing in those "
        "frequencies (the phase delay needs 2ω180 inside them). A heading response nears "
        "−180° slowly, so a few degrees move its crossings far. The standard's Level "
        "boundaries are not applied: read these numbers against its charts.</p>",
        _html_table(handling_quality_rows(result))])


def hybrid_muad_rows(result) -> list[list[str]]:
    """With ``[compare] hybrid``: per model and verification pair, the points inside MUAD of
    those counted (the comparison's band within MUAD's own range)."""
    muad = result.hybrid_comparison.muad
    pairs = list(dict.fromkeys(p for points in muad.values() for p in points))
    rows = [["model", *(f"MUAD {pair} [inside/counted]" for pair in pairs)]]
    for label in HYBRID_MODELS:
        points = muad.get(label, {})
        rows.append([label, *(f"{points[pair][0]}/{points[pair][1]}" if pair in points else "–"
                              for pair in pairs)])
    return rows


def hybrid_derivative_rows(result) -> list[list[str]]:
    """With ``[compare] hybrid``: the roll and pitch derivatives the flapping shapes, of the
    three models (the hybrid's with its flap tilts residualised) with Cramér-Rao bounds, beside
    the truth's 6-DoF linearisation when there is one."""
    comparison = result.hybrid_comparison
    reference = comparison.six_dof_reference
    units = comparison.estimate.units
    rows = [["derivative", "unit", *(["truth (6-DoF)"] if reference is not None else []),
             *(f"{label} (CR)" for label in HYBRID_MODELS),
             *([f"{label}/truth [-]" for label in HYBRID_MODELS] if reference is not None
               else [])]]
    for name in FLAP_SHAPED:
        estimates = [comparison.flap_shaped_derivatives[label][name] for label in HYBRID_MODELS]
        cells = [f"{_number(value)} ({_number(bound, 3)})" if bound is not None
                 else f"{_number(value)} (–)" for value, bound in estimates]
        truth = None if reference is None else reference[name]
        ratios = ([] if reference is None else
                  [_number(value / truth if truth else None, 3) for value, _ in estimates])
        rows.append([name, derivative_unit(name, units),
                     *([_number(truth)] if reference is not None else []), *cells, *ratios])
    return rows


def hybrid_term_rows(result) -> list[list[str]]:
    """With ``[compare] hybrid``: the flap time constants and the hybrid's rotor terms with
    their Cramér-Rao bounds beside the truth's flap-coupled reference (when there is one)."""
    comparison = result.hybrid_comparison
    reference = comparison.reference
    units = comparison.estimate.units
    with_reference = reference is not None
    rows = [["parameter", "unit", "identified", "CR",
             *(["reference (flap-coupled)", "identified/reference [-]"] if with_reference
               else [])]]
    for name, (tau, bound) in comparison.flap_time_constants().items():
        truth = -1.0 / reference[name] if with_reference else None
        rows.append([f"τ_f = −1/{name}", "s", _number(tau), _number(bound, 3),
                     *([_number(truth), _number(tau / truth, 3)] if with_reference else [])])
    for name, term in comparison.rotor_terms().items():
        truth = term["reference"]
        rows.append([name, derivative_unit(name, units), _number(term["identified"]),
                     _number(term["cramer_rao"], 3),
                     *([_number(truth), _number(term["identified"] / truth if truth else None,
                                                3)] if with_reference else [])])
    for name in comparison.structure.parameter_names:
        if delayed_derivative(name):
            item = comparison.estimate[name]
            rows.append([name, "s", _number(item.value), _number(item.cramer_rao, 3),
                         *(["–", "–"] if with_reference else [])])
    return rows


def hybrid_html(result, figures: Sequence = ()) -> str:
    """The case report's section on the three models with its ``figures`` (empty unless the
    case ran it)."""
    if result.hybrid_comparison is None:
        return ""
    comparison = result.hybrid_comparison
    reference = ("The reference is the truth model's full linearisation with the flap rates, "
                 "coning and inflow residualised: the flap-coupled model, not the 6-DoF one."
                 if comparison.reference is not None else "")
    reduced = "" if comparison.removed is None else (
        " Before that fit it was reduced by the case's criteria and selection rule, its flap "
        "damping and hub moments kept: "
        + (f"removed {html.escape(', '.join(comparison.removed))}." if comparison.removed
           else "nothing removed."))
    return "\n".join([
        '<h2 id="hybrid">Three models: no delays, delays, hybrid</h2>',
        "<p>The hybrid rotor-body model (docs/hybrid.md) is the selected model with the "
        "rotor's tip-path-plane tilts β1c, β1s as first-order states: the disc tilt carries the "
        "rotor's rate damping, the cyclic's and the velocities' roll and pitch moments and the "
        "rate terms of the force and yaw equations, with delays on the cyclic into flapping; "
        "it was fitted from the start whose quasi-steady form is the selected model "
        f"({comparison.estimate.iterations} iterations, {comparison.seconds:.1f} s).{reduced} "
        "All three are judged alike: their simulation of the identification maneuvers, and J "
        f"per pair over {html.escape(comparison.band.describe())} "
        f"({MISMATCH_COST_GUIDELINE_TEXT}): this comparison's own band, up to where the "
        f"flapping acts, so its J and MUAD counts differ from those of the verification "
        f"section, which counts {html.escape(result.case.band.describe())}.</p>",
        _html_table(hybrid_model_rows(result)),
        "<p>Points of each pair's error ε inside the MUAD envelope, of those the band and MUAD's "
        "own range count:</p>",
        _html_table(hybrid_muad_rows(result)),
        figures_html(figures),
        "<h3>Roll and pitch derivatives of the three models</h3>",
        "<p>The derivatives the rotor's flapping shapes; the hybrid's with its flap tilts "
        "residualised (e.g. L_p = τ_f·L_beta1s), their bounds propagated from its fit"
        + (", beside the truth model's 6-DoF linearisation (rotor and inflow residualised)"
           if comparison.six_dof_reference is not None else "")
        + ". A six-dof model's derivative of 0 with no bound was removed by the "
        "reduction.</p>",
        _html_table(hybrid_derivative_rows(result)),
        "<h3>Rotor terms of the hybrid model</h3>",
        f"<p>{reference}</p>" if reference else "",
        _html_table(hybrid_term_rows(result))])


def _csv(rows: Sequence[Sequence[str]]) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    return buffer.getvalue()


def _html_table(rows: Sequence[Sequence[str]], highlight: int | None = None) -> str:
    head = "".join(f"<th>{html.escape(c)}</th>" for c in rows[0])
    body = []
    for row in rows[1:]:
        marked = highlight is not None and row[highlight] in ("yes", "fail", "differs")
        cells = "".join(f"<td>{html.escape(str(c))}</td>" for c in row)
        attributes = ' class="mark"' if marked else ""
        body.append(f"<tr{attributes}>{cells}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def has_truth_model(result) -> bool:
    """Whether the case's data come from a truth model (a simulated helicopter); a
    files-source case is about the user's own aircraft, with measured data only."""
    return result.truth_derivatives is not None


# ----------------------------------------------------------------- HTML
_STYLE = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:0.8em 0;font-size:0.85em;display:block;max-width:100%;
overflow-x:auto}
th,td{border:1px solid #ccc;padding:3px 7px;text-align:right}th{background:#eee}
td:first-child,th:first-child{text-align:left}tr.mark{background:#fff3c4}
figure{margin:1em 0 1.6em}figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:0.88em;color:#333;max-width:62em}
nav.toc{background:#f7f7f7;border:1px solid #ddd;padding:0.4em 1.2em;margin:1em 0}
nav.toc ul{margin:0.2em 0;padding-left:1.2em}.pass{color:#176117}.fail{color:#a11}
.na{color:#777}code{background:#f4f4f4;padding:0 3px}"""


def _page(title: str, body: str, contents: Sequence[tuple[str, str]] = ()) -> str:
    """A self-contained page; ``contents`` lists (anchor, heading) pairs for its table of
    contents (nested entries start their heading with two spaces)."""
    toc = ""
    if contents:
        items = "".join(
            f'<li{" style=margin-left:1.2em" if text.startswith("  ") else ""}>'
            f'<a href="#{anchor}">{html.escape(text.strip())}</a></li>'
            for anchor, text in contents)
        toc = f'<nav class="toc"><strong>Contents</strong><ul>{items}</ul></nav>\n'
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<meta name=\"viewport\" content=\"width=device-width\">"
            f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head>"
            f"<body>\n<h1>{html.escape(title)}</h1>\n{toc}{body}\n</body></html>\n")


_VERDICT_CLASS = {"holds": "pass", "does not hold": "fail", "not checked": "na"}


def claim_rows(claims) -> list[list[str]]:
    """The claims table (the paper's as it states them, or the guidelines): claim, evidence
    (each number with its unit), verdict, why not checked."""
    return [["claim", "evidence [units as stated]", "verdict", "why not checked"]] + [
        [c.claim, c.evidence, c.verdict, c.reason] for c in claims]


def claims_html(claims) -> str:
    rows = "".join(f"<tr><td>{html.escape(c.claim)}</td><td>{html.escape(c.evidence)}</td>"
                   f'<td><span class="{_VERDICT_CLASS[c.verdict]}">{c.verdict}</span></td>'
                   f"<td>{html.escape(c.reason)}</td></tr>" for c in claims)
    head = "".join(f"<th>{html.escape(h)}</th>" for h in claim_rows(())[0])
    return f"<table><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>"


def figures_html(figures: Sequence[ReportFigure], prefix: str = "figures/") -> str:
    """Each figure linked to its SVG, with its caption under it."""
    return "".join(
        f'<figure><a href="{prefix}{html.escape(f.file[:-4])}.svg">'
        f'<img src="{prefix}{html.escape(f.file)}" alt="{html.escape(f.file)}"></a>'
        f"<figcaption>{f.caption}</figcaption></figure>" for f in figures)


def pair_anchor(pair: str) -> str:
    """HTML id of a verified pair's section, e.g. ``pair-q-long``."""
    return "pair-" + file_stem(pair.replace("/", "-"))


def _other_selections(path) -> str:
    """Where the other selection rules land on the path (tolerance rules with their
    tolerance)."""
    selections = path.selections()
    others = [f"{rule} ({path.rmse_tolerance:.0%}) step {index}" if rule != "lowest-rmse"
              else f"{rule} step {index}"
              for rule, index in selections.items() if rule != path.rule]
    text = f"Other rules would select: {', '.join(others)}." if others else ""
    lowest, lean = selections["lowest-rmse"], selections["parsimonious"]
    if path.rule == "lowest-rmse" and lean > lowest:
        steps = path.steps
        spread = steps[lean].rmse / steps[lowest].rmse - 1.0
        text += (f" The RMSE is flat over the path: step {lean} "
                 f"({plural(steps[lean].n_parameters, 'parameter')}) lies within "
                 f"{spread:.2%} of the lowest, so the lowest-RMSE rule chooses among nearly equal fits; the "
                 f"parsimonious rule ([reduction] rule = \"parsimonious\") keeps the smaller "
                 f"one.")
    return text


def _delays_text(result) -> str:
    estimate = result.estimates["with delays"]
    parts = [f"{delayed_derivative(n)} {estimate.values[i]:.3f} ± {estimate.cramer_rao[i]:.2g} s"
             for i, n in enumerate(estimate.parameter_names) if delayed_derivative(n)]
    declared = result.case.delayed(result.structures["with delays"].template.name)
    text = ", ".join(parts) or ("none" if declared else "none declared")
    if result.dropped_delays:
        text += (f" (dropped as undetermined: {', '.join(result.dropped_delays)})")
    truth = result.truth_delays
    if truth is not None:
        text += (". The truth model's own equivalent delays (its full linearisation's q and p "
                 f"responses to the cyclic, fitted over {truth.band[0]:g}–{truth.band[1]:g} "
                 "rad/s with the same delays, relative error "
                 f"{truth.relative_rms:.1%}): " + ", ".join(
                     f"{n} {v:.3f} s" for n, v in truth.delays.items()))
    return text + _profiles_text(result.delay_profiles)


#: A delay profile whose RMSE stays within this of the free fit's does not determine it.
FLAT_PROFILE = 0.01


def _profiles_text(profiles) -> str:
    """What the delay profiles say beyond the bounds: the delays whose profile is flat, and
    those that zero delay fits nearly as well (within :data:`FLAT_PROFILE`)."""
    if not profiles:
        return ""
    flat = [p for p in profiles if p.largest_rise < FLAT_PROFILE]
    near_zero = [p for p in profiles if p not in flat and p.rise_at_zero is not None
                 and p.rise_at_zero < FLAT_PROFILE]
    span = f"{min(p.grid.min() for p in profiles):g}–{max(p.grid.max() for p in profiles):g} s"
    parts = []
    if flat:
        parts.append("flat for " + ", ".join(
            f"{delayed_derivative(p.delay)} (at most {p.largest_rise:+.2%})" for p in flat)
            + ": the data do not determine " + ("it" if len(flat) == 1 else "them")
            + ", whatever the bounds say")
    if near_zero:
        parts.append("zero delay fits within 1 % for " + ", ".join(
            f"{delayed_derivative(p.delay)} ({p.rise_at_zero:+.2%})" for p in near_zero))
    if not parts:
        return f". The delay profiles (RMSE over {span}) determine every kept delay"
    return f". The delay profiles (RMSE relative to the free fit's, over {span}): " + \
        "; ".join(parts)


def _band_source(band) -> str:
    """Where the case's verification band comes from, in words."""
    if band == DEFAULT_BAND:
        return ("the default: the paper's MUAD practice, γ² > 0.8, on the range the MUAD "
                "envelopes are defined on")
    return "set by the case's [verification] table"


def _kinds(maneuvers) -> str:
    """The distinct maneuver kinds of a set (metadata ``kind``) in order of appearance, as
    `` (3211, sweep)``; empty when no maneuver states its kind."""
    kinds = dict.fromkeys(str(m.metadata["kind"]) for m in maneuvers if "kind" in m.metadata)
    return f" ({', '.join(kinds)})" if kinds else ""


def _verification_verdicts(result) -> tuple[list[str], list[str]]:
    """(passed, failed): one line per pair of the model with delays and its MUAD check."""
    passed, failed = [], []
    verification = result.verification.get("with delays")
    for item in () if verification is None else verification.pairs:
        check = item.checks.get("muad")
        if check is None or check.passed is None:
            continue
        line = (f"{item.pair} {check.n_inside}/{check.n_used} points inside MUAD "
                f"(worst {check.worst_margin_db:+.2f} dB / {check.worst_margin_deg:+.1f}°"
                f"{check.outside_text()})")
        (passed if check.passed else failed).append(line)
    return passed, failed


def summary_html(result, claims) -> str:
    """The case in a few lines: selected structure, verdicts, what fails and why."""
    path = result.path
    items = [f"Selected structure: step {path.selected_index} of {len(path.steps) - 1} by rule "
             f"<code>{html.escape(path.rule)}</code>, {path.selected.n_parameters} parameters; "
             f"{result.rmse_summary()} "
             f"(delays: {html.escape(_delays_text(result).split('. ')[0])})."]
    passed, failed = _verification_verdicts(result)
    if result.verification_data is None or not len(result.verification_data):
        items.append("Frequency-domain verification: not done, the case gives no sweeps "
                     "([data] verification).")
    else:
        items.append(f"Frequency-domain verification, {result.final_model_name}, in the "
                     f"verification band "
                     f"{html.escape(result.case.band.describe())}: {len(passed)} of "
                     f"{len(passed) + len(failed)} checked pairs inside MUAD"
                     + (f"; outside: {html.escape('; '.join(failed))}" if failed else "") + ".")
    if result.data_warnings:
        items.append(f"The checks of the identification data before the fit warned "
                     f"{len(result.data_warnings)} time(s): <ul>" + "".join(
                         f"<li>{html.escape(w)}</li>" for w in result.data_warnings) + "</ul>")
    if claims:
        decided, not_holding = claims_tally(claims)
        items.append(f"{claims_title(result)}: {len(decided) - len(not_holding)} of "
                     f"{len(decided)} hold" + ("; not: " + html.escape("; ".join(
                         f"{c.claim} ({c.evidence})" for c in not_holding))
                         if not_holding else "") + ".")
    return "<ul>" + "".join(f"<li>{item}</li>" for item in items) + "</ul>"


def case_html(result, figures: Mapping[str, Sequence[ReportFigure]],
              claims) -> str:
    """The case report page (figures referenced relative to the case directory; ``claims``
    from :func:`rotorid.study.claims.case_claims`)."""
    case, path = result.case, result.path
    estimates = result.estimates
    truth = has_truth_model(result)
    notes = sorted({n for v in result.verification.values() for n in v.notes})
    seconds = ", ".join(f"{k} {v:.0f} s" for k, v in result.seconds.items())
    if result.resumed_steps:
        seconds = (f"{seconds} (this run, which resumed after {result.resumed_steps} finished "
                   f"reduction steps)")
    verification_count = 0 if result.verification_data is None else len(result.verification_data)
    contents = [("summary", "Summary")]
    body = [
        f"<p>{html.escape(case.description)}. Trim: "
        f"{html.escape(result.condition.describe(estimates['no delays'].units))}. "
        f"{len(result.identification)} identification maneuvers"
        f"{html.escape(_kinds(result.identification))}, {verification_count} verification "
        f"maneuvers{'; ' + case.run_label if case.run_label else ''}. Units: "
        f"{estimates['no delays'].units}; "
        f"{html.escape(rmse_basis_text(estimates['no delays']))}. "
        f"Time: {html.escape(seconds)} (the figures and this report come after).</p>",
        "<p>Machine-readable results: <a href=\"result.json\">result.json</a>; tables: "
        + ", ".join(f'<a href="tables/{t}.csv">{t}.csv</a>'
                    for t in case_table_names(result, claims))
        + ".</p>",
        '<h2 id="summary">Summary</h2>', summary_html(result, claims)]
    if claims:
        title = f"{claims_title(result)}, measured"
        contents.append(("claims", title))
        body += [f'<h2 id="claims">{html.escape(title)}</h2>', claims_html(claims)]
    keys = bool(result.key_derivative_names())
    delays = _delays_text(result)
    # the paper's tables where the case reproduces the paper
    appendix = " (Appendix B)" if case.data_source in PAPER_SOURCES else ""
    contents += [("reduction", "Model reduction"), ("delays", "Time delays"),
                 ("parameters", "Identified parameters"),
                 *((("key-derivatives", "Key derivatives"),) if keys else ()),
                 ("modes", "Modes"), *((("fit-notes", "Fit notes"),) if fit_notes(result)
                                        else ()),
                 ("time-histories", "Time histories"),
                 *((("state-estimates", "State estimates"),) if figures.get("states")
                   else ()),
                 ("verification", "Frequency-domain verification")]
    key_text = (f"Identified ({result.final_model_name}) beside the truth model's residualised "
                "6-DoF linearisation and the published Helisim Bo-105 values (Padfield 2007). "
                "The verdict here compares the sign with the published value's (else the "
                "truth linearisation's: the basis column); the claims above check "
                "the paper's statements (e.g. N_v > 0 in hover), which the truth model itself "
                "may contradict, so a derivative can hold the paper's claim and differ from "
                "the truth model's sign."
                if truth else f"Identified values of the {result.final_model_name} (measured "
                              "data: compared only with the reference values the case file "
                              "gives, if any).")
    body += [
        '<h2 id="reduction">Model reduction</h2>',
        f"<p>Selected step {path.selected_index} of {len(path.steps) - 1} by rule "
        f"<code>{path.rule}</code>: "
        f"{path.selected.n_parameters} parameters, RMSE {path.selected.rmse:.4f}; "
        f"removed in order: {html.escape(', '.join(path.removed) or 'none')}. "
        f"{_other_selections(path)}</p>",
        *([f"<p><strong>The reduction {html.escape(path.stopped)}.</strong> The selection "
           f"is among the steps reached.</p>"] if path.stopped else []),
        figures_html(figures.get("reduction", [])),
        f"<h3>Removed parameters{appendix}</h3>", _html_table(removed_rows(result), 7),
        '<h2 id="delays">Time delays</h2>',
        f"<p>{html.escape(delays[:1].upper() + delays[1:])}. "
        f"{result.rmse_summary()}"
        f"{'' if result.kept_delays else ': one model, shown as the ' + ONE_MODEL}.</p>",
        figures_html(figures.get("delays", [])),
        f'<h2 id="parameters">Identified parameters{appendix}</h2>',
        "<p>CR: Cramér-Rao bound (in the parameter's unit); CR % and I %: Cramér-Rao bound and "
        "insensitivity relative to the value.</p>", _html_table(parameter_rows(result)),
        *(('<h2 id="key-derivatives">Key derivatives</h2>', f"<p>{key_text}</p>",
            _key_table(result, truth)) if keys else ()),
        reference_html(result), modes_html(result), fit_notes_html(result),
        '<h2 id="time-histories">Time histories of the identification maneuvers</h2>',
        figures_html(figures.get("time", [])),
        *(('<h2 id="state-estimates">State estimates of the identification maneuvers</h2>',
           "<p>What the estimator's filter makes of each record at the model with delays: the "
           "aircraft's states and its noise model's disturbances and gusts, each with the "
           "spread of its error; as maneuver files in <code>state_estimates/</code>. A gust "
           "estimate far larger than any plausible turbulence is a gust on its ridge "
           "(docs/estimation.md, \"The filter's state estimates\").</p>",
           figures_html(figures["states"])) if figures.get("states") else ()),
        '<h2 id="verification">Frequency-domain verification on the sweeps</h2>',
        f"<p>Every verdict (MUAD, AEE, the mismatch cost J, and the analytic comparison in "
        f"result.json) counts the same points: the verification band "
        f"{html.escape(result.case.band.describe())} ({_band_source(result.case.band)}).</p>",
        _html_table(verification_rows(result)), _unavailable_envelopes_html(result)]
    if notes:
        body += ["<h3>Verification notes</h3>",
                 "<ul>" + "".join(f"<li>{html.escape(n)}</li>" for n in notes) + "</ul>"]
    bode = {f.pair: f for f in figures.get("bode", [])}
    for error in figures.get("frequency", []):
        anchor = pair_anchor(error.pair)
        contents.append((anchor, f"  {error.pair}"))
        shown = [error] + ([bode[error.pair]] if error.pair in bode else [])
        body += [f'<h3 id="{anchor}">{html.escape(error.pair)}</h3>', figures_html(shown)]
    if result.case.reference:
        before = ("key-derivatives", "Key derivatives") if keys else ("parameters",
                                                                      "Identified parameters")
        contents.insert(contents.index(before) + 1, ("reference", "Reference values"))
    handling = handling_qualities_html(result)
    if handling:
        contents.append(("handling-qualities", "Handling qualities"))
        body.append(handling)
    if result.frequency_comparison:
        contents.append(("comparison", "Frequency-domain fit"))
        body.append(comparison_html(result))
    if result.estimator_comparison is not None:
        contents.append(("estimators", "Estimators side by side"))
        body.append(estimators_html(result))
    if result.hybrid_comparison is not None:
        contents.append(("hybrid", "Three models: no delays, delays, hybrid"))
        body.append(hybrid_html(result, figures.get("hybrid", [])))
    return _page(f"rotorid study — case {result.name}", "\n".join(body), contents)


#: Row builders of a case's tables by CSV name (``checks`` is built from the claims).
_TABLE_ROWS = {
    "removed": removed_rows, "parameters": parameter_rows,
    "key_derivatives": key_derivative_rows, "verification": verification_rows,
    "reference": reference_rows, "comparison_costs": comparison_cost_rows,
    "comparison_parameters": comparison_parameter_rows, "estimator_fits": estimator_fit_rows,
    "estimators": estimator_rows, "hybrid_models": hybrid_model_rows,
    "hybrid_terms": hybrid_term_rows, "hybrid_muad": hybrid_muad_rows,
    "hybrid_derivatives": hybrid_derivative_rows, "handling_qualities": handling_quality_rows,
    "modes": mode_rows,
}


def case_table_names(result, claims) -> list[str]:
    """The case's tables (``tables/<name>.csv``) in the report's order: the three every case
    has, the key derivatives where its structure can hold any, then those of its ``claims``,
    ``[reference]`` values and comparisons it ran."""
    return ["removed", "parameters",
            *(("key_derivatives",) if result.key_derivative_names() else ()), "modes",
            "verification",
            *(("handling_qualities",) if any(result.handling_qualities.values()) else ()),
            *(("checks",) if claims else ()),
            *(("reference",) if result.case.reference else ()),
            *(("comparison_costs", "comparison_parameters")
              if result.frequency_comparison else ()),
            *(("estimator_fits", "estimators")
              if result.estimator_comparison is not None else ()),
            *(("hybrid_models", "hybrid_muad", "hybrid_derivatives", "hybrid_terms")
              if result.hybrid_comparison is not None else ())]


def write_case_outputs(result, directory: str | Path,
                       progress: Callable[[str], None] | None = None) -> Path:
    """Write the figures, tables and ``report.html`` of one case; returns the report path.
    A case about measured data only (no truth model) gets the guidelines as its claims.
    ``progress(message)`` hears how many figures are written (:func:`case_figures`)."""
    directory = Path(directory)
    figures = case_figures(result, directory / "figures", progress)
    tables = directory / "tables"
    tables.mkdir(exist_ok=True)
    claims = case_claims(result)
    rows_of = {**_TABLE_ROWS, "checks": lambda _: claim_rows(claims)}
    for name in case_table_names(result, claims):
        atomic_write(tables / f"{name}.csv", _csv(rows_of[name](result)))
    return atomic_write(directory / "report.html", case_html(result, figures, claims))


def write_study_report(results: Mapping[str, object], out_dir: str | Path) -> Path:
    """Write ``<out>/report.html``: one summary per case, linking each case report."""
    out_dir = Path(out_dir)
    rmse_units = {rmse_unit(r.estimates["no delays"].output_units) for r in results.values()}
    unit = rmse_units.pop() if len(rmse_units) == 1 else "- or mixed units"
    rows = [["case", "trim", "parameters (removed) [-]", f"RMSE no delays [{unit}]",
             f"RMSE with delays [{unit}]", "delays [s]", "claims or guidelines holding [-]"]]
    sections, contents = [], [("overview", "Overview")]
    for name, result in results.items():
        checks = case_claims(result)
        decided, failed = claims_tally(checks)
        units = result.estimates["no delays"].units
        rows.append([name, result.condition.describe(units),
                     f"{result.path.selected.n_parameters} ({len(result.path.removed)})",
                     result.rmse_text("no delays"),
                     result.rmse_text("with delays") if result.kept_delays else "–",
                     _delays_text(result),
                     f"{len(decided) - len(failed)}/{len(decided)}" if checks else "–"])
        link = f"{html.escape(name)}/report.html"
        anchor = "case-" + file_stem(name)
        contents.append((anchor, f"Case {name} ({flight_label(result.condition, units)})"))
        rmse = ReportFigure("rmse.png", rmse_caption(result.path))
        sections.append(f'<h2 id="{anchor}"><a href="{link}">Case {html.escape(name)}</a></h2>'
                        + summary_html(result, checks)
                        + figures_html([rmse], prefix=f"{html.escape(name)}/figures/")
                        + (claims_html(checks) if checks else ""))
    bases = dict.fromkeys(rmse_basis_text(r.estimates["no delays"]) for r in results.values())
    body = ('<h2 id="overview">Overview</h2><p>Each case links to its full report: reduction '
            "path, parameter tables, time histories, frequency-domain verification. "
            + html.escape("; ".join(bases)) + ".</p>"
            + _html_table(rows) + "\n".join(sections))
    return atomic_write(out_dir / "report.html", _page("rotorid study report", body, contents))


class StudyReport:
    """The study pipeline's report writer (:class:`rotorid.study.pipeline.ReportWriter`):
    figures, tables and HTML per case, and the study's overview page."""

    def write_case(self, result, directory: str | Path,
                   progress: Callable[[str], None] | None = None) -> Path:
        return write_case_outputs(result, directory, progress)

    def write_study(self, results: Mapping[str, object], out_dir: str | Path) -> Path:
        return write_study_report(results, out_dir)
