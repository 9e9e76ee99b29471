"""The coning/inflow hybrid model (docs/hybrid.md, "Coning and inflow"): its known terms, the
truth model's coning and inflow rows against the hand derivation, the start's quasi-steady
form, and recovery of every parameter from data simulated with the model itself."""

import math

import numpy as np
import pytest
from hybrid_reference import (
    hybrid_reference,
    open_loop_maneuvers,
    recovery,
    six_dof_of,
    true_values,
)
from rotorid import FlightCondition, ModelStructure
from rotorid.errors import StructureError
from rotorid.model.coning_inflow import (
    CONING_DERIVATIVES,
    HEAVE_DERIVATIVES,
    INFLOW_DERIVATIVES,
    coning_gain,
    coning_inflow_from_hybrid,
)
from rotorid.model.hybrid import hybrid_from_six_dof
from rotorid.model.residualisation import residualise
from rotorid.model.templates import HYBRID, HYBRID_FLAP, HYBRID_INFLOW, HYBRID_INFLOW_FLAP
from rotorid.model.residualisation import derivatives_of
from rotorid.units import FLIGHT_TEST, SI
from rotorid_helisim.linearize import linearize

RADIUS = 4.91  #: m, the truth model's rotor


@pytest.mark.parametrize("units", ["flight-test", "si"])
def test_known_terms_are_the_hybrids_with_no_coning_or_inflow_term(units):
    """The coning and inflow rows have no known term (every coefficient depends on the
    rotor); the measured rotor outputs (``-flap`` templates) read their states."""
    condition = FlightCondition.from_airspeed(70.0, 2.0, -1.5)
    hybrid = ModelStructure.populated(condition, "hybrid", units).known_terms()
    for template in (HYBRID_FLAP, HYBRID_INFLOW, HYBRID_INFLOW_FLAP):
        known = ModelStructure.populated(condition, template, units).known_terms()
        assert np.array_equal(known.a[:10, :10], hybrid.a)
        assert not known.a[10:].any() and not known.a[:, 10:].any() and not known.d.any()
        assert np.array_equal(known.c[:8, :10], hybrid.c)
        assert np.array_equal(known.measured[:8, :10], hybrid.measured)
        for row, name in enumerate(template.outputs[8:], start=8):
            assert known.c[row].tolist() == [float(s == name) for s in template.states]
    assert ModelStructure.populated(condition, HYBRID_INFLOW, units).signals.states[
        "vi"].unit == ("ft/s" if units == "flight-test" else "m/s")


@pytest.fixture(scope="module")
def reference(truth_model, hover_trim, trim_70kt):
    """{airspeed: (condition, A, B)} of the coning/inflow reference, flight-test units."""
    return {kt: hybrid_reference(truth_model, trim, HYBRID_INFLOW)
            for kt, trim in ((0, hover_trim), (70, trim_70kt))}


def test_truth_rows_follow_the_hand_derivation(reference, truth_model, hover_trim):
    """Hover, flight-test units. First-order coning (β0'' dropped):
    β̇0 = −(8λβ²Ω/γ)·β0 + Ω·θ0 − (4/3)·Ω·(λ0 − μz), i.e. B0_vi = −B0_w = −4/(3R) and B0_coll =
    Ω times the collective gearing; momentum inflow (8/3π)λ0' = C_T − 2λ0² about hover:
    Vi_vi ≈ −(3π/2)·λ0·Ω and Vi_w ≈ −Vi_vi/2 (the thrust's own change moves them by 6–12 %)."""
    condition, a, b = reference[0]
    structure = ModelStructure.populated(condition, HYBRID_INFLOW)
    truth = derivatives_of(structure, a, b)
    config = truth_model.config
    omega, deg = config.omega, math.degrees(1.0)
    k = coning_gain(RADIUS, FLIGHT_TEST)
    assert k == pytest.approx(4.0 / (3.0 * RADIUS) * deg * 0.3048)
    assert truth["B0_beta0"] == pytest.approx(
        -8.0 * config.flap_frequency_squared * omega / config.lock_number, rel=1e-3)
    assert truth["B0_vi"] == pytest.approx(-k, rel=2e-3)
    assert truth["B0_w"] == pytest.approx(k, rel=2e-3)
    assert truth["B0_coll"] == pytest.approx(omega * config.mixing.gain[0] * deg, rel=1e-3)
    lambda0 = hover_trim.state[truth_model.index["lambda0"]]
    assert truth["Vi_vi"] == pytest.approx(-1.5 * math.pi * lambda0 * omega, rel=0.08)
    assert truth["Vi_w"] == pytest.approx(0.75 * math.pi * lambda0 * omega, rel=0.15)
    assert truth["Z_coll"] == pytest.approx(0.0, abs=1e-3)


