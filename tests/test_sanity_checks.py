"""Sanity checks before a fit (rotorid.estimation.sanity, rotorid.estimation.kinematics): each
fires on data the test spoils in one known way, with the numbers it was spoilt by, and clean
closed-loop data stay silent."""

from __future__ import annotations

import html
import json
import math
import warnings

import attrs
import numpy as np
import pytest
from hover_reference import closed_loop_maneuvers, true_structure
from rotorid import Maneuver, ManeuverSet
from rotorid.data import INPUT_CHANNELS, OUTPUT_CHANNELS
from rotorid.errors import DataWarning
from rotorid.estimation.kinematics import check_kinematics, kinematic_fits
from rotorid.estimation.sanity import check_before_fit, check_data
from rotorid.model.modelfile import parse_model
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.report.html import case_html, write_study_report
from rotorid.simulation.simulator import simulate
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import Study, checked_structure
from rotorid.units import FLIGHT_TEST
from rotorid_files.formats import write_maneuver


@pytest.fixture(scope="module")
def model():
    return true_structure()


@pytest.fixture(scope="module")
def clean(model):
    structure, values = model
    return closed_loop_maneuvers(structure, values, duration=10.0)


def _messages(maneuvers, structure=None, condition=None) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DataWarning)
        if structure is None:
            check_data(maneuvers, condition)
        else:
            check_before_fit(maneuvers, structure)
    return [str(w.message) for w in caught if issubclass(w.category, DataWarning)]


def _changed(maneuvers, change) -> ManeuverSet:
    """Every maneuver's outputs passed through ``change(outputs_copy) -> outputs``."""
    return ManeuverSet([m.with_outputs(change(m.outputs.copy())) for m in maneuvers])


def _column(name: str) -> int:
    return OUTPUT_CHANNELS.index(name)


def test_clean_data_raise_no_warning_and_keep_the_structure(model, clean):
    structure, _ = model
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)
        assert check_before_fit(clean, structure) == structure


def test_an_absolute_pitch_attitude_is_named_with_its_offset(model, clean):
    def offset(y):
        y[:, _column("theta")] += 5.0
        return y

    messages = _messages(_changed(clean, offset), model[0])
    [message] = [m for m in messages if m.startswith("output 'theta' starts away")]
    assert "absolute attitude" in message and "16 of 16" in message
    level = float(message.split(": ")[1].split(" deg")[0])
    assert level == pytest.approx(5.0, abs=0.1)
    assert "--trim first-second" in message


def test_az_holding_one_g_is_named_and_not_reported_as_an_offset(model, clean):
    def gravity(y):
        y[:, _column("az")] -= 9.80665 / 0.3048
        return y

    messages = _messages(_changed(clean, gravity), model[0])
    [message] = [m for m in messages if "'az'" in m]
    assert message.startswith("output 'az' holds 1 g (median -32.")
    assert "can ignore this" not in message
    # a model of one's own may read the total: told when to ignore it
    own = type("OwnModel", (), {"signals": model[0].signals})()
    [message] = [m for m in _messages(_changed(clean, gravity), own) if "'az'" in m]
    assert message.endswith("a model of one's own that reads the total acceleration can "
                            "ignore this")
    # a stated trim of −1 (g given where ft/s² was meant) already taken off: the suggestion
    # is the whole trim, not what is left
    stated = ManeuverSet([attrs.evolve(m, metadata={**m.metadata, "trim_removed": {"az": -1.0},
                                                    "trim_units": "flight-test"})
                          for m in _changed(clean, gravity)])
    [message] = [m for m in _messages(stated, model[0]) if "'az'" in m]
    median = float(message.split("(median ")[1].split(" ")[0])
    assert f"--trim az={median - 1.0:.4g}, which includes the -1 ft/s² already removed" \
        in message


def test_an_angle_in_deg_read_as_rad_is_named(model, clean):
    """φ recorded in deg but declared rad reaches 57.3 times its swing in deg: past 180°."""
    def read_as_rad(y):
        y[:, _column("phi")] = np.degrees(y[:, _column("phi")])
        return y

    largest = max(float(np.max(np.abs(m.channel("phi")))) for m in clean)
    assert largest < 180.0 < 57.3 * largest
    [message] = [m for m in _messages(_changed(clean, read_as_rad), model[0])
                 if "beyond any maneuver's angle" in m]
    assert message.startswith("output 'phi' reaches ") and '{"phi": "deg"}' in message
    assert not [m for m in _messages(clean, model[0]) if "beyond any maneuver's angle" in m]


