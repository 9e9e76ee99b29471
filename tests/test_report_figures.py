"""Each figure type of the study report, checked on the figure object: axis limits from the
coherent points, labels with units, legends outside the axes, no duplicate lines; and the
report of a case about measured data only (no truth model)."""

import re
import shutil

import attrs
import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from rotorid.report.html import write_case_outputs  # noqa: E402
from rotorid.report.plots.case import input_window, plot_rmse_path, plot_time_histories  # noqa: E402
from rotorid.report.plots.frequency import (  # noqa: E402
    common_branch_phase_deg,
    plot_bode,
    plot_error,
)
from rotorid.study.case import FlightCase  # noqa: E402
from rotorid.study.pipeline import run_case  # noqa: E402
from rotorid.study.reference import ReferenceValue  # noqa: E402
from rotorid.study.result import MODELS  # noqa: E402
from rotorid.verification.compare import envelopes_by_name  # noqa: E402
from rotorid.verification.envelopes import error_db_deg  # noqa: E402

UNIT = re.compile(r"\[[^\]]+\]")


@pytest.fixture(scope="module")
def hover(quick_study, tmp_path_factory):
    """The quick study's hover case as a CaseResult, resumed from a copy of its files."""
    out = tmp_path_factory.mktemp("figures")
    shutil.copytree(quick_study.out / "hover", out / "hover")
    return run_case(FlightCase.load("hover").quick(), out, resume=True, progress=None)


def _legend_outside(figure) -> None:
    """The figure's legends sit outside every axes' box (in display coordinates)."""
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    renderer = canvas.get_renderer()
    legends = figure.legends
    assert legends, "the figure has no figure-level legend"
    for legend in legends:
        box = legend.get_window_extent(renderer)
        for axis in figure.axes:
            assert not box.overlaps(axis.get_window_extent(renderer)), axis.get_ylabel()


def _no_duplicate_lines(axis) -> None:
    seen = []
    for line in axis.get_lines():
        x, y = (np.asarray(v, float) for v in line.get_data())
        for other in seen:
            assert not (x.shape == other[0].shape and np.array_equal(x, other[0], equal_nan=True)
                        and np.array_equal(y, other[1], equal_nan=True) and x.size), (
                f"{axis.get_ylabel()}: line {line.get_label()!r} drawn twice")
        seen.append((x, y))


def test_rmse_curve(hover):
    path = hover.path
    figure = plot_rmse_path(path, title="hover: RMSE")
    (axis, *_) = figure.axes
    rmse = np.array([s.rmse for s in path.steps])
    low, high = axis.get_ylim()
    # The region the rules look at: the lowest RMSE near the bottom, the band well visible.
    assert low < rmse.min() and high <= rmse.min() * 1.2
    band_height = rmse.min() * path.rmse_tolerance / (high - low)
    assert band_height > 0.05
    labels = [t.get_text() for t in figure.legends[0].get_texts()]
    # Where every selection rule lands, the path's own marked as selected.
    assert any(label.startswith(f"selected ({path.rule}") for label in labels)
    for rule in ("parsimonious", "first-rise"):
        assert sum(rule in label for label in labels) == 1, labels
    assert UNIT.search(axis.get_xlabel()) and UNIT.search(axis.get_ylabel())
    _legend_outside(figure)
    _no_duplicate_lines(axis)


def test_time_histories_draw_measured_thin_and_grey_behind_the_models(hover):
    maneuver = next(m for m in hover.identification if m.metadata["kind"] == "3211")
    index = list(hover.identification).index(maneuver)
    simulated = {label: hover.simulated(label)[index] for label in MODELS}
    figure = plot_time_histories(maneuver, simulated, title="t")
    outputs = figure.axes[:8]
    for axis in outputs:
        measured, *models = axis.get_lines()
        assert measured.get_label() == "measured"
        assert measured.get_linewidth() < min(m.get_linewidth() for m in models)
        assert measured.get_zorder() < min(m.get_zorder() for m in models)
        assert matplotlib.colors.to_rgb(measured.get_color()) == (0.6, 0.6, 0.6)   # grey
        assert UNIT.search(axis.get_ylabel())
        _no_duplicate_lines(axis)
    zooms = figure.axes[10:]
    start, end = input_window(maneuver)
    # A 3211 of 0.4 s steps starting at 2 s: the window spans it and not the whole record.
    assert start < 2.0 < 2.0 + 7 * 0.4 < end < maneuver.time[-1]
    assert len(zooms) == 2 and all(z.get_xlim()[1] <= end + 0.5 for z in zooms)
    assert {z.get_ylabel().split()[0] for z in zooms} == {"q", "p"}
    assert [t.get_text() for t in figure.legends[0].get_texts()] == ["measured", *MODELS]
    _legend_outside(figure)


