"""The truth model linearised about a trim, flown as a plant: a truth whose structure is known.

:meth:`LinearisedPlant.about` takes central differences of the truth model's state derivatives
and measurements in its states, sticks and gusts at a trim::

    ẋ = A·Δx + B·Δδ + G·g        y = y0 + C·Δx + D·Δδ + H·g

and residualises the rotor, inflow and actuator states (quasi-steady, as
:func:`.linearize.linearize` does), leaving the rigid body ``u v w p q r φ θ ψ`` (SI, sticks
in %), or keeps them (``rotor=True``: the rotor's own dynamics, linear).
:meth:`LinearisedPlant.longitudinal` also cuts the longitudinal motion (u w q θ, long and
coll, u_g w_g q_g, ax az q θ) from the lateral one, both ways. The plant has the interface the
flight harness flies (:mod:`.flight`), so the same maneuvers, loops, gusts and sensors give
data from a truth that a linear structure represents exactly or up to a known part: a Monte
Carlo on it separates the estimator's statistics from the model-structure error of the
nonlinear truth. :meth:`LinearisedPlant.of_structure` flies a rotorid linear structure itself
the same way: a truth of exactly the fitted structure's form.
"""

from __future__ import annotations

import hashlib
import math

import attrs
import numpy as np
from rotorid.data import OUTPUT_CHANNELS
from rotorid.errors import DataError
from rotorid.frozen import readonly_array
from rotorid.units import SI, channel_scale

from .linearize import _BLADE_STEP, _INFLOW_STEP, _STEPS
from .loops import BODY
from .model import ACTUATORS

#: Central-difference steps of the sticks (%) and the gusts (m/s, rad/s).
_STICK_STEP = 1e-2
_GUST_STEPS = (1e-2, 1e-2, 1e-2, 1e-3, 1e-3, 1e-3)
#: Longitudinal states, sticks, gusts and measurements (the rest is lateral).
_LONGITUDINAL = {"states": ("u", "w", "q", "theta"), "sticks": (0, 2), "gusts": (0, 2, 4),
                 "measurements": (0, 1, 2, 3)}


def _state_steps(names) -> np.ndarray:
    """Central-difference step per state (SI): the linearisation's, blade angles as such."""
    return np.array([_STEPS.get(n, _BLADE_STEP if n in ACTUATORS else _INFLOW_STEP)
                     if n not in ("phi", "theta", "psi") else 1e-3 for n in names])


def _jacobians(function, x0, stick0, steps):
    """Central differences of ``function(x, stick, gust)`` (B, k) in x, stick and gust:
    (k, n), (k, 4), (k, 6), from one batched call."""
    point = np.concatenate([x0, stick0, np.zeros(6)])
    step = np.concatenate([steps, np.full(4, _STICK_STEP), _GUST_STEPS])
    rows = np.concatenate([point + np.diag(step), point - np.diag(step)])
    n = x0.size
    values = function(rows[:, :n], rows[:, n:n + 4], rows[:, n + 4:])
    jacobian = ((values[:step.size] - values[step.size:]) / (2 * step[:, None])).T
    return jacobian[:, :n], jacobian[:, n:n + 4], jacobian[:, n + 4:]


