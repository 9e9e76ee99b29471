"""Figures, tables and HTML reports of a study, as the paper presents its results.

Per case (``<out>/<case>/``):

* ``figures/rmse.{png,svg}``: RMSE versus removed parameters (figs. 1, 6);
* ``figures/time_<maneuver>.{png,svg}``: truth, model without and with delays on each 2311
  input (figs. 2, 3, 7, 8, 11, 13, 15, 17);
* ``figures/error_<output>_<input>.{png,svg}``: ε against MUAD/AEE with coherence for each
  verified sweep pair (figs. 4, 5, 9, 10, 12, 14, 16, 18);
* ``figures/bode_<output>_<input>.{png,svg}``: Bode overlays of truth and model with delays;
* ``tables/removed.csv``, ``tables/parameters.csv`` (Appendix B), ``tables/key_derivatives.csv``,
  ``tables/checks.csv`` (the paper's claims, measured); with ``[compare] frequency``
  ``tables/comparison_costs.csv`` and ``tables/comparison_parameters.csv`` (the
  frequency-domain fit beside the time-domain fit);
* ``report.html`` linking all of it.

Per study: ``<out>/report.html``, a summary of every case linking the case reports.
Every file is written atomically.
"""

from __future__ import annotations

import csv
import html
import io
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.io import atomic_write
from rotorid.model.derivatives import delayed_derivative
from rotorid.report.plots.case import plot_rmse_path, plot_time_histories, save_figure
from rotorid.report.plots.frequency import plot_bode, plot_error
from rotorid.study.expectations import check_signs
from rotorid.study.result import KEY_DERIVATIVES, MODELS
from rotorid.units import unit_system
from rotorid.verification.compare import COHERENCE_THRESHOLD, envelopes_by_name
from rotorid.verification.envelopes import error_db_deg
from rotorid.verification.pairs import parse_pair

#: The on-axis pairs the paper requires inside the MUAD bounds with delays.
ON_AXIS_PAIRS = ("q/long", "p/lat", "r/ped", "az/coll")
#: The off-axis pairs whose phase error the delays should reduce.
OFF_AXIS_PAIRS = ("p/long", "q/lat")
#: The paper's plausible range of equivalent rotor delays, s.
DELAY_RANGE = (0.02, 0.15)
#: The paper's bound on the time-domain RMSE of the selected model.
RMSE_LIMIT = 2.0


@attrs.frozen
class Check:
    """One of the paper's claims, measured on a case: ``passed`` None means not applicable."""

    claim: str
    measured: str
    passed: bool | None


# ----------------------------------------------------------------- measured claims
def mean_phase_error(item, threshold: float = COHERENCE_THRESHOLD) -> float | None:
    """Mean |∠ε| in deg over the points where the truth's coherence ≥ ``threshold``."""
    _, phase = error_db_deg(item.error)
    with np.errstate(invalid="ignore"):
        used = (item.coherence >= threshold) & np.isfinite(phase)
    return float(np.mean(np.abs(phase[used]))) if used.any() else None


def _verified_pair(result, label: str, pair: str):
    verification = result.verification.get(label)
    return None if verification is None else verification.get(pair)


def paper_checks(result) -> list[Check]:
    """The paper's claims for one case (the study issue's acceptance list), measured."""
    checks = []
    for label in MODELS:
        rmse = result.estimates[label].rmse
        checks.append(Check(f"time-domain RMSE ≤ {RMSE_LIMIT:g} ({label})", f"{rmse:.3f}",
                            rmse <= RMSE_LIMIT))
    for pair in OFF_AXIS_PAIRS:
        errors = [_verified_pair(result, label, pair) for label in MODELS]
        phases = [None if e is None else mean_phase_error(e) for e in errors]
        if None in phases:
            checks.append(Check(f"{pair}: smaller phase error with delays",
                                "no coherent points or not verified", None))
            continue
        checks.append(Check(f"{pair}: smaller phase error with delays",
                            f"mean |∠ε| {phases[0]:.1f}° without, {phases[1]:.1f}° with",
                            phases[1] < phases[0]))
    for pair in ON_AXIS_PAIRS:
        item = _verified_pair(result, "with delays", pair)
        check = None if item is None else item.checks.get("muad")
        if check is None or check.passed is None:
            checks.append(Check(f"{pair} with delays inside MUAD (γ² ≥ {COHERENCE_THRESHOLD:g})",
                                "not verified" if check is None else check.status, None))
            continue
        checks.append(Check(f"{pair} with delays inside MUAD (γ² ≥ {COHERENCE_THRESHOLD:g})",
                            f"{check.n_inside}/{check.n_used} points inside, worst margin "
                            f"{check.worst_margin_db:+.2f} dB / {check.worst_margin_deg:+.1f}°",
                            bool(check.passed)))
    estimate = result.estimates["with delays"]
    low, high = DELAY_RANGE
    truth = {} if result.truth_delays is None else result.truth_delays.delays
    for i, name in enumerate(estimate.parameter_names):
        derivative = delayed_derivative(name)
        if derivative is not None:
            value = float(estimate.values[i])
            measured = f"{value:.3f} s"
            if derivative in truth:
                measured += f"; truth model's equivalent delay {truth[derivative]:.3f} s"
            checks.append(Check(f"delay on {derivative} within {low:g}–{high:g} s", measured,
                                low <= value <= high))
    for sign in key_derivative_checks(result):
        if sign.verdict in ("agrees", "differs"):
            checks.append(Check(f"sign of {sign.name} ({sign.basis})",
                                f"{sign.identified:+.4g} {sign.unit}", sign.verdict == "agrees"))
    return checks