def test_time_histories_of_a_record_on_a_range_clock_start_at_zero(hover):
    """A record time-stamped on the range's clock (seconds of day): its axes run from the
    record's start, which the label names in full, not from 15863530 s (1.58635e+07)."""
    maneuver = next(m for m in hover.identification if m.metadata["kind"] == "3211")
    index = list(hover.identification).index(maneuver)
    late = attrs.evolve(maneuver, time=maneuver.time + 15863530.0)
    figure = plot_time_histories(late, {"model": hover.simulated("with delays")[index]})
    start, end = input_window(maneuver)
    for axis in figure.axes:
        low, high = axis.get_xlim()
        assert -1.0 < low and high < maneuver.duration + 1.0
    zoom = figure.axes[-1]
    assert zoom.get_xlabel() == "time from the record's start at t = 15863530 s [s]"
    assert zoom.get_xlim()[0] == pytest.approx(start, abs=0.5)


def test_error_plot_limits_counts_and_legend(hover):
    pair = "p/long"
    errors = {label: hover.verification[label][pair] for label in MODELS}
    envelopes = [e for e in envelopes_by_name(hover.case.envelopes).values()
                 if e.kind == "bounds"]
    figure = plot_error(errors, envelopes, title="e")
    mag, phase, coherence = figure.axes[:3]
    for axis, part in ((mag, 0), (phase, 1)):
        values = np.concatenate([
            error_db_deg(item.error)[part][item.checked] for item in errors.values()])
        bounds = np.concatenate([line.get_ydata() for line in axis.get_lines()
                                 if line.get_linestyle() == "--"])     # the checked range's
        low, high = axis.get_ylim()
        held = np.concatenate([values, bounds[np.isfinite(bounds)]])
        span = held.max() - held.min()
        # From the checked points and bounds: they all show, with little more than a margin.
        assert low <= values.min() and high >= values.max()
        assert (high - low) < max(span, 10.0) * 1.2 + 1.0
    labels = [t.get_text() for t in figure.legends[0].get_texts()]
    assert not any("not available" in label for label in labels)
    for label, item in errors.items():
        check = item.checks["muad"]
        assert f"{label}: MUAD {check.n_inside}/{check.n_used} inside, {check.n_outside} " \
               "outside" in labels
    assert "filled: in the verification band, γ² ≥ 0.8 over 0.1–10 rad/s (checked)" in labels
    assert "open: γ² ≥ 0.6 outside the band (shown, not checked)" in labels
    assert "outside the band's frequency range" in labels
    assert len(coherence.get_lines()) == 2          # the truth's coherence once, the threshold
    assert coherence.get_lines()[1].get_ydata()[0] == 0.8
    # The grid runs past the band's 10 rad/s: that part is shaded on every panel.
    for axis in (mag, phase, coherence):
        (shaded,) = axis.patches                   # a Rectangle in data coordinates
        assert shaded.get_x() == 10.0 and axis.get_xlim()[1] > 10.0
    # MUAD drawn over the points' range: checked part dashed, extrapolated part dotted.
    muad = [line for line in mag.get_lines() if line.get_label().startswith("MUAD")]
    drawn = np.concatenate([line.get_xdata()[np.isfinite(line.get_ydata())] for line in muad])
    omega = errors["with delays"].omega
    assert drawn.min() <= omega.min() * 1.01 and drawn.max() >= omega.max() * 0.99
    ticks = [t.get_text() for t in coherence.get_xticklabels() if t.get_text()]
    assert {"1", "2", "5", "10"} <= set(ticks)
    for axis in (mag, phase, coherence):
        assert UNIT.search(axis.get_ylabel())
        _no_duplicate_lines(axis)
    assert UNIT.search(coherence.get_xlabel())
    _legend_outside(figure)


def test_bode_phases_share_one_branch(hover):
    item = hover.verification["with delays"]["q/long"]
    figure = plot_bode(item, "deg/s")
    mag, phase, coherence = figure.axes[:3]
    analytic = next(line for line in phase.get_lines() if line.get_color() == "C2")
    reference = np.interp(item.omega, analytic.get_xdata(), analytic.get_ydata())
    for line in phase.get_lines():
        x, y = line.get_xdata(), line.get_ydata()
        if len(x) == 0:
            continue
        # Every curve within half a turn of the analytic response, point by point.
        gap = np.abs(y - np.interp(x, item.omega, reference))
        assert np.all(gap[np.isfinite(gap)] <= 180.0), line.get_label()
    low, high = phase.get_ylim()
    assert high - low < 540.0
    # Magnitude limits from the coherent points and the analytic response only.
    coherent = np.concatenate([
        20 * np.log10(np.abs(r[c >= 0.8])) for r, c in (
            (item.truth.response, item.truth.coherence),
            (item.model.response, item.truth.coherence),
            (item.conditioned.response, item.conditioned.coherence))]
        + [20 * np.log10(np.abs(item.analytic))])
    low, high = mag.get_ylim()
    span = coherent.max() - coherent.min()
    assert low <= coherent.min() and coherent.max() <= high <= coherent.max() + 0.1 * span
    assert "[dB, deg/s/%]" in mag.get_ylabel() and UNIT.search(phase.get_ylabel())
    for axis in (mag, phase, coherence):
        _no_duplicate_lines(axis)
    _legend_outside(figure)


