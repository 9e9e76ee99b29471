"""Kinematic consistency of maneuver data, as flight-path reconstruction checks it.

The attitudes obey the linearised Euler kinematics, θ̇ = cos Φ0 q − sin Φ0 r and
φ̇ = p + tan Θ0 (sin Φ0 q + cos Φ0 r); where a maneuver carries the body velocities ``u v w``
as extra channels, they obey u̇ = ax + (gravity and kinematic terms) and likewise for v and w
(the known terms of :meth:`rotorid.model.structure.ModelStructure.known_state_matrix`). An
aeroplane's vanes give them too: at a trim speed U0 > 0, v = U0·β and w = U0·α (small
perturbations, β and α outputs in the unit system's angle unit), so the accelerometers' units
are checked against the vanes. For each such channel y with driver f, a least-squares fit
over the maneuvers in which it moves (at least :data:`MOVING_FRACTION` of its largest motion
in any maneuver: a roll attitude is checked on the roll records, not on pitch ones) of

    y_i(t) = y0_i + k · ∫ f_i dt − k · b_i · t

gives one scale factor k (1: consistent) and a bias b_i of the driver per maneuver (the
measured rates or accelerations minus the true ones). For a velocity the kinematic terms
(gravity, U0·r, …, from the gyros and attitudes the attitudes' fits check) are integrated and
taken out of y first, so that k and b_i are the accelerometer's alone. :func:`check_kinematics` reports every
fit on the ``rotorid.checks`` logger and warns when k or the bias is off.
"""

from __future__ import annotations

import logging
import math
import warnings

import attrs
import numpy as np
from scipy.integrate import cumulative_trapezoid

from rotorid.data import ManeuverSet
from rotorid.errors import DataWarning
from rotorid.model.structure import STATES, FlightCondition, ModelStructure
from rotorid.units import FOOT, G_SI, unit_system

#: A scale factor further than this from 1 is reported.
SCALE_TOLERANCE = 0.1
#: A bias larger than this fraction of the driver's RMS is reported.
BIAS_FRACTION = 0.05
#: A fit whose residual exceeds this fraction of the channel's variation (about each
#: maneuver's mean) compares noise with noise: the channel hardly moves, it is left out.
MOTION_FRACTION = 0.3
ACCELERATIONS = {"u": "ax", "v": "ay", "w": "az"}
#: Flow angles that give a body velocity at a trim speed: v = U0·β, w = U0·α.
FLOW_ANGLES = {"v": "beta", "w": "alpha"}
#: A maneuver takes part in a channel's fit when the channel's RMS motion (about its mean)
#: there is at least this fraction of the largest in any maneuver.
MOVING_FRACTION = 0.2


#: Where a user declares a channel's unit, for the advice of the checks.
WHERE_UNITS = ("the column's unit in the model's [channels] table, or the file header's "
               "channel_units")


@attrs.frozen
class KinematicFit:
    """The fit of one channel against its integrated driver.

    Attributes:
        channel: the integrated channel (``theta``, ``phi``, ``u``, ``v`` or ``w``).
        driver: what drives it, e.g. ``"q, r"`` or ``"ax, q, r, theta"``.
        scale: k, the channel's change per unit of integrated driver (1: consistent).
        bias: mean over the maneuvers of the driver's bias b_i, in the driver's unit (per s).
        largest_bias: the b_i of largest magnitude.
        residual: RMS of the fit's residual, in the channel's unit.
        driver_rms: RMS of the driver, in its unit.
        unit: the driver's unit.
    """

    channel: str
    driver: str
    scale: float
    bias: float
    largest_bias: float
    residual: float
    driver_rms: float
    unit: str

    def describe(self) -> str:
        return (f"{self.channel} against integrated {self.driver}: scale {self.scale:.4g}, "
                f"bias {self.bias:.3g} {self.unit} (largest {self.largest_bias:.3g}), "
                f"residual RMS {self.residual:.3g}")


