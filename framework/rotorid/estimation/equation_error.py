"""Equation-error start values for output-error estimation.

Output error from an all-zero start on unstable hover dynamics crawls or stalls: the first
simulated responses are far from the data and diverge. An equation-error fit gives a start near
the optimum at the cost of one linear least-squares problem per equation:

* the specific forces are measured, ``ax = ΣX·z``, ``ay = ΣY·z``, ``az = ΣZ·z``: regress them
  directly on the states and controls;
* the angular accelerations ``ṗ, q̇, ṙ`` come from central differences of the measured rates;
* the unmeasured velocity perturbations ``u, v, w`` are reconstructed by integrating the
  structure's own force equations: ``u̇ = ax + (known gravity/kinematic terms)`` and so on.

Delayed derivatives use their regressor shifted by the delay's initial value. The values are
start values only: their bias from noisy regressors is removed by the output-error fit.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import cumulative_trapezoid

from rotorid.data import ManeuverSet
from rotorid.model.structure import ModelStructure

_ACCELERATION = {"X": "ax", "Y": "ay", "Z": "az"}
_RATE = {"L": "p", "M": "q", "N": "r"}
_VELOCITY_EQUATION = {"u": "ax", "v": "ay", "w": "az"}


def reconstructed_states(structure: ModelStructure, maneuver) -> np.ndarray:
    """States (N, n) of one maneuver in structure units: the measured ones (q θ p φ r) as
    measured, the velocities u v w integrated from their specific forces."""
    states = structure.states
    x = np.zeros((maneuver.n_samples, len(states)))
    for row, name in enumerate(states):
        if name in structure.outputs:
            x[:, row] = maneuver.channel(name)
    known = structure.known_state_matrix()
    start = maneuver.initial_values(states)
    for name, accel in _VELOCITY_EQUATION.items():
        if name not in states or name in structure.outputs or accel not in structure.outputs:
            continue
        row = states.index(name)
        rate = maneuver.channel(accel) + x @ known[row]
        x[:, row] = start[row] + cumulative_trapezoid(rate, maneuver.time, initial=0.0)
    return x


def _regressor(structure: ModelStructure, maneuver, states: np.ndarray, variable: str,
               delay: float) -> np.ndarray:
    if variable in structure.controls:
        signal = maneuver.channel(variable)
    else:
        signal = states[:, structure.states.index(variable)]
    if delay <= 0.0:
        return signal
    return np.interp(maneuver.time - delay, maneuver.time, signal, left=0.0)


def equation_error_start(structure: ModelStructure, maneuvers: ManeuverSet) -> np.ndarray:
    """Start values for ``structure.parameter_names``: derivatives by equation error, delays at
    their initial values. Shape (n_parameters,)."""
    values = dict(zip(structure.parameter_names, structure.initial_values()))
    recon = [reconstructed_states(structure, m) for m in maneuvers]
    for letter in ("X", "Y", "Z", "L", "M", "N"):
        members = [d for d in structure.derivatives if d.letter == letter]
        free = [d for d in members if not d.fixed]
        if not free:
            continue
        targets, columns = [], [[] for _ in free]
        for m, states in zip(maneuvers, recon):
            if letter in _ACCELERATION:
                target = m.channel(_ACCELERATION[letter]).copy()
            else:
                target = np.gradient(m.channel(_RATE[letter]), m.time)
            for d in members:
                delay = d.delay.initial if d.delay is not None else 0.0
                regressor = _regressor(structure, m, states, d.variable, delay)
                if d.fixed:
                    target -= d.initial * regressor
                else:
                    columns[free.index(d)].append(regressor)
            targets.append(target)
        design = np.column_stack([np.concatenate(c) for c in columns])
        scale = np.where(np.std(design, axis=0) > 0, np.std(design, axis=0), 1.0)
        solution, *_ = np.linalg.lstsq(design / scale, np.concatenate(targets), rcond=None)
        for d, value in zip(free, solution / scale):
            values[d.name] = float(value)
    return np.array([values[n] for n in structure.parameter_names])