def test_common_branch_removes_whole_turns():
    omega = np.geomspace(1, 10, 50)
    reference = -100.0 * np.log10(omega) * 4 - 10.0          # down to -410 deg
    response = np.exp(1j * np.radians(reference + 5.0))       # principal values wrap
    phase = common_branch_phase_deg(response, reference)
    np.testing.assert_allclose(phase, reference + 5.0, atol=1e-9)


def test_a_report_about_measured_data_only(hover, tmp_path):
    """A files-source case (no truth model): no paper claims but the guidelines on its own
    verified pairs, no truth or Bo-105 values, every identification maneuver drawn, data
    called measured, units in every table."""
    maneuvers = [next(m for m in hover.identification if m.metadata["kind"] == kind)
                 for kind in ("3211", "2311")]
    identification = attrs.evolve(hover.identification, maneuvers=maneuvers)
    verification = {label: attrs.evolve(v, pairs=v.pairs[:1])
                    for label, v in hover.verification.items()}
    case = attrs.evolve(hover.case, data={"source": "files", "identification": "f/*.csv"},
                        description="Own aircraft, flight test")
    hybrid = attrs.evolve(hover.hybrid_comparison, reference=None, six_dof_reference=None)
    result = attrs.evolve(hover, case=case, identification=identification,
                          verification=verification, truth_derivatives=None,
                          truth_delays=None, hybrid_comparison=hybrid)
    heard = []
    page = write_case_outputs(result, tmp_path / "own", heard.append).read_text(
        encoding="utf-8")
    # Progress: a line per group of figures, counting up to every figure written.
    written = len(list((tmp_path / "own" / "figures").glob("*.png")))
    assert [line.split(" [")[0] for line in heard] == [
        "figures: reduction and delay profiles", "figures: time histories of 2 maneuvers",
        "figures: errors and frequency responses of 1 pair",
        f"figures: the hybrid's errors of {len(hybrid.verification['hybrid'].pairs)} pairs"]
    assert f"] {written}/{written}, about 0 s left" in heard[-1]
    assert 'id="hybrid"' in page and "(flap-coupled)" not in page
    for word in ("paper's claims", "Bo-105", "Helisim", "Padfield", "truth"):
        assert word not in page, word
    assert "measured" in page
    figures = sorted(p.name for p in (tmp_path / "own" / "figures").glob("time_*.png"))
    assert figures == sorted(f"time_{m.name}.png" for m in maneuvers)
    assert '<h2 id="claims">The guidelines, measured</h2>' in page
    checks = (tmp_path / "own" / "tables" / "checks.csv").read_text(encoding="utf-8")
    rows = checks.splitlines()[1:]
    assert len(rows) == 3                               # RMSE of both models, the one pair
    assert rows[2].startswith(f"{verification['with delays'].pairs[0].pair} with delays "
                              f"inside MUAD")
    assert 'id="reference"' not in page                  # no [reference]: no reference rows
    for table in re.findall(r"<table>.*?</table>", page, flags=re.DOTALL):
        header = re.search(r"<thead>(.*?)</thead>", table)[1]
        assert "[" in header or ">unit<" in header, header