def _states(maneuver, speed: float, angle_per_radian: float) -> np.ndarray:
    """(N, 8) states where known: measured q θ p φ r (those the record holds), velocities from
    extra channels or, at a trim ``speed`` U0 > 0 (the unit system's velocity unit), from the
    flow angles (``angle_per_radian``: the system's angle unit), else 0."""
    x = np.zeros((maneuver.n_samples, len(STATES)))
    for i, name in enumerate(STATES):
        if name in maneuver.output_names:
            x[:, i] = maneuver.channel(name)
        elif name in maneuver.extra_channels:
            x[:, i] = maneuver.extra_channels[name]
        elif speed > 0 and FLOW_ANGLES.get(name) in maneuver.output_names:
            x[:, i] = speed * maneuver.channel(FLOW_ANGLES[name]) / angle_per_radian
    return x


def _velocity_known(maneuver, channel: str, speed: float) -> bool:
    return (channel in maneuver.extra_channels
            or (speed > 0 and FLOW_ANGLES.get(channel) in maneuver.output_names))


def _moving(targets) -> list[int]:
    """The maneuvers whose target moves by at least :data:`MOVING_FRACTION` of the most."""
    motion = np.array([np.std(y) for y in targets])
    return [i for i, m in enumerate(motion) if m > 0 and m >= MOVING_FRACTION * motion.max()]


def _fit(targets, drivers, times) -> tuple[float, np.ndarray, float]:
    """Least-squares k, the biases b_i and the residual RMS (see the module docstring)."""
    n = len(targets)
    columns = [np.concatenate([cumulative_trapezoid(f, t, initial=0.0)
                               for f, t in zip(drivers, times)])]
    for i in range(n):
        for basis in (np.ones_like, lambda t: t - t[0]):
            columns.append(np.concatenate([basis(t) if j == i else np.zeros_like(t)
                                           for j, t in enumerate(times)]))
    design = np.column_stack(columns)
    y = np.concatenate(targets)
    solution, *_ = np.linalg.lstsq(design, y, rcond=None)
    scale = float(solution[0])
    biases = -solution[2::2] / scale if scale else np.full(n, np.nan)
    residual = float(np.sqrt(np.mean((y - design @ solution) ** 2)))
    return scale, biases, residual


def _channel_fit(channel: str, used: list[str], drivers, targets, times,
                 unit: str) -> KinematicFit | None:
    """The fit of one channel, or None where its residual exceeds :data:`MOTION_FRACTION` of
    its motion (or nothing moves)."""
    if not np.any(np.concatenate(drivers)) or np.ptp(np.concatenate(targets)) == 0:
        return None
    scale, biases, residual = _fit(targets, drivers, times)
    motion = np.sqrt(np.mean(np.concatenate([y - np.mean(y) for y in targets]) ** 2))
    if residual > MOTION_FRACTION * motion:
        return None
    return KinematicFit(channel, ", ".join(used), scale, float(np.mean(biases)),
                        float(biases[np.argmax(np.abs(biases))]), residual,
                        float(np.sqrt(np.mean(np.concatenate(drivers) ** 2))), unit)


