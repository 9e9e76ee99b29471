"""TOML model files: reading, writing, round trips and every bad key."""

import math
import tomllib

import pytest
from rotorid.errors import DataFileError, MissingFileError
from rotorid.model.derivatives import Delay, Derivative, Sign
from rotorid.model.modelfile import format_model, load_model, parse_model, save_model
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.units import SI

ISSUE_EXAMPLE = """
units = "flight-test"
[condition]
airspeed_kt = 0.0
theta0_deg = 0.0
phi0_deg = 0.0
[structure]
populate = "all"
[derivatives.L_lat]
initial = 1.0
sign = "positive"
delay = { initial = 0.05 }
[derivatives.M_w]
fixed = 0.0
"""


def parse(text, source="model.toml"):
    return parse_model(tomllib.loads(text), source=source)


def test_the_documented_example(tmp_path):
    path = tmp_path / "hover.toml"
    path.write_text(ISSUE_EXAMPLE)
    structure = load_model(path)
    assert structure.condition == FlightCondition()
    assert len(structure.derivatives) == 60 and structure.n_parameters == 60
    assert structure.derivative("L_lat") == Derivative("L_lat", 1.0, "positive", Delay(0.05))
    assert structure.derivative("M_w") == Derivative("M_w", 0.0, fixed=True)
    assert structure.parameter_names[-1] == "tau_L_lat"
    assert structure.names == ModelStructure.six_dof(FlightCondition()).names


def test_remove_and_condition_in_body_velocities():
    structure = parse("""
        units = "si"
        [condition]
        u0_fps = 100.0
        w0_mps = 2.0
        theta0_deg = 5.0
        [structure]
        remove = ["X_v", "N_long"]
    """)
    assert structure.units is SI
    assert structure.condition == FlightCondition(30.48, 0.0, 2.0, math.radians(5.0))
    assert len(structure.names) == 58 and "N_long" not in structure.names


def test_populate_none_keeps_only_the_declared_derivatives_in_file_order():
    structure = parse("""
        [condition]
        airspeed_kt = 70.0
        [structure]
        populate = "none"
        [derivatives.M_q]
        sign = "negative"
        [derivatives.X_u]
        [derivatives.L_p]
        delay = 0.02
    """)
    assert structure.names == ("M_q", "X_u", "L_p")
    assert structure.derivative("M_q").sign is Sign.NEGATIVE
    assert structure.derivative("L_p").delay == Delay(0.02)
    assert structure.condition.airspeed_kt == pytest.approx(70.0)


def reduced_structure():
    condition = FlightCondition.from_airspeed(70.0, theta0_deg=3.7, phi0_deg=-1.3)
    return (ModelStructure.six_dof(condition, signs={"L_p": "negative", "N_v": "positive"})
            .without("X_v", "Y_p", "Z_ped", "M_coll")
            .fixing("M_w", 0.0)
            .with_delays(["L_long", "M_lat"], initial=0.01, upper=0.3)
            .with_initial({"L_lat": 1.25, "Z_w": -0.6, "N_r": -1e-5})
            .replacing(Derivative("L_q", delay=Delay(0.04, fixed=True))))


@pytest.mark.parametrize("build", [
    reduced_structure,
    lambda: ModelStructure.six_dof(FlightCondition()),
    lambda: ModelStructure(FlightCondition(12.0, -1.5, 0.3, 0.1, -0.05),
                           [Derivative("N_r", -0.3), Derivative("L_p", sign="negative"),
                            Derivative("X_u", delay=Delay(0.1, 0.5, True))], units="si"),
])
def test_save_then_load_gives_an_equal_structure(tmp_path, build):
    structure = build()
    path = save_model(structure, tmp_path / "model.toml")
    assert load_model(path) == structure


def test_written_file_is_compact_and_readable():
    text = format_model(reduced_structure())
    assert 'populate = "all"' in text
    assert '"X_v", "Y_p", "Z_ped", "M_coll",' in text
    assert "[derivatives.M_w]\nfixed = 0.0\n" in text
    assert "[derivatives.L_long]\ndelay = { initial = 0.01, upper = 0.3 }" in text
    assert "[derivatives.L_q]\ndelay = { initial = 0.04, fixed = true }" in text
    assert "[derivatives.X_u]" not in text  # default settings are not repeated
    assert text.startswith("# rotorid model: ModelStructure(six-dof, 70.0 kt")


