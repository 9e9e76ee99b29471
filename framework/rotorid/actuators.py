"""Known actuator dynamics on the recorded inputs: each stick through a first-order lag.

A helicopter's control actuators put a lag between the recorded stick and the blade angle. A
delay on the flap equations' control terms (the hybrid model's) approximates it at the
multisteps' frequencies; in turbulence, where the stabilising loops answer the gusts with
faster stick activity, that approximation moved the hover roll damping by 14–20 %
(docs/estimation.md). When the actuators' time constant is known (from the aircraft's
documentation or a bench test), :func:`lagged_inputs` gives the fits the blade-angle demand
instead of the stick: every named input x passed through 1/(1 + τs) from its recorded initial
value, exact for the input held over each sample (zero-order hold): with a = e^(−dt/τ),

    y_{k+1} = a·y_k + (1 − a)·x_k,

and the value kept at sample k is the lag's mean over [t_k, t_k+1),

    ȳ_k = y_k + (x_k − y_k)·(1 − (τ/dt)·(1 − a)),

which a model that holds its input over the sample integrates exactly (to first order in its
own dynamics). Records with a first-order hold keep the lag's value at the sample instants
instead, driven by the interpolated input (exact for the linear input).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import DataError


def _checked_time_constant(time_constant_s: float) -> float:
    tau = float(time_constant_s)
    if not math.isfinite(tau) or tau <= 0.0:
        raise DataError(f"actuator time constant must be a finite number of seconds > 0, got "
                        f"{time_constant_s!r}")
    return tau


def _lagged(values: np.ndarray, dt: float, tau: float, hold: str) -> np.ndarray:
    """(N, k) ``values`` sampled every ``dt`` s through 1/(1 + τs), started at rest at the
    first sample, as the record's ``hold`` needs them (module docstring)."""
    decay = math.exp(-dt / tau)
    ramp = 1.0 - tau / dt * (1.0 - decay)          # a held step's mean over one sample
    state = values[0].astype(float)
    lagged = np.empty_like(values, dtype=float)
    for k, value in enumerate(values):
        if hold == "foh":
            lagged[k] = state
            following = values[min(k + 1, len(values) - 1)]
            slope = (following - value) / dt
            # exact response over the sample to x(t) = value + slope·t
            state = (decay * state + (1.0 - decay) * value
                     + slope * (dt - tau * (1.0 - decay)))
        else:
            lagged[k] = state + (value - state) * ramp
            state = decay * state + (1.0 - decay) * value
    return lagged


def lagged_inputs(maneuvers: ManeuverSet, time_constant_s: float,
                  inputs: Iterable[str] | None = None) -> ManeuverSet:
    """``maneuvers`` with each input named in ``inputs`` (default every input) passed through
    a first-order actuator lag of ``time_constant_s`` s (module docstring); the records given
    are not modified.

    Raises:
        DataError: a time constant that is not a positive number, or an input the records
            lack.
    """
    tau = _checked_time_constant(time_constant_s)
    lagged = []
    for maneuver in maneuvers:
        names = tuple(maneuver.input_names)
        chosen = names if inputs is None else tuple(inputs)
        missing = [name for name in chosen if name not in names]
        if missing:
            raise DataError(f"maneuver {maneuver.name!r} has no input {', '.join(missing)} to "
                            f"lag; its inputs are {', '.join(names) or 'none'}")
        dt = maneuver.dt                                # records are evenly sampled
        columns = [names.index(name) for name in chosen]
        values = np.array(maneuver.inputs, dtype=float)
        values[:, columns] = _lagged(values[:, columns], dt, tau, maneuvers.hold)
        lagged.append(attrs.evolve(maneuver, inputs=values))
    return attrs.evolve(maneuvers, maneuvers=lagged)
