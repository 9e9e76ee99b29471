"""Maneuvers and maneuver sets: validation, immutability, selection."""

import attrs
import numpy as np
import pytest
from rotorid.data import (
    ALL_CHANNELS,
    INPUT_CHANNELS,
    OUTPUT_CHANNELS,
    Maneuver,
    ManeuverSet,
)
from rotorid.errors import DataError, StructureError


def make(name="m", n=50, dt=0.02, units="flight-test", seed=0, **metadata):
    rng = np.random.default_rng(seed)
    return Maneuver(name, np.arange(n) * dt, rng.normal(size=(n, 4)), rng.normal(size=(n, 8)),
                    metadata=metadata, units=units)


def test_channel_order_is_the_papers():
    assert ALL_CHANNELS == ("time", "long", "lat", "coll", "ped", "ax", "az", "q", "theta",
                            "ay", "p", "phi", "r")


def test_maneuver_copies_and_freezes_its_arrays():
    time = np.arange(10) * 0.1
    outputs = np.ones((10, 8))
    maneuver = Maneuver("m", time, np.zeros((10, 4)), outputs)
    outputs[0, 0] = 99.0
    time[0] = -1.0
    assert maneuver.outputs[0, 0] == 1.0 and maneuver.time[0] == 0.0
    with pytest.raises(ValueError):
        maneuver.outputs[0, 0] = 5.0
    with pytest.raises(attrs.exceptions.FrozenInstanceError):
        maneuver.name = "other"


def test_channels_by_name_and_timing():
    maneuver = make(n=51, dt=0.02)
    assert maneuver.dt == pytest.approx(0.02) and maneuver.duration == pytest.approx(1.0)
    assert maneuver.n_samples == 51
    np.testing.assert_array_equal(maneuver.channel("lat"), maneuver.inputs[:, 1])
    np.testing.assert_array_equal(maneuver.channel("theta"),
                                  maneuver.outputs[:, OUTPUT_CHANNELS.index("theta")])
    with pytest.raises(DataError, match="unknown channel 'psi'"):
        maneuver.channel("psi")


def test_head_and_with_outputs_return_new_maneuvers():
    maneuver = make(n=100, dt=0.01)
    head = maneuver.head(0.5)
    assert head.n_samples == 51 and maneuver.n_samples == 100
    other = maneuver.with_outputs(np.zeros((100, 8)), name="sim")
    assert other.name == "sim" and np.all(other.outputs == 0) and np.any(maneuver.outputs != 0)


@pytest.mark.parametrize("time, fragment", [
    ([0.0, 0.1, 0.1, 0.3], r"channel 'time' does not increase at row 2"),
    ([0.0, 0.1, 0.05, 0.3], r"does not increase at row 2"),
    ([0.0, 0.1, 0.25, 0.3], r"not uniformly sampled at row 2"),
    ([0.0, np.nan, 0.2, 0.3], r"channel 'time' is not finite at row 1"),
])
def test_bad_time_vectors_name_channel_and_row(time, fragment):
    with pytest.raises(DataError, match=fragment):
        Maneuver("bad", time, np.zeros((4, 4)), np.zeros((4, 8)))


def test_a_single_sample_is_not_a_maneuver():
    with pytest.raises(DataError, match="at least 2 samples"):
        Maneuver("short", [0.0], np.zeros((1, 4)), np.zeros((1, 8)))


@pytest.mark.parametrize("block, channel", [("inputs", "coll"), ("outputs", "phi")])
def test_non_finite_values_name_channel_and_row(block, channel):
    arrays = {"inputs": np.zeros((5, 4)), "outputs": np.zeros((5, 8))}
    names = INPUT_CHANNELS if block == "inputs" else OUTPUT_CHANNELS
    arrays[block][3, names.index(channel)] = np.inf
    with pytest.raises(DataError, match=rf"maneuver 'bad': channel '{channel}' is NaN or "
                                        rf"infinite at row 3"):
        Maneuver("bad", np.arange(5.0), **arrays)


def test_wrong_shapes_are_rejected():
    with pytest.raises(DataError, match=r"expected shape \(5, 8\)"):
        Maneuver("bad", np.arange(5.0), np.zeros((5, 4)), np.zeros((4, 8)))
    with pytest.raises(DataError, match=r"expected shape \(5, 4\)"):
        Maneuver("bad", np.arange(5.0), np.zeros((5, 3)), np.zeros((5, 8)))
    with pytest.raises(DataError, match=r"initial_state must be a vector of states"):
        Maneuver("bad", np.arange(5.0), np.zeros((5, 4)), np.zeros((5, 8)),
                 initial_state=np.zeros((2, 4)))


