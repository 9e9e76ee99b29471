"""The figures of a case report, each with the caption the report shows under it.

:func:`case_figures` writes into ``<case>/figures/``: ``rmse``, ``delay_profiles`` (when the
case profiled its delays), ``time_<maneuver>`` for every identification maneuver, and ``error_<out>_<in>`` and ``bode_<out>_<in>`` for every verified
pair, ``states_<maneuver>`` for every identification maneuver where the estimator gave state
estimates (PNG and SVG each); titles name the flight condition ("hover", "70 kt").
"""

from __future__ import annotations

import html
from collections.abc import Callable, Sequence
from pathlib import Path

import attrs

from rotorid.progress import Countdown, counted
from rotorid.report.plots.case import plot_rmse_path, plot_time_histories, save_figure
from rotorid.report.plots.frequency import RELAXED_THRESHOLD, plot_bode, plot_error
from rotorid.report.plots.profiles import plot_delay_profiles
from rotorid.report.plots.states import NOISE_PREFIXES, plot_state_estimates, recorded_states
from rotorid.verification.compare import envelopes_by_name
from rotorid.verification.pairs import parse_pair


@attrs.frozen
class ReportFigure:
    """One figure of a report: its PNG file name (relative to ``figures/``), the caption
    under it, and the pair it belongs to ("" for figures of the whole case)."""

    file: str
    caption: str
    pair: str = ""


def file_stem(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)


def flight_label(condition, units: str = "flight-test") -> str:
    """``"hover"`` or the airspeed in the unit system's speed, e.g. ``"70 kt"`` or ``"40 m/s"``
    (``units = "si"``): how titles name a flight condition."""
    return "hover" if abs(condition.airspeed_kt) < 0.5 else condition.airspeed_text(units, 0)


def case_title(result) -> str:
    """How figure titles name a case: its flight condition (:func:`flight_label`), after the
    case's name where that says something else (``"quad-hover (hover)"``)."""
    label = flight_label(result.condition, result.estimates["no delays"].units)
    return label if result.name == label else f"{result.name} ({label})"


def rmse_caption(path) -> str:
    return ("RMSE (eq. 18) of each converged structure against the number of removed "
            "parameters; the name on the top axis is the parameter removed at that step. The "
            f"shaded band spans the lowest RMSE to {path.rmse_tolerance:.0%} above it (the "
            "tolerance rules' band); the star marks the structure selected by rule "
            f"<code>{html.escape(path.rule)}</code>, the other markers where the other rules "
            "(lowest-rmse, the paper's; parsimonious; first-rise) would land, one marker per "
            "step. The y-axis shows the region the rules "
            "look at; steps whose RMSE lies above it are drawn as open triangles at the top.")


def _profiles_caption(profiles) -> str:
    points = len(profiles[0].grid)
    return ("Delay profiles of the model with delays: for each kept delay, the RMSE (eq. 18) "
            f"with that delay fixed at each of {points} values from 0 s and every other "
            "parameter (the other delays included) refitted, relative to the RMSE of the fit "
            "with all delays free (%; linear within ±1 %, logarithmic beyond); the star marks "
            "the free fit's delay, crosses refits that did not converge. A deep, narrow "
            "minimum is a delay the data determine; a shallow one is a trade between the delay "
            "and the gains, whatever its Cramér-Rao bound says. det R of every refit is in "
            "result.json (delay_profiles).")


def _time_caption(maneuver, models: Sequence[str]) -> str:
    kind = maneuver.metadata.get("kind", "maneuver")
    axis = maneuver.metadata.get("axis")
    on = f" on {axis}" if axis else ""
    return (f"{html.escape(str(kind))} input{html.escape(on)} "
            f"(<code>{html.escape(maneuver.name)}</code>, identification data): measured "
            f"outputs (thin grey) behind the simulated outputs of the "
            f"{'models ' if len(models) > 1 else ''}{html.escape(' and '.join(models))}, fed "
            "the recorded inputs; below them the "
            "inputs, and last the on-axis and the main coupled output zoomed on the input "
            "window (shaded above).")


def _states_caption(maneuver, estimates) -> str:
    noise = [n for n in estimates.names if n[:2] in NOISE_PREFIXES]
    return (f"<code>{html.escape(maneuver.name)}</code>: the estimator's state estimates "
            f"along the record ({html.escape(estimates.method)}) for the model with delays, "
            f"each in a band of ±2 standard deviations of its error as the estimator states "
            f"it; first the noise model's states ({html.escape(', '.join(noise) or 'none')}: "
            "d_ a disturbance acceleration, g_ a gust), the turbulence as the identified "
            "model sees it. Thin grey: the record's own channel of the same name (a "
            "measured output; a generated record's true gust).")


