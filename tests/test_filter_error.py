"""The filter-error estimator: steady-state gain, sensitivities, recovery with process and
measurement noise, and reduction to output error in still air."""

import math
import warnings

import numpy as np
import pytest
import rotorid
import scipy.linalg
from rotorid import Derivative, FlightCondition, ModelStructure
from rotorid.errors import DataError, EstimationError, IdentifiabilityWarning
from rotorid.estimation.models import LinearModel
from rotorid_filter_error.estimator import FilterErrorProblem, unmeasured_gusts
from rotorid_filter_error.kalman import innovation_blocks
from rotorid_filter_error import riccati
from rotorid_filter_error.riccati import steady_state_filter
from rotorid_output_error.levenberg_marquardt import Settings
from rotorid.simulation.discretisation import COMPLEX_STEP
from test_output_error import HOVER, SMALL_TRUTH, doublet_maneuvers

#: Process noise per sample (structure units) and measurement-noise variances of the data.
PROCESS = {"w": 0.03, "q": 0.05, "v": 0.02, "p": 0.1, "r": 0.05}
VARIANCE = np.array([0.2, 0.2, 0.1, 0.1, 0.2, 0.1, 0.1, 0.1]) ** 2


def estimator(**options):
    return rotorid.create("estimators", "filter-error", **options)


def structure(delays=()):
    return ModelStructure(HOVER, [Derivative(n) for n in SMALL_TRUTH]).with_delays(delays)


def noisy_data(process, seed=1, dt=0.02, model=None, truth=SMALL_TRUTH, variance=VARIANCE,
               disturbances=None, gusts=None, initial_states=None, biases=None, trace=None):
    """Doublet maneuvers of ``model`` (default the small six-dof hover model) in its own
    channels, simulated by :func:`noisy_outputs` (``trace`` passed on); ``biases`` (records,
    p) are added to each record's outputs."""
    model = structure() if model is None else model
    controls = [rotorid.CONTROLS.index(u) for u in model.controls]
    records = [r for r in doublet_maneuvers(dt=dt) if np.any(r.inputs[:, controls])]
    inputs = [r.inputs[:, controls] for r in records]
    outputs = noisy_outputs(model, truth, inputs, dt, process, variance,
                            np.random.default_rng(seed), disturbances, gusts, initial_states,
                            trace=trace)
    if biases is not None:
        outputs = [y + b for y, b in zip(outputs, biases)]
    return rotorid.ManeuverSet([
        rotorid.Maneuver(r.name, r.time, u, y, input_names=model.controls,
                         output_names=model.outputs)
        for r, u, y in zip(records, inputs, outputs)])


def noisy_outputs(model, truth, inputs, dt, process, variance, rng, disturbances=None,
                  gusts=None, initial_states=None, substeps=1, trace=None):
    """The outputs (N_i, p) of ``model`` at ``truth`` for each input record (N_i, m),
    simulated independently of the estimator (zero-order-hold discretisation by one matrix
    exponential) from trim, with white process noise (state → σ per sample) added to the
    states each sample and white measurement noise of ``variance`` (p,); ``disturbances``
    (state → (σ, τ s)) adds to that state's equation a first-order Gauss-Markov acceleration
    of stationary standard deviation σ, held over each sample (an input of the matrix
    exponential) and started at zero, which the accelerometer reading that equation measures
    too; ``gusts`` (state → (σ, τ s)) adds a first-order Gauss-Markov air velocity g of that
    state, held over each sample and started at zero, which enters as the state's negative in
    the derivative terms: −(A − A0)·e_j·g in the state equations (discretised with the
    controls) and −(C − C0)·e_j·g in the outputs. ``initial_states`` (records, n) starts each
    record there instead of at trim. ``substeps`` > 1 steps the disturbances and gusts (and
    the states they drive) that many times per sample, each at its own Gauss-Markov decay: a
    continuous process to within 1/substeps of a sample, not one held over the sample.
    ``trace``, a list, receives per record the true (N_i, n + gusts + disturbances) states,
    gusts and disturbance accelerations at the samples."""
    a, b, c, d = model.matrices(model.as_vector(truth))
    n, m = b.shape
    gust = dict(gusts or {})
    gust_columns = [model.states.index(s) for s in gust]
    gust_input = -(a - model.known_state_matrix())[:, gust_columns]
    gust_reading = -(c - model.known_output_matrix())[:, gust_columns]
    coloured = dict(disturbances or {})
    coloured_rows = [model.states.index(s) for s in coloured]
    gusts_end = n + m + len(gust)
    block = np.zeros((gusts_end + len(coloured),) * 2)
    block[:n, :n], block[:n, n:n + m], block[:n, n + m:gusts_end] = a, b, gust_input
    block[coloured_rows, gusts_end + np.arange(len(coloured))] = 1.0
    step = dt / substeps
    exp = scipy.linalg.expm(block * step)
    phi, gamma = exp[:n, :n], exp[:n, n:n + m]
    gust_gamma, held = exp[:n, n + m:gusts_end], exp[:n, gusts_end:]
    rows = [model.states.index(s) for s in process]
    sigma = np.array(list(process.values()))
    decay = np.array([np.exp(-step / tau) for _, tau in coloured.values()])
    drive = np.array([size for size, _ in coloured.values()]) * np.sqrt(1 - decay**2)
    gust_decay = np.array([np.exp(-step / tau) for _, tau in gust.values()])
    gust_drive = np.array([size for size, _ in gust.values()]) * np.sqrt(1 - gust_decay**2)
    accelerometer = {"u": "ax", "w": "az", "v": "ay"}
    sensed = np.zeros((len(model.outputs), len(coloured)))
    for j, state in enumerate(coloured):
        if accelerometer.get(state) in model.outputs:
            sensed[model.outputs.index(accelerometer[state]), j] = 1.0
    records = []
    for i, record in enumerate(inputs):
        x = np.zeros(n) if initial_states is None else np.array(initial_states[i], dtype=float)
        outputs = np.empty((len(record), len(model.outputs)))
        acceleration, air = np.zeros(len(coloured)), np.zeros(len(gust))
        truth_states = np.empty((len(record), n + len(gust) + len(coloured)))
        for k, u in enumerate(record):
            outputs[k] = c @ x + d @ u + sensed @ acceleration + gust_reading @ air
            truth_states[k] = np.concatenate([x, air, acceleration])
            for _ in range(substeps):
                x = phi @ x + gamma @ u + gust_gamma @ air + held @ acceleration
                acceleration = decay * acceleration + drive * rng.standard_normal(len(coloured))
                air = gust_decay * air + gust_drive * rng.standard_normal(len(gust))
            x[rows] += sigma * rng.standard_normal(len(rows))
        records.append(outputs + rng.standard_normal(outputs.shape) * np.sqrt(variance))
        if trace is not None:
            trace.append(truth_states)
    return records


