"""Zero-phase low-pass and decimation of records (rotorid.resampling): a tone in the band
keeps its amplitude and phase, one above it goes, a trim offset stays, every channel is
filtered alike, bad settings are refused with the fix, and the kept samples' noise
correlation is predicted (against white noise run through the filter) and warned about."""

import warnings

import numpy as np
import pytest
from rotorid import Maneuver, ManeuverSet
from rotorid.errors import DataError, DataWarning
from rotorid.resampling import (
    decimated,
    decimated_maneuver,
    low_passed,
    noise_correlation,
    white_noise_factor,
)

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


def test_a_set_keeps_its_hold_names_and_metadata_and_says_how_it_was_filtered():
    """The metadata gains ``low_passed`` (each filtering after the earlier ones); the given
    set is left as it was."""
    time, low, _ = _tones(seconds=4.0)
    inputs = np.column_stack([low, 0 * low, 0 * low, 0 * low])
    maneuvers = ManeuverSet([Maneuver("a", time, inputs, np.zeros((time.size, 8)),
                                      metadata={"kind": "3211"})], hold="foh")
    out = decimated(maneuvers, factor=2, cutoff_hz=5.0)
    assert out.hold == "foh" and out.names == ("a",)
    assert out[0].metadata == {"kind": "3211",
                               "low_passed": "zero-phase low-pass at 5 Hz, every 2nd sample kept"}
    assert out[0].time.size == (time.size + 1) // 2
    assert low_passed(out, 2.0)[0].metadata["low_passed"] == (
        "zero-phase low-pass at 5 Hz, every 2nd sample kept; then zero-phase low-pass at 2 Hz")
    assert maneuvers[0].time.size == time.size and maneuvers[0].metadata == {"kind": "3211"}


@pytest.mark.parametrize("factor, cutoff, message", [
    (0, 4.0, "whole number ≥ 1"), (2.5, 4.0, "whole number ≥ 1"),
    (4, 6.3, "Nyquist frequency 6.25 Hz"), (4, -1.0, "between 0 and"),
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


@pytest.mark.parametrize("factor, cutoff", [(4, 4.0), (3, 6.0), (6, 4.0), (8, 3.0)])
def test_the_kept_noise_correlation_matches_white_noise_through_the_filter(factor, cutoff):
    rng = np.random.default_rng(11)
    time = np.arange(200_000) * DT
    noise = np.zeros((time.size, 8))
    noise[:, 0] = rng.standard_normal(time.size)
    record = _record(time, np.zeros((time.size, 4)), noise)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataWarning)
        kept = decimated_maneuver(record, factor, cutoff).outputs[:, 0]
    kept = kept - kept.mean()
    sample = np.mean(kept[:-1] * kept[1:]) / np.mean(kept ** 2)
    assert noise_correlation(DT, factor, cutoff) == pytest.approx(sample, abs=0.02)


def test_the_white_noise_factor_keeps_the_nyquist_frequency_just_above_the_cutoff():
    assert [white_noise_factor(DT, c) for c in (4.0, 6.0, 6.25, 5.0, 3.0, 20.0)] == \
        [6, 4, 4, 5, 8, 1]
    for cutoff in (1.3, 2.0, 4.0, 5.0, 7.7):
        factor = white_noise_factor(DT, cutoff)
        assert 0.5 / (factor * DT) >= cutoff > 0.5 / ((factor + 1) * DT)
        assert noise_correlation(DT, factor, cutoff) < 0.2
    with pytest.raises(DataError, match="Nyquist frequency 25 Hz"):
        white_noise_factor(DT, 30.0)


def test_decimation_that_colours_the_noise_warns_with_the_factor_to_use():
    time, low, _ = _tones(seconds=4.0)
    record = _record(time, np.column_stack([low] * 4), np.zeros((time.size, 8)))
    with pytest.warns(DataWarning, match=r"correlated 0\.51 .* keep every 6th sample"):
        decimated_maneuver(record, 4, 4.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)
        decimated_maneuver(record, 6, 4.0)
