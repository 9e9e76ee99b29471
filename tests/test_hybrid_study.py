"""The built-in cases' three models (``[compare] hybrid`` in hover.toml and forward.toml) on
the truth model's data: the hybrid's flap time constants and rotor terms against the truth's
flap-coupled linearisation, its quasi-steady roll and pitch derivatives against the truth's
6-DoF linearisation, and its J and MUAD against the delayed model's (issue "the hybrid
rotor-body model"; docs/study.md, "Three models").

The default suite reads the shared quick study; the slow test runs the full setup, where the
targets are stated (τ_f within 15 % of 16/(γΩ), damping and control within 20 % of the
flap-coupled reference, on-axis J below the delayed model's)."""

import contextlib
import io
import json

import numpy as np
import pytest
from rotorid.cli.main import main

#: The rotor's flap time constant 16/(γΩ) of the truth model, s (docs/hybrid.md).
FLAP_TIME_CONSTANT = 0.0711
#: The roll and pitch damping and control power, as the hybrid's quasi-steady form has them.
ROLL_PITCH = ("L_p", "L_lat", "M_q", "M_long")


def _hybrid(out, case) -> dict:
    return json.loads((out / case / "result.json").read_text(encoding="utf-8"))[
        "hybrid_comparison"]


def _check_rotor_terms(hybrid, time_constant_tolerance=0.15, term_tolerance=0.20):
    """τ_f of both flap equations near 16/(γΩ) and the rotor terms near the truth's
    flap-coupled values (the reference the comparison itself records)."""
    for name, tau in hybrid["flap_time_constants_s"].items():
        assert tau["identified"] == pytest.approx(FLAP_TIME_CONSTANT,
                                                  rel=time_constant_tolerance), name
    for name, term in hybrid["rotor_terms"].items():
        assert term["identified"] == pytest.approx(term["reference"], rel=term_tolerance), name


@pytest.mark.parametrize("case", ["hover", "forward"])
def test_quick_cases_hybrid_meets_the_rotor_targets_where_the_six_dof_models_do_not(
        quick_study, case):
    hybrid = _hybrid(quick_study.out, case)
    _check_rotor_terms(hybrid)
    truth = hybrid["six_dof_reference"]
    models = hybrid["models"]
    missed = []
    for name in ROLL_PITCH:
        quasi_steady = models["hybrid"]["flap_shaped_derivatives"][name]["value"]
        delayed = models["with delays"]["flap_shaped_derivatives"][name]["value"]
        assert quasi_steady == pytest.approx(truth[name], rel=0.10), name
        assert abs(quasi_steady / truth[name] - 1.0) < abs(delayed / truth[name] - 1.0), name
        if abs(delayed / truth[name] - 1.0) > 0.2:     # the equivalent system's
            missed.append(name)
    # the delayed 6-DoF model is an equivalent system: most of its roll and pitch terms are
    # far from the quasi-steady ones (on some machines the forward case's M_long lands 6 % off)
    assert len(missed) >= len(ROLL_PITCH) - 1, missed
    costs = {label: models[label]["mismatch_cost"] for label in models}
    mean = {label: np.mean([c["q/long"], c["p/lat"], c["q/lat"], c["p/long"]])
            for label, c in costs.items()}
    assert mean["hybrid"] < mean["with delays"] < mean["no delays"]
    inside = models["hybrid"]["muad_points_inside"]
    assert all(inside[p]["inside"] == inside[p]["counted"] > 100
               for p in ("q/long", "p/lat", "q/lat"))


def test_quick_report_shows_the_three_models(quick_study):
    page = (quick_study.out / "hover" / "report.html").read_text(encoding="utf-8")
    assert 'id="hybrid"' in page and "Roll and pitch derivatives of the three models" in page
    tables = quick_study.out / "hover" / "tables"
    for name in ("hybrid_models", "hybrid_muad", "hybrid_derivatives", "hybrid_terms"):
        assert (tables / f"{name}.csv").stat().st_size > 0


@pytest.mark.slow
def test_full_cases_hybrid_meets_the_issue_targets(tmp_path):
    """The full setup of both built-in cases (delay profiles off): τ_f within 15 %, the hub
    moments and cyclic into flapping within 20 % of the flap-coupled reference, and the
    on-axis cyclic J below the delayed model's."""
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main(["study", "all", "--no-figures", "--out", str(tmp_path)]) == 0
    for case in ("hover", "forward"):
        hybrid = _hybrid(tmp_path, case)
        _check_rotor_terms(hybrid)
        costs = {label: model["mismatch_cost"] for label, model in hybrid["models"].items()}
        for pair in ("q/long", "p/lat"):
            assert costs["hybrid"][pair] < costs["with delays"][pair], (case, pair)
