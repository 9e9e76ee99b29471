"""rotorid.actuators.lagged_inputs against scipy.signal.lsim of the continuous lag."""

import numpy as np
import pytest
import scipy.signal
from rotorid import Maneuver, ManeuverSet
from rotorid.actuators import lagged_inputs
from rotorid.errors import DataError

DT = 0.02
TAU = 0.03
FINE = 200                         # fine steps per sample of the reference


def _records(hold="zoh"):
    rng = np.random.default_rng(5)
    time = np.arange(150) * DT
    inputs = np.cumsum(rng.normal(size=(150, 4)), axis=0)
    outputs = rng.normal(size=(150, 8))
    return ManeuverSet([Maneuver("steps", time, inputs, outputs)], hold=hold)


def _continuous_lag(time, signal, interp=True):
    """The lag's response to ``signal`` at ``time``, linear between the samples (``interp``)
    or held, started at rest at signal[0]."""
    lag = scipy.signal.lti([1.0], [TAU, 1.0])
    _, response, _ = scipy.signal.lsim(lag, signal - signal[0], time, interp=interp)
    return response + signal[0]


def test_zero_order_hold_keeps_the_lags_mean_over_each_sample():
    records = _records()
    lagged = lagged_inputs(records, TAU, inputs=("lat",))
    source = records[0].inputs[:, 1]
    fine = np.arange(source.size * FINE) * DT / FINE
    response = _continuous_lag(fine, np.repeat(source, FINE), interp=False)
    means = response.reshape(source.size, FINE)
    # trapezoidal mean over each interval [t_k, t_k+1)
    ends = np.append(response[FINE::FINE], response[-1])
    mean = (means.sum(axis=1) - 0.5 * means[:, 0] + 0.5 * ends) / FINE
    np.testing.assert_allclose(lagged[0].inputs[:-1, 1], mean[:-1], rtol=1e-4, atol=1e-4)
    np.testing.assert_array_equal(lagged[0].inputs[:, [0, 2, 3]],
                                  records[0].inputs[:, [0, 2, 3]])


def test_first_order_hold_keeps_the_lags_sample_values_for_the_interpolated_input():
    records = _records("foh")
    lagged = lagged_inputs(records, TAU)
    time = records[0].time
    for column in range(4):
        reference = _continuous_lag(time, records[0].inputs[:, column])
        np.testing.assert_allclose(lagged[0].inputs[:, column], reference, rtol=1e-9,
                                   atol=1e-9)


def test_the_records_given_are_kept_and_bad_settings_refused():
    records = _records()
    before = records[0].inputs.copy()
    lagged_inputs(records, TAU)
    np.testing.assert_array_equal(records[0].inputs, before)
    with pytest.raises(DataError, match="time constant must be a finite number of seconds > 0"):
        lagged_inputs(records, 0.0)
    with pytest.raises(DataError, match="has no input elevator to lag; its inputs are long, "
                                        "lat, coll, ped"):
        lagged_inputs(records, TAU, inputs=("elevator",))
