"""The ``files`` data source: round trips of CSV, NPZ and MAT files and every bad input."""

import os
import stat
import warnings
import zipfile

import numpy as np
import pytest
import scipy.io
from rotorid.data import ALL_CHANNELS, Maneuver, ManeuverSet
from rotorid.errors import DataError, DataFileError, MissingFileError, StructureError
from rotorid.ingestion import Ingestion
from rotorid.io import atomic_write
from rotorid.model.structure import OUTPUTS
from rotorid.plugin.manager import create
from rotorid.units import FLIGHT_TEST, channel_scale
from rotorid_files.formats import (
    FileSource,
    convert_units,
    read_maneuver,
    write_maneuver,
)

FORMATS = ("csv", "npz", "mat")
METADATA = {"condition": "hover", "kind": "3211", "axis": "long", "direction": -1,
            "amplitude": 0.5, "tags": ["id", "pilot-a"], "note": "true", "trim": "Θ0 = 5°"}


def make(name="long_3211_neg", n=40, dt=0.04, seed=0, units="flight-test", **kwargs):
    rng = np.random.default_rng(seed)
    return Maneuver(name, 1.5 + np.arange(n) * dt, rng.normal(size=(n, 4)),
                    rng.normal(size=(n, 8)) * 10.0, units=units,
                    **{"metadata": METADATA, **kwargs})