def kinematic_fits(maneuvers: ManeuverSet,
                   condition: FlightCondition | None = None) -> tuple[KinematicFit, ...]:
    """The fit of every attitude, and of every velocity the maneuvers all carry, against its
    kinematic driver; channels that hardly move (see :data:`MOTION_FRACTION`) or have no
    moving driver are left out.

    An attitude its whole driver does not explain is fitted against each of the driver's
    terms alone (θ against q, φ against p): a rate gyro read in the wrong unit leaves the
    attitude to the other, small terms (r through sin Φ0), which then explain nothing, while
    the rate's own term does with the units' ratio as its scale."""
    system = unit_system(maneuvers.units)
    condition = condition or FlightCondition()
    known = ModelStructure(condition, (), system).known_state_matrix()
    speed = condition.u0 * system.length_per_metre
    channels = [a for a in ("theta", "phi") if a in maneuvers.output_names]
    channels += [v for v, a in ACCELERATIONS.items() if a in maneuvers.output_names
                 and all(_velocity_known(m, v, speed) for m in maneuvers)]
    all_states = [_states(m, speed, system.angle_per_radian) for m in maneuvers]
    fits = []
    for channel in channels:
        row = STATES.index(channel)
        terms = list(np.flatnonzero(known[row]))
        chosen = _moving([x[:, row] for x in all_states])
        if not chosen:                                  # the channel never moves
            continue
        taking = [maneuvers[i] for i in chosen]
        states = [all_states[i] for i in chosen]
        times = [m.time for m in taking]
        targets = [x[:, row] for x in states]
        if channel in ACCELERATIONS:
            # the kinematic terms (gravity, U0·r, …) come from the gyros and attitudes, which
            # the attitudes' fits check: taken out of the target, the scale is the
            # accelerometer's own
            acceleration = ACCELERATIONS[channel]
            remainders = [y - cumulative_trapezoid(x @ known[row], t, initial=0.0)
                          for y, x, t in zip(targets, states, times)]
            found = _channel_fit(channel, [acceleration] + [STATES[j] for j in terms],
                                 [m.channel(acceleration) for m in taking], remainders, times,
                                 system.label(acceleration))
        else:
            unit = f"{system.label(channel)}/s"
            found = _channel_fit(channel, [STATES[j] for j in terms],
                                 [x @ known[row] for x in states], targets, times, unit)
            alone = (_channel_fit(channel, [STATES[j]], [known[row, j] * x[:, j] for x in states],
                                  targets, times, unit) for j in terms if len(terms) > 1)
            found = found or min((fit for fit in alone if fit is not None),
                                 key=lambda fit: fit.residual, default=None)
        if found is not None:
            fits.append(found)
    return tuple(fits)


def _scale_advice(fit: KinematicFit) -> str:
    if abs(fit.scale + 1) < 0.15:
        return (f"{fit.channel} and its driver ({fit.driver}) move with opposite signs: one "
                f"of them is recorded with the other sign convention (a normal load factor "
                f"read as az needs scale = -1 in the channel map)")
    for gravity, unit in ((G_SI, "m/s²"), (G_SI / FOOT, "ft/s²")):
        if abs(abs(fit.scale) / gravity - 1) < 0.15:
            return (f"the accelerometers among {fit.driver} look recorded in g but read as "
                    f"{unit} (scale ≈ {gravity:.4g}): declare their unit \"g\" in the channel "
                    f"map")
    ratio = math.degrees(1.0)
    if abs(fit.scale / ratio - 1) < 0.15:
        return (f"{fit.channel} is in deg and its driver ({fit.driver}) in rad: declare the "
                f"driver's unit ({WHERE_UNITS}, e.g. {{\"q\": \"rad/s\"}})")
    if abs(fit.scale * ratio - 1) < 0.15:
        return (f"{fit.channel} is in rad and its driver ({fit.driver}) in deg: declare the "
                f"channel's unit ({WHERE_UNITS} {{\"{fit.channel}\": \"rad\"}})")
    return "check the calibration (scale factor) of these sensors"


def check_kinematics(maneuvers: ManeuverSet, condition: FlightCondition | None = None
                     ) -> tuple[KinematicFit, ...]:
    """Log every :func:`kinematic_fits` result on the ``rotorid.checks`` logger and issue a
    :class:`~rotorid.errors.DataWarning` for a scale factor or bias that is off; return the
    fits."""
    log = logging.getLogger("rotorid.checks")
    fits = kinematic_fits(maneuvers, condition)
    for fit in fits:
        log.info("kinematic consistency: %s", fit.describe())
        if not abs(fit.scale - 1) <= SCALE_TOLERANCE:
            warnings.warn(f"kinematic consistency: {fit.describe()}; a scale far from 1 "
                          f"means inconsistent units or sensors: {_scale_advice(fit)}",
                          DataWarning, stacklevel=2)
        elif abs(fit.bias) > BIAS_FRACTION * fit.driver_rms:
            warnings.warn(f"kinematic consistency: {fit.describe()}; the bias is "
                          f"{abs(fit.bias) / fit.driver_rms:.0%} of the driver's RMS "
                          f"({fit.driver_rms:.3g} {fit.unit}): estimate output biases "
                          f"(--output-biases) or remove the sensor bias first",
                          DataWarning, stacklevel=2)
    return fits