def test_rates_recorded_in_rad_per_s_are_named(model, clean):
    def in_radians(y):
        for name in ("q", "p", "r"):
            y[:, _column(name)] = np.radians(y[:, _column(name)])
        return y

    messages = _messages(_changed(clean, in_radians), model[0])
    assert any(m.startswith("the largest angular rate") and "rad/s?" in m for m in messages)
    # the attitudes (deg) change 57.3 times as fast as the integrated rates
    kinematic = [m for m in messages if m.startswith("kinematic consistency: theta")]
    assert kinematic and "its driver (q, r) in rad" in kinematic[0]


def test_one_gyro_read_in_the_wrong_unit_is_found_by_its_attitude(model, clean):
    """q recorded in rad/s but read as deg/s: θ̇ = cos Φ0 q − sin Φ0 r then follows neither
    term of its driver together, but q's alone with the units' ratio as the scale."""
    structure, _ = model

    def q_in_radians(y):
        y[:, _column("q")] = np.radians(y[:, _column("q")])
        return y

    wrong = _changed(clean, q_in_radians)
    [theta] = [f for f in kinematic_fits(wrong, structure.condition) if f.channel == "theta"]
    assert theta.driver == "q"
    assert theta.scale == pytest.approx(math.degrees(1.0), rel=0.03)   # the r term left out
    [message] = [m for m in _messages(wrong, structure)
                 if m.startswith("kinematic consistency: theta")]
    assert "theta is in deg and its driver (q) in rad" in message
    # the consistent channels keep their full drivers
    [phi] = [f for f in kinematic_fits(clean, structure.condition) if f.channel == "phi"]
    assert phi.driver == "q, p, r" and phi.scale == pytest.approx(1.0, abs=0.02)


def _checked_with_inputs_held(clean, held, model):
    """check_before_fit on ``clean`` with the ``held`` inputs at 0 throughout: what it
    returns, and the warnings' messages."""
    columns = [INPUT_CHANNELS.index(c) for c in held]
    still = []
    for m in clean:
        inputs = m.inputs.copy()
        inputs[:, columns] = 0.0
        still.append(attrs.evolve(m, inputs=inputs))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DataWarning)
        checked = check_before_fit(ManeuverSet(still), model)
    return checked, [str(w.message) for w in caught]


def test_an_input_that_never_moves_drops_its_derivatives_before_the_fit(model, clean):
    structure, _ = model
    reduced, messages = _checked_with_inputs_held(clean, ("lat",), structure)
    dropped = sorted(set(structure.names) - set(reduced.names))
    assert dropped == sorted(f"{letter}_lat" for letter in "XYZLMN")
    [message] = [m for m in messages if "'lat'" in m]
    assert message.startswith("input 'lat' never moves (constant 0 in every maneuver)")
    assert "drops X_lat, Y_lat, Z_lat, L_lat, M_lat, N_lat before the first fit" in message


def test_a_model_of_ones_own_hears_only_of_the_unmoving_inputs_it_reads(model, clean):
    """A model of one's own reading long and coll (its signals': a longitudinal structure's,
    as a nonlinear model would declare them) is told of coll held still, not of lat and ped,
    which it does not read; it is returned as None (nothing to drop)."""
    structure, _ = model
    longitudinal = ModelStructure(structure.condition, [], template="longitudinal")
    own = type("OwnModel", (), {"signals": longitudinal.signals})()
    checked, messages = _checked_with_inputs_held(clean, ("lat", "coll", "ped"), own)
    assert checked is None
    unmoving = [m for m in messages if "never moves" in m]
    assert len(unmoving) == 1 and unmoving[0].startswith("input 'coll' never moves")


def test_a_clipped_rate_gyro_and_a_dropout_are_named_with_time_and_length(model, clean):
    first = clean[0]
    q = first.outputs[:, _column("q")].copy()
    limit = 0.6 * q.max()
    clipped = np.minimum(q, limit)
    held = first.outputs[:, _column("p")].copy()
    held[400:408] = held[400]  # mid-record, away from the extremes
    outputs = first.outputs.copy()
    outputs[:, _column("q")], outputs[:, _column("p")] = clipped, held
    spoilt = ManeuverSet([first.with_outputs(outputs), *clean[1:]])
    messages = _messages(spoilt, model[0])
    clip = [m for m in messages if m.startswith("output 'q' sits at its extreme")]
    assert clip and f"{limit:.6g} deg/s" in clip[0]
    run = np.flatnonzero(clipped == limit)
    assert f"from t = {first.time[run[0]]:.4g} s" in clip[0]
    [dropout] = [m for m in messages if m.startswith("output 'p' repeats")]
    assert f"for 8 samples ({8 * first.dt:.3g} s) from t = {first.time[400]:.4g} s" in dropout