@pytest.mark.parametrize("unstable", [False, True])
def test_steady_state_gain_matches_scipy_dare(unstable):
    rng = np.random.default_rng(4)
    size, n_out = 6, 3
    phi = rng.normal(size=(size, size)) * 0.3 + np.eye(size) * (0.9 if not unstable else 1.05)
    h = rng.normal(size=(n_out, size))
    root = rng.normal(size=(size, size))
    q = root @ root.T * 0.01
    r = rng.uniform(0.05, 0.2, n_out)
    steady = steady_state_filter(phi[None], h[None], q[None], r[None])
    p = scipy.linalg.solve_discrete_are(phi.T, h.T, q, np.diag(r))
    gain = p @ h.T @ np.linalg.inv(h @ p @ h.T + np.diag(r))
    assert steady.covariance[0] == pytest.approx(p, rel=1e-9, abs=1e-12)
    assert steady.gain[0] == pytest.approx(gain, rel=1e-9, abs=1e-12)
    closed = phi @ (np.eye(size) - steady.gain[0] @ h)
    assert np.max(np.abs(np.linalg.eigvals(closed))) < 1.0


def test_steady_state_filter_where_the_doubling_overflows():
    """An unstable mode no process noise drives beside a slow, weakly observed one that noise
    drives (a hover model whose only process noise is a slow gust): the doubling's dual
    iterate overflows before P converges; the filter then has scipy's stabilising P, and its
    complex-step direction matches central differences of scipy's solution."""
    def system(coupling):
        phi = np.array([[1.2, 0.0, 0.0], [coupling, 0.9999, 0.0], [0.0, 0.1, 0.7]])
        return phi, np.diag([1.0, 1e-3, 1.0]), np.diag([0.0, 1e-4, 1e-2]), np.array(
            [0.01, 0.02, 0.05])

    def dare(coupling):
        phi, h, q, r = system(coupling)
        return scipy.linalg.solve_discrete_are(phi.T, h.T, q, np.diag(r))

    phi, h, q, r = system(0.3)
    with np.errstate(over="ignore", invalid="ignore"):
        assert riccati._doubling(phi[None], h[None], q[None], r[None]) is None
    phi_step = phi.astype(complex)
    phi_step[1, 0] += 1j * COMPLEX_STEP
    steady = steady_state_filter(np.stack([phi, phi_step]), np.stack([h, h]),
                                 np.stack([q, q]), np.stack([r, r]))
    for covariance in steady.covariance:
        assert covariance.real == pytest.approx(dare(0.3), rel=1e-9, abs=1e-12)
    assert steady.covariance[1].imag / COMPLEX_STEP == pytest.approx(
        (dare(0.3 + 1e-6) - dare(0.3 - 1e-6)) / 2e-6, rel=1e-5, abs=1e-9)
    gain = dare(0.3) @ h.T @ np.linalg.inv(h @ dare(0.3) @ h.T + np.diag(r))
    assert steady.gain[0] == pytest.approx(gain, rel=1e-9, abs=1e-12)


def test_steady_state_filter_where_the_doubling_ends_indefinite(monkeypatch):
    """A doubling that converges to a P with a negative eigenvalue (lost precision) is not
    used: the filter has scipy's stabilising P, for a real system and for the real part of
    a complex-step direction, whose imaginary part still matches central differences."""
    phi = np.array([[0.95, 0.1], [0.0, 0.8]])
    h, q, r = np.eye(2), np.diag([0.02, 0.01]), np.array([0.05, 0.1])
    indefinite = np.diag([1.0, -0.5])
    monkeypatch.setattr(riccati, "_doubling", lambda *system: np.broadcast_to(
        indefinite, system[2].shape).astype(system[2].dtype))

    def dare(entry):
        moved = phi.copy()
        moved[0, 1] = entry
        return scipy.linalg.solve_discrete_are(moved.T, h.T, q, np.diag(r))

    steady = steady_state_filter(phi[None], h[None], q[None], r[None])
    assert steady.covariance[0] == pytest.approx(dare(0.1), rel=1e-9, abs=1e-12)
    stepped = phi.astype(complex)
    stepped[0, 1] += 1j * COMPLEX_STEP
    steady = steady_state_filter(stepped[None], h[None], q[None].astype(complex),
                                 r[None].astype(complex))
    assert steady.covariance[0].real == pytest.approx(dare(0.1), rel=1e-9, abs=1e-12)
    assert steady.covariance[0].imag / COMPLEX_STEP == pytest.approx(
        (dare(0.1 + 1e-6) - dare(0.1 - 1e-6)) / 2e-6, rel=1e-5, abs=1e-9)