def test_out_of_order_structures_are_written_explicitly():
    structure = ModelStructure(FlightCondition(), [Derivative("N_r"), Derivative("L_p")])
    text = format_model(structure)
    assert 'populate = "none"' in text
    assert text.index("[derivatives.N_r]") < text.index("[derivatives.L_p]")


@pytest.mark.parametrize("text, fragment", [
    ('speed = 1\n[condition]\n', "model.toml: unknown key 'speed'; known keys: units, "),
    ('name = "own"\n[data]\nsource = "files"\n',
     r"model.toml: a study case file \(it has a \[data\] table\), not a model file: run it "
     r"with `rotorid study model.toml --out DIR`"),
    ('[condition]\nairspeed = 1\n', r"model.toml: \[condition\]: unknown key\(s\) \['airspeed'\]"),
    ('[condition]\n[structure]\nkeep = []\n',
     r"model.toml: \[structure\]: unknown key 'keep'"),
    ('[condition]\n[derivatives.L_p]\nvalue = 1\n',
     r"model.toml: \[derivatives.L_p\]: unknown key 'value'; known keys: initial, sign, delay,"),
    ('[condition]\n[derivatives.L_p]\ndelay = { initial = 0.1, max = 1 }\n',
     r"\[derivatives.L_p\].delay: unknown key 'max'"),
    ('[structure]\n', r"model.toml: missing \[condition\] table"),
    ('units = "imperial"\n[condition]\n', "model.toml: unknown unit system 'imperial'"),
    ('units = 1\n[condition]\n', "model.toml: units must be a string"),
    ('condition = 70\n', r"\[condition\] must be a table"),
    ('[condition]\nairspeed_kt = "70"\n', r"\[condition\] airspeed_kt must be a number"),
    ('[condition]\nairspeed_kt = true\n', r"\[condition\] airspeed_kt must be a number"),
    ('[condition]\nairspeed_kt = -10.0\n', "airspeed must be a finite number ≥ 0 kt"),
    ('[condition]\ntheta0_deg = 95.0\n', r"theta0 = .* is not within ±90°"),
    ('[condition]\n[structure]\npopulate = "full"\n', "populate = 'full'; use 'all' or"),
    ('[condition]\n[structure]\ntemplate = "vertical"\n',
     "template = 'vertical'; use 'six-dof' or 'longitudinal' or 'lateral' or "
     "'fixed-wing-longitudinal' or 'fixed-wing-lateral' or 'hybrid'"),
    ('[condition]\n[structure]\ntemplate = "longitudinal"\nremove = ["L_p"]\n',
     "derivative L_p does not fit the longitudinal template"),
    ('[condition]\n[structure]\ntemplate = "longitudinal"\n[derivatives.Y_v]\n',
     "derivative Y_v does not fit the longitudinal template"),
    ('[condition]\n[structure]\nremove = "X_u"\n', "remove must be a list of derivative names"),
    ('[condition]\n[structure]\nremove = ["X_q", "X_q"]\n', "remove lists X_q twice"),
    ('[condition]\n[structure]\nremove = ["W_u"]\n', "derivative W_u does not fit the six-dof template"),
    ('[condition]\n[structure]\npopulate = "none"\nremove = ["X_u"]\n',
     "remove needs populate = 'all'"),
    ('[condition]\n[structure]\nremove = ["M_w"]\n[derivatives.M_w]\nfixed = 0.0\n',
     r"M_w both removed and declared in \[derivatives\]"),
    ('[condition]\n[derivatives.L_k]\n', "derivative L_k does not fit the six-dof template"),
    ('[condition]\n[derivatives]\nL_p = 1.0\n', r"\[derivatives.L_p\] must be a table"),
    ('[condition]\n[derivatives.L_p]\ninitial = 1.0\nfixed = 0.0\n',
     "give 'initial' .* or 'fixed' .* not both"),
    ('[condition]\n[derivatives.L_p]\nfixed = true\n', r"\[derivatives.L_p\].fixed must be a "
                                                      r"number, got True"),
    ('[condition]\n[derivatives.L_p]\ninitial = "1"\n', r"\.initial must be a number"),
    ('[condition]\n[derivatives.L_p]\ninitial = nan\n', "initial value must be finite"),
    ('[condition]\n[derivatives.L_p]\nsign = "neg"\n', "unknown sign prior 'neg'"),
    ('[condition]\n[derivatives.L_p]\nsign = -1\n', r"\.sign must be a string"),
    ('[condition]\n[derivatives.L_p]\nfixed = 2.0\nsign = "negative"\n',
     "L_p: fixed value 2.0 contradicts its negative sign prior"),
    ('[condition]\n[derivatives.L_p]\ndelay = -0.01\n', "a delay cannot be negative"),
    ('[condition]\n[derivatives.L_p]\ndelay = "0.1"\n', r"\.delay must be a table"),
    ('[condition]\n[derivatives.L_p]\ndelay = { initial = 0.2, upper = 0.1 }\n',
     "exceeds its upper bound"),
    ('[condition]\n[derivatives.L_p]\ndelay = { fixed = "yes" }\n',
     r"\.delay.fixed must be a boolean"),
])
def test_bad_model_files_name_the_file_and_the_key(text, fragment):
    with pytest.raises(DataFileError, match=fragment) as caught:
        parse(text)
    assert str(caught.value).startswith("model.toml: ")