def _state_figures(result, figures_dir: Path, tally: FigureTally) -> list[ReportFigure]:
    """One figure of the state estimates per identification maneuver (``states_<name>``)."""
    estimates = result.state_estimates
    written = []
    for maneuver in result.identification:
        figure = plot_state_estimates(
            estimates, maneuver.name,
            recorded_states(maneuver, estimates.names, result.estimates["with delays"]),
            title=f"{case_title(result)}: state estimates ({maneuver.name})")
        name = f"states_{file_stem(maneuver.name)}"
        tally.save(figure, figures_dir / name)
        written.append(ReportFigure(f"{name}.png", _states_caption(maneuver, estimates)))
    tally.group_done(f"state estimates of {counted(len(written), 'maneuver')}")
    return written


def _error_caption(pair: str, muad_range: str, band) -> str:
    return (f"{html.escape(pair)}: error ε = H_model/H_measured of each model's response on "
            "the sweeps (magnitude in dB, phase as principal value in deg) against the MUAD "
            f"bounds (dashed over {muad_range}; dotted where extrapolated, never checked). "
            f"Filled markers: the verification band's points, {html.escape(band.describe())} "
            "(checked by every verdict: MUAD, AEE, J); open: other points with γ² ≥ "
            f"{min(RELAXED_THRESHOLD, band.coherence):g} (shown, not checked); lower "
            "coherence hidden; frequencies outside the band's range shaded. The legend counts each model's "
            "checked points inside and outside the bounds; the bottom panel is the coherence of "
            "the measured response with the band's threshold.")


def _bode_caption(pair: str, item, model_name: str) -> str:
    model = ("the model's response estimated from its simulation of the recorded sweep "
             "inputs, processed exactly like the measured one (simulated)"
             if item.model_source == "simulated" else
             "the model's apparent response: its analytic response to the pair's input plus "
             "the effect of the other recorded inputs, formed as in the measured estimate "
             "(used for a model that cannot be simulated over the whole sweep)")
    text = (f"{html.escape(pair)}, {model_name}. Blue: the measured response estimated "
            f"from the sweeps (single input); orange: {model}")
    conditioned = item.conditioned is not None and bool(item.conditioned.conditioned_on)
    if conditioned:
        text += (f"; red: the measured response conditioned on "
                 f"{html.escape(', '.join(item.conditioned.conditioned_on))} (the other inputs "
                 "that moved or that the model says drive the output, removed by partial "
                 "spectra; its partial coherence below)")
    if item.analytic is not None:
        text += ("; green line: the model's analytic response with exact delays, which the "
                 + ("conditioned response" if conditioned else "measured response (no other "
                    "input moved or drives the output, so it is conditioned on nothing)") + " is compared with")
    return text + (". Phases share one 360° branch; markers as in the error plots.")


def _muad_range(envelopes) -> str:
    """The MUAD envelope's frequency range of the case's ``envelopes`` (by name), as text."""
    muad = envelopes.get("muad")
    if muad is None or getattr(muad, "omega_range", None) is None:
        return "the envelope's range"
    low, high = muad.omega_range
    return f"{low:g}–{high:g} rad/s"


class FigureTally:
    """Saves a case's figures and counts them; after each group of figures it reports how
    many of ``total`` are written and the time left (``progress(message)``, optional)."""

    def __init__(self, total: int, progress: Callable[[str], None] | None = None):
        self._countdown = Countdown(total)
        self._progress = progress
        self._line = ""

    def save(self, figure, stem: Path) -> None:
        save_figure(figure, stem)
        self._line = self._countdown.step()

    def group_done(self, what: str) -> None:
        if self._progress is not None:
            self._progress(f"figures: {what} {self._line}")


def case_figure_count(result) -> int:
    """How many figures :func:`case_figures` writes for ``result``."""
    reference = result.verification.get("with delays")
    pairs = 0 if reference is None else len(reference.pairs)
    states = 0 if result.state_estimates is None else len(result.state_estimates.maneuvers)
    return (1 + bool(result.delay_profiles) + len(result.identification) + 2 * pairs
            + len(_hybrid_pairs(result)) + states)