def test_a_filter_without_a_steady_state_names_the_mode_no_output_sees():
    """An integrator (λ = 1) that no output reads beside a decaying state: no filter can
    correct it (Popov-Belevitch-Hautus); scipy's own solver refuses it too."""
    phi, output = np.diag([1.0, 0.5]), np.array([[0.0, 1.0]])
    with pytest.raises((np.linalg.LinAlgError, ValueError)):
        scipy.linalg.solve_discrete_are(phi.T, output.T, np.eye(2), np.eye(1))
    with pytest.raises(EstimationError, match=r"a mode that does not decay \(discrete "
                                              r"eigenvalue 1\) moves no output"):
        steady_state_filter(phi[None], output[None], np.eye(2)[None], np.ones((1, 1)))


def test_slow_gust_on_an_unstable_hover_model_is_fitted():
    """A 31 s gust on v, the small hover model's only process noise: the doubling overflows
    on some steps of the fit; the fit completes with finite Cramér-Rao bounds and its
    derivatives within 3 CR."""
    data = noisy_data({}, gusts={"v": (8.7, 31.0)})
    model = structure()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator(process_noise=(), gusts=("v",)).estimate(
            model, data, start={"G_v": 8.7, "Tg_v": 31.0})
    derivatives = slice(0, model.n_parameters)
    error = np.abs(result.values[derivatives] - model.as_vector(SMALL_TRUTH)) / (
        result.cramer_rao[derivatives])
    assert np.all(error < 3.0), dict(zip(model.parameter_names, error.round(2)))
    assert any(n.startswith("no output measures v: each such gust's size") for n in
               result.notes)


def test_a_gust_fitted_from_equation_error_starts_off_its_ridge():
    """A w gust on the small hover model (Z_w −0.32): started at the equation-error
    derivatives the fit follows the ridge where G_w grows as Z_w shrinks (Z_w near 0, G_w
    tens of ft/s); the default start, a first fit with a w acceleration in place of the gust,
    reaches the optimum of a fit started at the truth (the same cost), likelier than the
    ridge's, with Z_w and G_w within 3 CR of the truth's; the first fit's iterations are
    reported as its own stage."""
    data = noisy_data({}, gusts={"w": (5.0, 6.0)})
    model = structure()
    fit = estimator(process_noise=(), gusts=("w",))
    stages = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        default = estimator(process_noise=(), gusts=("w",),
                            callback=lambda stage, _: stages.append(stage)).estimate(model, data)
        ridge = fit.estimate(model, data, start=dict(zip(
            model.parameter_names, LinearModel(model).start_values(data))))
        at_truth = fit.estimate(model, data, start=SMALL_TRUTH)
    assert any(n.startswith("start values from a fit with accelerations in place of the "
                            "gusts on w") for n in default.notes)
    first = stages.index("full")
    assert first > 0 and set(stages[:first]) == {"gust-free start"} and set(
        stages[first:]) == {"full"}
    assert default.cost == pytest.approx(at_truth.cost, rel=1e-6)
    assert abs(ridge.value("Z_w")) < 0.05 and ridge.value("G_w") > 20.0
    assert ridge.cost > default.cost * (1 + 1e-3)
    for name, truth in (("Z_w", SMALL_TRUTH["Z_w"]), ("G_w", 5.0)):
        assert abs(default.value(name) - truth) < 3 * default[name].cramer_rao, name


def test_the_gust_free_first_fit_estimates_the_named_initial_gust_as_an_acceleration():
    """``initial_states = ("g_w",)`` on a w-gust fit from equation error: the first fit (an
    acceleration on w in place of the gust) estimates each record's initial ``d_w``, the
    gust fit its ``g_w``; both run."""
    data = noisy_data({}, gusts={"w": (5.0, 6.0)})
    stages = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator(process_noise=(), gusts=("w",), initial_states=("g_w",),
                           max_iterations=5, callback=lambda stage, _: stages.append(
                               stage)).estimate(structure(), data)
    assert "gust-free start" in stages
    assert any(n.startswith("start values from a fit with accelerations") for n in result.notes)
    initial = [n for n in result.parameter_names if n.startswith("x0_")]
    assert initial and all(n.endswith("_g_w") for n in initial)


def test_gusts_no_output_measures_are_named():
    """The hover outputs read no velocity; the fixed-wing ones read u and, as alpha, w."""
    hover = FilterErrorProblem(structure(), noisy_data({}), (), Settings(), (), ("u", "v"))
    assert unmeasured_gusts(hover) == ("u", "v")
    condition = FlightCondition(u0=50.0, w0=2.0, theta0=math.atan2(2.0, 50.0))
    wing = ModelStructure.populated(condition, "fixed-wing-longitudinal", "si")
    t = np.arange(0.0, 2.0, 0.02)
    channels = {name: np.zeros(t.size) for name in wing.controls + wing.outputs}
    record = rotorid.Maneuver("level", t, np.zeros((t.size, 0)), np.zeros((t.size, 0)),
                              input_names=(), output_names=(), units="si",
                              extra_channels=channels)
    problem = FilterErrorProblem(wing, rotorid.ManeuverSet([record]), (), Settings(), (),
                                 ("u", "w"))
    assert unmeasured_gusts(problem) == ()


