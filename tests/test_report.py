"""Study figures, tables and reports; the key-derivative sign check; the README's main command."""

import csv
import html
import json
import math
import re
import types
import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest
from rotorid.study.claims import mean_phase_error, paper_claims
from rotorid.verification.band import VerificationBand
from rotorid.study.expectations import (
    check_signs,
    derivative_scale,
    derivative_unit,
    regime_of,
)


def test_derivative_scales_are_the_unit_ratios():
    # (rad/s²)/(m/s) → (deg/s²)/(ft/s): 180/π deg per rad times 0.3048 m per ft.
    assert derivative_scale("M_w", "flight-test") == pytest.approx(180 / math.pi * 0.3048)
    # (m/s²)/(rad/s) → (ft/s²)/(deg/s)
    assert derivative_scale("X_q", "flight-test") == pytest.approx(1 / 0.3048 * math.pi / 180)
    assert derivative_scale("X_u", "flight-test") == 1.0
    assert derivative_scale("L_p", "flight-test") == pytest.approx(1.0)
    assert derivative_scale("M_w", "si") == 1.0
    assert derivative_unit("M_w", "flight-test") == "deg/s² per ft/s"
    assert derivative_unit("Y_p", "si") == "m/s² per rad/s"
    assert derivative_unit("Z_w", "flight-test") == "1/s"


def test_sign_check_verdicts():
    assert regime_of(0.0) == "hover" and regime_of(70.0) == "forward" and regime_of(30.0) is None
    identified = {"Z_w": (-0.3, 0.01), "L_v": (0.5, 0.01), "X_v": (0.001, 0.01),
                  "M_w": (0.2, 0.01)}
    truth = {"X_v": -0.01, "Y_v": -0.04}
    hover = {c.name: c for c in check_signs(("Z_w", "L_v", "X_v", "M_w", "Y_v"), identified,
                                            0.0, "flight-test", truth)}
    assert hover["Z_w"].verdict == "agrees"
    assert hover["Z_w"].reference == pytest.approx(-0.32)
    assert hover["L_v"].verdict == "differs"          # published L_v < 0 in hover
    assert hover["X_v"].verdict == "undetermined"     # |value| < 2 CR
    assert hover["X_v"].basis == "truth linearisation"
    assert hover["M_w"].verdict == "not checked"      # hover reference ≈ 0
    assert hover["Y_v"].verdict == "removed"
    assert hover["X_v"].ratio_to_truth == pytest.approx(-0.1)
    # In forward flight the Bo-105 has M_w > 0: the same value now agrees.
    forward = check_signs(("M_w",), identified, 70.0, "flight-test")
    assert forward[0].verdict == "agrees"
    assert forward[0].reference == pytest.approx(0.018 * 180 / math.pi * 0.3048)


def test_mean_phase_error_uses_the_band_points_only():
    omega = np.geomspace(1, 20, 7)
    band = VerificationBand()
    item = types.SimpleNamespace(
        error=np.exp(1j * np.radians([10, -10, 10, -10, 90, 90, 90])),
        checked=band.selects(omega, [0.9, 0.95, 0.8, 0.99, 0.5, np.nan, 1.0]))
    assert item.checked[-1] == False and omega[-1] > 10      # noqa: E712 (outside the range)
    assert mean_phase_error(item) == pytest.approx(10.0)
    item.checked = np.zeros(7, bool)
    assert mean_phase_error(item) is None


def _read_csv(path):
    with open(path, newline="") as handle:
        return list(csv.reader(handle))


