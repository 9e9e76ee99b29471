"""The simulation engine against independent references.

* no delays: the exact zero-order-hold solution built here from one matrix exponential;
* the interval integrals of the discretisation: the exponential of Van Loan's block matrix;
* delays: a fine-step trapezoidal integration of the delay differential equation
  (:mod:`delay_reference`), on the rates and attitudes and on the accelerometers, whose
  delayed state and control terms are read from that solution;
* sensitivities: central finite differences of the simulator;
* frequency response: the DFT of a simulated pulse response at a fine sample time.
"""

import numpy as np
import pytest
import scipy.linalg
from delay_reference import fine_states, sampled_outputs
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.errors import DataError, SimulationDivergedError, StructureError
from rotorid.simulation.discretisation import _integrals, discrete_maps
from rotorid.simulation.simulator import Simulator, sensitivities, simulate
from rotorid.simulation.transfer import frequency_response, pair_response

#: The six-dof states' force and moment rows: u w q v p r.
EQUATION_ROWS = (0, 1, 2, 4, 5, 7)

DAMPING = {"X_u": -0.5, "Z_w": -0.8, "M_q": -2.0, "L_p": -4.0, "N_r": -1.0, "Y_v": -0.3,
           "L_lat": 1.0, "M_long": 0.5, "N_ped": 0.8, "Z_coll": -1.2}


def stable_values(structure, seed=1, delays=None):
    rng = np.random.default_rng(seed)
    names = structure.parameter_names
    values = structure.initial_values()
    free = [i for i, n in enumerate(names) if not n.startswith("tau_")]
    values[free] = rng.normal(size=len(free)) * 0.05
    for name, value in {**DAMPING, **(delays or {})}.items():
        if name in names:
            values[names.index(name)] = value
    return values


def multistep_inputs(n, dt, seed, hold):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    knots = np.arange(0.0, t[-1] + 0.5, 0.5)
    levels = rng.normal(size=(knots.size, 4))
    levels[0] = 0.0  # records start in trim (the FOH history ramps from trim at t = −dt)
    if hold == "zoh":
        return t, levels[np.minimum((t / 0.5 + 1e-9).astype(int), knots.size - 1)]
    return t, np.column_stack([np.interp(t, knots, levels[:, i]) for i in range(4)])


def one_maneuver(t, u, name="m"):
    return Maneuver(name, t, u, np.zeros((t.size, 8)))


CONDITION = FlightCondition.from_airspeed(60.0, theta0_deg=3.0, phi0_deg=-2.0)


@pytest.mark.parametrize("units", ["flight-test", "si"])
def test_no_delay_matches_exact_zoh_solution(units):
    structure = ModelStructure.six_dof(CONDITION, units=units)
    values = stable_values(structure)
    t, u = multistep_inputs(400, 0.02, 3, "zoh")
    m = Maneuver("m", t, u, np.zeros((t.size, 8)), units=units)
    y = simulate(structure, values, ManeuverSet([m]))[0]

    a, b, c, d = structure.matrices(values)
    block = np.zeros((12, 12))
    block[:8, :8], block[:8, 8:] = a, b
    ex = scipy.linalg.expm(block * 0.02)
    x, expected = np.zeros(8), []
    for k in range(t.size):
        expected.append(c @ x + d @ u[k])
        x = ex[:8, :8] @ x + ex[:8, 8:] @ u[k]
    expected = np.array(expected)
    assert np.max(np.abs(y - expected)) <= 1e-9 * np.max(np.abs(expected))


@pytest.mark.parametrize("length", [0.004, 0.02, 0.5])
def test_interval_integrals_match_the_exponential_of_a_block_matrix(length):
    """e^{As}, Γ(s) = ∫₀ˢ e^{Aσ} dσ and K(s) = ∫₀ˢ e^{Aσ}(s − σ) dσ are the blocks of
    exp([[A, I, 0], [0, 0, I], [0, 0, 0]]·s) (Van Loan); ‖A‖ ≈ 30 needs doubling steps for the
    longer intervals."""
    a = np.random.default_rng(4).normal(size=(8, 8)) * 4.0
    block = np.zeros((24, 24))
    block[:8, :8], block[:8, 8:16], block[8:16, 16:] = a, np.eye(8), np.eye(8)
    exact = scipy.linalg.expm(block * length)
    columns = list(EQUATION_ROWS)
    phi, gam, kin = _integrals(a[None].astype(complex), np.array([[length]], dtype=complex),
                               EQUATION_ROWS)
    for ours, reference in ((phi, exact[:8, :8]), (gam, exact[:8, 8:16][:, columns]),
                            (kin, exact[:8, 16:][:, columns])):
        np.testing.assert_allclose(ours[0, 0].real, reference, rtol=1e-10,
                                   atol=1e-12 * np.abs(reference).max())