def test_a_mapping_is_required():
    with pytest.raises(DataFileError, match="<string>: a model file must be a table"):
        parse_model(["units"])


def test_file_errors(tmp_path):
    with pytest.raises(MissingFileError, match="model file .*absent.toml does not exist"):
        load_model(tmp_path / "absent.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("[condition\nairspeed_kt = 1\n")
    with pytest.raises(DataFileError, match=r"broken.toml: not a valid TOML file: .*line 1"):
        load_model(broken)
    typo = tmp_path / "typo.toml"
    typo.write_text("[condition]\n[structure]\npopulat = 'none'\n")
    with pytest.raises(DataFileError, match=r"typo.toml: \[structure\]: unknown key 'populat'"):
        load_model(typo)


def test_save_is_atomic_and_overwrites(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text("old")
    save_model(ModelStructure.six_dof(FlightCondition()), path)
    assert load_model(path) == ModelStructure.six_dof(FlightCondition())
    assert [p.name for p in tmp_path.iterdir()] == ["m.toml"]


def test_a_template_control_linked_in_degrees_is_a_control_in_degrees():
    """A template's controls are in % of travel unless the channel map links one in another
    unit: the elevator's column in deg makes the model's elevator, and its derivatives, per
    deg (controls are never converted), the throttle linked in % per %; unlinked, the
    template's own "control unit". A case's [data] channels do the same to its structure."""
    from rotorid.model.modelfile import case_model
    from rotorid.model.parameter_units import structure_parameter_units

    channels = {"DE_deg": {"signal": "elevator", "unit": "deg"},
                "THR_pct": {"signal": "throttle", "unit": "%"}}
    model = parse_model({"units": "si", "condition": {"u0_mps": 50.0},
                         "structure": {"template": "fixed-wing-longitudinal"},
                         "channels": channels})
    inputs = model.signals.inputs
    assert (inputs["elevator"].unit, inputs["throttle"].unit) == ("deg", "%")
    units = structure_parameter_units(model)
    assert units["M_elevator"] == "rad/s² per deg" and units["M_throttle"] == "rad/s² per %"
    case = {"structure": {"template": "fixed-wing-longitudinal"}, "data": {"channels": channels}}
    assert case_model(case, {"u0_mps": 50.0}, "si", "case").signals.inputs == inputs
    bare = parse_model({"units": "si", "condition": {"u0_mps": 50.0},
                        "structure": {"template": "fixed-wing-longitudinal"}})
    assert bare.signals.inputs["elevator"].unit == "%"
    assert structure_parameter_units(bare)["M_elevator"] == "rad/s² per control unit"
