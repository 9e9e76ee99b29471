"""The fit report in the outputs' and parameters' own units: derivative units from the signals
they connect, residual RMS and noise standard deviation per output, and the RMSE given only
where it is dimensionless (each residual counted in its reference unit: ft/s, ft/s², deg,
deg/s, deg/s²)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
import rotorid
from rotorid import Derivative, Estimate, FlightCondition, ModelStructure
from rotorid.estimation.integrated import InitialConditions, IntegratedModel
from rotorid.model.modelfile import load_model
from rotorid.model.nonlinear import Parameter
from rotorid.model.parameter_units import structure_parameter_units
from test_integrated_model import STICK_IN_LONG, Pendulum, pendulum_data

FIXED_WING = Path(__file__).parents[1] / "docs" / "examples" / "fixed_wing_linear.toml"
HOVER = FlightCondition.from_airspeed(0.0)


def test_helicopter_derivative_units_by_hand():
    structure = ModelStructure.six_dof(HOVER).with_delays(["L_lat"])
    units = structure_parameter_units(structure)
    # u̇ [ft/s²] per u [ft/s] and ṗ [deg/s²] per p [deg/s]: 1/s.
    assert units["X_u"] == units["L_p"] == "1/s"
    assert units["X_q"] == "ft/s² per deg/s"        # u̇ from q
    assert units["M_w"] == "deg/s² per ft/s"        # q̇ from w
    assert units["Z_coll"] == "ft/s² per %"         # helicopter controls in % of travel
    assert units["L_lat"] == "deg/s² per %"
    assert units["tau_L_lat"] == "s"


def test_si_helicopter_and_declared_fixed_wing_units_by_hand():
    si = structure_parameter_units(ModelStructure.six_dof(HOVER, units="si"))
    assert si["M_u"] == "rad/s² per m/s" and si["N_ped"] == "rad/s² per %"
    units = structure_parameter_units(load_model(FIXED_WING))
    # States V [m/s], alpha [rad], q [rad/s]; controls in the units the file states for them
    # (elevator deg, thrust N).
    assert units["X_V"] == "1/s"
    assert units["X_alpha"] == "m/s² per rad"       # V̇ from α
    assert units["Z_V"] == "rad/s per m/s"          # α̇ from V
    assert units["Z_alpha"] == "1/s"                # α̇ from α
    assert units["M_alpha"] == "1/s²"               # q̇ [rad/s²] from α [rad]
    assert units["M_q"] == "1/s"
    assert units["X_thrust"] == "m/s² per N"
    assert units["Z_elevator"] == "rad/s per deg"
    assert units["M_elevator"] == "rad/s² per deg"
    # The built-in fixed-wing template states none: its controls are in "control unit".
    template = structure_parameter_units(ModelStructure.populated(
        FlightCondition(u0=50.0), "fixed-wing-longitudinal", "si"))
    assert template["M_elevator"] == "rad/s² per control unit"


def _residuals(n_outputs):
    """Two maneuvers whose first two outputs have hand-computable RMS, the rest zero."""
    residuals = [np.zeros((2, n_outputs)), np.zeros((2, n_outputs))]
    residuals[0][:, 0], residuals[1][:, 0] = [1.0, -1.0], [3.0, -3.0]    # RMS √5
    residuals[0][:, 1], residuals[1][:, 1] = [2.0, 2.0], [0.0, 0.0]      # RMS √2
    return residuals


def test_residual_rms_per_output_and_the_report_in_output_units():
    structure = ModelStructure(HOVER, [Derivative("L_p"), Derivative("M_long")])
    estimate = Estimate.from_fit(structure, [-1.0, 0.5], np.diag([4.0, 1.0]), _residuals(8),
                                 estimator="hand")
    np.testing.assert_allclose(estimate.residual_rms, [math.sqrt(5), math.sqrt(2), 0, 0, 0,
                                                       0, 0, 0])
    assert estimate.output_units == ("ft/s²", "ft/s²", "deg/s", "deg", "ft/s²", "deg/s",
                                     "deg", "deg/s")
    report = estimate.report()
    assert "    ax          ft/s²              2.236         2.236" in report
    assert "    az          ft/s²              1.414         1.414" in report
    # Flight-test outputs are in their reference units: eq. 18 as it stands, √(28/32).
    assert estimate.rmse == pytest.approx(math.sqrt(28 / 32))
    assert (f"RMSE               = {math.sqrt(28 / 32):.6g} (dimensionless: eq. 18 with the "
            f"residuals counted in ft/s², deg/s, deg)") in report
    rows = {line.split()[0]: line.split(None, 5)[5] for line in report.splitlines()
            if line.startswith(("    L_p ", "    M_long "))}
    assert rows == {"L_p": "1/s", "M_long": "deg/s² per %"}


def test_si_residuals_are_counted_in_reference_units():
    structure = load_model(FIXED_WING)
    residuals = _residuals(7)                       # V in m/s and alpha in rad
    estimate = Estimate.from_fit(structure, structure.initial_values(),
                                 np.eye(structure.n_parameters), residuals, estimator="hand")
    foot, degree = 0.3048, math.pi / 180
    by_hand = math.sqrt((20 / foot**2 + 8 / degree**2) / (4 * 7))
    assert estimate.rmse == pytest.approx(by_hand, rel=1e-12)
    assert estimate.rmse_basis.startswith("dimensionless")
    np.testing.assert_allclose(estimate.residual_rms[:2], [math.sqrt(5), math.sqrt(2)])
    assert estimate.output_units[:2] == ("m/s", "rad")


class _Unitless:
    """A model of the plain protocol, declaring no units."""

    parameter_names = ("k",)
    output_names = ("y1", "y2")


def test_the_rmse_of_outputs_without_units_is_not_given():
    estimate = Estimate.from_fit(_Unitless(), [1.0], np.eye(1), _residuals(2),
                                 estimator="hand", start=[0.0])
    assert estimate.rmse_basis == ""
    assert "RMSE               = not given: the model declares no output units" in (
        estimate.report())
    record = json.loads(estimate.to_json())
    assert record["rmse"] is None and record["rmse_history"] is None
    assert record["residual_rms"] == pytest.approx([math.sqrt(5), math.sqrt(2)])
    assert math.isnan(Estimate.from_dict(record).rmse)


def test_a_record_written_before_the_units_reads_with_defaults():
    structure = ModelStructure(HOVER, [Derivative("L_p")])
    record = Estimate.from_fit(structure, [-1.0], np.eye(1), _residuals(8),
                               estimator="hand").as_dict()
    for key in ("output_units", "residual_rms", "rmse_basis"):
        del record[key]
    del record["parameters"]["L_p"]["unit"]
    old = Estimate.from_dict(record)
    assert old.output_units == () and old.residual_rms.size == 0 and old.parameter_units == {}


class _PendulumWithUnits(Pendulum):
    parameters = (Parameter("omega2", 5.0, lower=0.0, unit="1/s²"),
                  Parameter("damping", 0.3, unit="1/s"),
                  Parameter("gain", 0.05, unit="rad/s² per %"))


def test_a_nonlinear_model_of_ones_own_is_reported_in_its_signals_units():
    model, data = pendulum_data(seed=11)
    fitted = IntegratedModel(_PendulumWithUnits(), channels=STICK_IN_LONG,
                             initial=InitialConditions(fixed={"theta": 0.0, "q": 0.0}))
    estimate = rotorid.create("estimators", "output-error").estimate(fitted, data)
    assert estimate.output_units == ("rad", "rad/s")
    assert estimate.parameter_units == {"omega2": "1/s²", "damping": "1/s",
                                        "gain": "rad/s² per %"}
    # Residual RMS per output, recomputed from the data (deg → rad) and the fitted model.
    measured = np.concatenate([np.radians(m.columns(("theta", "q"))) for m in data])
    simulated = np.concatenate(fitted.simulate(estimate.values, data))
    by_hand = np.sqrt(np.mean((measured - simulated) ** 2, axis=0))
    np.testing.assert_allclose(estimate.residual_rms, by_hand, rtol=1e-9)
    # The RMSE counts them in deg and deg/s: a pure number.
    in_reference = by_hand * np.degrees(1.0)
    assert estimate.rmse == pytest.approx(math.sqrt(np.mean(in_reference**2)), rel=1e-6)
    assert "(dimensionless: eq. 18 with the residuals counted in deg, deg/s)" in (
        estimate.report())


def test_an_rmse_is_labelled_a_pure_number_only_where_every_output_has_a_reference_unit():
    from rotorid.estimation.estimate import rmse_unit

    assert rmse_unit(("deg/s", "ft/s²", "deg")) == "-"
    assert rmse_unit(("rad/s", "m/s²")) == "-"                 # counted in deg/s and ft/s²
    assert rmse_unit(("deg/s", "N")) == "mixed units"          # a force has no reference unit
