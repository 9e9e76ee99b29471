"""The frequency-response estimator: its cost and Jacobian, exact and noisy recovery."""

import types
import warnings

import attrs
import numpy as np
import pytest
import rotorid
from rotorid.data import Maneuver, ManeuverSet
from rotorid.errors import IdentifiabilityWarning, VerificationError
from rotorid.model.derivatives import Derivative
from rotorid.simulation.transfer import (
    compared_response,
    frequency_response,
    response_sensitivities,
)
from rotorid.verification.compare import default_omega
from rotorid.verification.frequency import FrequencyResponse, response_from_maneuvers
from rotorid_envelopes.cost import MismatchCost
from rotorid_frequency_response.cost import Mismatch, MismatchProblem
from rotorid_frequency_response.estimator import (
    FrequencyResponseEstimator,
    best_start,
    unstable_poles_above,
    varied_starts,
)
from rotorid_frequency_response.levenberg_marquardt import Settings, run
from rotorid_frequency_response.pairs import excited_band, pair_data
from rotorid_signals.signals import Sweep

HOVER = rotorid.FlightCondition.from_airspeed(0.0)
PAIRS = ("p/lat", "phi/lat", "q/long", "theta/long")
#: A decoupled pitch/roll model with rotor-like control delays (flight-test units).
TRUTH = {"L_p": -3.0, "L_lat": 0.9, "M_q": -1.5, "M_long": 0.6, "tau_L_lat": 0.06,
         "tau_M_long": 0.04}


def _structure(names=("L_p", "L_lat", "M_q", "M_long"), delays=("L_lat", "M_long")):
    return rotorid.ModelStructure(HOVER, [Derivative(n) for n in names]).with_delays(delays)


def _analytic_responses(structure, values, omega, pairs=PAIRS):
    h = frequency_response(structure, values, omega)
    return [FrequencyResponse(control, output, omega,
                              h[:, rotorid.OUTPUTS.index(output),
                                rotorid.CONTROLS.index(control)],
                              np.ones(omega.size), np.zeros(omega.size))
            for output, control in (p.split("/") for p in pairs)]


def test_response_sensitivities_match_central_differences():
    structure = rotorid.ModelStructure.six_dof(
        rotorid.FlightCondition.from_airspeed(60.0, theta0_deg=3.0)).with_delays(
        ["L_lat", "M_long", "L_p"]).fixing("N_r", -1.0)
    values = np.random.default_rng(1).normal(size=structure.n_parameters) * 0.3
    values[structure.is_delay()] = [0.03, 0.05, 0.07]
    omega = np.geomspace(0.3, 20.0, 15)
    h, dh = response_sensitivities(structure, values, omega)
    np.testing.assert_allclose(h, frequency_response(structure, values, omega), rtol=1e-12,
                               atol=1e-14 * np.abs(h).max())
    for k in range(structure.n_parameters):
        step = np.zeros_like(values)
        step[k] = 1e-6
        central = (frequency_response(structure, values + step, omega)
                   - frequency_response(structure, values - step, omega)) / 2e-6
        assert np.abs(dh[:, k] - central).max() <= 1e-7 * np.abs(central).max()


def test_compared_response_is_the_mixed_entry_with_central_difference_derivatives():
    structure = rotorid.ModelStructure.six_dof(
        rotorid.FlightCondition.from_airspeed(60.0, theta0_deg=3.0)).with_delays(
        ["L_lat", "M_long", "L_p"]).fixing("N_r", -1.0)
    rng = np.random.default_rng(2)
    values = rng.normal(size=structure.n_parameters) * 0.3
    values[structure.is_delay()] = [0.03, 0.05, 0.07]
    omega = np.geomspace(0.3, 20.0, 15)
    rows = rng.integers(0, structure.n_outputs, omega.size)
    mixing = rng.normal(size=(omega.size, 4)) + 1j * rng.normal(size=(omega.size, 4))

    def mixed(parameters):
        full = frequency_response(structure, parameters, omega)
        return np.einsum("fi,fi->f", full[np.arange(omega.size), rows], mixing)

    h, dh = compared_response(structure, values, omega, rows, mixing)
    reference = mixed(values)
    np.testing.assert_allclose(h, reference, rtol=1e-12, atol=1e-14 * np.abs(reference).max())
    assert compared_response(structure, values, omega, rows, mixing, False)[1] is None
    for k in range(structure.n_parameters):
        step = np.zeros_like(values)
        step[k] = 1e-6
        central = (mixed(values + step) - mixed(values - step)) / 2e-6
        assert np.abs(dh[:, k] - central).max() <= 1e-7 * np.abs(central).max()