def test_held_equation_forcing_matches_the_exponential_of_a_block_matrix():
    """Pe, the map of an acceleration held over the sample on each equation row, is the
    input block of exp([[A, E], [0, 0]]·dt); its parameter derivatives match central
    differences."""
    structure = ModelStructure.six_dof(CONDITION)
    values = stable_values(structure)
    maps = discrete_maps(structure, values, 0.02, with_derivatives=True)
    a = structure.matrices(values)[0]
    block = np.zeros((14, 14))
    block[:8, :8] = a
    block[EQUATION_ROWS, 8 + np.arange(6)] = 1.0
    exact = scipy.linalg.expm(block * 0.02)[:8, 8:]
    np.testing.assert_allclose(maps.Pe, exact, rtol=1e-10, atol=1e-14)
    k, h = structure.parameter_names.index("M_q"), 1e-6
    shifted = [discrete_maps(structure, values + sign * h * np.eye(values.size)[k], 0.02).Pe
               for sign in (1, -1)]
    np.testing.assert_allclose(maps.dPe[k], (shifted[0] - shifted[1]) / (2 * h), atol=1e-9)


def relative_rms_errors(delays, dt, hold, seed):
    """Relative RMS error per output channel of the simulation with ``delays`` (tau_ name →
    s) against the fine delay-equation reference."""
    structure = ModelStructure.six_dof(CONDITION).with_delays([name[4:] for name in delays])
    values = stable_values(structure, delays=delays)
    t, u = multistep_inputs(int(4.0 / dt), dt, seed, hold)
    y = simulate(structure, values, ManeuverSet([one_maneuver(t, u)], hold=hold))[0]
    ref = sampled_outputs(structure, values, t, u, dt, hold, fine=0.0005)
    rms = np.sqrt(np.mean((y - ref) ** 2, axis=0) / np.mean(ref**2, axis=0))
    return dict(zip(structure.outputs, rms))


@pytest.mark.parametrize("dt", [0.02, 0.01])
@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_fractional_delays_match_fine_dde_solution(dt, hold):
    delays = {"tau_L_p": 0.037, "tau_L_lat": 0.037, "tau_M_long": 0.061, "tau_M_q": 0.013,
              "tau_L_q": 0.005}
    errors = relative_rms_errors(delays, dt, hold, seed=5)
    for channel in ("q", "theta", "p", "phi", "r"):
        assert errors[channel] < 1e-3, (channel, errors[channel])


@pytest.mark.parametrize("dt", [0.02, 0.01])
@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_delayed_specific_force_terms_match_fine_dde_solution(dt, hold):
    """Every output, the accelerometers included, with delayed control terms (a direct term
    of the output: ZOH reads the held sample before t_n − τ, FOH interpolates) and delayed
    state terms (interpolated history), fractions of the sample time far from one half so
    that swapped interpolation weights show."""
    delays = {"tau_X_long": 0.047, "tau_Z_coll": 0.0235, "tau_Y_ped": 0.0035,
              "tau_X_q": 0.0165, "tau_Z_w": 0.004, "tau_Y_p": 0.0335, "tau_L_lat": 0.037}
    errors = relative_rms_errors(delays, dt, hold, seed=6)
    for channel, error in errors.items():
        assert error < 1e-3, (channel, error)


def test_treating_held_inputs_as_interpolated_would_be_wrong():
    """The hold matters: a ZOH record simulated as FOH departs from the exact solution."""
    structure = ModelStructure.six_dof(CONDITION).with_delays(["L_lat"])
    values = stable_values(structure, delays={"tau_L_lat": 0.037})
    t, u = multistep_inputs(200, 0.02, 7, "zoh")
    zoh = simulate(structure, values, ManeuverSet([one_maneuver(t, u)], hold="zoh"))[0]
    foh = simulate(structure, values, ManeuverSet([one_maneuver(t, u)], hold="foh"))[0]
    p = structure.outputs.index("p")
    assert np.sqrt(np.mean((zoh[:, p] - foh[:, p]) ** 2)) > 1e-3 * np.sqrt(np.mean(zoh[:, p] ** 2))


@pytest.mark.parametrize("hold", ["zoh", "foh"])
def test_sensitivities_match_central_differences(hold):
    delays = {"tau_L_p": 0.037, "tau_L_lat": 0.061, "tau_M_q": 0.013, "tau_X_long": 0.005}
    structure = ModelStructure.six_dof(CONDITION).with_delays([n[4:] for n in delays])
    values = stable_values(structure, delays=delays)
    t, u = multistep_inputs(150, 0.02, 9, hold)
    t2, u2 = multistep_inputs(90, 0.025, 10, hold)
    maneuvers = ManeuverSet([one_maneuver(t, u, "a"), one_maneuver(t2, u2, "b")], hold=hold)
    _, sens = sensitivities(structure, values, maneuvers)
    simulator = Simulator(structure, maneuvers)
    for k, name in enumerate(structure.parameter_names):
        h = 1e-7 if name.startswith("tau_") else 1e-6
        up, down = values.copy(), values.copy()
        up[k] += h
        down[k] -= h
        for i, (yp, ym) in enumerate(zip(simulator.outputs(up), simulator.outputs(down))):
            fd = (yp - ym) / (2 * h)
            scale = np.max(np.abs(fd))
            if scale == 0:
                assert np.max(np.abs(sens[i][:, k, :])) == 0
                continue
            assert np.max(np.abs(sens[i][:, k, :] - fd)) <= 1e-5 * scale, (name, i)


