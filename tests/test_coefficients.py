"""Non-dimensional coefficients (rotorid.model.coefficients, ``rotorid coefficients``).

The reference is independent of the conversion's closed forms: an aeroplane whose forces and
moments are written from known coefficients (q̄·S·C with α = atan(w/u), β = asin(v/V),
p̂ = p·b/2V …), its accelerations solved from the rigid body's inertia matrix (Ixz ≠ 0), and
its dimensional derivatives taken by central differences in the model's own units (ft/s, deg,
deg/s; controls in deg). Converting those back must give the coefficients that flew them.
"""

import math

import attrs
import numpy as np
import pytest
from rotorid import FlightCondition, ModelStructure
from rotorid.cli.main import main
from rotorid.errors import UsageError
from rotorid.model.coefficients import Aircraft, non_dimensional
from rotorid.model.templates import FIXED_WING_LATERAL, FIXED_WING_LONGITUDINAL
from rotorid.units import DEGREE, FOOT

AIRCRAFT = {"mass_kg": 1100.0, "wing_area_m2": 16.2, "span_m": 11.0, "chord_m": 1.49,
            "ixx_kgm2": 1285.0, "iyy_kgm2": 1825.0, "izz_kgm2": 2667.0, "ixz_kgm2": 120.0,
            "density_kgm3": 1.112}
SPEED = 55.0  #: trim airspeed, m/s (level, α0 = 0)
#: Coefficients per radian (speed: per V; rates: per 2V/ℓ); ``CX0`` the trim's.
TRUE = {"CX0": -0.03, "CX_u_own": 0.02, "CX_alpha": 0.18, "CZ_alpha": -4.6, "CZ_q": -3.9,
        "CZ_elevator": -0.43, "Cm_alpha": -0.89, "Cm_q": -12.4, "Cm_elevator": -1.28,
        "CY_beta": -0.31, "CY_p": -0.04, "CY_r": 0.21, "CY_rudder": 0.19,
        "Cl_beta": -0.089, "Cl_p": -0.47, "Cl_r": 0.096, "Cl_aileron": -0.18,
        "Cl_rudder": 0.015, "Cn_beta": 0.065, "Cn_p": -0.03, "Cn_r": -0.099,
        "Cn_aileron": -0.005, "Cn_rudder": -0.074}


def _accelerations(x: dict) -> dict:
    """The aeroplane's aerodynamic accelerations (SI-rad) at body velocities, rates and
    control deflections ``x`` (SI-rad)."""
    a, c = AIRCRAFT, TRUE
    speed = math.sqrt(x["u"]**2 + x["v"]**2 + x["w"]**2)
    alpha, beta = math.atan2(x["w"], x["u"]), math.asin(x["v"] / speed)
    p, q, r = (x[k] * length / (2 * speed) for k, length in
               (("p", a["span_m"]), ("q", a["chord_m"]), ("r", a["span_m"])))
    force = 0.5 * a["density_kgm3"] * speed**2 * a["wing_area_m2"]
    cx = c["CX0"] + c["CX_u_own"] * (speed - SPEED) / SPEED + c["CX_alpha"] * alpha
    cz = c["CZ_alpha"] * alpha + c["CZ_q"] * q + c["CZ_elevator"] * x["elevator"]
    cm = c["Cm_alpha"] * alpha + c["Cm_q"] * q + c["Cm_elevator"] * x["elevator"]
    cy = c["CY_beta"] * beta + c["CY_p"] * p + c["CY_r"] * r + c["CY_rudder"] * x["rudder"]
    cl = (c["Cl_beta"] * beta + c["Cl_p"] * p + c["Cl_r"] * r + c["Cl_aileron"] * x["aileron"]
          + c["Cl_rudder"] * x["rudder"])
    cn = (c["Cn_beta"] * beta + c["Cn_p"] * p + c["Cn_r"] * r + c["Cn_aileron"] * x["aileron"]
          + c["Cn_rudder"] * x["rudder"])
    inertia = np.array([[a["ixx_kgm2"], -a["ixz_kgm2"]], [-a["ixz_kgm2"], a["izz_kgm2"]]])
    p_dot, r_dot = np.linalg.solve(inertia, force * a["span_m"] * np.array([cl, cn]))
    return {"X": force * cx / a["mass_kg"], "Y": force * cy / a["mass_kg"],
            "Z": force * cz / a["mass_kg"], "L": p_dot,
            "M": force * a["chord_m"] * cm / a["iyy_kgm2"], "N": r_dot}