def test_cost_matches_the_mismatch_envelope_and_its_jacobian_central_differences():
    structure = _structure()
    omega = np.geomspace(0.5, 12.0, 39)       # the 20 J points fall on every second node
    measured = _analytic_responses(structure, TRUTH, omega)
    problem = MismatchProblem(structure, [pair_data(r) for r in measured])
    values = structure.as_vector({**TRUTH, "L_p": -2.0, "M_long": 0.8, "tau_L_lat": 0.1})
    mismatch = problem.evaluate(values)
    model = frequency_response(structure, values, omega)
    for response, cost in zip(measured, mismatch.pair_costs):
        ratio = model[:, rotorid.OUTPUTS.index(response.output),
                      rotorid.CONTROLS.index(response.input)] / response.response
        reference = MismatchCost().check(ratio, response.coherence, omega).cost
        assert cost == pytest.approx(reference, rel=1e-9)
    assert mismatch.cost == pytest.approx(sum(mismatch.pair_costs), rel=1e-12)
    for k in range(values.size):
        step = np.zeros_like(values)
        step[k] = 1e-6 * max(1.0, abs(values[k]))
        central = (problem.evaluate(values + step, False).residuals
                   - problem.evaluate(values - step, False).residuals) / (2 * step[k])
        assert np.abs(mismatch.jacobian[:, k] - central).max() <= 1e-6 * np.abs(central).max()


def test_exact_recovery_of_a_delayed_model_from_its_analytic_responses():
    names = ("L_p", "L_lat", "M_q", "M_long", "L_v", "M_u", "X_u", "Y_v", "X_long", "Y_lat")
    truth = {**TRUTH, "L_v": -0.05, "M_u": 0.02, "X_u": -0.03, "Y_v": -0.05,
             "X_long": -0.3, "Y_lat": 0.3}
    structure = _structure(names)
    omega = np.geomspace(0.3, 15.0, 39)
    responses = _analytic_responses(structure, truth, omega, (*PAIRS, "ax/long", "ay/lat"))
    start = {name: 0.5 * value for name, value in truth.items()}
    estimate = FrequencyResponseEstimator().estimate(structure, responses, start=start)
    assert estimate.converged
    assert estimate.cost < 1e-20
    np.testing.assert_allclose(estimate.values, structure.as_vector(truth), rtol=1e-9)
    pairs = len(PAIRS) + 2
    assert f"J points           = {estimate.n_samples} over {pairs} pairs" in estimate.report()


def _sweeps(structure, values, noise, seed):
    """Two lateral and two longitudinal 60 s sweeps of the model, with white output noise."""
    rng = np.random.default_rng(seed)
    sweep = Sweep(amplitude=1.0, omega_min=0.4, omega_max=15.0, sweep_time=50.0,
                  sample_time=0.02)
    time = np.arange(int(round(sweep.duration / 0.02)) + 1) * 0.02
    maneuvers = []
    for axis in ("lat", "long"):
        for sign in (1.0, -1.0):
            inputs = np.zeros((time.size, 4))
            inputs[:, rotorid.CONTROLS.index(axis)] = sign * sweep(time)
            maneuvers.append(Maneuver(f"{axis}{sign:+.0f}", time, inputs,
                                      np.zeros((time.size, 8)),
                                      metadata={"axis": axis, "omega_min": 0.4}))
    clean = ManeuverSet(maneuvers)
    outputs = rotorid.simulate(structure, values, clean)
    return ManeuverSet([Maneuver(m.name, m.time, m.inputs,
                                 y + noise * rng.standard_normal(y.shape), metadata=m.metadata)
                        for m, y in zip(clean, outputs)])