def claims_tally(checks: Sequence[Check]) -> tuple[list[Check], list[Check]]:
    """(decided, failed): the checks with a verdict, and those that do not hold."""
    decided = [c for c in checks if c.passed is not None]
    return decided, [c for c in decided if not c.passed]


def key_derivative_checks(result):
    """Sign checks of the key derivatives of the model with delays."""
    estimate = result.estimates["with delays"]
    identified = {name: (float(estimate.values[i]), float(estimate.cramer_rao[i]))
                  for i, name in enumerate(estimate.parameter_names)}
    return check_signs(KEY_DERIVATIVES, identified, result.condition.airspeed_kt,
                       estimate.units, result.truth_derivatives)


# ----------------------------------------------------------------- tables
def _number(value, digits: int = 4) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return f"{value:.{digits}g}"


def removed_rows(result) -> list[list[str]]:
    """Appendix B, removed parameters: step, parameter, criterion, metric, RMSE, iterations."""
    rows = [["step", "removed", "criterion", "metric %", "parameters", "RMSE", "iterations",
             "selected"]]
    selected = result.path.selected_index
    for step in result.path.steps:
        removal = step.removal
        rows.append([str(step.index), "—" if removal is None else removal.parameter,
                     "" if removal is None else removal.criterion,
                     "" if removal is None else _number(removal.metric, 3),
                     str(step.n_parameters), f"{step.rmse:.4f}", str(step.estimate.iterations),
                     "yes" if step.index == selected else ""])
    return rows


def parameter_rows(result) -> list[list[str]]:
    """Appendix B, identified parameters of both models: value, CR bound, CR %, insens. %."""
    header = ["parameter"]
    for label in MODELS:
        header += [f"{label}: value", f"{label}: CR", f"{label}: CR %", f"{label}: I %"]
    names = list(result.estimates["no delays"].parameter_names)
    names += [n for n in result.estimates["with delays"].parameter_names if n not in names]
    rows = [header]
    for name in names:
        row = [name]
        for label in MODELS:
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


def key_derivative_rows(result) -> list[list[str]]:
    rows = [["derivative", "unit", "identified", "CR bound", "truth linearisation",
             "identified / truth", "published reference", "expected sign from", "sign"]]
    for check in key_derivative_checks(result):
        rows.append([check.name, check.unit, _number(check.identified), _number(check.cramer_rao, 3),
                     _number(check.truth_linearisation), _number(check.ratio_to_truth, 3),
                     _number(check.reference, 3), check.basis, check.verdict])
    return rows


def verification_rows(result) -> list[list[str]]:
    """Per sweep pair and model: coherent points, MUAD/AEE status, worst margins, J."""
    rows = [["pair", "model", f"points γ² ≥ {COHERENCE_THRESHOLD:g}", "MUAD", "worst margin dB / deg", "AEE",
             "J (mismatch)", "mean |∠ε| deg"]]
    for label in MODELS:
        verification = result.verification.get(label)
        for item in () if verification is None else verification.pairs:
            muad, aee = item.checks.get("muad"), item.checks.get("aee")
            cost = item.checks.get("mismatch-cost")
            rows.append([item.pair, label, "" if muad is None else str(muad.n_used),
                         "" if muad is None else muad.status,
                         "" if muad is None else f"{_number(muad.worst_margin_db, 3)} / "
                                                 f"{_number(muad.worst_margin_deg, 3)}",
                         "" if aee is None else aee.status,
                         "" if cost is None else _number(cost.cost, 3),
                         _number(mean_phase_error(item), 3)])
    return rows


