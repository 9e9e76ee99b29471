"""Batched flight of a plant through several maneuvers at once.

The plant is any object with ``state_names``, ``n_states``, ``derivatives(x, stick)`` and
``measurements(x, stick)`` working on batches (rows) of states; flights in turbulence also pass
``gust=`` (B, 6) to both (:mod:`.turbulence`). All maneuvers start in trim
(each row may have its own) and run side by side as one batch; a maneuver leaves the batch when
its record ends.

Timing is that of a digital flight-test setup running at the sample rate:

* at each sample instant t_k the pilot signal and the loops (computed from the state at t_k)
  give the stick δ_k, which is recorded and held until t_{k+1} (an exact zero-order hold);
* the measurements y_k are taken at t_k with δ_k applied (and the gust g_k, held like δ_k);
* between samples the plant is integrated with classical fixed-step RK4, ``substeps`` steps per
  sample (0.005 s at 50 Hz with the default 4, resolving the ≈ 93 rad/s advancing flap mode of
  truth-model.md §2.6 with |λ·h| < 0.5).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import attrs
import numpy as np
from rotorid.errors import DataError, SimulationDivergedError

from .loops import feedback


@attrs.frozen(eq=False)
class FlightRecord:
    """Sampled histories of a batch of maneuvers, padded to the longest with NaN.

    Attributes:
        time: (N,) sample instants in s, starting at 0.
        n_samples: (B,) valid samples per maneuver.
        states: (B, N, n_states) plant states (SI).
        stick: (B, N, 4) recorded stick positions, pilot signal plus loops, total % of travel.
        pilot: (B, N, 4) pilot signal, % perturbation from trim.
        measurements: (B, N, 8) noise-free ``[ax az q θ ay p φ r]``, total, SI.
    """

    time: np.ndarray
    n_samples: np.ndarray
    states: np.ndarray
    stick: np.ndarray
    pilot: np.ndarray
    measurements: np.ndarray


def rk4_step(derivatives: Callable, x: np.ndarray, stick: np.ndarray, h: float) -> np.ndarray:
    """One classical Runge–Kutta step of length ``h`` s with the stick held constant."""
    k1 = derivatives(x, stick)
    k2 = derivatives(x + 0.5 * h * k1, stick)
    k3 = derivatives(x + 0.5 * h * k2, stick)
    k4 = derivatives(x + h * k3, stick)
    return x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def fly(plant, trim_state, trim_stick, pilot, n_samples, gains, sample_time: float,
        substeps: int = 4, progress: Callable[[float], None] | None = None,
        gusts: np.ndarray | None = None) -> FlightRecord:
    """Fly B maneuvers together from trim.

    Args:
        plant: the plant (see the module docstring).
        trim_state: (n_states,) trim state, or (B, n_states) for maneuvers flown from
            different trims (several flight conditions in one batch).
        trim_stick: (4,) or (B, 4) trim stick in %.
        pilot: (B, N, 4) pilot signal at the sample instants, % perturbation from trim.
        n_samples: (B,) record length of each maneuver in samples (≤ N).
        gains: (B, 4, 9) loop gain matrices (see :class:`~.loops.LoopGains`).
        sample_time: s; substeps: RK4 steps per sample.
        progress: optional callback receiving the completed fraction (0–1).
        gusts: optional (B, N, 6) gusts at the sample instants (m/s, rad/s); None is still air.
    """
    pilot = np.asarray(pilot, dtype=float)
    n_samples = np.asarray(n_samples, dtype=int)
    gains = np.asarray(gains, dtype=float)
    batch, length, _ = pilot.shape
    if n_samples.shape != (batch,) or n_samples.max() > length or n_samples.min() < 2:
        raise DataError(f"n_samples must give 2…{length} samples for each of the {batch} "
                        f"maneuvers, got {n_samples}")
    if substeps < 1:
        raise DataError(f"substeps must be ≥ 1, got {substeps}")
    if gusts is not None and np.shape(gusts) != (batch, length, 6):
        raise DataError(f"gusts must have shape ({batch}, {length}, 6), got {np.shape(gusts)}")
    trim_state = np.broadcast_to(np.asarray(trim_state, dtype=float), (batch, plant.n_states))
    trim_stick = np.broadcast_to(np.asarray(trim_stick, dtype=float), (batch, 4))
    names = tuple(plant.state_names)
    h = sample_time / substeps

    states = np.full((batch, length, plant.n_states), np.nan)
    stick = np.full((batch, length, 4), np.nan)
    outputs = np.full((batch, length, 8), np.nan)
    x = trim_state.copy()
    active = np.arange(batch)
    for k in range(length):
        still = n_samples[active] > k
        if not still.all():  # drop the maneuvers whose record has ended
            x, active = x[still], active[still]
        delta = -np.einsum("bij,bj->bi", gains[active],
                           feedback(x, trim_state[active], names))
        applied = trim_stick[active] + pilot[active, k] + delta
        states[active, k] = x
        stick[active, k] = applied
        if gusts is None:
            derivatives, measurements = plant.derivatives, plant.measurements
        else:
            gust = gusts[active, k]
            derivatives = partial(plant.derivatives, gust=gust)
            measurements = partial(plant.measurements, gust=gust)
        outputs[active, k] = measurements(x, applied)
        if k == length - 1:
            break
        for _ in range(substeps):
            x = rk4_step(derivatives, x, applied, h)
        if not np.all(np.isfinite(x)):
            bad = active[np.flatnonzero(~np.all(np.isfinite(x), axis=1))[0]]
            raise SimulationDivergedError(
                f"the flight of maneuver #{bad} diverged at t = {(k + 1) * sample_time:.3f} s; "
                f"reduce the input amplitude or the sample time / raise substeps")
        if progress is not None and k % 50 == 0:
            progress(k / (length - 1))
    if progress is not None:
        progress(1.0)
    return FlightRecord(np.arange(length) * sample_time, n_samples, states, stick,
                        pilot, outputs)
