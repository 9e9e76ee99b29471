"""Time of one outputs-plus-sensitivities evaluation on the paper-size problem.

The problem: 16 maneuvers of 15 s at 50 Hz (3211/2311 multisteps on each axis with a doublet on
a second axis, zero-order hold), 8 outputs, the fully populated 60-parameter six-DoF structure
at 70 kt, once without delays and once with the paper's 8 delays (``PAPER_DELAYED``, 68
parameters).

For each case, in the same run:

* rotorid: ``Simulator.outputs_and_sensitivities`` (outputs and ∂y/∂θ for every parameter);
* reference without delays: ``scipy.signal.dlsim`` of the ZOH-discretised system
  (``scipy.signal.cont2discrete``) per maneuver, with central finite differences per parameter
  (2·60 + 1 discretisations, 16 simulations each);
* reference with delays: scipy has no delayed simulation; the plain practice (MATLAB's
  ``pade``, then ``lsim``) replaces each delay by its second-order Padé approximant, so the
  reference is ``scipy.signal.dlsim`` of the ZOH-discretised Padé-augmented system (8 + 2·8
  states) per maneuver, with central finite differences per parameter. Its difference from
  rotorid's exact sensitivities includes the Padé approximation error.
* like for like, for both cases: central finite differences over rotorid's own outputs-only
  path (2·P + 1 batched ``Simulator.outputs`` calls): what the sensitivity recursion saves
  over re-simulating.

Every figure is the median wall time of several repeats (the machine may be shared; the
fastest repeat is printed too, and the load average, since other work on the cores slows every
figure). BLAS runs on one thread unless ``--threads`` says otherwise (the simulator itself
limits BLAS to one thread while it runs). Targets (2 cores): ≤ 30 ms without delays,
≤ 60 ms with the 8 delays, ≥ 50× faster than the reference. The largest difference between
rotorid's sensitivities and the reference's finite differences is printed as a sanity check.

    .venv/bin/python benchmarks/bench_simulation.py [--repeats 9] [--reference-repeats 3]
"""

from __future__ import annotations

import argparse
import os
import sys


def _threads_from_argv(default: str = "1") -> str:
    """The --threads value, read before numpy is imported (BLAS fixes its pool at load)."""
    for k, arg in enumerate(sys.argv):
        if arg == "--threads" and k + 1 < len(sys.argv):
            return sys.argv[k + 1]
        if arg.startswith("--threads="):
            return arg.split("=", 1)[1]
    return default


for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = _threads_from_argv()

import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import scipy.signal  # noqa: E402
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure  # noqa: E402
from rotorid.model.structure import PAPER_DELAYED  # noqa: E402
from rotorid.simulation.simulator import Simulator  # noqa: E402
from rotorid_signals.signals import Multistep  # noqa: E402

DT = 0.02
DURATION = 15.0
N_MANEUVERS = 16
TARGET_MS = {False: 30.0, True: 60.0}
TARGET_RATIO = 50.0
#: Dominant damping and control terms of a stable 70 kt model (flight-test units).
DAMPING = {"X_u": -0.03, "Z_w": -0.8, "M_q": -1.6, "L_p": -6.0, "N_r": -0.8, "Y_v": -0.15,
           "M_long": 0.6, "L_lat": 1.8, "Z_coll": -1.0, "N_ped": 0.9, "N_v": 0.02}
#: The paper's delays τ1 … τ8 in s, fractions of the 20 ms sample time included.
DELAYS = {"L_p": 0.013, "L_q": 0.047, "L_long": 0.061, "L_lat": 0.037, "M_p": 0.024,
          "M_q": 0.008, "M_long": 0.052, "M_lat": 0.071}