def assert_same(a: Maneuver, b: Maneuver):
    assert (a.name, a.units, a.metadata) == (b.name, b.units, b.metadata)
    for field in ("time", "inputs", "outputs"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    if a.initial_state is None:
        assert b.initial_state is None
    else:
        np.testing.assert_array_equal(a.initial_state, b.initial_state)


def columns(maneuver):
    return {c: np.array(maneuver.channel(c)) for c in ALL_CHANNELS}


# ----------------------------------------------------------------- round trips
@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("units", ["flight-test", "si"])
def test_round_trip_is_exact_with_metadata(tmp_path, fmt, units):
    maneuver = make(units=units, initial_state=np.linspace(-1, 1, 8))
    path = write_maneuver(maneuver, tmp_path / f"x.{fmt}")
    assert_same(maneuver, read_maneuver(path))


@pytest.mark.parametrize("fmt", FORMATS)
def test_round_trip_without_metadata_or_initial_state(tmp_path, fmt):
    maneuver = Maneuver("plain", np.arange(5) * 0.1, np.eye(5, 4), np.eye(5, 8))
    assert_same(maneuver, read_maneuver(write_maneuver(maneuver, tmp_path / f"p.{fmt}")))


def test_csv_layout_is_readable(tmp_path):
    path = write_maneuver(make(), tmp_path / "m.csv")
    lines = path.read_text().splitlines()
    assert lines[:4] == ["# name: long_3211_neg", "# units: flight-test", "# condition: hover",
                         '# kind: "3211"']
    assert lines[10] == ",".join(ALL_CHANNELS)
    assert len(lines) == 11 + 40


def test_csv_written_by_hand_defaults_to_flight_test_and_file_name(tmp_path):
    path = tmp_path / "hover_sweep.csv"
    rows = ["# recorded on the truth model", "# kind: sweep", "",
            ",".join(reversed(ALL_CHANNELS))]
    rows += [",".join(["1"] * 12 + [str(t)]) for t in (0.0, 0.5, 1.0)]
    path.write_text("\n".join(rows) + "\n\n")
    maneuver = read_maneuver(path)
    assert (maneuver.name, maneuver.units, maneuver.metadata) == ("hover_sweep", "flight-test",
                                                                  {"kind": "sweep"})
    np.testing.assert_array_equal(maneuver.time, [0.0, 0.5, 1.0])
    assert np.all(maneuver.outputs == 1.0)


def test_units_are_declared_in_the_header(tmp_path):
    si = make(units="si")
    text = (tmp_path / "a.csv")
    write_maneuver(si, text)
    assert "# units: si" in text.read_text().splitlines()
    assert read_maneuver(text).units == "si"


def test_conversion_between_unit_systems(tmp_path):
    si = make(units="si", initial_state=np.ones(8))
    ft = convert_units(si, "flight-test")
    scale = channel_scale(OUTPUTS, FLIGHT_TEST)
    np.testing.assert_allclose(ft.outputs, si.outputs * scale)
    np.testing.assert_array_equal(ft.inputs, si.inputs)
    assert ft.units == "flight-test" and ft.initial_state[2] == pytest.approx(180 / np.pi)
    assert convert_units(ft, "si").outputs == pytest.approx(si.outputs)
    assert convert_units(si, "si") is si


def test_writers_leave_the_maneuver_alone(tmp_path):
    maneuver = make()
    before = (maneuver.outputs.copy(), dict(maneuver.metadata))
    for fmt in FORMATS:
        write_maneuver(maneuver, tmp_path / f"w.{fmt}")
    np.testing.assert_array_equal(maneuver.outputs, before[0])
    assert maneuver.metadata == before[1]


# ----------------------------------------------------------------- FileSource
def test_source_loads_a_file_a_directory_and_a_glob(tmp_path):
    source = FileSource()
    paths = source.save([make("b", seed=1), make("a", seed=2)], tmp_path / "out", format="npz")
    assert [p.name for p in paths] == ["b.npz", "a.npz"]
    write_maneuver(make("c", seed=3), tmp_path / "out" / "c.csv")
    (tmp_path / "out" / "notes.txt").write_text("not a maneuver")
    assert source.load(tmp_path / "out").names == ("a", "b", "c")
    assert source.load(tmp_path / "out" / "b.npz").names == ("b",)
    assert source.load(str(tmp_path / "out" / "*.npz")).names == ("a", "b")


@pytest.mark.parametrize("fmt", FORMATS)
def test_save_then_load_gives_the_same_set(tmp_path, fmt):
    maneuvers = ManeuverSet([make("one", seed=1), make("two", seed=2, n=25)])
    FileSource().save(maneuvers, tmp_path, format=fmt)
    loaded = FileSource(hold="foh").load(tmp_path)
    assert loaded.hold == "foh"
    for a, b in zip(maneuvers, loaded):
        assert_same(a, b)


def test_source_converts_units_on_request(tmp_path):
    write_maneuver(make("ft"), tmp_path / "ft.csv")
    write_maneuver(make("si", units="si"), tmp_path / "si.csv")
    with pytest.raises(DataFileError, match=r"files mix unit systems \['flight-test', 'si'\]"):
        FileSource().load(tmp_path)
    loaded = FileSource(units="flight-test").load(tmp_path)
    assert loaded.units == "flight-test"
    np.testing.assert_allclose(loaded["si"].outputs,
                               make("si").outputs * channel_scale(OUTPUTS, FLIGHT_TEST))


def test_source_is_registered_as_the_files_data_source(tmp_path):
    write_maneuver(make(), tmp_path / "m.mat")
    source = create("data-sources", "files", hold="foh")
    assert isinstance(source, FileSource) and source.load(tmp_path).hold == "foh"


@pytest.mark.parametrize("action, error, fragment", [
    (lambda p: FileSource().load(p / "missing.csv"), MissingFileError, "no such file"),
    (lambda p: FileSource().load(str(p / "*.csv")), MissingFileError, "no file matches"),
    (lambda p: FileSource().load(p), DataFileError, "no maneuver files"),
    (lambda p: read_maneuver(p / "gone.npz"), MissingFileError, "does not exist"),
    (lambda p: read_maneuver(p / "data.xlsx"), DataFileError, "unknown maneuver file format"),
    (lambda p: write_maneuver(make(), p / "m.txt"), DataFileError, "use .csv, .npz, .mat"),
    (lambda p: FileSource().save([make()], p, format="xls"), DataFileError, "use csv, npz, mat"),
    (lambda p: FileSource().save([make("a/b")], p), DataFileError, "cannot be a file name"),
    (lambda p: FileSource().save([make("a"), make("a")], p), DataFileError,
     "two maneuvers are named 'a'"),
    (lambda p: FileSource(hold="cubic"), DataError, "unknown input hold 'cubic'"),
    (lambda p: FileSource(units="imperial"), StructureError, "unknown unit system 'imperial'"),
])
def test_source_errors(tmp_path, action, error, fragment):
    with pytest.raises(error, match=fragment):
        action(tmp_path)


def test_the_same_name_in_two_files_names_both(tmp_path):
    write_maneuver(make("same"), tmp_path / "first.csv")
    write_maneuver(make("same"), tmp_path / "second.npz")
    with pytest.raises(DataFileError, match=r"'same' is used by both .*first.csv and .*second.npz"):
        FileSource().load(tmp_path)


def test_metadata_that_cannot_be_stored_is_refused(tmp_path):
    with pytest.raises(DataFileError, match="metadata key 'units' cannot be stored"):
        write_maneuver(make(metadata={"units": "si"}), tmp_path / "m.csv")
    with pytest.raises(DataFileError, match="cannot store"):
        write_maneuver(make(metadata={"when": object()}), tmp_path / "m.npz")
    assert not list(tmp_path.iterdir())


# ----------------------------------------------------------------- bad CSV files
def csv_text(maneuver=None, header=None, edit=None):
    lines = [",".join(header or ALL_CHANNELS)]
    table = np.column_stack(list(columns(maneuver or make(n=6, dt=0.5)).values()))
    lines += [",".join(repr(v) for v in row) for row in table.tolist()]
    if edit:
        edit(lines)
    return "\n".join(lines) + "\n"


def set_cell(row, channel, text):
    def edit(lines):
        fields = lines[1 + row].split(",")
        fields[ALL_CHANNELS.index(channel)] = text
        lines[1 + row] = ",".join(fields)
    return edit


@pytest.mark.parametrize("text, fragment", [
    (csv_text(edit=set_cell(3, "time", "3.2")),
     r"channel 'time' is not uniformly sampled at row 3 .*row 0 is line 2"),
    (csv_text(edit=set_cell(2, "time", "0.5")), r"channel 'time' does not increase at row 2"),
    (csv_text(edit=set_cell(4, "q", "nan")), r"line 6 \(row 4\), channel 'q': value is empty, NaN"),
    (csv_text(edit=set_cell(1, "ped", "-inf")), r"line 3 \(row 1\), channel 'ped': .*infinite"),
    (csv_text(edit=set_cell(0, "ay", "1,5")), r"line 2: expected 13 values .* got 14"),
    (csv_text(edit=set_cell(2, "phi", "abc")), r"line 4 \(row 2\), channel 'phi': 'abc' is not"),
    (csv_text(edit=set_cell(2, "phi", "")), r"line 4 \(row 2\), channel 'phi': value is empty"),
    (csv_text(edit=lambda lines: lines.__setitem__(5, lines[5].rsplit(",", 1)[0])),
     r"line 6: expected 13 values \(one per channel of the header row\), got 12"),
    (csv_text(header=ALL_CHANNELS[:-1] + ("q",), edit=lambda lines: None),
     r"line 1: channel 'q' appears twice in the header row"),
    ("\n".join(csv_text().splitlines()[:1] + [
        ",".join(["0"] * 12) for _ in range(3)]), r"line 2: expected 13 values"),
    ("# only: comments\n\n", "no header row"),
    ("# kind: a\n# kind: b\n" + csv_text(), r"line 2: header key 'kind' is given twice"),
    ("# units: imperial\n" + csv_text(), "bad header: unknown unit system 'imperial'"),
    ("# initial_state: [[1, 2]]\n" + csv_text(), "initial_state must be a vector"),
    ("# name: 3\n" + csv_text(), "header 'name' must be a non-empty string"),
    (csv_text().splitlines()[0] + "\n", "at least 2 samples"),
])
def test_bad_csv_files_are_rejected_naming_file_line_and_channel(tmp_path, text, fragment):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(DataFileError, match=fragment) as caught:
        read_maneuver(path)
    assert str(path) in str(caught.value)


def test_missing_and_unknown_csv_channels(tmp_path):
    """A file may lack channels (a model that uses one names it); a misspelt one is refused."""
    path = tmp_path / "m.csv"
    header = [c for c in ALL_CHANNELS if c != "theta"]
    path.write_text("\n".join([",".join(header)]
                              + [",".join([str(0.1 * row)] + ["0"] * 11) for row in range(3)]))
    maneuver = read_maneuver(path)
    assert maneuver.output_names == ("ax", "az", "q", "ay", "p", "phi", "r")
    with pytest.raises(DataError, match="maneuver 'm' has no channel 'theta', which the model"):
        maneuver.channel("theta")
    path.write_text("\n".join([",".join(header + ["Theta"])] + [",".join(["0"] * 13)] * 3))
    with pytest.raises(DataFileError, match=r"unknown channel\(s\) 'Theta'"):
        read_maneuver(path)
    path.write_text("\n".join([",".join(ALL_CHANNELS[1:])] + [",".join(["0"] * 12)] * 3))
    with pytest.raises(DataFileError, match=r"missing channel\(s\) time"):
        read_maneuver(path)
    path.write_text("\n".join([",".join(ALL_CHANNELS + ("psi",))] + [",".join(["0"] * 14)] * 3))
    with pytest.raises(DataFileError, match=r"unknown channel\(s\) 'psi'"):
        read_maneuver(path)


def test_columns_a_channel_map_leaves_unlinked_travel_unused(tmp_path):
    """Read for a model (through its channel map), a flight-test file's further columns are
    no error: they travel as extra channels; read plainly, the same file is refused."""
    path = tmp_path / "flight.csv"
    header = ["time", "PITCH_RATE_degps", "ELEV_pct", "ALT_m"]
    path.write_text("\n".join([",".join(header)]
                              + [f"{0.1 * row},{row},{-row},{1000 + row}" for row in range(4)]))
    channels = {"PITCH_RATE_degps": {"signal": "q", "unit": "deg/s"},
                "ELEV_pct": {"signal": "long", "unit": "%"}}
    maneuver = read_maneuver(path, Ingestion(channels=channels))
    assert maneuver.input_names == ("long",) and maneuver.output_names == ("q",)
    assert np.array_equal(maneuver.channel("ALT_m"), [1000.0, 1001.0, 1002.0, 1003.0])
    assert np.allclose(maneuver.channel("q"), [0.0, 1.0, 2.0, 3.0])
    with pytest.raises(DataFileError, match=r"unknown channel\(s\) 'PITCH_RATE_degps', "
                                            r"'ELEV_pct', 'ALT_m'"):
        read_maneuver(path)


def test_a_file_naming_the_channels_themselves_is_read_through_a_map_that_links_others(
        tmp_path):
    """A file that holds the channels under their own names (as rotorid simulate writes them)
    reads as it is through a map whose linked columns it lacks altogether; a file holding
    some linked columns, or lacking the channel too, is told the missing linked column."""
    path = tmp_path / "simulated.csv"
    path.write_text("# units: si\ntime,long,q\n" + "".join(f"{0.1 * k},{k},{0.01 * k}\n"
                                                          for k in range(4)))
    channels = {"PITCH_RATE_degps": {"signal": "q", "unit": "deg/s"},
                "ELEV_pct": {"signal": "long", "unit": "%", "scale": -1.0}}
    maneuver = read_maneuver(path, Ingestion(channels=channels))
    assert np.allclose(maneuver.channel("q"), [0.0, 0.01, 0.02, 0.03])
    assert np.allclose(maneuver.channel("long"), [0.0, 1.0, 2.0, 3.0])
    path.write_text("time,long,pitch_rate\n0,0,0\n0.1,1,1\n")
    with pytest.raises(DataFileError, match="has no column 'PITCH_RATE_degps' .linked to 'q'"):
        read_maneuver(path, Ingestion(channels=channels))
    path.write_text("time,ELEV_pct,q\n0,0,0\n0.1,1,1\n")     # in the map's naming: a typo
    with pytest.raises(DataFileError, match="has no column 'PITCH_RATE_degps' .linked to 'q'"):
        read_maneuver(path, Ingestion(channels=channels))


def test_non_utf8_csv_is_rejected(tmp_path):
    path = tmp_path / "m.csv"
    path.write_bytes(b"\xff\xfe" + "time".encode("utf-16-le"))
    with pytest.raises(DataFileError, match="not a UTF-8 text file"):
        read_maneuver(path)


# ----------------------------------------------------------------- bad NPZ and MAT files
def save_arrays(path, arrays):
    if path.suffix == ".npz":
        np.savez(path, **arrays)
    else:
        scipy.io.savemat(path, arrays, oned_as="column")


def edited(**changes):
    arrays = columns(make(n=10))
    for key, value in changes.items():
        if value is None:
            del arrays[key]
        else:
            arrays[key] = value(arrays) if callable(value) else value
    return arrays


def nan_at(channel, row):
    def change(arrays):
        values = arrays[channel].copy()
        values[row] = np.nan
        return values
    return change


@pytest.mark.parametrize("fmt", ["npz", "mat"])
@pytest.mark.parametrize("arrays, fragment", [
    (edited(time=None), r"missing channel\(s\) time;"),
    (edited(ay=lambda a: a["ay"][:-1]), r"channel 'ay' has 9 samples but 'time' has 10"),
    (edited(p=nan_at("p", 7)), r"channel 'p' is NaN or infinite at row 7"),
    (edited(time=lambda a: a["time"][::-1].copy()), r"channel 'time' does not increase at row 1"),
    (edited(time=lambda a: a["time"] ** 2), r"channel 'time' is not uniformly sampled at row 1"),
    (edited(r=np.zeros((10, 2))), r"channel 'r' must be a vector, got shape \(10, 2\)"),
    (edited(extra=np.zeros(10)), r"unknown channel\(s\) 'extra'"),
    (edited(header=np.array("{not json")), "variable 'header' is not valid JSON"),
    (edited(header=np.array("[1, 2]")), "variable 'header' must hold a JSON object"),
    (edited(header=np.array('{"units": "feet"}')), "unknown unit system 'feet'"),
])
def test_bad_array_files_are_rejected_naming_file_and_channel(tmp_path, fmt, arrays, fragment):
    path = tmp_path / f"bad.{fmt}"
    save_arrays(path, arrays)
    with pytest.raises(DataFileError, match=fragment) as caught:
        read_maneuver(path)
    assert str(path) in str(caught.value)


@pytest.mark.parametrize("fmt", ["npz", "mat"])
def test_array_files_without_header_default_to_flight_test(tmp_path, fmt):
    path = tmp_path / f"sweep_lat.{fmt}"
    save_arrays(path, edited())
    maneuver = read_maneuver(path)
    assert (maneuver.name, maneuver.units, maneuver.metadata) == ("sweep_lat", "flight-test", {})


def test_npz_with_a_channel_stored_twice(tmp_path):
    path = tmp_path / "twice.npz"
    np.savez(path, **edited())
    buffer = tmp_path / "q.npy"
    np.save(buffer, np.zeros(10))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # zipfile warns about the duplicate
        with zipfile.ZipFile(path, "a") as archive:
            archive.write(buffer, "q.npy")
    with pytest.raises(DataFileError, match=r"channel\(s\) q stored twice"):
        read_maneuver(path)


def test_npz_with_pickled_objects_is_refused(tmp_path):
    path = tmp_path / "pickled.npz"
    np.savez(path, **edited(kind=np.array([{"a": 1}], dtype=object)))
    with pytest.raises(DataFileError, match="pickled objects are refused"):
        read_maneuver(path)


@pytest.mark.parametrize("fmt, fragment", [
    ("npz", "cannot read as a NumPy .npz archive"), ("mat", "cannot read as a MATLAB .mat file"),
])
def test_files_of_another_kind_are_rejected(tmp_path, fmt, fragment):
    path = tmp_path / f"wrong.{fmt}"
    path.write_text("time,long\n0,1\n")
    with pytest.raises(DataFileError, match=fragment):
        read_maneuver(path)


def test_a_npy_array_is_not_a_maneuver(tmp_path):
    path = tmp_path / "array.npz"
    with open(path, "wb") as handle:
        np.save(handle, np.zeros(3))
    with pytest.raises(DataFileError, match="a .npy array, not a .npz archive"):
        read_maneuver(path)


def test_non_numeric_channel_is_rejected(tmp_path):
    path = tmp_path / "text.npz"
    np.savez(path, **edited(q=np.array(["a"] * 10)))
    with pytest.raises(DataFileError, match=r"channel 'q' is not numeric"):
        read_maneuver(path)


# ----------------------------------------------------------------- atomic writes
def test_atomic_write_replaces_keeps_mode_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "file.txt"
    atomic_write(target, "first")
    os.chmod(target, 0o640)
    atomic_write(target, b"second")
    assert target.read_text() == "second"
    assert stat.S_IMODE(target.stat().st_mode) == 0o640
    assert [p.name for p in tmp_path.iterdir()] == ["file.txt"]


def test_atomic_write_failure_leaves_the_old_file(tmp_path):
    target = tmp_path / "file.txt"
    atomic_write(target, "old")

    def fail(handle):
        handle.write(b"partial")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        atomic_write(target, fail)
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["file.txt"]


def test_atomic_write_needs_an_existing_directory(tmp_path):
    with pytest.raises(MissingFileError, match="does not exist"):
        atomic_write(tmp_path / "nowhere" / "file.txt", "x")


def test_a_file_without_time_read_for_a_model_is_told_how_to_link_its_time(tmp_path):
    import rotorid

    signals = rotorid.ModelStructure.populated(rotorid.FlightCondition(u0=40.0),
                                               "fixed-wing-lateral", units="si").signals
    path = tmp_path / "flight.csv"
    path.write_text("Time,aileron,p\n0,0,0\n0.1,1,1\n")
    with pytest.raises(DataFileError, match=(
            r"missing channel\(s\) time; a maneuver file needs time, then any of v,p,phi,r,"
            r"aileron,rudder,beta,ay; name the file's time column 'time' or link it in the "
            r"model's channel map, e.g. Time = \{ signal = \"time\", unit = \"s\" \}")):
        read_maneuver(path, Ingestion(signals=signals))