def test_a_files_case_is_compared_with_the_users_reference(hover, tmp_path):
    """[reference] values: each beside the identified one, the verdict from two combined
    bounds, a removed derivative named; table in the report, CSV and result.json."""
    estimate = hover.estimates["with delays"]
    m_q, bound = estimate.value("M_q"), float(estimate.cramer_rao[estimate.index("M_q")])
    removed = hover.path.removed[0]
    reference = {"M_q": ReferenceValue(m_q + 3.0 * bound, 2.0 * bound, "previous model"),
                 "L_v": ReferenceValue(-2.0 * estimate.value("L_v"), None, "wind tunnel"),
                 removed: ReferenceValue(1.0)}
    case = attrs.evolve(hover.case, data={"source": "files", "identification": "f/*.csv"},
                        reference=reference)
    # two maneuvers, one verified pair and no hybrid section: the figures are not the point
    identification = attrs.evolve(hover.identification,
                                  maneuvers=list(hover.identification)[:2])
    verification = {label: attrs.evolve(v, pairs=v.pairs[:1])
                    for label, v in hover.verification.items()}
    result = attrs.evolve(hover, case=case, truth_derivatives=None, truth_delays=None,
                          identification=identification, verification=verification,
                          hybrid_comparison=None)
    rows = {r["name"]: r for r in result.as_dict()["reference_comparison"]}
    # 3 CR off with a reference uncertainty of 2 CR: √(1 + 4) = 2.24 CR combined, 1.34 < 2.
    assert rows["M_q"]["difference"] == pytest.approx(-3.0 * bound)
    assert rows["M_q"]["combined_bound"] == pytest.approx(5 ** 0.5 * bound)
    assert rows["M_q"]["verdict"] == "agrees" and rows["M_q"]["source"] == "previous model"
    assert rows["L_v"]["verdict"] == "differs"            # opposite sign, twice the size
    assert rows[removed]["verdict"] == "removed" and rows[removed]["identified"] is None
    page = write_case_outputs(result, tmp_path / "own").read_text(encoding="utf-8")
    assert '<h2 id="reference">Reference values</h2>' in page
    assert '<a href="#reference">Reference values</a>' in page
    table = (tmp_path / "own" / "tables" / "reference.csv").read_text().splitlines()
    assert table[0].startswith("derivative,unit,identified,CR bound,reference")
    assert [line.split(",")[0] for line in table[1:]] == ["M_q", "L_v", removed]


def _synthetic_state_estimates(maneuvers):
    """State estimates of q (the record's own q, so its grey line lies under the estimate),
    a w disturbance and a w gust along each of ``maneuvers``."""
    from rotorid.estimation.state_estimates import StateEstimates

    rng = np.random.default_rng(0)
    values = [np.column_stack([m.channel("q"), rng.normal(size=(m.n_samples, 2))])
              for m in maneuvers]
    return StateEstimates(("q", "d_w", "g_w"), ("deg/s", "ft/s²", "ft/s"),
                          [m.name for m in maneuvers], [m.time for m in maneuvers], values,
                          [0.1, 0.5, 1.0], "Kalman filter x̂(n|n), steady-state gain")


def test_a_case_with_state_estimates_draws_and_writes_them(hover, quick_study, tmp_path):
    """A case whose estimator gave state estimates: a figure per identification maneuver
    (the noise model's states first), a report section with its contents entry and progress
    line, the estimates as maneuver files in state_estimates/ and their summary in
    result.json."""
    import json

    from rotorid.study.persistence import save_result
    from rotorid_files.formats import read_maneuver

    maneuvers = list(hover.identification)[:2]
    result = attrs.evolve(hover, identification=attrs.evolve(hover.identification,
                                                             maneuvers=maneuvers),
                          verification={}, verification_data=None,     # fewer figures
                          state_estimates=_synthetic_state_estimates(maneuvers))
    heard = []
    page = write_case_outputs(result, tmp_path / "case", heard.append).read_text(
        encoding="utf-8")
    figures = sorted(p.name for p in (tmp_path / "case" / "figures").glob("states_*.png"))
    assert figures == sorted(f"states_{m.name}.png" for m in maneuvers)
    assert any(line.startswith("figures: state estimates of 2 maneuvers") for line in heard)
    assert '<a href="#state-estimates">State estimates</a>' in page
    assert '<h2 id="state-estimates">' in page and "states_" in page
    save_result(tmp_path / "case", result)
    record = json.loads((tmp_path / "case" / "result.json").read_text(encoding="utf-8"))
    assert record["state_estimates"]["names"] == ["q", "d_w", "g_w"]
    assert record["state_estimates"]["units"]["d_w"] == "ft/s²"
    written = read_maneuver(tmp_path / "case" / "state_estimates" / f"{maneuvers[0].name}.csv")
    np.testing.assert_allclose(written.channel("g_w"), result.state_estimates.values[0][:, 2])
    without = (quick_study.out / "hover" / "report.html").read_text(encoding="utf-8")
    assert "state-estimates" not in without and '<h2 id="reduction">' in without


def test_the_states_figure_puts_the_noise_model_first_with_the_recorded_channel_behind(hover):
    from rotorid.report.plots.states import plot_state_estimates, recorded_states

    maneuver = hover.identification[0]
    estimates = _synthetic_state_estimates([maneuver])
    figure = plot_state_estimates(estimates, maneuver.name,
                                  recorded_states(maneuver, estimates.names))
    panels = [axis for axis in figure.axes if axis.get_visible()]
    assert [axis.get_ylabel() for axis in panels] == [
        "disturbance w [ft/s²]", "gust w [ft/s]", "q [deg/s]"]
    assert [line.get_label() for line in panels[2].lines] == ["recorded", "estimate"]
    assert all(UNIT.search(axis.get_ylabel()) for axis in panels)
    _legend_outside(figure)