def test_recovery_within_three_cramer_rao_bounds_from_noisy_sweeps():
    structure = _structure()
    sweeps = _sweeps(structure, TRUTH, noise=0.1, seed=7)
    estimator = FrequencyResponseEstimator(pairs=PAIRS)
    estimate = estimator.estimate(structure, sweeps)
    truth = structure.as_vector(TRUTH)
    assert estimate.converged
    assert np.all(np.isfinite(estimate.cramer_rao))
    assert np.all(np.abs(estimate.values - truth) <= 3.0 * estimate.cramer_rao)
    derivatives = ~structure.is_delay()
    assert np.all(estimate.cramer_rao_pct[derivatives] < 25.0)     # the bounds say something
    assert np.mean(np.diag(estimate.noise_covariance)) < 20.0       # J per pair on the diagonal


def test_j_points_end_at_the_highest_frequency_the_sweeps_excite():
    sweeps = _sweeps(_structure(), TRUTH, noise=0.1, seed=7)
    recorded = ManeuverSet([attrs.evolve(m, metadata={**m.metadata, "omega_max": 5.0})
                            for m in sweeps])
    open_ended = FrequencyResponseEstimator(pairs=PAIRS).fit_data(sweeps)
    ended = FrequencyResponseEstimator(pairs=PAIRS).fit_data(recorded)
    assert max(p.omega.max() for p in open_ended) > 8.0
    assert max(p.omega.max() for p in ended) <= 5.0
    assert min(p.omega.size for p in ended) >= 15            # the points move, not vanish
    assert excited_band(recorded, (1.0, 4.0)) == (1.0, 4.0)  # a narrower band stays
    broken = ManeuverSet([attrs.evolve(sweeps[0], metadata={**sweeps[0].metadata,
                                                             "omega_max": -1.0})])
    with pytest.raises(VerificationError, match="omega_max must be the sweep's "
                                                        "highest frequency"):
        excited_band(broken)


def test_sweeps_with_a_correlated_second_input_are_fitted_through_the_apparent_response():
    """A pedal input that follows the lateral sweep (as a yaw damper would) moves p and r
    too; the single-input responses p/lat and r/lat contain its effect, which the
    estimator's mixing carries to the model side. Comparing the model's own responses
    with them instead leaves a large J and biased estimates."""
    structure = rotorid.ModelStructure(HOVER, [
        Derivative("L_p"), Derivative("L_lat"), Derivative("N_r"), Derivative("N_lat"),
        Derivative("L_ped", initial=0.4, fixed=True),
        Derivative("N_ped", initial=1.2, fixed=True)])
    truth = {"L_p": -3.0, "L_lat": 0.9, "N_r": -0.8, "N_lat": 0.2}
    rng = np.random.default_rng(3)
    sweep = Sweep(amplitude=1.0, omega_min=0.4, omega_max=15.0, sweep_time=50.0,
                  sample_time=0.02)
    time = np.arange(int(round(sweep.duration / 0.02)) + 1) * 0.02
    maneuvers = []
    for sign in (1.0, -1.0):
        inputs = np.zeros((time.size, 4))
        inputs[:, 1] = sign * sweep(time)
        lagged = np.interp(time - 0.2, time, inputs[:, 1], left=0.0)
        inputs[:, 3] = -0.8 * lagged + 0.1 * rng.standard_normal(time.size)
        maneuvers.append(Maneuver(f"lat{sign:+.0f}", time, inputs, np.zeros((time.size, 8)),
                                  metadata={"axis": "lat", "omega_min": 0.4}))
    clean = ManeuverSet(maneuvers)
    sweeps = ManeuverSet([Maneuver(m.name, m.time, m.inputs,
                                   y + 0.05 * rng.standard_normal(y.shape), metadata=m.metadata)
                          for m, y in zip(clean, rotorid.simulate(structure, truth, clean))])
    pairs = ("p/lat", "phi/lat", "r/lat")
    estimator = FrequencyResponseEstimator(pairs=pairs)
    estimate = estimator.estimate(structure, sweeps)
    values = structure.as_vector(truth)
    assert np.all(np.abs(estimate.values - values) <= 3.0 * estimate.cramer_rao)
    assert np.all(np.isfinite(estimate.cramer_rao))
    assert estimate.cost < 20.0 * len(pairs)

    single = [response_from_maneuvers(sweeps, "lat", p.split("/")[0], default_omega(sweeps))
              for p in pairs]
    with warnings.catch_warnings():         # the direct fit runs off into a flat valley
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        direct = estimator.estimate(structure, single, start=estimate.values)
    assert direct.cost > 10.0 * estimate.cost