def test_batched_maneuvers_equal_single_runs_and_initial_state():
    structure = ModelStructure.six_dof(CONDITION).with_delays(["M_long"])
    values = stable_values(structure, delays={"tau_M_long": 0.05})
    t, u = multistep_inputs(120, 0.02, 11, "zoh")
    short = one_maneuver(t[:60], u[:60] * 2, "short")
    x0 = np.linspace(-1, 1, 8)
    long = Maneuver("long", t, u, np.zeros((t.size, 8)), initial_state=x0)
    together = simulate(structure, values, ManeuverSet([long, short]))
    alone = [simulate(structure, values, ManeuverSet([m]))[0] for m in (long, short)]
    for batched, single in zip(together, alone):
        assert np.allclose(batched, single, rtol=1e-12, atol=1e-12 * np.abs(single).max())
    _, _, c, _ = structure.matrices(values)
    assert np.allclose(together[0][0], c @ x0 + 0.0)


def test_frequency_response_matches_pulse_response_dft():
    """Rates and attitudes, and the accelerometers with a delayed control (Z_coll) and a
    delayed state (X_q) in their direct terms; delays off the sample grid."""
    structure = ModelStructure.six_dof(CONDITION).with_delays(
        ["L_lat", "M_long", "L_p", "Z_coll", "X_q"])
    values = structure.as_vector({**DAMPING, "M_u": 0.2, "M_w": -0.05, "L_v": -0.2, "X_q": 0.4,
                                  "tau_L_lat": 0.06, "tau_M_long": 0.04, "tau_L_p": 0.02,
                                  "tau_Z_coll": 0.031, "tau_X_q": 0.023})
    slowest = np.linalg.eigvals(structure.matrices(values)[0]).real.max()
    assert slowest < -0.1, "the pulse response must decay within the record"
    dt, n = 0.002, 40000
    t = np.arange(n) * dt
    omega = np.array([0.5, 1.0, 2.0, 5.0, 10.0])
    analytic = frequency_response(structure, values, omega)
    pairs = {0: ("ax", "q", "p", "phi"), 1: ("p", "phi"), 2: ("az",)}
    for j, outputs in pairs.items():
        u = np.zeros((n, 4))
        u[0, j] = 1.0
        y = simulate(structure, values, ManeuverSet([one_maneuver(t, u)]))[0]
        # DFT of the response to a pulse of width dt, corrected for the pulse's own spectrum.
        phase = np.exp(-1j * np.outer(omega, t))
        pulse = (1 - np.exp(-1j * omega * dt)) / (1j * omega)
        estimate = (phase @ y) * dt / pulse[:, None]
        for output in outputs:
            k = structure.outputs.index(output)
            ref = analytic[:, k, j]
            assert np.all(np.abs(estimate[:, k] - ref) <= 2e-3 * np.abs(ref) + 1e-9), (j, k)
    single = pair_response(structure, values, omega, "p", "lat")
    assert np.allclose(single, analytic[:, 5, 1])


def test_divergence_is_reported_not_crashed():
    structure = ModelStructure.six_dof(CONDITION)
    values = stable_values(structure)
    values[structure.parameter_names.index("L_p")] = 50.0   # violently unstable roll
    t, u = multistep_inputs(1500, 0.02, 3, "zoh")
    with pytest.raises(SimulationDivergedError, match="diverged"):
        simulate(structure, values, ManeuverSet([one_maneuver(t, u)]))


def test_bad_inputs_are_rejected_clearly():
    structure = ModelStructure.six_dof(CONDITION)
    t, u = multistep_inputs(50, 0.02, 3, "zoh")
    maneuvers = ManeuverSet([one_maneuver(t, u)])
    with pytest.raises(StructureError, match="60 free parameters"):
        simulate(structure, np.zeros(3), maneuvers)
    with pytest.raises(StructureError, match="non-finite"):
        simulate(structure, np.full(60, np.nan), maneuvers)
    with pytest.raises(DataError, match="initial_states"):
        simulate(structure, None, maneuvers, initial_states=np.zeros((2, 8)))
    si = ManeuverSet([Maneuver("m", t, u, np.zeros((t.size, 8)), units="si")])
    with pytest.raises(DataError, match="units"):
        simulate(structure, None, si)
    with pytest.raises(StructureError, match="unknown output"):
        pair_response(structure, None, [1.0], "x", "lat")
