"""Named signals, signal sets, unit conversions and channel maps (rotorid.model.signals)."""

import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest
from rotorid.errors import RotoridError, SignalError
from rotorid.model.signals import ChannelLink, ChannelMap, ModelSignals, Signal, SignalSet
from rotorid.units import canonical_unit, conversion_factor

LONGITUDINAL = SignalSet([
    Signal("V", "m/s", "velocity", "airspeed"),
    Signal("alpha", "rad", "angle"),
    Signal("q", "rad/s", "rate"),
    Signal("az", "m/s²", "acceleration"),
    Signal("elevator", "rad", "control"),
    Signal("thrust", "N", "control"),
])


@pytest.mark.parametrize("source, target, factor", [
    ("kt", "m/s", 0.514444444444),          # 1852 m / 3600 s
    ("kt", "ft/s", 1.687809857101),         # 0.5144444 / 0.3048
    ("ft/s", "m/s", 0.3048),
    ("g", "m/s²", 9.80665),
    ("g", "ft/s²", 32.174048556430),        # 9.80665 / 0.3048
    ("deg", "rad", 0.017453292520),         # π / 180
    ("rad/s", "deg/s", 57.295779513082),    # 180 / π
    ("deg/s²", "rad/s²", 0.017453292520),
    ("lbf", "N", 4.4482216152605),
    ("%", "%", 1.0),
])
def test_conversion_factors_match_hand_computed_values(source, target, factor):
    assert conversion_factor(source, target) == pytest.approx(factor, rel=1e-11)


def test_ascii_spellings_and_unknown_or_incompatible_units():
    assert canonical_unit("ft/s^2") == "ft/s²"
    assert Signal("ax", "m/s^2", "acceleration").unit == "m/s²"
    with pytest.raises(SignalError, match="unknown unit 'mph'"):
        canonical_unit("mph")
    with pytest.raises(SignalError, match=r"cannot convert % \(travel\) to deg \(angle\)"):
        conversion_factor("%", "deg")


def test_a_signal_names_a_unit_that_does_not_fit_its_kind():
    with pytest.raises(SignalError, match=r"signal 'q': unit deg does not fit kind 'rate'; "
                                          r"use one of rad/s, deg/s"):
        Signal("q", "deg", "rate")
    with pytest.raises(SignalError, match="unknown signal kind 'speed'"):
        Signal("V", "m/s", "speed")
    with pytest.raises(SignalError, match="'q dot' is not a valid name"):
        Signal("q dot", "rad/s²", "angular-acceleration")
    for unit in ("%", "deg", "rad", "N", "lbf"):
        assert Signal("c", unit, "control").unit == unit


def test_signal_set_order_lookup_and_errors():
    assert LONGITUDINAL.names == ("V", "alpha", "q", "az", "elevator", "thrust")
    assert LONGITUDINAL.index("q") == 2
    assert LONGITUDINAL.indices(["az", "V"]) == [3, 0]
    assert LONGITUDINAL["alpha"].unit == "rad" and LONGITUDINAL[0].description == "airspeed"
    assert "thrust" in LONGITUDINAL and "beta" not in LONGITUDINAL
    assert LONGITUDINAL.units[:2] == ("m/s", "rad")
    with pytest.raises(SignalError, match="unknown signal 'beta'; signals: V, alpha, q"):
        LONGITUDINAL.index("beta")
    with pytest.raises(SignalError, match="duplicate signal 'q' in a signal set"):
        SignalSet([Signal("q", "rad/s", "rate"), Signal("q", "deg/s", "rate")])
    with pytest.raises(SignalError, match="holds Signal values"):
        SignalSet(["q"])
    with pytest.raises(AttributeError):
        LONGITUDINAL.signals = ()                       # frozen


def test_channel_map_reads_renamed_scaled_columns_in_the_signals_units():
    channels = ChannelMap.from_mapping({
        "VTAS_KT": {"signal": "V", "unit": "kt"},
        "Q_degps": {"signal": "q", "unit": "deg/s"},
        "NZ": {"signal": "az", "unit": "g", "scale": -1.0, "offset": 1.0},
        "DELV": {"signal": "elevator", "unit": "deg", "scale": -0.5},
    }, source="case.toml")
    columns = {"VTAS_KT": np.array([100.0, 120.0]), "Q_degps": np.array([0.0, 90.0]),
               "NZ": np.array([1.0, 1.5]), "DELV": np.array([4.0, -2.0]),
               "alpha": np.array([2.0, 4.0]), "unused": np.array([7.0, 7.0])}
    values = channels.read(columns, LONGITUDINAL, ["V", "q", "az", "elevator", "alpha"],
                           "file 'run.csv'", column_units={"alpha": "deg"})
    expected = np.array([
        # 100 kt, 0 deg/s, (−1 + 1) g, −0.5·4 deg, alpha column in its own unit (deg)
        [51.4444444444, 0.0, 0.0, -2 * math.pi / 180, 2 * math.pi / 180],
        # 120 kt, 90 deg/s = π/2 rad/s, (−1.5 + 1) g = −4.903325 m/s², +1 deg, 4 deg
        [61.7333333333, math.pi / 2, -4.903325, math.pi / 180, 4 * math.pi / 180],
    ])
    np.testing.assert_allclose(values, expected, rtol=1e-10, atol=1e-14)
    assert channels.link("q") == ChannelLink("Q_degps", "q", "deg/s")
    assert channels.link("alpha") is None
    assert channels.read(columns, LONGITUDINAL, [], "file 'run.csv'").shape == (2, 0)