def comparison_cost_rows(result) -> list[list[str]]:
    """With ``[compare] frequency``: J per pair of the time- and frequency-domain fits of each
    model, their sum, and both fits' RMSE and worst TIC on the identification multisteps."""
    rows = [["model", "pair", "time-domain fit", "frequency-domain fit"]]
    for label, comparison in result.frequency_comparison.items():
        costs = comparison.pair_costs
        for pair in costs["time"]:
            rows.append([label, f"J {pair}", _number(costs["time"][pair], 3),
                         _number(costs["frequency"][pair], 3)])
        rows.append([label, "J total", *(_number(sum(costs[m].values()), 4)
                                         for m in ("time", "frequency"))])
        metrics = comparison.time_metrics
        rows.append([label, "multistep RMSE", *(
            "diverges" if metrics[m] is None else _number(metrics[m].rmse, 3)
            for m in ("time", "frequency"))])
        rows.append([label, "multistep TIC, worst output", *(
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
        for name in fits[0].parameter_names:
            row = [label, name]
            for estimate in fits:
                i = estimate.index(name)
                row += [_number(float(estimate.values[i])),
                        _number(float(estimate.cramer_rao[i]), 3)]
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
        "<h2>Frequency-domain fit beside the time-domain fit</h2>",
        "<p>Each model's structure fitted to the verification sweeps' frequency responses by "
        "the mismatch cost J (frequency-response estimator, from equation-error start values), "
        "then judged like the time-domain fit: J per pair on the same measured responses, "
        f"RMSE and TIC on the identification multisteps. Fits: {html.escape(runs)}.</p>",
        _html_table(comparison_cost_rows(result)),
        "<h3>Estimates with Cramér-Rao bounds</h3>",
        _html_table(comparison_parameter_rows(result))])


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


# ----------------------------------------------------------------- figures
def _stem(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)


def case_figures(result, figures_dir: Path) -> dict[str, list[str]]:
    """Write the case's figures; returns section → figure file names (PNG, relative)."""
    figures_dir.mkdir(parents=True, exist_ok=True)
    written = {"reduction": [], "time": [], "frequency": [], "bode": []}
    units = unit_system(result.estimates["with delays"].units)
    name = result.name
    figure = plot_rmse_path(result.path, title=f"{name}: RMSE versus removed parameters")
    save_figure(figure, figures_dir / "rmse")
    written["reduction"].append("rmse.png")
    doublets = [m for m in result.identification if m.metadata.get("kind") == "2311"]
    outputs = ({label: result.simulated(label, ManeuverSet(doublets,
                                                           hold=result.identification.hold))
                for label in MODELS} if doublets else {})
    for index, maneuver in enumerate(doublets):
        simulated = {label: outputs[label][index] for label in MODELS}
        figure = plot_time_histories(maneuver, simulated,
                                     title=f"{name}: 2311 input on {maneuver.metadata.get('axis')}"
                                           f" ({maneuver.name})")
        stem = f"time_{_stem(maneuver.name)}"
        save_figure(figure, figures_dir / stem)
        written["time"].append(f"{stem}.png")
    envelopes = [e for e in envelopes_by_name(result.case.envelopes).values()
                 if e.kind == "bounds"]
    reference = result.verification.get("with delays")
    for item in () if reference is None else reference.pairs:
        output, control = parse_pair(item.pair)
        errors = {label: result.verification[label][item.pair] for label in MODELS
                  if label in result.verification}
        figure = plot_error(errors, envelopes,
                            title=f"{name}: {item.pair} error ε = H_model/H_truth (sweeps)")
        stem = f"error_{output}_{control}"
        save_figure(figure, figures_dir / stem)
        written["frequency"].append(f"{stem}.png")
        figure = plot_bode(item, output_unit=units.label(output),
                           title=f"{name}: {item.pair} frequency responses (model with delays)")
        stem = f"bode_{output}_{control}"
        save_figure(figure, figures_dir / stem)
        written["bode"].append(f"{stem}.png")
    return written


# ----------------------------------------------------------------- HTML
_STYLE = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:0.8em 0;font-size:0.85em}
th,td{border:1px solid #ccc;padding:3px 7px;text-align:right}th{background:#eee}
td:first-child,th:first-child{text-align:left}tr.mark{background:#fff3c4}
img{max-width:100%;border:1px solid #ddd;margin:0.4em 0}.pass{color:#176117}.fail{color:#a11}
.na{color:#777}code{background:#f4f4f4;padding:0 3px}"""


def _page(title: str, body: str) -> str:
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head>"
            f"<body>\n<h1>{html.escape(title)}</h1>\n{body}\n</body></html>\n")


def _verdict(passed: bool | None) -> str:
    if passed is None:
        return '<span class="na">n/a</span>'
    return '<span class="pass">yes</span>' if passed else '<span class="fail">no</span>'


def checks_html(checks: Sequence[Check]) -> str:
    rows = "".join(f"<tr><td>{html.escape(c.claim)}</td><td>{html.escape(c.measured)}</td>"
                   f"<td>{_verdict(c.passed)}</td></tr>" for c in checks)
    return ("<table><thead><tr><th>claim</th><th>measured</th><th>holds</th></tr></thead>"
            f"<tbody>{rows}</tbody></table>")


def _images(files: Sequence[str], prefix: str = "figures/") -> str:
    return "".join(f'<p><a href="{prefix}{html.escape(f[:-4])}.svg">'
                   f'<img src="{prefix}{html.escape(f)}" alt="{html.escape(f)}"></a></p>'
                   for f in files)


def _delays_text(result) -> str:
    estimate = result.estimates["with delays"]
    parts = [f"{delayed_derivative(n)} {estimate.values[i]:.3f} ± {estimate.cramer_rao[i]:.3f} s"
             for i, n in enumerate(estimate.parameter_names) if delayed_derivative(n)]
    text = ", ".join(parts) or "none"
    if result.dropped_delays:
        text += (f" (dropped as undetermined: {', '.join(result.dropped_delays)})")
    truth = result.truth_delays
    if truth is not None:
        text += (". The truth model's own equivalent delays (its full linearisation's q and p "
                 f"responses to the cyclic, fitted over {truth.band[0]:g}–{truth.band[1]:g} "
                 "rad/s with the same delays, relative error "
                 f"{truth.relative_rms:.1%}): " + ", ".join(
                     f"{n} {v:.3f} s" for n, v in truth.delays.items()))
    return text


def _kinds(maneuvers) -> list[str]:
    """The distinct maneuver kinds of a set (metadata ``kind``), in order of appearance."""
    return list(dict.fromkeys(str(m.metadata.get("kind", "unspecified")) for m in maneuvers))


def case_html(result, figures: Mapping[str, list[str]], claims: Sequence[Check]) -> str:
    """The case report page (figures referenced relative to the case directory; ``claims``
    from :func:`paper_checks`)."""
    case, path = result.case, result.path
    estimates = result.estimates
    notes = sorted({n for v in result.verification.values() for n in v.notes})
    seconds = ", ".join(f"{k} {v:.0f} s" for k, v in result.seconds.items())
    if result.resumed_steps:
        seconds = (f"{seconds} (this run, which resumed after {result.resumed_steps} finished "
                   f"reduction steps)")
    verification_count = 0 if result.verification_data is None else len(result.verification_data)
    body = [
        f"<p>{html.escape(case.description)}. Trim: {html.escape(result.condition.describe())}. "
        f"{len(result.identification)} identification maneuvers "
        f"({', '.join(_kinds(result.identification))}), {verification_count} verification "
        f"maneuvers; "
        f"{'quick' if case.is_quick else 'full'} set. Units: {estimates['no delays'].units}. "
        f"Time: {html.escape(seconds)}.</p>",
        "<p>Machine-readable results: <a href=\"result.json\">result.json</a>; tables: "
        + ", ".join(f'<a href="tables/{t}.csv">{t}.csv</a>'
                    for t in ("removed", "parameters", "key_derivatives", "verification",
                              "checks")) + ".</p>",
        "<h2>The paper's claims, measured</h2>", checks_html(claims),
        "<h2>Model reduction</h2>",
        f"<p>Selected step {path.selected_index} of {len(path.steps) - 1} by rule "
        f"<code>{path.rule}</code> (tolerance {path.rmse_tolerance:.0%}): "
        f"{path.selected.n_parameters} parameters, RMSE {path.selected.rmse:.4f}; "
        f"removed in order: {html.escape(', '.join(path.removed) or 'none')}.</p>",
        _images(figures.get("reduction", [])),
        "<h3>Removed parameters (Appendix B)</h3>", _html_table(removed_rows(result), 7),
        "<h2>Time delays</h2>", f"<p>{html.escape(_delays_text(result))}. RMSE without delays "
        f"{estimates['no delays'].rmse:.4f}, with delays {estimates['with delays'].rmse:.4f}.</p>",
        "<h2>Identified parameters (Appendix B)</h2>",
        "<p>CR: Cramér-Rao bound; CR % and I %: Cramér-Rao bound and insensitivity relative to "
        "the value.</p>", _html_table(parameter_rows(result)),
        "<h2>Key derivatives: signs and magnitudes</h2>",
        "<p>Identified (model with delays) beside the truth model's residualised 6-DoF "
        "linearisation and the published Helisim Bo-105 values (Padfield 2007).</p>",
        _html_table(key_derivative_rows(result), 8),
        "<h2>Time histories on the 2311 inputs</h2>", _images(figures.get("time", [])),
        "<h2>Frequency-domain verification on the sweeps</h2>",
        "".join(f"<p class=\"na\">note: {html.escape(n)}</p>" for n in notes),
        _html_table(verification_rows(result)),
        _images(figures.get("frequency", [])),
        "<h3>Bode overlays (model with delays)</h3>",
        "<p>Truth estimated from the sweeps, the model's single-input response (simulated, or "
        "apparent for an unstable model), and its analytic response with exact delays.</p>",
        _images(figures.get("bode", [])),
        comparison_html(result),
    ]
    return _page(f"rotorid study — case {result.name}", "\n".join(body))


def write_case_outputs(result, directory: str | Path) -> Path:
    """Write the figures, tables and ``report.html`` of one case; returns the report path."""
    directory = Path(directory)
    figures = case_figures(result, directory / "figures")
    tables = directory / "tables"
    tables.mkdir(exist_ok=True)
    claims = paper_checks(result)
    checks = [["claim", "measured", "holds"]] + [
        [c.claim, c.measured, "" if c.passed is None else str(c.passed).lower()]
        for c in claims]
    for name, rows in (("removed", removed_rows(result)), ("parameters", parameter_rows(result)),
                       ("key_derivatives", key_derivative_rows(result)),
                       ("verification", verification_rows(result)), ("checks", checks)):
        atomic_write(tables / f"{name}.csv", _csv(rows))
    if result.frequency_comparison:
        atomic_write(tables / "comparison_costs.csv", _csv(comparison_cost_rows(result)))
        atomic_write(tables / "comparison_parameters.csv",
                     _csv(comparison_parameter_rows(result)))
    return atomic_write(directory / "report.html", case_html(result, figures, claims))


def write_study_report(results: Mapping[str, object], out_dir: str | Path) -> Path:
    """Write ``<out>/report.html``: one summary per case, linking each case report."""
    out_dir = Path(out_dir)
    rows = [["case", "trim", "parameters (removed)", "RMSE no delays", "RMSE with delays",
             "delays", "claims holding"]]
    sections = []
    for name, result in results.items():
        checks = paper_checks(result)
        decided, failed = claims_tally(checks)
        rows.append([name, result.condition.describe(),
                     f"{result.path.selected.n_parameters} ({len(result.path.removed)})",
                     f"{result.estimates['no delays'].rmse:.4f}",
                     f"{result.estimates['with delays'].rmse:.4f}", _delays_text(result),
                     f"{len(decided) - len(failed)}/{len(decided)}"])
        link = f"{html.escape(name)}/report.html"
        sections.append(f"<h2><a href=\"{link}\">Case {html.escape(name)}</a></h2>"
                        + _images(["rmse.png"], prefix=f"{html.escape(name)}/figures/")
                        + checks_html(checks))
    body = ("<p>Each case links to its full report: reduction path, Appendix-B tables, time "
            "histories, frequency-domain verification.</p>" + _html_table(rows)
            + "\n".join(sections))
    return atomic_write(out_dir / "report.html", _page("rotorid study report", body))


class StudyReport:
    """The study pipeline's report writer (:class:`rotorid.study.pipeline.ReportWriter`):
    figures, tables and HTML per case, and the study's overview page."""

    def write_case(self, result, directory: str | Path) -> Path:
        return write_case_outputs(result, directory)

    def write_study(self, results: Mapping[str, object], out_dir: str | Path) -> Path:
        return write_study_report(results, out_dir)