def problem(delayed: bool) -> tuple[ModelStructure, np.ndarray, ManeuverSet]:
    """Structure, parameter vector and maneuvers of the paper-size problem."""
    condition = FlightCondition.from_airspeed(70.0, theta0_deg=1.2, phi0_deg=-1.5)
    structure = ModelStructure.six_dof(condition)
    if delayed:
        structure = structure.with_delays(PAPER_DELAYED)
    rng = np.random.default_rng(2024)
    names = structure.parameter_names
    values = np.array([0.0 if n.startswith("tau_") else rng.normal(scale=0.02) for n in names])
    for name, value in DAMPING.items():
        values[names.index(name)] = value
    if delayed:
        for name, tau in DELAYS.items():
            values[names.index(f"tau_{name}")] = tau
    time_axis = np.arange(int(round(DURATION / DT)) + 1) * DT
    maneuvers = []
    for i in range(N_MANEUVERS):
        axis, second = i % 4, (i + 1 + i // 4) % 4
        inputs = np.zeros((time_axis.size, 4))
        kind = "3211" if i % 8 < 4 else "2311"
        sign = 1.0 if i % 2 == 0 else -1.0
        inputs[:, axis] = Multistep(kind, 3.0 * sign, 0.4 + 0.1 * (i // 4), start=1.0,
                                    sample_time=DT)(time_axis)
        inputs[:, second] += Multistep("doublet", 1.0, 0.6, start=7.0, sample_time=DT)(time_axis)
        maneuvers.append(Maneuver(f"m{i:02d}", time_axis, inputs,
                                  np.zeros((time_axis.size, 8))))
    return structure, values, ManeuverSet(maneuvers)


def timings(function, repeats: int) -> tuple[float, float, object]:
    """Median and minimum wall time in s over ``repeats`` calls, and the last result."""
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times), result


def pade_system(structure, values) -> tuple[np.ndarray, ...]:
    """A, B, C, D with every delayed term through a second-order Padé approximant of e^(−sτ)."""
    table = structure.terms(values)
    n_lag = 2 * int(np.count_nonzero(table.delay > 0))
    a = np.zeros((8 + n_lag, 8 + n_lag))
    b = np.zeros((8 + n_lag, 4))
    c = np.zeros((8, 8 + n_lag))
    d = np.zeros((8, 4))
    a[:8, :8] = structure.known_state_matrix()
    c[:, :8] = structure.known_output_matrix()
    lag = 8
    for eq, src, gain, tau, out, weight in zip(table.equation, table.source, table.gain,
                                               table.delay, table.output, table.weight):
        direct, column = (a, src) if src < 8 else (b, src - 8)
        direct_out = c if src < 8 else d
        if tau <= 0:
            direct[eq, column] += gain
            if out >= 0:
                direct_out[out, column] += weight * gain
            continue
        ap, bp, cp, dp = scipy.signal.tf2ss([tau**2 / 12, -tau / 2, 1.0],
                                            [tau**2 / 12, tau / 2, 1.0])
        block = slice(lag, lag + 2)
        a[block, block] = ap
        (a if src < 8 else b)[block, column] = bp[:, 0]
        direct[eq, column] += gain * dp[0, 0]
        a[eq, block] += gain * cp[0]
        if out >= 0:
            direct_out[out, column] += weight * gain * dp[0, 0]
            c[out, block] += weight * gain * cp[0]
        lag += 2
    return a, b, c, d


def _dlsim_outputs(structure, values, maneuvers) -> list[np.ndarray]:
    system = scipy.signal.cont2discrete(pade_system(structure, values), DT, method="zoh")
    return [scipy.signal.dlsim(system[:4] + (DT,), m.inputs, m.time)[1] for m in maneuvers]


def central_differences(outputs, values: np.ndarray, steps: np.ndarray):
    """Outputs and (N_i, P, 8) central-difference sensitivities of ``outputs(values)``."""
    base = outputs(values)
    columns = []
    for k, h in enumerate(steps):
        up, down = values.copy(), values.copy()
        up[k] += h
        down[k] -= h
        columns.append([(yp - ym) / (2 * h) for yp, ym in zip(outputs(up), outputs(down))])
    return base, [np.stack([col[i] for col in columns], axis=1) for i in range(len(base))]


def worst_difference(sens, reference, norm=np.max) -> float:
    """Largest difference of rotorid's and the reference's sensitivities per parameter,
    relative to the reference's size: ``norm`` is the peak (default) or e.g. the RMS over
    samples and outputs, pooled over the maneuvers."""
    fast, ref = np.concatenate(sens), np.concatenate(reference)
    scale = np.maximum(norm(np.abs(ref), axis=(0, 2)), 1e-300)
    return float((norm(np.abs(fast - ref), axis=(0, 2)) / scale).max())


def rms(values, axis):
    return np.sqrt(np.mean(values**2, axis=axis))


def run_case(delayed: bool, repeats: int, reference_repeats: int) -> None:
    structure, values, maneuvers = problem(delayed)
    simulator = Simulator(structure, maneuvers)
    simulator.outputs_and_sensitivities(values)  # warm-up
    fast, fastest, (_, sens) = timings(lambda: simulator.outputs_and_sensitivities(values),
                                       repeats)
    steps = np.where(structure.is_delay(), 1e-6, 1e-6 * np.maximum(1.0, np.abs(values)))
    label = ("scipy.signal.dlsim (ZOH-discretised" + (", delays by Padé" if delayed else "")
             + ") per maneuver, central differences")
    outputs = lambda v: _dlsim_outputs(structure, v, maneuvers)  # noqa: E731
    slow, _, (_, reference) = timings(lambda: central_differences(outputs, values, steps),
                                      reference_repeats)
    target = TARGET_MS[delayed]
    ratio = slow / fast
    title = f"with the 8 paper delays ({structure.n_parameters} parameters)" if delayed else \
        f"without delays ({structure.n_parameters} parameters)"
    print(f"\n{title}")
    print(f"  rotorid outputs + sensitivities : {fast * 1e3:9.1f} ms (median of {repeats}, "
          f"fastest {fastest * 1e3:.1f} ms; target ≤ {target:g} ms: "
          f"{'met' if fast * 1e3 <= target else 'NOT met'})")
    print(f"  reference                       : {slow * 1e3:9.1f} ms (median of "
          f"{reference_repeats}) — {label}")
    print(f"  ratio reference / rotorid       : {ratio:9.1f}× (target ≥ {TARGET_RATIO:g}×: "
          f"{'met' if ratio >= TARGET_RATIO else 'NOT met'})")
    if delayed:
        print(f"  largest RMS difference / RMS per parameter: "
              f"{worst_difference(sens, reference, rms):.1e} (the Padé approximant: its "
              f"response to a step starts at once and dips, the exact delay waits τ)")
    else:
        print(f"  max |rotorid − reference| / scale per parameter: "
              f"{worst_difference(sens, reference):.1e} (finite-difference truncation and "
              f"rounding)")
    own, _, (_, own_reference) = timings(
        lambda: central_differences(simulator.outputs, values, steps), reference_repeats)
    print(f"  like for like: central differences over rotorid's outputs-only path "
          f"{own * 1e3:.1f} ms, ratio {own / fast:.1f}×; max difference "
          f"{worst_difference(sens, own_reference):.1e}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9,
                        help="repeats of the rotorid evaluation (median reported)")
    parser.add_argument("--reference-repeats", type=int, default=3,
                        help="repeats of the reference (median reported)")
    parser.add_argument("--threads", default="1",
                        help="BLAS threads (set before numpy loads; default 1)")
    args = parser.parse_args()
    samples = int(round(DURATION / DT)) + 1
    print(f"paper-size problem: {N_MANEUVERS} maneuvers × {samples} samples at {1 / DT:g} Hz, "
          f"8 outputs")
    print(f"python {platform.python_version()}, numpy {np.__version__}, scipy "
          f"{scipy.__version__}, {os.cpu_count()} CPUs, BLAS threads "
          f"{os.environ['OPENBLAS_NUM_THREADS']}, load average {os.getloadavg()[0]:.2f}")
    for delayed in (False, True):
        run_case(delayed, args.repeats, args.reference_repeats)


if __name__ == "__main__":
    main()