#: SI-rad value of one unit of each variable and equation in the flight-test system (deg).
PER_UNIT = {"u": FOOT, "v": FOOT, "w": FOOT, "p": DEGREE, "q": DEGREE, "r": DEGREE,
            "elevator": DEGREE, "aileron": DEGREE, "rudder": DEGREE, "throttle": 1.0,
            "X": FOOT, "Y": FOOT, "Z": FOOT, "L": DEGREE, "M": DEGREE, "N": DEGREE}


def _dimensional(structure) -> dict:
    """Every derivative of ``structure`` by central differences of :func:`_accelerations`,
    in flight-test units per the variable's unit."""
    trim = {"u": SPEED, "v": 0.0, "w": 0.0, "p": 0.0, "q": 0.0, "r": 0.0, "elevator": 0.0,
            "aileron": 0.0, "rudder": 0.0, "throttle": 0.0}
    values = {}
    for derivative in structure.derivatives:
        letter, variable = derivative.letter, derivative.variable
        step = 1e-4 / PER_UNIT[variable]
        up, down = dict(trim), dict(trim)
        up[variable] += step * PER_UNIT[variable]
        down[variable] -= step * PER_UNIT[variable]
        slope = (_accelerations(up)[letter] - _accelerations(down)[letter]) / (2 * step)
        values[derivative.name] = slope / PER_UNIT[letter]
    return values


def _structure(template, controls):
    return ModelStructure.populated(FlightCondition(u0=SPEED),
                                    attrs.evolve(template, control_units=controls),
                                    "flight-test")


@pytest.mark.parametrize("template, controls", [
    (FIXED_WING_LONGITUDINAL, {"elevator": "deg"}),
    (FIXED_WING_LATERAL, {"aileron": "deg", "rudder": "deg"})], ids=["longitudinal", "lateral"])
def test_coefficients_of_finite_difference_derivatives_are_those_that_flew(template, controls):
    structure = _structure(template, controls)
    rows, skipped = non_dimensional(structure, _dimensional(structure), Aircraft(**AIRCRAFT))
    found = {row.name: row.value for row in rows}
    expected = {name: value for name, value in TRUE.items() if name in found}
    if template is FIXED_WING_LONGITUDINAL:
        expected["CX_u"] = 2 * TRUE["CX0"] + TRUE["CX_u_own"]
        assert any(reason.startswith("X_throttle: throttle is a control in %")
                   for reason in skipped), skipped
    assert len(expected) >= 8
    for name, value in expected.items():
        assert found[name] == pytest.approx(value, rel=1e-5, abs=1e-7), name
    # terms the aeroplane has none of come out zero (Z_u, M_u at α0 = 0; Y_v's partners)
    zero = {"CZ_u", "Cm_u", "CX_q", "CX_elevator", "CY_aileron"} & set(found)
    assert zero and all(abs(found[name]) < 1e-6 for name in zero)


def test_coefficients_carry_the_estimates_bounds_through_the_inertia_coupling():
    """With an estimate, each coefficient's bound is its covariance propagated: for Cl_p,
    √(a²σ_L² + c²σ_N² + 2ac·ρσ_Lσ_N) with a, c the conversion's factors on L_p and N_p."""
    from rotorid.estimation.estimate import Estimate

    structure = _structure(FIXED_WING_LATERAL, {"aileron": "deg", "rudder": "deg"})
    values = _dimensional(structure)
    names = structure.parameter_names
    bounds = np.array([0.05 * abs(values[n]) + 1e-3 for n in names])
    correlation = np.eye(len(names))
    i, j = names.index("L_p"), names.index("N_p")
    correlation[i, j] = correlation[j, i] = 0.6
    estimate = attrs.evolve(_estimate_stub(Estimate, names, values, bounds),
                            correlation=correlation)
    aircraft = Aircraft(**AIRCRAFT)
    rows, _ = non_dimensional(structure, values, aircraft, estimate)
    cl_p = next(row for row in rows if row.name == "Cl_p")
    speed, pressure = SPEED, 0.5 * AIRCRAFT["density_kgm3"] * SPEED**2
    scale = (AIRCRAFT["ixx_kgm2"] / (pressure * AIRCRAFT["wing_area_m2"] * AIRCRAFT["span_m"])
             * 2 * speed / AIRCRAFT["span_m"])
    a, c = scale, -scale * AIRCRAFT["ixz_kgm2"] / AIRCRAFT["ixx_kgm2"]
    expected = math.sqrt((a * bounds[i])**2 + (c * bounds[j])**2
                         + 2 * a * c * 0.6 * bounds[i] * bounds[j])
    assert cl_p.bound == pytest.approx(expected, rel=1e-4)
    assert cl_p.value == pytest.approx(TRUE["Cl_p"], rel=1e-5)