def test_reference_keeps_the_coupled_coning_inflow_mode(reference, truth_model, hover_trim):
    """The full hover model's coning/inflow mode (−17.9 rad/s) survives as the reference's
    inflow mode (−18.1), beside the first-order coning at −80."""
    _, a, _ = reference[0]
    eigenvalues = np.linalg.eigvals(a)
    real = np.sort(eigenvalues[np.abs(eigenvalues.imag) < 1e-9].real)
    assert real[0] == pytest.approx(-80.1, abs=0.5)
    assert real[1] == pytest.approx(-18.1, abs=0.2)
    full = linearize(truth_model, hover_trim, full=True).eigenvalues
    assert np.min(np.abs(full - (-17.9))) < 0.05


def test_start_has_the_hybrid_model_as_its_quasi_steady_form(reference):
    condition, a, b = reference[70]
    a_h, b_h = residualise(a, b, HYBRID_INFLOW.states, HYBRID.states)
    six_dof, values = six_dof_of(condition, a_h, b_h)
    hybrid = hybrid_from_six_dof(six_dof, values, flap_time_constant=0.09)
    hybrid_values = hybrid.initial_values()
    extended = coning_inflow_from_hybrid(hybrid, hybrid_values, RADIUS)
    assert extended.template is HYBRID_INFLOW
    assert extended.derivative("B0_vi").fixed
    assert "Z_coll" not in extended.names
    assert extended.derivative("Bc_long").delay is not None
    assert extended.derivative("B0_coll").delay is not None
    a_e, b_e, _, _ = extended.matrices()
    a_q, b_q = residualise(a_e, b_e, extended.states, HYBRID.states)
    a_0, b_0, _, _ = hybrid.matrices(hybrid_values)
    assert a_q == pytest.approx(a_0, abs=1e-9)
    assert b_q == pytest.approx(b_0, abs=1e-9)


def test_start_refuses_what_it_cannot_map(reference):
    condition, _, _ = reference[70]
    hybrid = ModelStructure.populated(condition, "hybrid")
    with pytest.raises(StructureError, match="Z_w"):
        coning_inflow_from_hybrid(hybrid, hybrid.initial_values(), RADIUS)
    with pytest.raises(StructureError, match="radius"):
        coning_inflow_from_hybrid(hybrid.with_initial({"Z_w": -0.5}),
                                  hybrid.with_initial({"Z_w": -0.5}).initial_values(), 0.0)
    with pytest.raises(StructureError, match="hybrid structure"):
        six_dof = ModelStructure.six_dof(condition)
        coning_inflow_from_hybrid(six_dof, six_dof.initial_values(), RADIUS)
    assert coning_gain(RADIUS, SI) == pytest.approx(4.0 / (3.0 * RADIUS))


def test_every_parameter_recovered_within_3_cramer_rao_bounds(reference):
    """Data simulated with the 70 kt coning/inflow reference (multisteps of 6 % of travel;
    β0 β1c β1s measured with 0.1 deg noise, vi unmeasured; delays 0.03 s on the controls
    into flapping and on B0_coll); the fit starts from the coning/inflow start of the hybrid
    start (τ_f 0.12 s) of the quasi-steady 6-DoF model.

    Over noise seeds 1–6 all six fits converged, the errors in bounds had an RMS of
    0.80–1.18 and a largest of 2.3–3.2 among the 84 parameters (seed 6: N_w at 3.24); the test
    uses seed 1. With 2 % multisteps (the coning then moves about as much as its noise) three
    of six fits stopped unconverged; with
    β0 unmeasured Vi_beta0 and Z_vi have no finite bound even with B0_coll fixed as well
    (docs/hybrid.md)."""
    condition, a, b = reference[70]
    a_h, b_h = residualise(a, b, HYBRID_INFLOW.states, HYBRID.states)
    six_dof, six_values = six_dof_of(condition, a_h, b_h)
    hybrid = hybrid_from_six_dof(six_dof, six_values, flap_time_constant=0.12,
                                 template="hybrid-flap")
    structure = coning_inflow_from_hybrid(hybrid, hybrid.initial_values(), RADIUS)
    assert structure.template is HYBRID_INFLOW_FLAP
    truth = derivatives_of(structure, a, b)
    structure = structure.fixing("B0_vi", truth["B0_vi"])
    values = true_values(structure, a, b)
    maneuvers = open_loop_maneuvers(structure, values, seed=1, amplitude=6.0)
    estimate, error = recovery(structure, maneuvers, values)
    worst = {n: round(float(e), 2) for n, e in zip(structure.parameter_names, error)
             if abs(e) > 3.0}
    assert not worst, f"beyond 3 Cramér-Rao bounds: {worst}"
    assert 0.7 < np.sqrt(np.mean(error**2)) < 1.3
    assert set(CONING_DERIVATIVES + INFLOW_DERIVATIVES + HEAVE_DERIVATIVES) <= set(
        structure.names)
    relative = {n: estimate.cramer_rao[structure.parameter_names.index(n)] / abs(truth[n])
                for n in ("B0_beta0", "Vi_vi", "Z_beta0")}
    assert max(relative.values()) < 0.1, relative
