"""Zero-phase low-pass and decimation of records (rotorid.resampling): a tone in the band
keeps its amplitude and phase, one above it goes, a trim offset stays, every channel is
filtered alike, and bad settings are refused with the fix."""

import numpy as np
import pytest
from rotorid import Maneuver, ManeuverSet
from rotorid.errors import DataError
from rotorid.resampling import decimated, decimated_maneuver

DT = 0.02


def _record(time, inputs, outputs, **fields):
    return Maneuver("m", time, inputs, outputs, **fields)


def _tones(low_hz=0.5, high_hz=20.0, seconds=20.0):
    time = np.arange(int(seconds / DT) + 1) * DT
    low = np.sin(2 * np.pi * low_hz * time + 0.3)
    high = 0.5 * np.sin(2 * np.pi * high_hz * time)
    return time, low, high


def test_a_tone_in_the_band_keeps_amplitude_and_phase_and_one_above_it_goes():
    time, low, high = _tones()
    inputs = np.zeros((time.size, 4))
    inputs[:, 0] = low + high
    outputs = np.zeros((time.size, 8))
    outputs[:, 2] = 3.0 + low                       # a trim offset on the channel
    record = decimated_maneuver(_record(time, inputs, outputs, extra_channels={"V": low}),
                                factor=4, cutoff_hz=4.0)
    np.testing.assert_allclose(record.time, time[::4])
    middle = slice(25, -25)                          # away from the edges' padding
    # Butterworth gain at 0.5 Hz of a 4 Hz cut, both passes: |H|² = 1/(1 + (1/8)^8)
    np.testing.assert_allclose(record.inputs[middle, 0], low[::4][middle], atol=1e-4)
    np.testing.assert_allclose(record.outputs[middle, 2], 3.0 + low[::4][middle], atol=1e-4)
    np.testing.assert_allclose(record.extra_channels["V"][middle], low[::4][middle], atol=1e-4)
    assert np.all(record.outputs[:, 0] == 0.0)           # an untouched channel stays exact


def test_a_set_keeps_its_hold_names_and_metadata():
    time, low, _ = _tones(seconds=4.0)
    inputs = np.column_stack([low, 0 * low, 0 * low, 0 * low])
    maneuvers = ManeuverSet([Maneuver("a", time, inputs, np.zeros((time.size, 8)),
                                      metadata={"kind": "3211"})], hold="foh")
    out = decimated(maneuvers, factor=2, cutoff_hz=5.0)
    assert out.hold == "foh" and out.names == ("a",)
    assert out[0].metadata == {"kind": "3211"} and out[0].time.size == (time.size + 1) // 2
    assert maneuvers[0].time.size == time.size       # the given set is left as it was


@pytest.mark.parametrize("factor, cutoff, message", [
    (0, 4.0, "whole number ≥ 1"), (2.5, 4.0, "whole number ≥ 1"),
    (4, 6.25, "Nyquist frequency 6.25 Hz"), (4, -1.0, "between 0 and"),
])
def test_bad_settings_are_refused_with_the_fix(factor, cutoff, message):
    time, low, _ = _tones(seconds=4.0)
    record = _record(time, np.column_stack([low] * 4), np.zeros((time.size, 8)))
    with pytest.raises(DataError, match=message):
        decimated_maneuver(record, factor, cutoff)


def test_short_records_are_refused():
    short = _record(np.arange(10) * DT, np.zeros((10, 4)), np.zeros((10, 8)))
    with pytest.raises(DataError, match="too few to filter"):
        decimated_maneuver(short, 2, 5.0)