def _estimate_stub(cls, names, values, bounds):
    """An :class:`Estimate` of ``values`` with ``bounds`` (the fields a fit would fill)."""
    count = len(names)
    return cls(estimator="output-error", parameter_names=names,
               values=[values[n] for n in names], start=np.zeros(count), cramer_rao=bounds,
               insensitivity=bounds, correlation=np.eye(count), information=np.eye(count),
               noise_covariance=np.eye(1), output_names=("p",), cost=1.0, rmse=1.0,
               cost_history=(1.0,), rmse_history=(1.0,), iterations=1, converged=True,
               stop_reason="test", n_samples=100)


def test_aircraft_data_are_checked_with_the_fix():
    with pytest.raises(UsageError, match="missing ixz_kgm2.*give mass_kg"):
        Aircraft.from_mapping({k: v for k, v in AIRCRAFT.items() if k != "ixz_kgm2"})
    with pytest.raises(UsageError, match="unknown key.*mass"):
        Aircraft.from_mapping({**AIRCRAFT, "mass": 3.0})
    with pytest.raises(UsageError, match="span_m = -11.0.*positive"):
        Aircraft.from_mapping({**AIRCRAFT, "span_m": -11.0})
    with pytest.raises(UsageError, match="density_kgm3 = nan"):
        Aircraft.from_mapping({**AIRCRAFT, "density_kgm3": float("nan")})
    assert Aircraft.from_mapping({**AIRCRAFT, "ixz_kgm2": -40}).ixz_kgm2 == -40.0


def test_hover_has_no_coefficients():
    structure = ModelStructure.populated(FlightCondition(), "longitudinal", "flight-test")
    with pytest.raises(UsageError, match="trim airspeed"):
        non_dimensional(structure, {}, Aircraft(**AIRCRAFT))


def test_the_command_prints_and_writes_the_declared_aeroplanes_coefficients(tmp_path, capsys):
    """``rotorid coefficients`` on the identified model of docs/examples/fixed_wing_linear.toml
    (states V, alpha, q, theta; elevator in deg, thrust in N): a coefficient per derivative of
    a force or moment on V, α, q or the elevator with a finite bound, the thrust's left out
    and named; the CSV holds the same numbers; an existing CSV is kept without --force."""
    from rotorid.estimation.result_file import load_result
    from test_cli_verify_fixed_wing import _identified

    result = _identified(tmp_path, capsys)
    aircraft = tmp_path / "aircraft.toml"
    aircraft.write_text("[aircraft]\n" + "".join(f"{k} = {v}\n" for k, v in AIRCRAFT.items()),
                        encoding="utf-8")
    table = tmp_path / "coefficients.csv"
    assert main(["coefficients", str(result), "--aircraft", str(aircraft), "--csv",
                 str(table)]) == 0
    printed = capsys.readouterr().out
    assert "left out: X_thrust: thrust is a control in N: no coefficient" in printed
    identified = load_result(result)
    rows, _ = non_dimensional(identified.structure, identified.values, Aircraft(**AIRCRAFT),
                              identified.estimate)
    lines = table.read_text(encoding="utf-8").splitlines()
    assert lines[0] == "coefficient,derivative,value,cramer_rao"
    written = {line.split(",")[0]: [float(x) for x in line.split(",")[2:]] for line in lines[1:]}
    assert set(written) == {row.name for row in rows} == {
        "CX_V", "CX_alpha", "CZ_V", "CZ_alpha", "CZ_elevator", "Cm_alpha", "Cm_q", "Cm_elevator"}
    for row in rows:
        assert written[row.name] == [row.value, row.bound]
        assert 0 < row.bound < abs(row.value), row
        assert row.name in printed
    pressure = 0.5 * AIRCRAFT["density_kgm3"] * 50.0**2
    moment = AIRCRAFT["iyy_kgm2"] / (pressure * AIRCRAFT["wing_area_m2"] * AIRCRAFT["chord_m"])
    assert written["Cm_q"][0] == pytest.approx(
        identified.values["M_q"] * moment * 2 * 50.0 / AIRCRAFT["chord_m"], rel=1e-9)
    assert main(["coefficients", str(result), "--aircraft", str(aircraft), "--csv",
                 str(table)]) != 0
    assert "exists already" in capsys.readouterr().err
