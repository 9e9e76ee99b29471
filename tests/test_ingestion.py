"""Ingestion (rotorid.ingestion, Maneuver.from_columns/from_dataframe, the files source's
options and MAT layouts): trim removal, resampling with the method stated, units per channel."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import scipy.io
from rotorid import Maneuver
from rotorid.data import ALL_CHANNELS
from rotorid.errors import DataError, DataFileError, DataWarning
from rotorid.ingestion import Ingestion
from rotorid.plugin.manager import create
from rotorid_files.formats import read_maneuver, write_maneuver


def _columns(time, make=lambda t, k: (k + 1) * np.sin(0.5 * t + k)) -> dict:
    """Every channel of ALL_CHANNELS over ``time``: channel k is ``make(time, k)``."""
    columns = {name: make(time, k) for k, name in enumerate(ALL_CHANNELS[1:])}
    return {"time": time, **columns}


class Table:
    """A table as pandas shows one (``columns``, ``table[name]``), without pandas."""

    def __init__(self, columns: dict):
        self._columns = columns
        self.columns = list(columns)

    def __getitem__(self, name):
        return self._columns[name]


def test_first_second_trim_removes_each_channels_starting_level():
    time = np.arange(0.0, 5.0, 0.01)
    columns = _columns(time, lambda t, k: np.where(t > 2.0, 1.0, 0.0) + 10.0 * k)
    m = Maneuver.from_columns("trimmed", columns, ingestion={"trim": "first-second"})
    assert np.allclose(m.outputs[:200], 0.0) and np.allclose(m.outputs[-1], 1.0)
    assert m.metadata["trim_removed"]["r"] == pytest.approx(10.0 * (len(ALL_CHANNELS) - 2))
    assert m.metadata["trim_removed"]["long"] == 0.0


def test_stated_trim_values_are_subtracted_and_unknown_channels_named():
    time = np.arange(0.0, 2.0, 0.02)
    columns = _columns(time)
    columns["theta"] = columns["theta"] + 5.0
    m = Maneuver.from_columns("stated", columns, ingestion={"trim": {"theta": 5.0}})
    assert np.allclose(m.channel("theta"), _columns(time)["theta"])
    with pytest.raises(DataError, match="trim value for unknown channel 'pitch'"):
        Maneuver.from_columns("bad", columns, ingestion={"trim": {"pitch": 5.0}})


def test_stated_trim_values_are_read_in_the_models_unit_system(tmp_path):
    """A flight-test file (deg, ft/s²) read for an SI model: the trim is given in rad and
    m/s², as the model states its signals, and the record ends at zero in both; the
    trim removed is recorded in those units. Controls are not converted."""
    time = np.arange(0.0, 2.0, 0.02)
    columns = _columns(time, lambda t, k: np.zeros_like(t))
    columns.update(phi=np.full_like(time, 0.6), ay=np.full_like(time, 0.25),
                   lat=np.full_like(time, 2.0))
    path = write_maneuver(Maneuver.from_columns("trimmed", columns), tmp_path / "t.csv")
    trim = {"phi": math.radians(0.6), "ay": 0.25 * 0.3048, "lat": 2.0}
    source = create("data-sources", "files", units="si", ingestion={"trim": trim})
    m = source.load(path)[0]
    for channel in ("phi", "ay", "lat"):
        assert np.allclose(m.channel(channel), 0.0, atol=1e-12), channel
    assert m.metadata["trim_units"] == "si"
    assert m.metadata["trim_removed"] == pytest.approx(trim)
    plain = create("data-sources", "files", ingestion={"trim": {"phi": 0.6}}).load(path)[0]
    assert np.allclose(plain.channel("phi"), 0.0)
    assert plain.metadata["trim_units"] == "flight-test"


def test_linear_resampling_of_jittered_time_states_the_method():
    rng = np.random.default_rng(3)
    time = np.cumsum(rng.uniform(0.015, 0.025, 500))
    line = _columns(time, lambda t, k: 2.0 * t - k)
    m = Maneuver.from_columns("jitter", line, ingestion={"resample": "linear",
                                                         "sample_time": 0.02})
    assert m.dt == pytest.approx(0.02)
    assert m.time[0] == time[0] and m.time[-1] <= time[-1]
    assert np.allclose(m.channel("q"), 2.0 * m.time - ALL_CHANNELS.index("q") + 1)
    assert m.metadata["resampled"].startswith("linear interpolation onto a uniform 0.02 s grid")


def test_non_uniform_time_is_refused_without_resampling_and_the_error_says_how():
    time = np.array([0.0, 0.02, 0.04, 0.07, 0.09])
    with pytest.raises(DataError, match="not uniformly sampled at row 3.*resample"):
        Maneuver.from_columns("uneven", _columns(time))


def test_decimation_removes_what_would_alias():
    """1 kHz record: a 1 Hz motion plus 180 Hz vibration, decimated to 50 Hz. Taking every
    20th sample aliases the vibration to 20 Hz at full amplitude; the anti-aliased decimation
    keeps the 1 Hz motion alone."""
    time = np.arange(0.0, 20.0, 0.001)
    columns = _columns(time, lambda t, k: np.sin(2 * math.pi * t)
                       + 0.5 * np.sin(2 * math.pi * 180.0 * t))
    m = Maneuver.from_columns("vibration", columns,
                              ingestion={"resample": "decimate", "sample_time": 0.02})
    assert m.dt == pytest.approx(0.02)
    inner = slice(50, -50)                       # away from the filter's end effects
    motion = np.sin(2 * math.pi * m.time)
    assert np.max(np.abs(m.channel("p")[inner] - motion[inner])) < 0.01
    subsampled = columns["p"][::20]
    assert np.max(np.abs(subsampled[inner] - motion[inner])) > 0.4
    assert "anti-aliased decimation by 20" in m.metadata["resampled"]


def test_decimation_keeps_a_records_ends_and_its_trim():
    """A 50 Hz record still carrying its trim (az about −1 g) with a slow motion, decimated to
    0.16 s: the first and last kept samples stay on the record (no pull towards zero at the
    ends), and the trim removed after it is the record's own first second's."""
    time = np.arange(0.0, 15.0001, 0.02)
    columns = _columns(time, lambda t, k: -32.17 + k + np.sin(0.4 * t) + 0.1 * t)
    m = Maneuver.from_columns("trimmed-late", columns, ingestion={
        "resample": "decimate", "sample_time": 0.16, "trim": "first-second"})
    for channel in ("az", "q", "theta"):
        recorded = np.interp(m.time, time, columns[channel])
        trim = m.metadata["trim_removed"][channel]
        assert trim == pytest.approx(np.mean(columns[channel][time <= 1.0]), abs=0.01)
        assert np.max(np.abs(m.channel(channel) - (recorded - trim))) < 0.01, channel


def test_a_time_gap_is_warned_about_once_with_its_length():
    time = np.concatenate([np.arange(0.0, 3.0, 0.02), np.arange(3.5, 6.0, 0.02)])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DataWarning)
        m = Maneuver.from_columns("gap", _columns(time), ingestion={"resample": "linear"})
    [warning] = caught
    assert "1 time gap(s)" in str(warning.message)
    assert "the longest 0.52 s after t = 2.98 s" in str(warning.message)
    assert m.duration == pytest.approx(5.98)


def test_channel_units_convert_into_the_unit_system():
    time = np.arange(0.0, 2.0, 0.02)
    columns = _columns(time)
    radians = dict(columns, q=np.radians(columns["q"]), ax=columns["ax"] / 32.174)
    m = Maneuver.from_columns("units", radians,
                              ingestion={"channel_units": {"q": "rad/s", "ax": "g"}})
    assert np.allclose(m.channel("q"), columns["q"])
    assert np.allclose(m.channel("ax"), columns["ax"], rtol=1e-4)
    assert m.metadata["converted_units"] == {"q": "rad/s", "ax": "g"}
    with pytest.raises(DataError, match="'long' cannot be given a unit"):
        Maneuver.from_columns("units", columns, ingestion={"channel_units": {"long": "deg"}})
    with pytest.raises(DataError, match="cannot convert deg"):
        Maneuver.from_columns("units", columns, ingestion={"channel_units": {"q": "deg"}})


def test_from_dataframe_takes_any_table_and_keeps_extra_columns():
    time = np.arange(0.0, 2.0, 0.02)
    columns = _columns(time)
    columns["u"] = 3.0 * time
    m = Maneuver.from_dataframe(Table(columns), "table", metadata={"kind": "doublet"})
    assert np.array_equal(m.channel("theta"), columns["theta"])
    assert np.array_equal(m.extra_channels["u"], columns["u"])
    assert m.metadata == {"kind": "doublet"}
    with pytest.raises(DataError, match=r"maneuver 'x': missing column\(s\) time;"):
        Maneuver.from_dataframe(Table({k: v for k, v in columns.items() if k != "time"}), "x")
    pandas = pytest.importorskip("pandas")
    frame = pandas.DataFrame(columns)
    assert np.array_equal(Maneuver.from_dataframe(frame, "frame").outputs, m.outputs)


def _record(tmp_path, time, name="uneven"):
    path = tmp_path / f"{name}.csv"
    lines = [",".join(ALL_CHANNELS)]
    columns = _columns(time)
    lines += [",".join(repr(float(columns[c][i])) for c in ALL_CHANNELS)
              for i in range(time.size)]
    path.write_text("# units: flight-test\n" + "\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_the_files_source_resamples_and_trims_when_asked(tmp_path):
    rng = np.random.default_rng(5)
    path = _record(tmp_path, np.cumsum(rng.uniform(0.015, 0.025, 300)))
    with pytest.raises(DataFileError, match="not uniformly sampled"):
        create("data-sources", "files").load(path)
    source = create("data-sources", "files",
                    ingestion={"resample": "linear", "trim": "first-second"})
    [m] = source.load(path)
    assert "resampled" in m.metadata and "trim_removed" in m.metadata
    assert abs(np.mean(m.outputs[m.time <= m.time[0] + 1.0])) < 1e-12
    with pytest.raises(DataError, match="unknown resampling method 'cubic'"):
        create("data-sources", "files", ingestion={"resample": "cubic"})


def test_a_case_gives_ingestion_settings_in_its_data_table(tmp_path):
    path = _record(tmp_path, np.cumsum(np.random.default_rng(6).uniform(0.015, 0.025, 300)))
    data = create("data-sources", "files").case_data(
        {"identification": str(path), "resample": "linear", "sample_time": 0.05,
         "channel_units": {"q": "rad/s"}}, tmp_path)
    [m] = data.identification
    assert m.dt == pytest.approx(0.05) and m.metadata["converted_units"] == {"q": "rad/s"}


def test_a_csv_header_declares_the_unit_of_a_channel(tmp_path):
    time = np.arange(0.0, 2.0, 0.02)
    path = _record(tmp_path, time, "perchannel")
    path.write_text('# channel_units: {"p": "rad/s"}\n' + path.read_text(encoding="utf-8"),
                    encoding="utf-8")
    m = read_maneuver(path)
    assert np.allclose(m.channel("p"), np.degrees(_columns(time)["p"]))


def test_mat_files_in_struct_and_column_matrix_layouts(tmp_path):
    time = np.arange(0.0, 2.0, 0.02)
    reference = Maneuver.from_columns("ref", _columns(time))
    channels = {c: reference.channel(c) for c in ALL_CHANNELS}
    order = list(reversed(ALL_CHANNELS))
    matrix = np.column_stack([channels[c] for c in order])
    names = np.array(order, dtype=object)                         # a MATLAB cell array
    layouts = {
        "struct": {"flight": {**channels, "header": '{"name": "flight_1"}'}},
        "matrix": {"data": matrix, "channels": names},
        "struct_of_matrix": {"run": {"data": matrix, "channels": names}},
        "char_rows": {"data": matrix.T, "channels": np.array(order)},   # channels as rows
    }
    for layout, variables in layouts.items():
        path = tmp_path / f"{layout}.mat"
        scipy.io.savemat(path, variables)
        m = read_maneuver(path)
        assert np.allclose(m.outputs, reference.outputs), layout
        assert np.allclose(m.inputs, reference.inputs), layout
        assert m.name == ("flight_1" if layout == "struct" else layout)
    scipy.io.savemat(tmp_path / "short.mat", {"data": matrix, "channels": names[:-1]})
    with pytest.raises(DataFileError, match="'data' has 13 columns but 'channels' names 12"):
        read_maneuver(tmp_path / "short.mat")


def test_nan_dropouts_are_interpolated_across_only_when_resampling(tmp_path):
    time = np.arange(0.0, 2.0, 0.02)
    path = _record(tmp_path, time, "dropout")
    lines = path.read_text(encoding="utf-8").splitlines()
    header = lines[1].split(",")
    for row in (20, 21, 22):                                 # samples 20–22 of q missing
        fields = lines[2 + row].split(",")
        fields[header.index("q")] = "nan"
        lines[2 + row] = ",".join(fields)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(DataFileError, match="line 23 \\(row 20\\), channel 'q': value is empty, NaN"):
        read_maneuver(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DataWarning)
        [m] = create("data-sources", "files", ingestion={"resample": "linear"}).load(path)
    [warning] = caught
    assert "channel 'q' has 1 NaN gap(s), 3 samples, the first at t = 0.4 s" in \
        str(warning.message)
    q = _columns(time)["q"]
    # a straight line between samples 19 and 23
    assert np.allclose(m.channel("q")[20:23], q[19] + (q[23] - q[19]) * np.array([1, 2, 3]) / 4)
    assert m.metadata["resampled"] == ("linear interpolation across 3 NaN samples on the "
                                       "recorded 0.02 s grid")


def test_body_velocity_columns_are_read_as_extra_channels_and_written_back(tmp_path):
    time = np.arange(0.0, 2.0, 0.02)
    columns = {**_columns(time), "u": 10.0 * np.sin(time)}           # u recorded in kt
    m = Maneuver.from_columns("with_u", columns,
                              ingestion={"channel_units": {"u": "kt"}})
    assert np.allclose(m.extra_channels["u"], columns["u"] * 1852.0 / 3600.0 / 0.3048)
    path = write_maneuver(m, tmp_path / "with_u.csv")
    header_row = next(line for line in path.read_text(encoding="utf-8").splitlines()
                      if not line.startswith("#"))
    assert header_row == ",".join((*ALL_CHANNELS, "u"))
    again = read_maneuver(path)
    assert np.array_equal(again.extra_channels["u"], m.extra_channels["u"])
    assert np.array_equal(again.outputs, m.outputs)


def test_a_trim_naming_a_linked_column_asks_for_its_channel():
    with pytest.raises(DataError, match=r"trim value for column 'DELE', which the channel map "
                                        r"links to 'long': give the trim of 'long' instead"):
        Ingestion(trim={"DELE": 1.0}, channels={"DELE": {"signal": "long", "unit": "%"}})
    kept = Ingestion(trim={"long": 1.0}, channels={"DELE": {"signal": "long", "unit": "%"}})
    assert kept.trim == {"long": 1.0}


def test_csv_clock_times_and_empty_dropouts_are_read(tmp_path):
    """A range's IRIG time (day of year first) is read as seconds, and empty fields are
    dropouts, interpolated when resampling, as a literal NaN is."""
    time = np.arange(0.0, 2.0, 0.02)
    columns = _columns(time, lambda t, k: 2.0 * t + k)
    path = write_maneuver(Maneuver.from_columns("clock", columns), tmp_path / "clock.csv")
    lines = path.read_text(encoding="utf-8").splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("time,"))
    for row in range(time.size):
        fields = lines[first + 1 + row].split(",")
        seconds = 31.25 + time[row]
        fields[0] = f"312:14:02:{seconds:06.3f}"
        if row == 10:
            fields[ALL_CHANNELS.index("q")] = ""
        lines[first + 1 + row] = ",".join(fields)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.warns(DataWarning, match="NaN"):
        m = read_maneuver(path, Ingestion(resample="linear"))
    assert m.time[0] == pytest.approx(312 * 86400 + 14 * 3600 + 2 * 60 + 31.25, abs=1e-6)
    assert np.allclose(m.channel("q"), columns["q"], atol=1e-9)


def test_a_sweeps_axis_naming_a_linked_column_becomes_its_channel(tmp_path):
    """A range file's header names the column it sweeps (``axis: PITCH_CMD``); read through
    a channel map linking that column to ``long``, the maneuver sweeps ``long``."""
    time = np.arange(0.0, 2.0, 0.02)
    columns = _columns(time)
    path = write_maneuver(Maneuver.from_columns("sweep", columns, metadata={"axis": "long"}),
                          tmp_path / "sweep.csv")
    text = path.read_text(encoding="utf-8").replace("# axis: long", "# axis: PITCH_CMD")
    path.write_text(text.replace("time,long,", "time,PITCH_CMD,", 1), encoding="utf-8")
    channels = {"PITCH_CMD": {"signal": "long", "unit": "%"}}
    m = read_maneuver(path, Ingestion(channels=channels))
    assert m.metadata["axis"] == "long"
    assert np.allclose(m.channel("long"), columns["long"])


def test_epoch_times_and_microseconds_are_read_as_uniform_time():
    """A logger's epoch clock (1.76e9 s at 100 Hz, steps jittering by its round-off) is
    uniform; a time column in µs converts to s; a real jump still stops the read."""
    from rotorid.data import check_time

    epoch = 1.764e9 + np.arange(500) * 0.01
    assert check_time(epoch, "log") == pytest.approx(0.01, rel=1e-6)
    jumped = epoch.copy()
    jumped[250:] += 0.003
    with pytest.raises(DataError, match="not uniformly sampled at row 250"):
        check_time(jumped, "log")
    time = np.arange(0.0, 2.0, 0.02)
    columns = _columns(time)
    columns["TIME_us"] = columns.pop("time") * 1e6
    m = Maneuver.from_columns("px4", columns, ingestion={
        "channels": {"TIME_us": {"signal": "time", "unit": "µs"}}})
    assert m.dt == pytest.approx(0.02)


def test_a_moment_of_a_clock_timed_record_is_told_from_its_start():
    from rotorid.ingestion import moment_text

    assert moment_text(np.arange(5) * 0.1, 3) == "t = 0.3 s"
    clock = 15863530.0 + np.arange(5) * 0.02
    assert moment_text(clock, 3) == "0.06 s into the record (t = 15863530.06 s)"