@attrs.frozen(eq=False)
class LinearisedPlant:
    """A linear plant over n states (SI), sticks in %, gusts (6,).

    Attributes:
        trim_state: (n,) and trim_stick: (4,) the trim it is linearised about.
        a, b, g: state derivative per state (n, n), stick (n, 4) and gust (n, 6).
        c, d, h: the measurements ``[ax az q θ ay p φ r]`` likewise, (8, ·).
        trim_measurements: (8,) the measurements at trim.
        airspeed_kt: the trim's airspeed.
        config: what it is (the data cache tells plants apart by it).
        state_names: the n states: :data:`.loops.BODY`, or the truth model's own.
    """

    trim_state: np.ndarray = attrs.field(converter=readonly_array)
    trim_stick: np.ndarray = attrs.field(converter=readonly_array)
    a: np.ndarray = attrs.field(converter=readonly_array)
    b: np.ndarray = attrs.field(converter=readonly_array)
    g: np.ndarray = attrs.field(converter=readonly_array)
    c: np.ndarray = attrs.field(converter=readonly_array)
    d: np.ndarray = attrs.field(converter=readonly_array)
    h: np.ndarray = attrs.field(converter=readonly_array)
    trim_measurements: np.ndarray = attrs.field(converter=readonly_array)
    airspeed_kt: float = 0.0
    config: str = ""
    state_names: tuple = BODY

    @property
    def n_states(self) -> int:
        return len(self.state_names)

    @classmethod
    def about(cls, model, trim, rotor: bool = False) -> "LinearisedPlant":
        """``model`` (a :class:`~.model.Bo105Model`) linearised about ``trim``, its rotor,
        inflow and actuator states residualised, or kept with ``rotor``."""
        names = tuple(model.state_names)
        x0 = np.asarray(trim.state, dtype=float)
        stick0 = np.asarray(trim.stick, dtype=float)
        steps = _state_steps(names)
        a, b, g = _jacobians(lambda x, s, w: model.derivatives(x, s, gust=w), x0, stick0, steps)
        c, d, h = _jacobians(lambda x, s, w: model.measurements(x, s, gust=w), x0, stick0,
                             steps)
        trim_measurements = model.measurements(x0[None], stick0[None])[0]
        config = f"linearised at {trim.airspeed_kt:g} kt: {model.config!r}"
        if rotor:
            return cls(x0, stick0, a, b, g, c, d, h, trim_measurements, trim.airspeed_kt,
                       f"{config}, rotor kept", names)
        kept = [names.index(n) for n in BODY]
        dropped = [i for i in range(len(names)) if i not in kept]
        # quasi-steady dropped states: 0 = A_dk·x + A_dd·x_d + B_d·δ + G_d·g
        solve = np.linalg.solve(a[np.ix_(dropped, dropped)],
                                np.hstack([a[np.ix_(dropped, kept)], b[dropped], g[dropped]]))

        def reduced(matrix, stick, gust):
            coupling = matrix[:, dropped] @ solve
            return (matrix[:, kept] - coupling[:, :len(kept)], stick - coupling[:, 9:13],
                    gust - coupling[:, 13:])

        a, b, g = reduced(a[kept], b[kept], g[kept])
        c, d, h = reduced(c, d, h)
        return cls(x0[kept], stick0, a, b, g, c, d, h, trim_measurements, trim.airspeed_kt,
                   config)

    @classmethod
    def of_structure(cls, structure, values, trim_stick) -> "LinearisedPlant":
        """A rotorid linear ``structure`` at ``values`` (its delays dropped) as a plant about
        its flight condition's attitude and ``trim_stick`` (4,) %: states :data:`.loops.BODY`
        (the heading added, ψ̇ from the Euler kinematics) and the structure's others, SI;
        translational gusts through −(A − A0)'s u, v, w columns and the accelerometers'
        −(C − C0)'s, as the truth model's act (:mod:`rotorid_filter_error`'s ``gusts``);
        rotational gusts act on nothing. The structure needs the six-dof states and outputs."""
        missing = [n for n in BODY if n != "psi" and n not in structure.states] + [
            y for y in OUTPUT_CHANNELS if y not in structure.outputs]
        if missing:
            raise DataError(f"a structure flown as a plant needs the six-dof states and "
                            f"outputs; {structure.template.name!r} lacks {', '.join(missing)}")
        a, b, c, d = structure.matrices(values)
        a_known, c_known = structure.known_state_matrix(), structure.known_output_matrix()
        names = BODY + tuple(s for s in structure.states if s not in BODY)
        kept = [names.index(s) for s in structure.states]
        rows = [structure.outputs.index(y) for y in OUTPUT_CHANNELS]
        to_si = channel_scale(structure.states, SI, structure.units)
        out_si = channel_scale(OUTPUT_CHANNELS, SI, structure.units)[:, None]
        n = len(names)

        def states_si(matrix):
            full = np.zeros((n, n))
            full[np.ix_(kept, kept)] = to_si[:, None] * matrix / to_si[None, :]
            return full

        def outputs_si(matrix):
            full = np.zeros((len(OUTPUT_CHANNELS), n))
            full[:, kept] = out_si * matrix[rows] / to_si[None, :]
            return full

        state, aero = states_si(a), states_si(a - a_known)
        output, aero_output = outputs_si(c), outputs_si(c - c_known)
        condition = structure.condition
        tilt = 1.0 / math.cos(condition.theta0)
        state[names.index("psi"), names.index("q")] = math.sin(condition.phi0) * tilt
        state[names.index("psi"), names.index("r")] = math.cos(condition.phi0) * tilt
        inputs = np.zeros((n, 4))
        inputs[kept] = to_si[:, None] * b
        gust, gust_reading = np.zeros((n, 6)), np.zeros((len(OUTPUT_CHANNELS), 6))
        for column, velocity in enumerate(("u", "v", "w")):
            gust[:, column] = -aero[:, names.index(velocity)]
            gust_reading[:, column] = -aero_output[:, names.index(velocity)]
        trim_state = np.zeros(n)
        trim_state[names.index("theta")], trim_state[names.index("phi")] = (condition.theta0,
                                                                           condition.phi0)
        digest = hashlib.sha1(np.concatenate([state.ravel(), inputs.ravel(),
                                              output.ravel()]).tobytes()).hexdigest()[:12]
        return cls(trim_state, trim_stick, state, inputs, gust, output, out_si * d[rows],
                   gust_reading, np.zeros(len(OUTPUT_CHANNELS)), condition.airspeed_kt,
                   f"{structure.template.name} structure {digest}", names)

    def longitudinal(self) -> "LinearisedPlant":
        """This plant with the longitudinal motion cut from the lateral one, both ways (the
        rigid-body plant only)."""
        if self.state_names != BODY:
            raise DataError("the longitudinal cut needs the rigid-body plant; linearise with "
                            "the rotor residualised (rotor=False)")
        states = np.isin(BODY, _LONGITUDINAL["states"])
        sticks = np.isin(np.arange(4), _LONGITUDINAL["sticks"])
        gusts = np.isin(np.arange(6), _LONGITUDINAL["gusts"])
        outputs = np.isin(np.arange(8), _LONGITUDINAL["measurements"])

        def cut(matrix, rows, columns):
            return np.where(rows[:, None] == columns[None, :], matrix, 0.0)

        return attrs.evolve(
            self, a=cut(self.a, states, states), b=cut(self.b, states, sticks),
            g=cut(self.g, states, gusts), c=cut(self.c, outputs, states),
            d=cut(self.d, outputs, sticks), h=cut(self.h, outputs, gusts),
            config=f"{self.config}, longitudinal")

    def derivatives(self, x, stick, gust=None) -> np.ndarray:
        """State derivatives (B, n) at states (B, n), sticks (B, 4) and gusts (B, 6)."""
        slope = (x - self.trim_state) @ self.a.T + (stick - self.trim_stick) @ self.b.T
        return slope if gust is None else slope + gust @ self.g.T

    def measurements(self, x, stick, gust=None) -> np.ndarray:
        """Total measurements (B, 8) ``[ax az q θ ay p φ r]``, SI."""
        y = (self.trim_measurements + (x - self.trim_state) @ self.c.T
             + (stick - self.trim_stick) @ self.d.T)
        return y if gust is None else y + gust @ self.h.T