def test_filtered_output_sensitivities_match_finite_differences():
    """Complex-step innovations and innovation covariance against central differences, for
    a derivative, a delay, a process-noise and a measurement-noise parameter."""
    model = structure(delays=("L_lat",))
    data = noisy_data(PROCESS)
    problem = FilterErrorProblem(model, data, tuple(PROCESS), Settings())
    values = np.concatenate([model.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.05}),
                             list(PROCESS.values()), VARIANCE])
    system, steady = problem.filter(values, directions=True)
    _assert_matches_central_differences(problem, system, steady, values,
                                        ("M_q", "tau_L_lat", "F_p", "R_q"), floor=1e-2)


def _assert_matches_central_differences(problem, system, steady, values, names, floor=0.0):
    """The innovations' exact sensitivities and those of B (the innovation covariance)
    against central differences of ``problem.innovations``, for the parameters ``names``
    (relative step 1e-6 of the value, at least of ``floor``)."""
    sens = np.concatenate([d for _, _, d, _ in innovation_blocks(system, steady, problem.records)])
    d_innovation = steady.innovation.imag / COMPLEX_STEP
    for name in names:
        k = problem.parameter_names.index(name)
        step = 1e-6 * max(abs(values[k]), floor)
        up, down = values.copy(), values.copy()
        up[k] += step
        down[k] -= step
        (nu_up, b_up), (nu_down, b_down) = problem.innovations(up), problem.innovations(down)
        expected = (nu_up - nu_down) / (2 * step)
        assert sens[..., k] == pytest.approx(expected, rel=1e-5, abs=1e-6 * np.abs(
            expected).max()), name
        assert d_innovation[k] == pytest.approx((b_up - b_down) / (2 * step), rel=1e-5,
                                                abs=1e-9), name


def test_disturbance_sensitivities_match_finite_differences():
    """The same check for the coloured disturbances' size D and correlation time T."""
    model = structure()
    disturbances = {"q": (2.0, 1.5), "p": (5.0, 0.8)}
    data = noisy_data({}, disturbances=disturbances)
    problem = FilterErrorProblem(model, data, ("w",), Settings(), tuple(disturbances))
    assert problem.parameter_names[model.n_parameters:model.n_parameters + 5] == (
        "F_w", "D_q", "D_p", "T_q", "T_p")
    values = np.concatenate([model.as_vector(SMALL_TRUTH), [0.01, 2.0, 5.0, 1.5, 0.8],
                             VARIANCE])
    system, steady = problem.filter(values, directions=True)
    assert system.size == 8 + 2
    _assert_matches_central_differences(problem, system, steady, values, ("L_p", "D_q", "T_p"))


#: Gusts of the linear tests: state → (standard deviation ft/s, correlation time s).
GUSTS = {"w": (3.0, 1.0), "v": (4.0, 1.0)}


def test_gust_sensitivities_match_finite_differences():
    """The same check for the gusts' size and correlation time, and for the derivatives
    through which a gust acts (X_u, L_v) and a delay, beside a roll disturbance."""
    model = structure(delays=("L_lat",))
    gusts = {"u": (6.0, 2.0), **GUSTS}
    data = noisy_data({}, disturbances={"p": (3.0, 0.8)}, gusts=gusts)
    problem = FilterErrorProblem(model, data, (), Settings(), ("p",), ("u", "w", "v"))
    assert problem.parameter_names[model.n_parameters:model.n_parameters + 8] == (
        "D_p", "G_u", "G_w", "G_v", "T_p", "Tg_u", "Tg_w", "Tg_v")
    values = np.concatenate([model.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.05}),
                             [3.0, 6.0, 3.0, 4.0, 0.8, 2.0, 1.0, 1.0], VARIANCE])
    system, steady = problem.filter(values, directions=True)
    assert system.size == 8 + 4                  # one roll disturbance, three gusts
    _assert_matches_central_differences(problem, system, steady, values,
                                        ("X_u", "L_v", "tau_L_lat", "G_v", "Tg_u"), floor=1e-2)


def test_recovers_derivatives_and_gusts_within_3_cr():
    """Gusts on w and v acting through the derivatives (correlation time 1 s, 3 and 4 ft/s)
    and a Gauss-Markov yaw disturbance: every derivative, gust size and correlation time,
    and R is recovered within 3 CR, while output error on the same data misses some
    derivative by more than 5 CR."""
    data = noisy_data({}, disturbances={"r": (2.0, 0.8)}, gusts=GUSTS)
    model = structure()
    result = estimator(process_noise=(), disturbances=("r",), gusts=tuple(GUSTS)).estimate(
        model, data)
    assert result.converged, result.stop_reason
    assert result.parameter_names[model.n_parameters:model.n_parameters + 6] == (
        "D_r", "G_w", "G_v", "T_r", "Tg_w", "Tg_v")
    truth = np.concatenate([model.as_vector(SMALL_TRUTH), [2.0, 3.0, 4.0, 0.8, 1.0, 1.0],
                            VARIANCE])
    error = np.abs(result.values - truth) / result.cramer_rao
    assert np.all(error < 3.0), dict(zip(result.parameter_names, error.round(2)))
    biased = rotorid.create("estimators", "output-error").estimate(model, data)
    assert np.max(np.abs(biased.values - model.as_vector(SMALL_TRUTH))
                  / biased.cramer_rao) > 5.0