def test_sets_index_select_and_merge():
    a = make("a", kind="3211", axis="long")
    b = make("b", kind="2311", axis="long")
    c = make("c", kind="sweep", axis="lat")
    maneuvers = ManeuverSet([a, b])
    assert len(maneuvers) == 2 and maneuvers.names == ("a", "b")
    assert maneuvers["b"] is b and maneuvers[0] is a and list(maneuvers) == [a, b]
    assert maneuvers.n_samples == 100
    assert maneuvers.select(kind="2311").names == ("b",)
    assert maneuvers.merged([c]).select(axis="long").names == ("a", "b")
    assert maneuvers.select(lambda m: m.name != "a").names == ("b",)
    with pytest.raises(DataError, match="no maneuver matches"):
        maneuvers.select(kind="doublet")
    with pytest.raises(DataError, match="no maneuver named 'z'; have: a, b"):
        maneuvers["z"]


@pytest.mark.parametrize("build, fragment", [
    (lambda: ManeuverSet([]), "at least one maneuver"),
    (lambda: ManeuverSet([make("a"), make("a", seed=1)]), r"duplicate maneuver name\(s\) in the "
                                                          r"set: a"),
    (lambda: ManeuverSet([make("a"), make("b", units="si")]), "maneuvers mix unit systems"),
    (lambda: ManeuverSet([make("a")], hold="linear"), "unknown input hold 'linear'"),
])
def test_bad_sets_are_rejected(build, fragment):
    with pytest.raises(DataError, match=fragment):
        build()


def test_units_are_a_known_unit_system():
    assert make(units="si-rad").units == "si"
    with pytest.raises(StructureError, match="unknown unit system 'feet'"):
        make(units="feet")


def test_extra_channels_are_read_by_name_cut_with_the_record_and_checked():
    base = make(n=10)
    speed = 50.0 + np.arange(10.0)
    maneuver = attrs.evolve(base, extra_channels={"V": speed})
    speed[0] = -1.0                                           # the maneuver keeps its copy
    np.testing.assert_array_equal(maneuver.channel("V"), 50.0 + np.arange(10.0))
    assert not maneuver.channel("V").flags.writeable
    np.testing.assert_array_equal(maneuver.head(0.1).channel("V"), [50.0, 51.0, 52.0, 53.0,
                                                                    54.0, 55.0])
    assert maneuver.with_outputs(np.zeros((10, 8))).channel("V")[9] == 59.0
    # a channel of a known kind the record lacks: the model uses it, and the fixes are named
    with pytest.raises(DataError, match="has no channel 'beta', which the model uses; .*"
                                        "leave the output out of the fit .*the record's "
                                        "channels: time, .*, r, V$"):
        maneuver.channel("beta")
    with pytest.raises(DataError, match="unknown channel 'bta'; channels: time, .*, r, V$"):
        maneuver.channel("bta")
    with pytest.raises(DataError, match="extra channel 'q' repeats an input or output channel"):
        attrs.evolve(base, extra_channels={"q": np.zeros(10)})
    with pytest.raises(DataError, match=r"expected shape \(10, 1\) for channels V, got \(9, 1\)"):
        attrs.evolve(base, extra_channels={"V": np.zeros(9)})
    with pytest.raises(DataError, match="channel 'V' is NaN or infinite at row 3"):
        attrs.evolve(base, extra_channels={"V": np.where(np.arange(10) == 3, np.nan, 1.0)})


def test_new_outputs_drop_the_conversion_note_of_the_outputs_they_replace():
    """The note that the recorded outputs were converted from other units does not describe
    simulated ones; an extra channel's note stays."""
    time = np.arange(5) * 0.1
    maneuver = Maneuver("m", time, np.zeros((5, 1)), np.ones((5, 2)), input_names=("long",),
                        output_names=("q", "theta"), extra_channels={"u": np.ones(5)},
                        metadata={"converted_units": {"q": "rad/s", "u": "m/s"}, "pilot": "A"})
    simulated = maneuver.with_outputs(np.zeros((5, 2)))
    assert simulated.metadata == {"converted_units": {"u": "m/s"}, "pilot": "A"}
    assert maneuver.metadata["converted_units"] == {"q": "rad/s", "u": "m/s"}
    only_outputs = attrs.evolve(maneuver, metadata={"converted_units": {"q": "rad/s"}})
    assert "converted_units" not in only_outputs.with_outputs(np.zeros((5, 2))).metadata