def test_channel_map_without_links_reads_columns_named_like_the_signals():
    columns = {"alpha": np.array([0.1]), "thrust": np.array([900.0])}
    values = ChannelMap().read(columns, LONGITUDINAL, ["thrust", "alpha"], "maneuver 'm'")
    np.testing.assert_array_equal(values, [[900.0, 0.1]])


@pytest.mark.parametrize("table, columns, message", [
    ({"DELV": {"signal": "elevator", "unit": "deg"}}, {"DELE": [0.0]},
     r"^file 'run.csv' has no column 'DELV' \(linked to signal 'elevator' in case.toml\); "
     r"columns: DELE; correct the column name in case.toml$"),
    ({}, {"DELE": [0.0]},
     r"^file 'run.csv' has no column 'elevator' for signal 'elevator'; link the column that "
     r"holds it in case.toml"),
    ({"DELV": {"signal": "elevon", "unit": "deg"}}, {"DELV": [0.0]},
     r"^case.toml: column 'DELV' is linked to unknown signal 'elevon'; signals: V, alpha"),
    ({"DELV": {"signal": "elevator", "unit": "%"}}, {"DELV": [0.0]},
     r"^case.toml: column 'DELV' has unit %, which does not fit signal 'elevator' \(control "
     r"in rad\); give the column's unit as one of rad, deg$"),
    ({"Q": {"signal": "q", "unit": "deg"}}, {"Q": [0.0]},
     r"^case.toml: column 'Q' has unit deg, which does not fit signal 'q' \(rate in rad/s\)"),
])
def test_bad_channel_maps_are_one_line_errors_naming_the_file_and_the_fix(table, columns,
                                                                          message):
    channels = ChannelMap.from_mapping(table, source="case.toml")
    name = next(iter(table.values()), {"signal": "elevator"})["signal"]
    with pytest.raises(SignalError, match=message) as caught:
        channels.read({k: np.array(v) for k, v in columns.items()}, LONGITUDINAL, [name],
                      "file 'run.csv'")
    assert "\n" not in str(caught.value)


def test_a_column_in_the_records_own_unit_must_fit_the_signal():
    with pytest.raises(SignalError, match=r"maneuver 'm': column 'elevator' is in %, which "
                                          r"does not fit signal 'elevator'"):
        ChannelMap(source="model.py").read({"elevator": np.zeros(3)}, LONGITUDINAL,
                                           ["elevator"], "maneuver 'm'", {"elevator": "%"})


@pytest.mark.parametrize("table, message", [
    ({"Q1": {"signal": "q", "unit": "deg/s"}, "Q2": {"signal": "q", "unit": "rad/s"}},
     r"^case.toml: signal 'q' is linked to several columns \(Q1, Q2\); keep one link per signal$"),
    ({"Q": "q"}, r"^case.toml: channel 'Q' needs a table with 'signal' and 'unit'"),
    ({"Q": {"signal": "q", "unit": "deg/s", "gain": 2}},
     r"^case.toml: channel 'Q' has unknown key 'gain'; keys: signal, unit, scale, offset$"),
    ({"Q": {"signal": "q", "unit": "degps"}}, r"^case.toml: channel 'Q': unknown unit 'degps'"),
])
def test_bad_channel_tables_are_refused_when_read(table, message):
    with pytest.raises(SignalError, match=message):
        ChannelMap.from_mapping(table, source="case.toml")


def test_signal_errors_are_rotorid_value_errors():
    assert issubclass(SignalError, RotoridError) and issubclass(SignalError, ValueError)


def test_the_conventions_channel_table_example_reads():
    text = (Path(__file__).resolve().parents[1] / "docs" / "conventions.md").read_text()
    (example,) = re.findall(r"^```toml\n(\[channels\].*?)^```$", text, flags=re.M | re.S)
    channels = ChannelMap.from_mapping(tomllib.loads(example)["channels"], "conventions.md")
    signals = SignalSet([Signal("q", "rad/s", "rate"), Signal("elevator", "rad", "control"),
                         Signal("az", "m/s²", "acceleration")])
    values = channels.read({"Q_degps": np.array([180.0]), "DELV": np.array([90.0]),
                            "NZ": np.array([0.0])}, signals, ["q", "elevator", "az"], "a file")
    np.testing.assert_allclose(values, [[math.pi, -math.pi / 2, 9.80665]])


def test_model_signals_share_a_name_only_with_one_unit_and_never_with_an_input():
    rate = Signal("q", "rad/s", "rate")
    declared = ModelSignals(SignalSet([rate, Signal("theta", "rad", "angle")]),
                            SignalSet([Signal("elevator", "rad", "control")]),
                            SignalSet([Signal("az", "m/s²", "acceleration"), rate]))
    assert declared.all.names == ("q", "theta", "elevator", "az")
    with pytest.raises(SignalError, match=r"^signal 'q' is a state in rad/s \(rate\) and an "
                                          r"output in deg/s \(rate\); declare one unit"):
        ModelSignals(SignalSet([rate]), SignalSet([]),
                     SignalSet([Signal("q", "deg/s", "rate")]))
    with pytest.raises(SignalError, match="signal 'q' is both a state and an input"):
        ModelSignals(SignalSet([rate]), SignalSet([rate]), SignalSet([]))
