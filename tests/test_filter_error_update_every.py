"""Filter error with a measurement update at every N-th sample (``update_every``): the lifted
system against a filter that steps through every sample and updates at every N-th, its
sensitivities against finite differences, recovery within 3 CR, and the records it is meant
for (:func:`rotorid.resampling.low_passed`)."""

import warnings

import numpy as np
import pytest
import rotorid
from rotorid.errors import DataError, EstimationError, IdentifiabilityWarning
from rotorid.resampling import decimated, low_passed
from rotorid_filter_error.estimator import FilterErrorProblem
from rotorid_filter_error.kalman import Records
from rotorid_output_error.levenberg_marquardt import Settings
from rotorid.simulation.simulator import lagged_sources
from test_filter_error import (GUSTS, PROCESS, SMALL_TRUTH, VARIANCE,
                               _assert_matches_central_differences, estimator, noisy_data,
                               structure)

EVERY = 4


def _periodic_filter_innovations(problem_every_sample, values, every):
    """Innovations of maneuver 0 at samples 0, N, 2N, … and their covariance from a filter
    that predicts through every sample and updates at every N-th: the periodic Riccati
    recursion run to its steady state, written out here sample by sample."""
    system, _ = problem_every_sample.filter(values)
    phi, h = system.transition[0].real, system.output[0].real
    parts = problem_every_sample.split(values)
    process = np.zeros_like(phi)
    rows = problem_every_sample.noise_rows
    process[rows, rows] = parts.process**2
    measurement = np.diag(parts.measurement)
    covariance = np.eye(phi.shape[0])
    for _ in range(100_000):
        start = covariance
        for step in range(every):
            if step == 0:
                innovation = h @ covariance @ h.T + measurement
                gain = covariance @ h.T @ np.linalg.inv(innovation)
                covariance = covariance - gain @ h @ covariance
            covariance = phi @ covariance @ phi.T + process
        if np.max(np.abs(covariance - start)) < 1e-15 * np.max(np.abs(covariance)):
            break
    records = problem_every_sample.records
    lagged = lagged_sources(records.inputs, system.taps)[:, 0]
    state_forcing = system.state_forcing[0].real
    output_forcing = system.output_forcing[0].real
    state = np.zeros(phi.shape[0])
    state[:system.states.size] = records.x0[0, system.states]
    innovations = []
    for n in range(records.lengths[0]):
        predicted = h @ state + lagged[n] @ output_forcing
        if n % every == 0:
            innovations.append(records.outputs[n, 0] - predicted)
            state = state + gain @ innovations[-1]
        state = phi @ state + lagged[n] @ state_forcing
    return np.array(innovations), innovation


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_lifted_filter_is_the_filter_updating_at_every_nth_sample(hold):
    """With a delay (inputs read several samples back) and either hold (FOH reads one sample
    ahead), the lifted system's innovations and their covariance equal those of the filter
    that steps through every sample and takes every N-th measurement."""
    model = structure(delays=("L_lat",))
    data = noisy_data(PROCESS)
    data = rotorid.ManeuverSet(list(data), hold=hold)
    values = np.concatenate([model.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.07}),
                             list(PROCESS.values()), VARIANCE])
    every_sample = FilterErrorProblem(model, data, tuple(PROCESS), Settings())
    lifted = FilterErrorProblem(model, data, tuple(PROCESS), Settings(), update_every=EVERY)
    innovations, covariance = lifted.innovations(values)
    expected, expected_covariance = _periodic_filter_innovations(every_sample, values, EVERY)
    assert covariance == pytest.approx(expected_covariance, rel=1e-8)
    length = lifted.records.lengths[0]
    assert length == len(expected) == -(-data[0].n_samples // EVERY)
    assert innovations[:length, 0] == pytest.approx(expected, rel=1e-7, abs=1e-9)
    assert lifted.n_samples == sum(-(-m.n_samples // EVERY) for m in data)


def test_lifted_records_keep_every_input_sample():
    data = noisy_data({})
    records = Records.from_maneuvers(data, structure())
    lifted = records.lifted(3)
    assert lifted.dt == pytest.approx(3 * records.dt)
    first = data[0].inputs
    blocks = lifted.inputs[:, 0].reshape(lifted.inputs.shape[0], 3, -1)
    assert blocks.reshape(-1, first.shape[1])[:len(first)] == pytest.approx(first)
    assert lifted.outputs[:, 0] == pytest.approx(records.outputs[::3, 0])
    assert records.lifted(1) is records


def test_lifted_sensitivities_match_finite_differences():
    """Derivatives, a delay and the gusts' size and correlation time, through the lifted
    system's powers and sums."""
    model = structure(delays=("L_lat",))
    data = noisy_data({}, disturbances={"p": (3.0, 0.8)}, gusts=GUSTS)
    problem = FilterErrorProblem(model, data, (), Settings(), ("p",), tuple(GUSTS),
                                 update_every=EVERY)
    values = np.concatenate([model.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.05}),
                             [3.0, 3.0, 4.0, 0.8, 1.0, 1.0], VARIANCE])
    system, steady = problem.filter(values, directions=True)
    _assert_matches_central_differences(problem, system, steady, values,
                                        ("M_q", "L_v", "tau_L_lat", "G_w", "Tg_v", "R_p"),
                                        floor=1e-2)


def test_updating_at_every_second_sample_recovers_derivatives_and_noise_within_3_cr():
    """White process noise at the sample rate and white measurement noise: the lifted model
    is exact, so every derivative, F and R is recovered within 3 CR from half the
    innovations. The sway's process noise F_v (0.02 ft/s per sample, seen only through the
    small Y_v in ay) is barely identified even at every sample (0.0095 ± 0.0064 on these
    data); from half the samples it reaches its bound 0 with an infinite bound."""
    data = noisy_data(PROCESS, seed=3)
    model = structure()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator(process_noise=tuple(PROCESS), update_every=2).estimate(model, data)
    assert result.converged, result.stop_reason
    unbounded = [n for n, b in zip(result.parameter_names, result.cramer_rao)
                 if not np.isfinite(b)]
    assert unbounded == ["F_v"] and result.value("F_v") == 0.0
    truth = np.concatenate([model.as_vector(SMALL_TRUTH), list(PROCESS.values()), VARIANCE])
    error = np.abs(result.values - truth) / result.cramer_rao
    assert np.all(error < 3.0), dict(zip(result.parameter_names, error.round(2)))
    assert result.n_samples == sum(-(-m.n_samples // 2) for m in data)
    assert any("one measurement update per 2 samples" in n for n in result.notes)


def test_update_every_is_checked():
    for bad in (0, 1.5, True):
        with pytest.raises(EstimationError, match="update_every must be a whole number ≥ 1"):
            estimator(update_every=bad)

    class OwnModel:
        pass

    with pytest.raises(EstimationError, match="update_every = 3 is for linear structures"):
        estimator(update_every=3).estimate(OwnModel(), noisy_data({}))


def test_low_passed_records_keep_every_sample():
    """The same zero-phase low-pass as decimation's, every sample kept, without decimation's
    warning (the correlated neighbours are not innovations of the filter updating at every
    N-th sample); the given records are left as they were."""
    data = noisy_data(PROCESS)
    before = data[0].outputs.copy()
    with pytest.warns(rotorid.errors.DataWarning, match="correlated"):
        reference = decimated(data, 1, 4.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        filtered = low_passed(data, 4.0)
    assert [m.n_samples for m in filtered] == [m.n_samples for m in data]
    for mine, theirs in zip(filtered, reference):
        assert mine.outputs == pytest.approx(theirs.outputs)
        assert mine.inputs == pytest.approx(theirs.inputs)
    assert np.array_equal(data[0].outputs, before)
    with pytest.raises(DataError, match="cutoff 30.0 Hz must lie between 0 and the records' "
                                        "Nyquist frequency 25 Hz"):
        low_passed(data, 30.0)