def test_errors_name_the_problem_and_the_fix():
    structure = _structure()
    omega = np.geomspace(0.5, 12.0, 39)
    responses = _analytic_responses(structure, TRUTH, omega)
    coupled = _structure(("L_p", "L_lat", "M_q", "M_long", "N_lat"))
    yaw = _analytic_responses(coupled, {**TRUTH, "N_lat": 0.3}, omega, ["r/lat"])
    with pytest.raises(rotorid.EstimationError, match="no response on r/lat"):
        FrequencyResponseEstimator().estimate(structure, [*responses, *yaw], start=TRUTH)
    with pytest.raises(rotorid.EstimationError, match="equation-error start values need"):
        FrequencyResponseEstimator().estimate(structure, responses)
    with pytest.raises(rotorid.EstimationError, match="no response given for pair"):
        FrequencyResponseEstimator(pairs=["q/lat"]).estimate(structure, responses,
                                                             start=TRUTH)
    sweeps = _sweeps(structure, TRUTH, noise=0.0, seed=0).select(axis="lat")
    with pytest.raises(rotorid.EstimationError, match="no sweep excites 'long'"):
        FrequencyResponseEstimator(pairs=["q/long"]).estimate(structure, sweeps)


def test_varied_starts_keep_signs_zeros_and_delays():
    structure = _structure(("L_p", "L_lat", "M_q", "M_long", "N_lat"))
    start = structure.as_vector({**TRUTH, "N_lat": 0.0})
    starts = varied_starts(structure, start, 5, seed=1)
    assert len(starts) == 5 and np.array_equal(starts[0], start)
    delay = structure.is_delay()
    for varied in starts[1:]:
        assert np.array_equal(varied[delay], start[delay])
        assert np.array_equal(np.sign(varied), np.sign(start))
        ratio = varied[~delay & (start != 0)] / start[~delay & (start != 0)]
        assert np.all(ratio != 1.0)
    with pytest.raises(rotorid.EstimationError, match="starts must be a whole number"):
        FrequencyResponseEstimator(starts=0)


def test_several_starts_keep_the_lowest_cost_of_the_single_fits():
    """The multi-start result is the best of the fits from each varied start alone."""
    structure = _structure()
    sweeps = _sweeps(structure, TRUTH, noise=0.3, seed=2)
    single = FrequencyResponseEstimator(pairs=PAIRS)
    data = single.fit_data(sweeps)
    start = structure.as_vector({**TRUTH, "tau_L_lat": 0.0, "tau_M_long": 0.0}) * 2.0
    costs = [single.estimate(structure, data, start=s).cost
             for s in varied_starts(structure, start, 3, seed=4)]
    best = FrequencyResponseEstimator(pairs=PAIRS, starts=3, seed=4).estimate(
        structure, data, start=start)
    assert best.cost == pytest.approx(min(costs), rel=1e-12)
    assert any(note.startswith("best of 3 starts") for note in best.notes)