def test_recovers_derivatives_and_coloured_disturbances_within_3_cr():
    """Gauss-Markov disturbance accelerations on the heave, pitch and roll equations
    (correlation times of 2, 1.5 and 0.8 s, far from white at 50 Hz; the heave one also in
    az): with disturbances on w, q and p and no white process noise, every derivative, D, T
    and R is recovered within 3 CR."""
    disturbances = {"w": (0.5, 2.0), "q": (2.0, 1.5), "p": (5.0, 0.8)}
    data = noisy_data({}, disturbances=disturbances)
    result = estimator(process_noise=(), disturbances=tuple(disturbances)).estimate(
        structure(), data)
    assert result.converged, result.stop_reason
    truth = np.concatenate([structure().as_vector(SMALL_TRUTH), [0.5, 2.0, 5.0, 2.0, 1.5, 0.8],
                            VARIANCE])
    error = np.abs(result.values - truth) / result.cramer_rao
    assert np.all(error < 3.0), dict(zip(result.parameter_names, error.round(2)))


def test_recovers_derivatives_process_and_measurement_noise_within_3_cr():
    data = noisy_data(PROCESS)
    result = estimator(process_noise=tuple(PROCESS)).estimate(structure(), data)
    assert result.converged, result.stop_reason
    truth = np.concatenate([structure().as_vector(SMALL_TRUTH), list(PROCESS.values()),
                            VARIANCE])
    error = np.abs(result.values - truth) / result.cramer_rao
    assert np.all(error < 3.0), dict(zip(result.parameter_names, error.round(2)))
    assert result.noise_covariance == pytest.approx(np.diag(VARIANCE), rel=0.1, abs=1e-12)


def test_longitudinal_template_recovers_derivatives_and_noise_within_3_cr():
    """A longitudinal structure (four states, two controls, four outputs) on records holding
    only its channels; the process noise enters its three equations by default."""
    truth = {n: SMALL_TRUTH[n] for n in ("X_u", "X_q", "X_long", "Z_w", "Z_coll", "M_u", "M_q",
                                         "M_long")}
    model = ModelStructure(HOVER, [Derivative(n) for n in truth], template="longitudinal")
    process = {"u": 0.005, "w": 0.03, "q": 0.05}
    variance = VARIANCE[:4]
    data = noisy_data(process, model=model, truth=truth, variance=variance)
    assert data.output_names == ("ax", "az", "q", "theta")
    result = estimator().estimate(model, data)
    assert result.converged, result.stop_reason
    assert result.parameter_names[len(truth):] == ("F_u", "F_w", "F_q", "R_ax", "R_az", "R_q",
                                                   "R_theta")
    expected = np.concatenate([model.as_vector(truth), list(process.values()), variance])
    error = np.abs(result.values - expected) / result.cramer_rao
    assert np.all(error < 3.0), dict(zip(result.parameter_names, error.round(2)))