def test_the_quick_hover_study_writes_a_complete_linked_report(quick_study):
    """The README's main command (run for both built-in cases), end to end: data, reduction,
    delays, verification, report."""
    out = quick_study.out
    assert quick_study.status == 0
    printed = quick_study.printed
    assert f"report: {out}/report.html" in printed
    lines = printed.splitlines()
    assert sum("paper's claims:" in line for line in lines) == 2     # hover and forward
    claims = [lines[i + 1] for i, line in enumerate(lines[:-1]) if line.startswith("hover: ")]
    assert len(claims) == 1
    held, decided, unchecked = map(int, re.search(
        r"paper's claims: (\d+)/(\d+) hold, (\d+) not checked", claims[0]).groups())
    # The paper's 14 claims in hover: two RMSE guidelines, four derivative signs, six MUAD
    # claims, two off-axis phase claims. The RMSE, on-axis MUAD and phase claims hold; the
    # paper's "M_w removed in hover" does not (the truth model's M_w is not negligible,
    # docs/study.md), and each failure is listed with its evidence.
    failures = claims[0].partition("; not: ")[2]
    assert decided + unchecked == 14 and (held == decided) == (not failures)
    for claim in ("RMSE", "phase error", *(f"{p} with delays" for p in
                                           ("q/long", "p/lat", "r/ped", "az/coll"))):
        assert claim not in failures, failures
    case = out / "hover"
    record = json.loads((case / "result.json").read_text())

    # Every image, link and anchor of both reports exists; every SVG is well-formed XML.
    for page in (out / "report.html", case / "report.html"):
        text = page.read_text()
        for target in re.findall(r'(?:src|href)="([^"]+)"', text):
            if target.startswith("#"):
                assert f'id="{target[1:]}"' in text, f"{page.name}: no anchor {target}"
            else:
                assert (page.parent / target).is_file(), f"{page.name} links missing {target}"
    figures = sorted(p.name for p in (case / "figures").glob("*.png"))
    assert "rmse.png" in figures
    # The delay profiles stored in result.json are drawn in the delays section, captioned.
    assert "delay_profiles.png" in figures
    report = (case / "report.html").read_text()
    delays_section = report.split('<h2 id="delays">')[1].split("<h2")[0]
    assert 'src="figures/delay_profiles.png"' in delays_section
    assert "<figcaption>Delay profiles of the model with delays" in delays_section
    # One verification band, stated beside the verdicts.
    assert "verification band γ² ≥ 0.8 over 0.1–10 rad/s" in report
    band_column = [row[2] for row in _read_csv(case / "tables" / "verification.csv")[1:]]
    assert set(band_column) == {"γ² ≥ 0.8 over 0.1–10 rad/s"}
    assert record["frequency_verification"]["with delays"]["band"] == {
        "coherence": 0.8, "omega_min": 0.1, "omega_max": 10.0}
    # Every identification maneuver: 3211 and 2311 per control, ± direction.
    assert sorted(f for f in figures if f.startswith("time_")) == sorted(
        f"time_hover_{kind}_{axis}_{sign}.png" for kind in ("3211", "2311")
        for axis in ("long", "lat", "coll", "ped") for sign in ("pos", "neg"))
    assert {f"error_{p.replace('/', '_')}.png" for p in
            ("q/long", "p/long", "q/lat", "p/lat", "r/coll", "az/coll", "r/ped", "ay/ped")
            } <= set(figures)
    for svg in (case / "figures").glob("*.svg"):
        ElementTree.parse(svg)

    # Appendix-B tables agree with result.json.
    removed = _read_csv(case / "tables" / "removed.csv")
    assert [row[1] for row in removed[2:]] == [s["removed"] for s in
                                               record["reduction"]["steps"][1:]]
    selected_rows = [row for row in removed[1:] if row[7] == "yes"]
    assert [int(r[0]) for r in selected_rows] == [record["reduction"]["selected_step"]]
    parameters = _read_csv(case / "tables" / "parameters.csv")
    with_delays = record["estimates"]["with delays"]["parameters"]
    for row in parameters[1:]:
        if row[0] in with_delays:
            assert float(row[6]) == pytest.approx(with_delays[row[0]]["value"], rel=1e-3)
    assert parameters[0][:3] == ["parameter", "unit", "no delays: value"]
    units = {row[0]: row[1] for row in parameters[1:]}
    assert units["M_q"] == "1/s" and units["tau_M_q"] == "s"
    checks = _read_csv(case / "tables" / "checks.csv")
    assert checks[1:] == [[c["claim"], c["evidence"], c["verdict"], c["reason"]]
                          for c in record["claims"]]
    rmse_claims = [row for row in checks if row[0].startswith("time-domain RMSE")]
    assert len(rmse_claims) == 2 and all(row[2] == "holds" for row in rmse_claims)
    assert not [row for row in checks if row[0].startswith("delay on")]  # the paper gives no range
    assert record["reduction"]["selections"]["lowest-rmse"] == record["reduction"][
        "selected_step"]
    # One profile per kept delay on the quick grid; fixing a delay never beats the free fit
    # (det R, up to the fits' convergence).
    profiles = record["delay_profiles"]
    kept = record["estimates"]["with delays"]["delays"]
    assert [p["delay"] for p in profiles] == [f"tau_{d}" for d in kept]
    for profile in profiles:
        assert profile["grid_s"] == [0.0, 0.15, 0.3]
        assert min(profile["det_r"]) >= profile["free_det_r"] * (1 - 1e-3), profile["delay"]
    signs = {row[0]: row for row in _read_csv(case / "tables" / "key_derivatives.csv")[1:]}
    assert signs["Z_w"][8] == "agrees"      # heave damping: robustly negative in hover
    # Every note of the final fits appears in the report's fit notes, with its models.
    fit_section = report.split('<h2 id="fit-notes">')[1].split("<h2")[0]
    for label, estimate in record["estimates"].items():
        for note in estimate["notes"]:
            item = fit_section.split(html.escape(note))[1].split("</li>")[0]
            assert label in item, (note, item)