def test_flight_path_reconstruction_finds_a_rate_bias_and_a_scale_factor(model, clean):
    structure, _ = model

    def biased(y):
        y[:, _column("q")] += 0.5
        return y

    [theta] = [f for f in kinematic_fits(_changed(clean, biased), structure.condition)
               if f.channel == "theta"]
    # θ̇ = cos Φ0 q − sin Φ0 r: a bias of 0.5 deg/s on q is cos Φ0 · 0.5 on the driver
    assert theta.bias == pytest.approx(0.5 * math.cos(structure.condition.phi0), rel=0.05)
    assert theta.scale == pytest.approx(1.0, abs=0.02)
    assert any("bias" in m and m.startswith("kinematic consistency: theta")
               for m in _messages(_changed(clean, biased), structure))

    def scaled(y):
        y[:, _column("p")] *= 1.25
        return y

    [phi] = [f for f in kinematic_fits(_changed(clean, scaled), structure.condition)
             if f.channel == "phi"]
    assert phi.scale == pytest.approx(1 / 1.25, rel=0.03)


def _hover_record(ax_scale: float, theta_amplitude: float) -> ManeuverSet:
    """Analytic hover record, at rest for 1 s, then with s = t − 1 s: θ = A (1 − cos ωs) (deg),
    u = 3 ft/s (1 − cos 2ωs), u̇ = ax − g θ (rad); ``ax`` is recorded ``ax_scale`` times its
    true value. Sensor noise of 0.001 keeps the outputs from repeating a value."""
    t = np.arange(0.0, 20.0, 0.01)
    s = np.maximum(t - 1.0, 0.0)
    omega = 0.8
    theta = theta_amplitude * (1 - np.cos(omega * s))
    u = 3.0 * (1 - np.cos(2 * omega * s))
    ax = 6.0 * omega * np.sin(2 * omega * s) + FLIGHT_TEST.g * np.radians(theta)
    outputs = np.zeros((t.size, 8))
    outputs[:, _column("theta")] = theta
    outputs[:, _column("q")] = theta_amplitude * omega * np.sin(omega * s)
    outputs[:, _column("ax")] = ax_scale * ax
    outputs += np.random.default_rng(1).normal(scale=1e-3, size=outputs.shape)
    inputs = np.zeros((t.size, 4))
    inputs[:, 0] = np.sin(omega * s)
    return ManeuverSet([Maneuver("analytic", t, inputs, outputs, extra_channels={"u": u})])


def test_accelerations_are_checked_against_velocities_where_the_data_carry_them():
    consistent = {f.channel: f for f in kinematic_fits(_hover_record(1.0, 2.0))}
    assert consistent["theta"].scale == pytest.approx(1.0, abs=1e-3)
    assert consistent["u"].driver == "ax, theta"
    assert consistent["u"].unit == "ft/s²"
    assert consistent["u"].scale == pytest.approx(1.0, abs=1e-3)
    assert not _messages(_hover_record(1.0, 2.0))
    # with θ = 0 the driver is ax alone: recorded 0.8 times too small, u needs k = 1.25
    [u] = kinematic_fits(_hover_record(0.8, 0.0))
    assert u.scale == pytest.approx(1.25, rel=1e-3)
    [message] = [m for m in _messages(_hover_record(0.8, 0.0)) if m.startswith("kinematic")]
    assert message.startswith("kinematic consistency: u against integrated ax, theta: "
                              "scale 1.25")


def test_a_study_drops_unexcited_derivatives_and_reports_each_warning(model, clean):
    structure, _ = model
    still = ManeuverSet([attrs.evolve(m, inputs=m.inputs * [1, 1, 0, 1]) for m in clean])
    lines = []
    checked, messages = checked_structure(FlightCase.load("hover"), structure, still,
                                          lambda case, message: lines.append((case, message)))
    assert {"Z_coll", "M_coll"}.isdisjoint(checked.names) and "Z_w" in checked.names
    assert lines == [("hover", line) for _, line in lines]
    assert any(line.startswith("warning: input 'coll' never moves") for _, line in lines)
    assert [f"warning: {m}" for m in messages] == [line for _, line in lines
                                                   if line.startswith("warning: ")]
    # the kinematic fits the checks log are the case's progress lines too (not bare lines)
    fits = [line for _, line in lines if line.startswith("kinematic consistency: ")]
    assert {line.split(" against")[0] for line in fits} >= {"kinematic consistency: theta",
                                                           "kinematic consistency: phi"}
    assert len(fits) + len(messages) == len(lines)