def test_levenberg_marquardt_converges_on_a_curved_valley():
    """Rosenbrock's valley as residuals (e = [10(θ₂ − θ₁²), 1 − θ₁], minimum 0 at (1, 1)):
    the accelerated steps follow the curve to the minimum within the iteration limit."""

    class Valley:
        def evaluate(self, values, jacobian=True):
            x, y = values
            residuals = np.array([10.0 * (y - x * x), 1.0 - x])
            matrix = np.array([[-20.0 * x, 10.0], [-1.0, 0.0]]) if jacobian else None
            return Mismatch(residuals, matrix, (float(residuals @ residuals),))

    result = run(Valley(), np.array([-1.2, 1.0]), (np.full(2, -np.inf), np.full(2, np.inf)),
                 Settings(max_iterations=200, cost_tolerance=1e-14))
    assert result.converged
    assert np.allclose(result.values, [1.0, 1.0], atol=1e-5)
    assert all(b < a for a, b in zip(result.cost_history, result.cost_history[1:]))


def test_unstable_poles_above_the_band_are_found_and_passed_over():
    """A roll-rate model with L_p = +300 1/s has its pole at +300 rad/s (above a 20 rad/s
    band); L_p = +0.5 is unstable but inside the band, L_p = −3 is stable."""
    structure = _structure(("L_p", "L_lat"), delays=())
    poles = unstable_poles_above(structure, {"L_p": 300.0, "L_lat": 0.9}, 20.0)
    assert poles == pytest.approx([300.0])
    for slow in (0.5, -3.0):
        assert unstable_poles_above(structure, {"L_p": slow, "L_lat": 0.9}, 20.0).size == 0

    def result(l_p, cost):
        return types.SimpleNamespace(values=structure.as_vector({"L_p": l_p, "L_lat": 0.9}),
                                     mismatch=types.SimpleNamespace(cost=cost))

    best, notes = best_start(structure, [result(-3.0, 50.0), result(300.0, 10.0), None],
                              20.0)
    assert best == 0
    assert "10.0 (unstable pole above the band)" in notes[0] and "—" in notes[0]
    best, notes = best_start(structure, [result(300.0, 10.0)], 20.0)
    assert best == 0 and "unstable poles above the J band (20 rad/s): 300" in notes[0]


def test_an_aeroplane_is_fitted_on_its_own_channels_from_sweeps():
    """The fixed-wing lateral template (controls aileron, rudder; outputs beta p phi r ay,
    SI) from noisy aileron and rudder sweeps: the pairs are the aeroplane's own, and every
    derivative comes back within 3 Cramér-Rao bounds."""
    condition = rotorid.FlightCondition(u0=40.0)
    truth = {"Y_v": -0.25, "L_v": -0.2, "L_p": -5.0, "L_r": 1.2, "L_aileron": 15.0,
             "N_v": 0.1, "N_r": -1.0, "N_rudder": -4.6, "Y_rudder": 3.0}
    structure = rotorid.ModelStructure.populated(condition, "fixed-wing-lateral", units="si")
    structure = structure.without(*[n for n in structure.names if n not in truth])
    sweep = Sweep(amplitude=0.02, omega_min=0.4, omega_max=15.0, sweep_time=50.0,
                  sample_time=0.02)
    time = np.arange(int(round(sweep.duration / 0.02)) + 1) * 0.02
    clean = ManeuverSet([
        Maneuver(axis, time, np.column_stack([sweep(time) * (axis == "aileron"),
                                              sweep(time) * (axis == "rudder")]),
                 np.zeros((time.size, 5)), units="si", input_names=structure.controls,
                 output_names=structure.outputs, metadata={"axis": axis, "omega_min": 0.4})
        for axis in structure.controls])
    rng = np.random.default_rng(11)
    sweeps = ManeuverSet([m.with_outputs(y + 1e-4 * rng.standard_normal(y.shape))
                          for m, y in zip(clean, rotorid.simulate(structure, truth, clean))])
    estimator = FrequencyResponseEstimator()
    pairs = [p.pair for p in estimator.fit_data(sweeps) if not isinstance(p, str)]
    assert {"p/aileron", "r/rudder", "ay/rudder"} <= set(pairs)
    estimate = estimator.estimate(structure, sweeps)
    assert estimate.converged
    errors = np.abs(estimate.values - structure.as_vector(truth))
    assert np.all(errors <= 3.0 * estimate.cramer_rao), dict(zip(structure.names, errors))
    assert np.all(estimate.cramer_rao_pct < 25.0)