#: τ_f = 16/(γΩ) of the Bo-105 rotor, s (truth-model.md §9).
FLAP_TIME_CONSTANT = 0.071
#: Relative RMSE rise within which a delay profile does not tell two delays apart.
FLAT_PROFILE = 0.01


def _undetermined_at(profile, value: float) -> bool:
    """Whether the data cannot tell delay ``value`` (s) from the identified one: the profile,
    interpolated at ``value``, costs less than :data:`FLAT_PROFILE` more RMSE."""
    return float(np.interp(value, profile.grid, profile.relative_rmse)) < FLAT_PROFILE


@pytest.mark.slow
def test_the_full_study_reproduces_the_papers_claims(tmp_path):
    """`rotorid study all` (full setup, both conditions), structures selected by the lowest
    RMSE: the RMSE guideline, the on-axis MUAD claims and the off-axis phase claims hold; what
    may fail is what docs/study.md discusses (M_w, whose truth-model value contradicts the
    paper in both conditions, and the off-axis MUAD bounds at the lowest frequencies). Every
    identified rotor delay lies within one flap time constant (τ_f = 16/(γΩ) = 0.071 s,
    truth-model.md §9, the scale of the lag that equivalent delays stand in for) of the truth
    model's own equivalent delay, fitted independently in the frequency domain to its full
    linearisation with the same delays (rotorid.verification.equivalent_delays), unless the
    delay's profile shows the data cannot tell the two apart (less than 1 % RMSE between
    them: 70 kt M_lat, docs/study.md); M_q's within 0.04 s."""
    from rotorid.study.pipeline import Study

    results = Study(["hover", "forward"], tmp_path, executor="process", progress=None).run()
    for name, result in results.items():
        failed = [c.claim for c in paper_claims(result) if c.verdict == "does not hold"]
        assert all(c.startswith(("M_w", "p/long with delays inside", "q/lat with delays inside"))
                   for c in failed), (name, failed)
        estimate = result.estimates["with delays"]
        truth = result.truth_delays.delays
        assert set(truth) == {n[4:] for n in estimate.parameter_names if n.startswith("tau_")}
        profiles = {p.delay: p for p in result.delay_profiles}
        for derivative, value in truth.items():
            delay = f"tau_{derivative}"
            close = abs(estimate.value(delay) - value) < FLAP_TIME_CONSTANT
            assert close or _undetermined_at(profiles[delay], value), (name, derivative)
        assert abs(estimate.value("tau_M_q") - truth["M_q"]) < 0.04
        assert result.truth_delays.relative_rms < 0.06
        assert result.path.steps[-1].n_parameters == 0       # reduced down to nothing
        _, rmse = result.path.rmse_curve()
        assert result.path.selected_index == int(np.argmin(rmse))