def test_a_study_records_its_data_warnings_and_its_report_shows_them(tmp_path):
    """A files case whose structure has Z_coll while its doublets move long only: the warning
    that drops Z_coll is in result.json and in the report's summary (the case page and the
    study page), word for word."""
    structure = parse_model({"units": "flight-test", "condition": {"airspeed_kt": 0.0},
                             "structure": {"populate": "none"},
                             "derivatives": {"M_q": {}, "M_long": {}}}, "model")
    n = 500
    inputs = np.zeros((n, 4))
    inputs[25:75, 0], inputs[75:125, 0] = 4.0, -4.0
    blank = ManeuverSet([Maneuver("doublet_long", np.arange(n) * 0.02, inputs,
                                  np.zeros((n, 8)))])
    [outputs] = simulate(structure, structure.as_vector({"M_q": -2.0, "M_long": 0.8}), blank)
    noise = np.random.default_rng(0).normal(size=outputs.shape) * 0.05
    (tmp_path / "ident").mkdir()
    path = write_maneuver(blank[0].with_outputs(outputs + noise),
                          tmp_path / "ident" / "doublet.csv")
    lines = path.read_text(encoding="utf-8").splitlines()
    lines[-100] = lines[-100].rsplit(",", 1)[0] + ","          # r drops out for a sample
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    case = tmp_path / "mine.toml"
    case.write_text('name = "mine"\n[data]\nsource = "files"\nidentification = "ident"\n'
                    'resample = "linear"\n'
                    '[condition]\nairspeed_kt = 0.0\n[structure]\npopulate = "none"\n'
                    '[derivatives]\nM_q = {}\nM_long = {}\nZ_coll = {}\n'
                    '[delays]\nderivatives = []\n')
    result = Study([FlightCase.load(case)], tmp_path / "out", progress=None).run()["mine"]
    [warning] = [w for w in result.data_warnings if "'coll' never moves" in w]
    assert warning.startswith("input 'coll' never moves (constant 0 in every maneuver)")
    assert "drops Z_coll before the first fit" in warning
    [dropout] = [w for w in result.data_warnings if "NaN" in w]          # from reading
    assert "'r'" in dropout and "doublet" in dropout
    record = json.loads((tmp_path / "out" / "mine" / "result.json").read_text())
    assert record["data_warnings"] == list(result.data_warnings)
    shown = "".join(f"<li>{html.escape(w)}</li>" for w in result.data_warnings)
    assert shown in case_html(result, {}, [])
    assert shown in write_study_report({"mine": result}, tmp_path / "out").read_text()


def test_an_offset_on_a_channel_of_ones_own_is_named_with_its_declared_unit():
    """A model's own output (an aeroplane's airspeed V) recorded on top of its trim: named
    with the unit the model's signals declare, and without a unit where none do."""
    from rotorid.model.signals import ModelSignals, Signal, SignalSet

    t = np.arange(0.0, 10.0, 0.02)
    elevator = np.where((t > 2.0) & (t < 3.0), 1.0, 0.0)
    speed = 40.0 + 0.5 * np.sin(2 * np.pi * t)    # whole periods: the first second's mean is 40
    maneuvers = ManeuverSet([Maneuver(f"m{k}", t, elevator[:, None], speed[:, None],
                                      units="si", input_names=("elevator",),
                                      output_names=("V",)) for k in range(2)])
    signals = ModelSignals(states=SignalSet([Signal("V", "m/s", "velocity")]),
                           inputs=SignalSet([Signal("elevator", "deg", "control")]),
                           outputs=SignalSet([Signal("V", "m/s", "velocity")]))
    [declared] = _messages_of(lambda: check_data(maneuvers, None, signals))
    assert declared.startswith("output 'V' starts away from zero in 2 of 2 maneuvers: 40 m/s "
                               "(mean of the first 1 s of m1) against a swing of 0.998 m/s;")
    [bare] = _messages_of(lambda: check_data(maneuvers))
    assert "maneuvers: 40 (mean of the first" in bare


def _messages_of(check) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DataWarning)
        check()
    return [str(w.message) for w in caught if issubclass(w.category, DataWarning)]