@attrs.frozen(eq=False)
class _Trim:
    state: np.ndarray
    stick: np.ndarray


def linearised_trim(plant: LinearisedPlant, airspeed_kt: float) -> _Trim:
    """The :class:`~.source.HelisimSource` trimmer of a :class:`LinearisedPlant`: its own
    trim, which holds at its airspeed only."""
    if abs(airspeed_kt - plant.airspeed_kt) > 1e-9:
        raise DataError(f"the linearised plant holds at {plant.airspeed_kt:g} kt, not at "
                        f"{airspeed_kt:g} kt; linearise the truth model at that airspeed")
    return _Trim(plant.trim_state, plant.trim_stick)


#: What flies the maneuvers in :func:`source_flown_by`: the truth model or a linearisation.
TRUTHS = ("nonlinear", "linear", "linear-longitudinal", "linear-rotor")


def source_flown_by(truth: str, airspeed_kt: float = 0.0):
    """A :class:`~.source.HelisimSource` whose maneuvers (same loops, gusts and sensors) are
    flown by ``truth`` (:data:`TRUTHS`): the truth model (``"nonlinear"``), its linearisation
    at ``airspeed_kt`` with the rotor, inflow and actuator states residualised (``"linear"``),
    that linearisation's longitudinal part alone (``"linear-longitudinal"``) or the
    linearisation with those states kept (``"linear-rotor"``)."""
    from .source import HelisimSource

    if truth not in TRUTHS:
        raise DataError(f"unknown truth {truth!r}; choose one of {', '.join(TRUTHS)}")
    source = HelisimSource()
    if truth == "nonlinear":
        return source
    plant = LinearisedPlant.about(source.plant, source.trim(airspeed_kt),
                                  rotor=truth == "linear-rotor")
    return HelisimSource(plant=plant.longitudinal() if truth == "linear-longitudinal"
                         else plant, trimmer=linearised_trim)