def test_key_derivatives_are_those_the_cases_structure_can_hold():
    """The helicopter's key derivatives where the structure's shape has them (the six-dof
    template all nine, the longitudinal template its own four); an aeroplane declared in β has
    none, so its report has no key-derivative section or table."""
    import sys
    import tomllib
    from pathlib import Path

    import rotorid
    from rotorid.model.modelfile import parse_model
    from rotorid.report.html import case_table_names
    from rotorid.study.result import KEY_DERIVATIVES, CaseResult

    sys.path.insert(0, str(Path(__file__).parent))
    from test_filter_error import AEROPLANE_LATERAL

    def names(structure):
        return CaseResult.key_derivative_names(types.SimpleNamespace(
            structures={"with delays": structure}))

    hover = rotorid.FlightCondition.from_airspeed(0.0)
    assert names(rotorid.ModelStructure.six_dof(hover)) == KEY_DERIVATIVES
    assert names(rotorid.ModelStructure.populated(hover, "longitudinal")) == (
        "M_w", "Z_w", "M_u", "X_u")
    aeroplane = types.SimpleNamespace(
        key_derivative_names=lambda: names(parse_model(tomllib.loads(AEROPLANE_LATERAL), "a")),
        handling_qualities={}, case=types.SimpleNamespace(reference=None),
        frequency_comparison=None, estimator_comparison=None, hybrid_comparison=None)
    assert aeroplane.key_derivative_names() == ()
    assert case_table_names(aeroplane, ()) == ["removed", "parameters", "modes",
                                                "verification"]


def test_the_bode_caption_names_the_response_the_analytic_one_is_compared_with():
    from rotorid.report.figures import _bode_caption

    single = types.SimpleNamespace(model_source="simulated", conditioned=None, analytic=object())
    assert ("which the measured response (no other input moved or drives the output, so "
            "it is conditioned on nothing) is compared with") in _bode_caption("p/aileron", single, "identified model")
    loops = types.SimpleNamespace(
        model_source="simulated", analytic=object(),
        conditioned=types.SimpleNamespace(conditioned_on=("lat", "ped")))
    caption = _bode_caption("q/long", loops, "model with delays")
    assert caption.startswith("q/long, model with delays. Blue")
    assert _bode_caption("p/aileron", single, "identified model").startswith(
        "p/aileron, identified model. Blue")
    assert "red: the measured response conditioned on lat, ped" in caption
    assert "which the conditioned response is compared with" in caption


def test_a_flat_rmse_path_is_named_beside_the_lowest_rmse_selection():
    """RMSE 1.0, 1.009, 0.998, 1.003: the lowest is step 2, the parsimonious rule (1 %) keeps
    step 3, 0.50 % above it; the report says the path is flat there."""
    from rotorid import Derivative, ModelStructure
    from rotorid.estimation.reduction import ReductionPath, ReductionStep
    from rotorid.report.html import _other_selections
    from test_estimation_rules import HOVER, estimate_of

    structure = ModelStructure(HOVER, [Derivative("L_p")])
    steps = [ReductionStep(k, None, estimate_of(np.eye(1), [1.0], ("L_p",), rmse=rmse),
                           structure) for k, rmse in enumerate((1.0, 1.009, 0.998, 1.003))]
    text = _other_selections(ReductionPath(steps, "lowest-rmse", 0.01))
    assert text.startswith("Other rules would select: parsimonious (1%) step 3, first-rise "
                           "(1%) step 3.")
    assert "step 3 (1 parameter) lies within 0.50% of the lowest" in text
    assert "flat" not in _other_selections(ReductionPath(steps[:3], "lowest-rmse", 0.01))


def test_the_delay_section_says_what_the_profiles_determine():
    """Three profiles over 0, 0.15, 0.3 s: one flat (RMSE at most 0.05 % worse), one that zero
    delay fits within 1 % but 0.3 s does not, one that every other value fits worse."""
    from rotorid.estimation.profiles import DelayProfile
    from rotorid.report.html import _profiles_text

    def profile(name, rises):
        rmse = 1.0 + np.array(rises)
        return DelayProfile(name, [0.0, 0.15, 0.3], rmse, rmse, [True] * 3, 0.1, 1.0, 1.0)

    text = _profiles_text([profile("tau_M_p", [0.0005, 0.0001, 0.0]),
                           profile("tau_M_q", [0.0036, 0.0, 0.03]),
                           profile("tau_L_p", [0.017, 0.04, 0.4])])
    assert text == (". The delay profiles (RMSE relative to the free fit's, over 0–0.3 s): flat "
                    "for M_p (at most +0.05%): the data do not determine it, whatever the "
                    "bounds say; zero delay fits within 1 % for M_q (+0.36%)")
    assert _profiles_text([profile("tau_L_p", [0.017, 0.04, 0.4])]) == (
        ". The delay profiles (RMSE over 0–0.3 s) determine every kept delay")
    assert _profiles_text(()) == ""