def case_figures(result, figures_dir: Path,
                 progress: Callable[[str], None] | None = None) -> dict[str, list[ReportFigure]]:
    """Write the case's figures; returns section → figures (PNG file name and caption).

    Every identification maneuver gets a time-history figure, whatever its kind. With
    ``progress``, a line after each group of figures says how many are written."""
    figures_dir.mkdir(parents=True, exist_ok=True)
    tally = FigureTally(case_figure_count(result), progress)
    written = {"reduction": [], "delays": [], "time": [], "frequency": [], "bode": []}
    signals = result.structures["with delays"].signals
    flight = case_title(result)
    figure = plot_rmse_path(result.path, title=f"{flight}: RMSE versus removed parameters")
    tally.save(figure, figures_dir / "rmse")
    written["reduction"].append(ReportFigure("rmse.png", rmse_caption(result.path)))
    if result.delay_profiles:
        figure = plot_delay_profiles(result.delay_profiles,
                                     title=f"{flight}: delay profiles (model with delays)")
        tally.save(figure, figures_dir / "delay_profiles")
        written["delays"].append(ReportFigure("delay_profiles.png",
                                              _profiles_caption(result.delay_profiles)))
    tally.group_done("reduction" + (" and delay profiles" if result.delay_profiles else ""))
    maneuvers = list(result.identification)
    names = [result.model_name(label) for label in result.models]
    outputs = [result.simulated(label) for label in result.models]
    for index, maneuver in enumerate(maneuvers):
        simulated = {name: fit[index] for name, fit in zip(names, outputs)}
        kind, axis = maneuver.metadata.get("kind"), maneuver.metadata.get("axis")
        what = " ".join(str(v) for v in (kind, "input on" if axis else None, axis) if v)
        figure = plot_time_histories(maneuver, simulated,
                                     title=f"{flight}: {what or 'maneuver'} ({maneuver.name})",
                                     signals=signals)
        name = f"time_{file_stem(maneuver.name)}"
        tally.save(figure, figures_dir / name)
        written["time"].append(ReportFigure(f"{name}.png", _time_caption(maneuver, names)))
    tally.group_done(f"time histories of {counted(len(maneuvers), 'maneuver')}")
    if result.state_estimates is not None:
        written["states"] = _state_figures(result, figures_dir, tally)
    by_name = envelopes_by_name(result.case.envelopes, band=result.case.band)
    envelopes = [e for e in by_name.values() if e.kind == "bounds"]
    reference = result.verification.get("with delays")
    muad_range = _muad_range(by_name)
    for item in () if reference is None else reference.pairs:
        output, control = parse_pair(item.pair, signals.outputs.names, signals.inputs.names)
        errors = {result.model_name(label): result.verification[label][item.pair]
                  for label in result.models if label in result.verification}
        figure = plot_error(errors, envelopes,
                            title=f"{flight}: {item.pair} error ε = H_model/H_measured")
        stem = f"error_{output}_{control}"
        tally.save(figure, figures_dir / stem)
        written["frequency"].append(ReportFigure(f"{stem}.png",
                                                 _error_caption(item.pair, muad_range,
                                                                item.band),
                                                 item.pair))
        figure = plot_bode(item, signals.outputs[output].unit, signals.inputs[control].unit,
                           title=f"{flight}: {item.pair} frequency responses "
                                 f"({result.final_model_name})")
        stem = f"bode_{output}_{control}"
        tally.save(figure, figures_dir / stem)
        caption = _bode_caption(item.pair, item, result.final_model_name)
        written["bode"].append(ReportFigure(f"{stem}.png", caption, item.pair))
    if reference is not None:
        tally.group_done("errors and frequency responses of "
                         f"{counted(len(reference.pairs), 'pair')}")
    written["hybrid"] = hybrid_figures(result, figures_dir, flight, signals, tally)
    return written


def _hybrid_pairs(result) -> tuple:
    """The verified pairs of ``[compare] hybrid`` (none without it)."""
    comparison = result.hybrid_comparison
    if comparison is None or not comparison.verification:
        return ()
    return tuple(comparison.verification["hybrid"].pairs)


def hybrid_figures(result, figures_dir: Path, flight: str, signals,
                   tally: FigureTally | None = None) -> list[ReportFigure]:
    """With ``[compare] hybrid``: per verified pair, ε of the three models over 1–20 rad/s
    (saved through ``tally`` when given)."""
    if tally is None:
        tally = FigureTally(len(_hybrid_pairs(result)))
    comparison = result.hybrid_comparison
    written = []
    for item in _hybrid_pairs(result):
        output, control = parse_pair(item.pair, signals.outputs.names, signals.inputs.names)
        errors = {label: verification[item.pair]
                  for label, verification in comparison.verification.items()}
        figure = plot_error(errors, title=f"{flight}: {item.pair} error ε = "
                                          f"H_model/H_measured, three models")
        stem = f"hybrid_error_{output}_{control}"
        tally.save(figure, figures_dir / stem)
        written.append(ReportFigure(
            f"{stem}.png",
            f"{item.pair}: magnitude and phase of ε = H_model/H_measured for the models without "
            f"and with delays and the hybrid model; filled markers are the points J counts "
            f"({item.band.describe()}); 0 dB and 0° is a perfect match.", item.pair))
    if written:
        tally.group_done(f"the hybrid's errors of {counted(len(written), 'pair')}")
    return written