def test_a_fixed_wing_template_with_its_own_signals_recovers_within_3_cr():
    """The fixed-wing longitudinal template (controls elevator and throttle; outputs u, alpha,
    q, theta, q_dot, ax, az, the last three with direct control terms) in SI units, on
    records holding its signals as named channels, simulated here with process noise on u, w
    and q: every derivative, F and R within 3 CR."""
    condition = FlightCondition(u0=50.0, w0=2.0, theta0=math.atan2(2.0, 50.0))
    truth = {"X_u": -0.04, "X_w": 0.08, "X_elevator": 0.5, "X_throttle": 2.0, "Z_u": -0.3,
             "Z_w": -2.0, "Z_q": -1.5, "Z_elevator": -6.0, "M_u": 0.01, "M_w": -0.08,
             "M_q": -2.5, "M_elevator": -12.0}
    model = ModelStructure.populated(condition, "fixed-wing-longitudinal", "si")
    model = model.without(*[n for n in model.names if n not in truth])
    process = {"u": 0.01, "w": 0.02, "q": 0.004}
    sigma = np.array(list(process.values()))
    variance = np.array([0.05, 0.002, 0.003, 0.002, 0.01, 0.1, 0.1]) ** 2
    t = np.arange(0.0, 10.0, 0.02)
    inputs = [np.column_stack([
        np.where((t > 1) & (t < 2), elevator, 0.0) - np.where((t > 2) & (t < 3), elevator, 0.0),
        np.where((t > 4) & (t < 7), throttle, 0.0)
        + np.where((t > 5) & (t < 6), 0.5 * elevator, 0.0)])
        for elevator, throttle in [(0.02, 0.0), (-0.02, 0.0), (0.0, 0.1), (0.015, -0.1)]]
    outputs = noisy_outputs(model, truth, inputs, 0.02, process, variance,
                            np.random.default_rng(4))
    records = [rotorid.Maneuver(f"record {k}", t, np.zeros((t.size, 0)), np.zeros((t.size, 0)),
                                input_names=(), output_names=(), units="si",
                                extra_channels={**dict(zip(model.controls, u.T)),
                                                **dict(zip(model.outputs, y.T))})
               for k, (u, y) in enumerate(zip(inputs, outputs))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator().estimate(model, rotorid.ManeuverSet(records))
    assert result.parameter_names[len(truth):] == (
        "F_u", "F_w", "F_q", "R_u", "R_alpha", "R_q", "R_theta", "R_q_dot", "R_ax", "R_az")
    expected = np.concatenate([model.as_vector(truth), sigma, variance])
    error = np.abs(result.values - expected) / result.cramer_rao
    assert result.converged and np.all(error < 3.0), dict(zip(result.parameter_names,
                                                              error.round(2)))


def test_a_continuous_gust_is_fitted_without_the_bias_of_holding_it_over_a_sample():
    """A light aeroplane (fixed-wing longitudinal, SI, 50 m/s) in a continuous vertical gust
    (σ 1 m/s, correlation time 2 s, simulated 20 steps per sample) at 50 Hz, 16 records of
    12 s: the gust's effect over each sample is its mean over the interval. Held over the
    sample instead, the same fit left Z_w and M_w 16 % low (2 CR on four records), which on
    these 16 records is 4 CR; here both, and the gust, are within 2 CR."""
    truth = {"X_u": -0.045, "X_w": 0.1, "X_throttle": 0.02, "Z_u": -0.39, "Z_w": -2.0,
             "Z_q": -1.2, "Z_elevator": -0.105, "M_u": 0.002, "M_w": -0.1, "M_q": -3.0,
             "M_elevator": -0.21}
    model = ModelStructure.populated(FlightCondition(u0=50.0), "fixed-wing-longitudinal",
                                     "si")
    model = model.without(*[n for n in model.names if n not in truth])
    variance = np.array([0.1, 0.001, 0.003, 0.002, 0.01, 0.05, 0.05]) ** 2
    t = np.arange(0.0, 12.0, 0.02)

    def pulse(start, length):
        return np.where((t >= start) & (t < start + length), 1.0, 0.0)

    multistep = 3 * pulse(1, 1.5) - 2 * pulse(2.5, 1) + pulse(3.5, 0.5) - pulse(4, 0.5)
    inputs = [np.column_stack([sign * multistep, 20.0 * pulse(6, 3) * (k % 2)])
              for k, sign in enumerate([1, -1] * 8)]
    outputs = noisy_outputs(model, truth, inputs, 0.02, {}, variance,
                            np.random.default_rng(11), gusts={"w": (1.0, 2.0)}, substeps=20)
    records = rotorid.ManeuverSet([
        rotorid.Maneuver(f"record {k}", t, u, y, units="si", input_names=model.controls,
                         output_names=model.outputs)
        for k, (u, y) in enumerate(zip(inputs, outputs))])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator(process_noise=(), gusts=("w",)).estimate(model, records)
    assert result.converged, result.stop_reason
    error = {name: (result.value(name) - value) / result.cramer_rao[result.index(name)]
             for name, value in {**truth, "G_w": 1.0, "Tg_w": 2.0}.items()}
    assert abs(error["Z_w"]) < 2.0 and abs(error["M_w"]) < 2.0, error
    assert result.cramer_rao[result.index("Z_w")] < 0.04 * 2.0       # 16 % would be > 4 CR
    assert all(abs(e) < 3.0 for e in error.values()), error


def test_output_error_is_biased_on_the_same_data():
    """The reason for the filter: output error misses some derivatives by many CR bounds."""
    data = noisy_data(PROCESS)
    model = structure()
    result = rotorid.create("estimators", "output-error").estimate(model, data)
    error = np.abs(result.values - model.as_vector(SMALL_TRUTH)) / result.cramer_rao
    assert error.max() > 5.0


def _still_air_fit_from_output_error(**options):
    """(structure, filter-error estimate) on still-air data, started from output error's
    derivatives; asserts that the derivatives stay within 1 CR of output error's."""
    data = noisy_data({})
    model = structure()
    output_error = rotorid.create("estimators", "output-error", noise="diagonal").estimate(
        model, data)
    start = dict(zip(model.parameter_names, output_error.values))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)   # noise sizes → 0: flat
        filtered = estimator(**options).estimate(model, data, start=start)
    k = model.n_parameters
    difference = np.abs(filtered.values[:k] - output_error.values) / output_error.cramer_rao
    assert np.all(difference < 1.0), dict(zip(model.parameter_names, difference.round(2)))
    return model, filtered


def test_in_still_air_filter_error_reduces_to_output_error():
    """Without process noise the output-error solution (F = 0) is where filter error ends:
    started from output error's derivatives (F and R from their default starts), it stays
    within 1 CR of them and the process noise it finds is small."""
    model, filtered = _still_air_fit_from_output_error()
    f = filtered.values[model.n_parameters:model.n_parameters + 6]
    assert np.all(f < 0.2 * np.array([0.03, 0.03, 0.05, 0.02, 0.1, 0.05]))


def test_with_gusts_in_still_air_filter_error_reduces_to_output_error():
    """The gust and disturbance states find nothing to follow in data without model error or
    process noise: started from output error's derivatives, the derivatives stay within 1 CR
    of output error's and the yaw disturbance and the v gust go to their floors."""
    _, filtered = _still_air_fit_from_output_error(process_noise=(), disturbances=("r",),
                                                   gusts=("w", "v"))
    assert filtered.value("D_r") < 0.01 and filtered.value("G_v") < 0.01