def _aeroplane_lateral(ay_factor: float):
    """Rudder and aileron doublets of an aeroplane's lateral template at 60 m/s (SI), with
    ``ay`` recorded ``ay_factor`` times its true value (9.81: in g, read as m/s²)."""
    condition = FlightCondition.from_airspeed(60.0 / 0.5144444, theta0_deg=2.0)
    structure = ModelStructure.populated(condition, "fixed-wing-lateral", "si")
    values = dict.fromkeys(structure.parameter_names, 0.0)
    values.update({"Y_v": -0.2, "L_v": -0.15, "L_p": -6.0, "L_r": 1.2, "N_v": 0.08,
                   "N_p": -0.5, "N_r": -1.0})
    controls = structure.controls
    values.update({f"L_{controls[0]}": 0.3, f"N_{controls[1]}": -0.1,
                   f"Y_{controls[1]}": 0.06})
    time = np.arange(0.0, 10.0, 0.02)
    records = []
    for axis in range(2):
        inputs = np.zeros((time.size, len(controls)))
        inputs[(time > 1.0) & (time < 2.0), axis] = 2.0
        inputs[(time >= 2.0) & (time < 3.0), axis] = -2.0
        records.append(Maneuver(f"doublet_{controls[axis]}", time, inputs,
                                np.zeros((time.size, len(structure.outputs))), units="si",
                                input_names=controls, output_names=structure.outputs))
    blank = ManeuverSet(records)
    simulated = simulate(structure, structure.as_vector(values), blank)
    column = structure.outputs.index("ay")
    outputs = []
    for y in simulated:
        y = y.copy()
        y[:, column] *= ay_factor
        outputs.append(y)
    return ManeuverSet([m.with_outputs(y) for m, y in zip(blank, outputs)]), condition


def test_the_vanes_check_the_accelerometers_unit():
    """v = U0·β: the lateral accelerometer integrates to the sideslip's velocity with scale 1
    when its unit is right, and 1/9.81 when it holds g read as m/s²."""
    right, condition = _aeroplane_lateral(1.0)
    [v] = [f for f in kinematic_fits(right, condition) if f.channel == "v"]
    assert v.scale == pytest.approx(1.0, abs=0.02) and v.driver.startswith("ay")
    wrong, _ = _aeroplane_lateral(1.0 / 9.80665)
    with pytest.warns(DataWarning, match=r"kinematic consistency: v against integrated ay.*"
                                         r"look recorded in g but read as m/s²"):
        [v] = [f for f in check_kinematics(wrong, condition) if f.channel == "v"]
    assert v.scale == pytest.approx(9.80665, rel=0.02)
    # the other sign convention: scale −1, named as such
    flipped, _ = _aeroplane_lateral(-1.0)
    with pytest.warns(DataWarning, match=r"move with opposite signs.*scale = -1"):
        [v] = [f for f in check_kinematics(flipped, condition) if f.channel == "v"]
    assert v.scale == pytest.approx(-1.0, abs=0.05)


def test_a_control_recorded_on_its_trim_is_named():
    """The rudder held at its 2.07 deg trim under ±2 deg doublets: an offset the derivatives
    would take up, named with the model's unit; the same records from zero are quiet."""
    from rotorid.model.signals import ModelSignals, Signal, SignalSet

    t = np.arange(0.0, 8.0, 0.02)
    doublet = np.where((t > 2.0) & (t < 3.0), 2.0, 0.0) - np.where((t >= 3.0) & (t < 4.0),
                                                                   2.0, 0.0)
    signals = ModelSignals(
        states=SignalSet([Signal("r", "deg/s", "rate")]),
        inputs=SignalSet([Signal("rudder", "deg", "control")]),
        outputs=SignalSet([Signal("r", "deg/s", "rate")]))

    def records(trim):
        return ManeuverSet([Maneuver(f"m{k}", t, (doublet + trim)[:, None],
                                     np.cumsum(doublet)[:, None] * 0.01,
                                     input_names=("rudder",), output_names=("r",))
                            for k in range(2)])

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DataWarning)
        check_data(records(2.07), signals=signals)
    [message] = [str(w.message) for w in caught if "input 'rudder'" in str(w.message)]
    assert message.startswith("input 'rudder' starts away from zero in 2 of 2 maneuvers: "
                              "2.07 deg (mean of the first 1 s of m")
    assert "--trim rudder=VALUE" in message
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DataWarning)
        check_data(records(0.0), signals=signals)
    assert not [w for w in caught if "input 'rudder'" in str(w.message)]


def test_an_attitude_that_never_moves_is_left_out_of_the_kinematic_fits():
    t = np.arange(0.0, 5.0, 0.02)
    outputs = np.zeros((t.size, 8))
    outputs[:, 2] = np.sin(t)                       # q
    outputs[:, 3] = 1.0 - np.cos(t)                 # θ = ∫q
    inputs = np.zeros((t.size, 4))
    inputs[:, 0] = np.sin(t)
    fits = kinematic_fits(ManeuverSet([Maneuver("pitch", t, inputs, outputs)]))
    assert [f.channel for f in fits] == ["theta"]      # φ, all zero, is not fitted