def test_a_pair_the_structure_cannot_fit_is_named_with_the_others_to_keep():
    """The truth couples roll to pitch through the pitch rate (L_q); a structure that couples
    them through the stick (L_long) instead has the wrong shape on p/long, fits it far above
    the guideline, and the note says which pairs to keep."""
    truth_structure = _structure(names=("L_p", "L_lat", "L_q", "M_q", "M_long"))
    sweeps = _sweeps(truth_structure, {**TRUTH, "L_q": 4.0}, noise=0.05, seed=3)
    fitted = _structure(names=("L_p", "L_lat", "L_long", "M_q", "M_long"))
    estimate = FrequencyResponseEstimator(pairs=(*PAIRS, "p/long")).estimate(fitted, sweeps)
    [note] = [n for n in estimate.notes if n.startswith("pairs the structure does not fit")]
    assert "p/long (J " in note
    assert "pairs = [p/lat, phi/lat, q/long, theta/long]" in note


def test_identify_takes_the_pairs_and_band_of_the_frequency_response_estimator(tmp_path,
                                                                            capsys):
    import json

    from rotorid.cli import main as cli
    from rotorid_files.formats import write_maneuver

    sweeps = _sweeps(_structure(), TRUTH, noise=0.05, seed=5)
    for m in sweeps:
        write_maneuver(m, tmp_path / f"{m.name}.csv")
    model = tmp_path / "model.toml"
    model.write_text('units = "flight-test"\n[condition]\nairspeed_kt = 0.0\n[structure]\n'
                     'populate = "none"\n[derivatives]\nL_p = {}\nL_lat = {}\nM_q = {}\n'
                     'M_long = {}\n', encoding="utf-8")
    out = tmp_path / "fr.json"
    argv = ["identify", str(model), str(tmp_path / "*.csv"), "--out", str(out), "--quiet",
            "--estimator", "frequency-response"]
    assert cli.main([*argv, "--pairs", "p/lat,q/long", "--band", "0.5,12"]) == 0, \
        capsys.readouterr().err
    record = json.loads(out.read_text(encoding="utf-8"))
    assert record["estimator_options"] == {"pairs": ["p/lat", "q/long"], "band": [0.5, 12.0]}
    assert record["outputs"] == ["p/lat", "q/long"]
    capsys.readouterr()
    assert cli.main([*argv, "--force", "--band", "12,0.5"]) == 2
    assert "--band needs two frequencies in rad/s, lowest first" in capsys.readouterr().err
    assert cli.main([*argv[:-2], "--force", "--pairs", "p/lat"]) == 2
    assert "--pairs: the frequency-response estimator's" in capsys.readouterr().err


def _pair_at(output, control, low, high):
    from rotorid_frequency_response.pairs import PairData

    omega = np.geomspace(low, high, 5)
    return PairData(output, control, omega, np.zeros(5), np.zeros(5), np.ones(5),
                    np.ones((5, 1)), (control,))


def test_default_pairs_leave_out_those_coherent_over_less_than_an_octave():
    """Of the default pairs (every output over every swept input), one coherent only over
    7.06–7.25 rad/s (the quick hover sweeps' az/long) is named with its range and left out;
    were no broader pair left, none would be."""
    from rotorid_frequency_response.estimator import broad_pairs

    broad, narrow = _pair_at("q", "long", 0.8, 12.0), _pair_at("az", "long", 7.06, 7.25)
    kept = broad_pairs((broad, narrow, "ay/long"))
    assert kept[0] is broad and kept[2] == "ay/long"
    assert kept[1] == ("az/long (coherent over 7.06–7.25 rad/s only, less than a factor 2; "
                       "name it in pairs to fit it)")
    assert broad_pairs((narrow,)) == (narrow,)
    fitted, notes = FrequencyResponseEstimator()._usable(kept)
    assert fitted == [broad]
    assert notes == ["pairs left out: az/long (coherent over 7.06–7.25 rad/s only, less than "
                     "a factor 2; name it in pairs to fit it), ay/long (no frequency with "
                     "γ² ≥ 0.6)"]