def test_a_disturbance_no_output_measures_needs_a_start_value_and_takes_it():
    """A flap tilt has no output, so its disturbance has no default start: refused without
    one, naming the parameter and the setting, and fitted from a given one."""
    flap = {"Bc_beta1c": -14.0, "Bs_beta1s": -15.0, "M_beta1c": -48.0, "L_beta1s": -180.0,
            "Bc_long": 1.5, "Bs_lat": -1.0}
    model = ModelStructure(HOVER, [Derivative(n, initial=v) for n, v in flap.items()],
                           template="hybrid")
    data = noisy_data({})
    with pytest.raises(EstimationError, match="D_beta1c has no default start; give its start "
                                              "value or leave beta1c out of disturbances"):
        estimator(process_noise=(), disturbances=("beta1c",)).estimate(model, data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator(process_noise=(), disturbances=("beta1c",), max_iterations=1
                           ).estimate(model, data, start={"D_beta1c": 1.0})
    assert result.start[result.index("D_beta1c")] == 1.0


def test_start_values_and_options_are_checked():
    data = noisy_data(PROCESS)
    with pytest.raises(EstimationError, match="process_noise"):
        estimator(process_noise=("u", "u"))
    with pytest.raises(EstimationError, match="process_noise names x, not states"):
        estimator(process_noise=("u", "x")).estimate(structure(), data)
    with pytest.raises(EstimationError, match="unknown parameters"):
        estimator().estimate(structure(), data, start={"F_theta": 1.0})
    with pytest.raises(EstimationError, match="a linear model structure .* or a nonlinear "
                                              "model of one's own"):
        estimator().estimate(object(), data)
    with pytest.raises(EstimationError, match="no finite likelihood at the start values: the "
                                              "Kalman filter does not exist .*; give other "
                                              "start"):
        estimator(process_noise=tuple(PROCESS)).estimate(structure(), data,
                                                         start={"M_q": 1e6})
    with pytest.raises(EstimationError, match="gusts names theta, which known terms"):
        estimator(gusts=("theta",)).estimate(structure(), data)
    with pytest.raises(EstimationError, match="gusts names v, which the delayed derivatives "
                                              "L_v read; .* remove their delays"):
        estimator(gusts=("v",)).estimate(structure(delays=("L_v",)), data)
    coarse = noisy_data(PROCESS, dt=0.04)[0]
    mixed = rotorid.ManeuverSet([data[1], coarse])
    with pytest.raises(DataError, match="one sample time"):
        estimator().estimate(structure(), mixed)


def test_a_disturbance_read_by_an_accelerometer_needs_no_seen_state():
    """Without a derivative of w (as after a reduction removed them) no output sees the state
    w: white process noise on it changes no innovation and is refused, but a disturbance of
    the w equation is an acceleration az reads, and it is fitted."""
    model = ModelStructure(HOVER, [Derivative(n) for n in SMALL_TRUTH if n != "Z_w"])
    data = noisy_data({}, disturbances={"w": (1.0, 1.0)})
    with pytest.raises(EstimationError, match="process_noise names w, which no output of the "
                                              "structure sees"):
        estimator(process_noise=("w",)).estimate(model, data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator(process_noise=(), disturbances=("w",), max_iterations=30
                           ).estimate(model, data, start={"D_w": 0.5, "T_w": 0.5})
    assert result.value("D_w") == pytest.approx(1.0, rel=0.5)
    assert result.value("Z_coll") == pytest.approx(SMALL_TRUTH["Z_coll"], rel=0.1)


#: A light aeroplane's lateral-directional model as a declared structure (SI, β as a state).
AEROPLANE_LATERAL = """units = "si"
[condition]
u0_mps = 40.0
[structure]
name = "aeroplane-lateral"
states = { beta = "angle", p = "rate", phi = "angle", r = "rate" }
controls = { aileron = "deg", rudder = "deg" }
outputs = { beta = "angle", p = "rate", phi = "angle", r = "rate", ay = "acceleration" }
equations = { Y = "beta", L = "p", N = "r" }
populate = "none"
[structure.known]
beta = { phi = 0.2451663, r = -1.0 }
phi = { p = 1.0 }
[structure.output_equations]
ay = { "d(beta)" = 40.0, r = 40.0, phi = -9.80665 }
[derivatives]
Y_beta = { sign = "negative" }
Y_rudder = {}
L_beta = {}
L_p = { sign = "negative" }
L_r = {}
L_aileron = {}
L_rudder = {}
N_beta = { sign = "positive" }
N_p = {}
N_r = { sign = "negative" }
N_aileron = {}
N_rudder = {}
"""
AEROPLANE_TRUTH = {"Y_beta": -0.25, "Y_rudder": 0.001, "L_beta": -8.0, "L_p": -5.0,
                   "L_r": 1.2, "L_aileron": 0.26, "L_rudder": 0.03, "N_beta": 4.0,
                   "N_p": -0.3, "N_r": -1.0, "N_aileron": -0.005, "N_rudder": -0.08}


def test_a_start_from_output_error_avoids_the_poorer_optimum_of_a_free_process_noise():
    """Noise-only aeroplane records: from equation error, the process noise on β follows the
    data into an optimum with Y_β and N_β of the wrong sign, and the estimate says how to avoid
    it; started from an output-error fit (start='output-error') filter error reduces to output
    error at a cost hundreds of times lower."""
    import tomllib

    from rotorid.model.modelfile import parse_model
    from rotorid_filter_error.estimator import POORER_OPTIMUM_ADVICE

    structure = parse_model(tomllib.loads(AEROPLANE_LATERAL), "aeroplane")
    time = np.arange(751) * 0.02

    def pulses(*spec):
        return sum(amplitude * ((time >= start) & (time < end)) for start, end, amplitude in spec)

    inputs = {"ail_3211": (pulses((1, 1.9, 5), (1.9, 2.5, -5), (2.5, 2.8, 5), (2.8, 3.1, -5)),
                           0 * time),
              "rud_doublet": (0 * time, pulses((1, 2, 6), (2, 3, -6))),
              "both": (pulses((1, 1.8, -4), (1.8, 2.6, 4)), pulses((5, 6.2, -5), (6.2, 7.4, 5)))}
    clean = rotorid.ManeuverSet([
        rotorid.Maneuver(name, time, np.column_stack(u), np.zeros((time.size, 5)), units="si",
                         input_names=structure.controls, output_names=structure.outputs)
        for name, u in inputs.items()])
    rng = np.random.default_rng(42)
    noise = np.array([math.radians(0.2), math.radians(0.3), math.radians(0.2),
                      math.radians(0.3), 0.05])
    data = rotorid.ManeuverSet([
        m.with_outputs(y + rng.normal(size=y.shape) * noise)
        for m, y in zip(clean, rotorid.simulate(structure, AEROPLANE_TRUTH, clean))])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        plain = rotorid.create("estimators", "filter-error").estimate(structure, data)
        started = rotorid.create("estimators", "filter-error",
                                 start="output-error").estimate(structure, data)
    output_error = rotorid.create("estimators", "output-error").estimate(structure, data)
    assert {"Y_beta", "N_beta"} <= set(plain.sign_violations)
    assert plain.notes[-1] == POORER_OPTIMUM_ADVICE
    assert started.notes[0].startswith("start values from an output-error fit (")
    assert started.converged and not started.sign_violations
    assert POORER_OPTIMUM_ADVICE not in started.notes
    assert started.cost < 1e-2 * plain.cost            # 959 times lower
    n = structure.n_parameters
    assert np.all(np.abs(started.values[:n] - output_error.values[:n])
                  <= output_error.cramer_rao[:n])


def test_a_disturbance_the_data_do_not_hold_ends_at_its_floor_and_is_named():
    """A yaw disturbance fitted to records without one: its size ends at its floor, and the
    notes say so and to leave r out of the disturbances."""
    estimate = estimator(process_noise=(), disturbances=("r",)).estimate(structure(),
                                                                         noisy_data({}))
    assert "D_r" in estimate.at_bound
    [note] = [n for n in estimate.notes if n.startswith("D_r ended at the floor of its size")]
    assert note.endswith("leave r out of the disturbances or gusts and refit")


def test_a_correlation_time_limit_holds_a_slow_disturbance_and_is_named():
    """A 20 s heave disturbance over the 12 s doublet records: free, its correlation time
    goes well beyond 2 s; with ``longest_correlation = {"T_w": 2}`` it starts (from 5 s) and
    ends at 2 s, flagged at its bound and named in the notes."""
    data = noisy_data({}, disturbances={"w": (0.5, 20.0)})
    options = dict(process_noise=(), disturbances=("w",), max_iterations=30)
    start = {"D_w": 0.5, "T_w": 5.0}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        free = estimator(**options).estimate(structure(), data, start=start)
        held = estimator(longest_correlation={"T_w": 2}, **options).estimate(
            structure(), data, start=start)
    assert free.value("T_w") > 4.0
    assert held["T_w"].start == 2.0 and held.value("T_w") == pytest.approx(2.0)
    assert "T_w" in held.at_bound and "T_w" not in free.at_bound
    assert any(n.startswith("T_w (2 s) ended at the longest correlation time allowed")
               for n in held.notes)


def test_correlation_time_limits_are_checked():
    """A limit is a positive time on a correlation time of the noise model, above the
    shortest the fit allows."""
    data = noisy_data({})
    with pytest.raises(EstimationError, match="longest_correlation names 'D_w', which is no "
                                              "correlation time"):
        estimator(longest_correlation={"D_w": 3.0})
    with pytest.raises(EstimationError, match="longest_correlation gives T_w the limit -1; a "
                                              "limit is a positive time in s"):
        estimator(longest_correlation={"T_w": -1})
    with pytest.raises(EstimationError, match="longest_correlation maps correlation times"):
        estimator(longest_correlation=3.0)
    with pytest.raises(EstimationError, match="longest_correlation names T_q, not a "
                                              "correlation time of this noise model; its "
                                              "correlation times are T_w, Tg_v"):
        estimator(disturbances=("w",), gusts=("v",),
                  longest_correlation={"T_q": 3.0}).check_structure(structure())
    with pytest.raises(EstimationError, match="it has no disturbances or gusts"):
        estimator(longest_correlation={"T_w": 3.0}).check_structure(structure())
    with pytest.raises(EstimationError, match=r"holds T_w \(0.01 s, shortest 0.02 s\) at or "
                                              r"below the shortest"):
        estimator(process_noise=(), disturbances=("w",),
                  longest_correlation={"T_w": 0.01}).estimate(structure(), data)


def test_a_gust_limit_also_holds_the_gust_free_first_fit():
    """From equation error a w gust's fit starts with a w acceleration in its place, whose
    ``T_w`` takes the gust's limit ``Tg_w`` (the first fit's noise model has no ``Tg_w``);
    the gust fit keeps ``Tg_w`` within it."""
    data = noisy_data({}, gusts={"w": (5.0, 6.0)})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator(process_noise=(), gusts=("w",), longest_correlation={"Tg_w": 0.5},
                           max_iterations=5).estimate(structure(), data)
    assert any(n.startswith("start values from a fit with accelerations") for n in result.notes)
    assert result.value("Tg_w") <= 0.5


def test_a_correlation_time_ending_at_its_shortest_is_named():
    """A heave disturbance of 1 ms correlation (white at 50 Hz): its correlation time ends at
    one sample, and the notes say the disturbance became noise and to refit from the expected
    size and compare the costs."""
    data = noisy_data({}, disturbances={"w": (1.0, 0.001)})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = estimator(process_noise=(), disturbances=("w",), max_iterations=30).estimate(
            structure(), data)
    assert result.value("T_w") == pytest.approx(0.02) and "T_w" in result.at_bound
    [note] = [n for n in result.notes if n.startswith("T_w (0.02 s) ended at the shortest")]
    assert note.endswith("compare the costs")
