"""A nonlinear model of one's own (:mod:`rotorid.model.nonlinear`) seen through the model
protocol of :mod:`rotorid.estimation.models`, so any estimator identifies it.

:class:`IntegratedModel` reads the model's inputs and measured outputs from the maneuvers
through a :class:`~rotorid.model.signals.ChannelMap` (converted once into the signals' units),
sets each maneuver's initial state (:class:`InitialConditions`), integrates the model with
:mod:`rotorid.simulation.integrators` under the maneuvers' input hold, and gives sensitivities
∂y/∂ψ with respect to the estimated parameters ψ: by finite differences of one batched
simulation of every perturbed parameter vector (``"central"``, the default, or ``"forward"``;
relative ``step``), or exactly from the model's own Jacobians (``"model"``, the default when the
model provides them). Maneuvers with the same sample time are simulated in one batch; with
finite differences a simulation anticipates the sensitivities at its values (``anticipate``).
"""

from __future__ import annotations

from collections.abc import Mapping

import attrs
import numpy as np

from rotorid.data import Maneuver, ManeuverSet
from rotorid.errors import StructureError
from rotorid.model.nonlinear import NonlinearModel, has_own_jacobians
from rotorid.model.signals import ChannelMap, ModelSignals
from rotorid.simulation.integrators import Integration, integrate, integrate_with_tangents
from rotorid.units import CHANNEL_KINDS, unit_system

SENSITIVITY_METHODS = ("central", "forward", "model")


@attrs.frozen
class InitialConditions:
    """Where each maneuver's initial state comes from.

    Attributes:
        fixed: state name → value in the state's unit, the same for every maneuver.
        estimated: states whose initial value is estimated per maneuver, as parameters
            ``x0_<maneuver>_<state>`` starting from the fixed value or the data.
    States not fixed are read from the data: the first sample of the signal of that name.
    """

    fixed: Mapping[str, float] = attrs.field(
        factory=dict, converter=lambda m: {k: float(v) for k, v in dict(m).items()})
    estimated: tuple[str, ...] = attrs.field(default=(), converter=tuple)


@attrs.frozen
class Record:
    """One maneuver in the model's signals: inputs (N, m) and the initial state (n,) from the
    fixed values and the data."""

    name: str
    t0: float
    dt: float
    inputs: np.ndarray
    initial_state: np.ndarray


class IntegratedModel:
    """A :class:`~rotorid.model.nonlinear.NonlinearModel` as an identifiable model.

    Args:
        model: the author's model (signals, parameters, derivatives, outputs).
        channels: links from maneuver channels to the model's signals; unlinked signals are
            read from the channel of the same name.
        initial: the initial conditions; estimating some needs ``maneuvers``, given here or
            later through :meth:`for_maneuvers` (``rotorid identify`` does that).
        maneuvers: the maneuvers whose initial states are estimated (their names name the
            parameters; their data give the start values).
        sensitivities: ``"central"``, ``"forward"`` or ``"model"``; default ``"model"`` when
            the model has ``derivative_jacobians`` and ``output_jacobians``, else ``"central"``.
        step: relative finite-difference step: h_k = step · max(|ψ_k|, 1).
        integration: the scheme and sub-steps (:class:`~rotorid.simulation.integrators.Integration`).
        anticipate: with finite differences, let every :meth:`simulate` integrate the
            perturbed parameter vectors too, so that the sensitivities the estimator asks for
            after accepting a step are ready. A vectorised model's time per call hardly grows
            with the rows, so this roughly halves a fit's integrations; turn it off for a model
            whose cost grows with the batch.
    """

    def __init__(self, model, *, channels: ChannelMap = ChannelMap(),
                 initial: InitialConditions = InitialConditions(),
                 maneuvers: ManeuverSet | None = None, sensitivities: str | None = None,
                 step: float = 1e-6, integration: Integration = Integration(),
                 anticipate: bool = True):
        if not isinstance(model, NonlinearModel):
            raise StructureError(f"{type(model).__name__} is not a nonlinear model: it needs "
                                 "signals, parameters, derivatives() and outputs()")
        self.model = model
        self.signals = model.signals
        self.channels = channels
        channels.check(self.signals.all)
        self.initial = initial
        self.step = float(step)
        self.integration = integration
        self.method = sensitivities or ("model" if has_own_jacobians(model) else "central")
        self.anticipate = bool(anticipate) and self.method != "model"
        self._last = None
        self._check_options(maneuvers)
        parameters = tuple(model.parameters)
        self._free = [k for k, p in enumerate(parameters) if not p.fixed]
        self._theta = np.array([p.start for p in parameters], dtype=float)
        self._estimated = self.signals.states.indices(initial.estimated)
        self._maneuver_names = (maneuvers.names if initial.estimated and maneuvers is not None
                                else ())
        self.parameter_names = tuple(parameters[k].name for k in self._free) + tuple(
            f"x0_{m}_{s}" for m in self._maneuver_names for s in initial.estimated)
        self.output_names = self.signals.outputs.names
        self.output_units = self.signals.outputs.units
        self.parameter_units = {p.name: p.unit for p in parameters if p.unit}
        self.parameter_units.update(
            {f"x0_{m}_{s}": self.signals.states[s].unit
             for m in self._maneuver_names for s in initial.estimated})
        self.fixed = {p.name: p.start for p in parameters if p.fixed}
        self._cache: dict[int, tuple[ManeuverSet, list[Record]]] = {}
        self._start_states = (np.concatenate([r.initial_state[self._estimated]
                                              for r in self.records(maneuvers)])
                              if self._maneuver_names else np.zeros(0))

    def _check_options(self, maneuvers):
        if self.method not in SENSITIVITY_METHODS:
            raise StructureError(f"unknown sensitivity method {self.method!r}; use one of "
                                 f"{', '.join(SENSITIVITY_METHODS)}")
        if self.method == "model" and not has_own_jacobians(self.model):
            raise StructureError(f"{type(self.model).__name__} has no derivative_jacobians and "
                                 "output_jacobians; use sensitivities='central' or 'forward'")
        names = [p.name for p in self.model.parameters]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise StructureError(f"parameter {repeated[0]!r} is declared twice; give every "
                                 "parameter its own name")
        if not self.step > 0:
            raise StructureError(f"the finite-difference step must be positive, got {self.step}")
        for name in (*self.initial.fixed, *self.initial.estimated):
            if name not in self.signals.states:
                raise StructureError(f"initial condition for {name!r}, which is not a state; "
                                     f"states: {', '.join(self.signals.states.names)}")

    def for_maneuvers(self, maneuvers: ManeuverSet) -> "IntegratedModel":
        """This model with its estimated initial states (if any) set up for ``maneuvers``: one
        set per maneuver, parameters ``x0_<maneuver>_<state>`` starting from their data."""
        if not self.initial.estimated:
            return self
        return IntegratedModel(self.model, channels=self.channels, initial=self.initial,
                               maneuvers=maneuvers, sensitivities=self.method, step=self.step,
                               integration=self.integration, anticipate=self.anticipate)

    @property
    def columns(self) -> tuple[str, ...]:
        """The data columns the model reads: each signal's linked column, else its name (a
        file reader keeps these, :attr:`rotorid.ingestion.Ingestion.keep_columns`)."""
        linked = {link.signal: link.column for link in self.channels.links}
        return tuple(dict.fromkeys(linked.get(s.name, s.name) for s in self.signals.all))

    # ------------------------------------------------------------ the model protocol
    def initial_values(self) -> np.ndarray:
        """(P,) starts: the free parameters', then the estimated initial states'."""
        return np.concatenate([self._theta[self._free], self._start_states])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        parameters = [self.model.parameters[k] for k in self._free]
        extra = np.full(self._start_states.size, np.inf)
        return (np.concatenate([[p.lower for p in parameters], -extra]),
                np.concatenate([[p.upper for p in parameters], extra]))

    def measured(self, maneuvers: ManeuverSet, columns=None) -> list[np.ndarray]:
        """Measured outputs (N_i, ny) per maneuver, in the output signals' units; with
        ``columns`` (indices into ``output_names``) those outputs only."""
        names = (self.output_names if columns is None
                 else [self.output_names[i] for i in np.atleast_1d(columns)])
        return [self._read(m, names) for m in maneuvers]

    def simulate(self, values, maneuvers: ManeuverSet) -> list[np.ndarray]:
        """Outputs (N_i, ny) per maneuver; non-finite where the simulation blew up.

        With ``anticipate`` the finite-difference sensitivities come from the same batched
        integration and are kept for a following :meth:`sensitivities` at these values.
        """
        if self.anticipate:
            return self.sensitivities(values, maneuvers)[0]
        batch = np.asarray(values, dtype=float)[None, :]
        return [y[:, 0] for y in self._simulate_batch(batch, maneuvers)]

    def sensitivities(self, values, maneuvers: ManeuverSet):
        """Outputs (N_i, ny) and sensitivities (N_i, P, ny) per maneuver (read-only arrays)."""
        values = np.asarray(values, dtype=float)
        last = self._last
        if last is not None and last[0] is maneuvers and np.array_equal(last[1], values):
            return last[2], last[3]
        if self.method == "model":
            outputs, sens = self._exact_sensitivities(values, maneuvers)
        else:
            outputs, sens = self._finite_difference_sensitivities(values, maneuvers)
        for array in (*outputs, *sens):
            array.setflags(write=False)
        self._last = (maneuvers, values.copy(), outputs, sens)
        return outputs, sens

    # ------------------------------------------------------------ data
    def records(self, maneuvers: ManeuverSet) -> list[Record]:
        """Each maneuver's inputs and initial state in the model's signals (cached)."""
        cached = self._cache.get(id(maneuvers))
        if cached is None or cached[0] is not maneuvers:
            cached = (maneuvers, [self._record(m) for m in maneuvers])
            self._cache[id(maneuvers)] = cached
        return cached[1]

    def _read(self, maneuver: Maneuver, names) -> np.ndarray:
        """The signals called ``names`` from ``maneuver``, (N, len(names)), signal units."""
        columns, units = maneuver_columns(maneuver, self.signals)
        return self.channels.read(columns, self.signals.all, names,
                                  f"maneuver {maneuver.name!r}", units)

    def _record(self, maneuver: Maneuver) -> Record:
        states = self.signals.states
        from_data = [s for s in states.names if s not in self.initial.fixed]
        columns, _ = maneuver_columns(maneuver, self.signals)
        unmeasured = [s for s in from_data
                      if self.channels.link(s) is None and s not in columns]
        if unmeasured:
            how = ("; with it in estimated as well, the fit estimates it from there"
                   if unmeasured[0] in self.initial.estimated else "")
            raise StructureError(
                f"state {unmeasured[0]!r} starts each maneuver from the data, but maneuver "
                f"{maneuver.name!r} has no column for it: give its start, "
                f"InitialConditions(fixed={{{unmeasured[0]!r}: 0.0}}){how}, or link the column "
                f"that holds it in {self.channels.source}")
        initial = np.array([self.initial.fixed.get(s, np.nan) for s in states.names])
        initial[states.indices(from_data)] = self._read(maneuver, from_data)[0]
        return Record(maneuver.name, float(maneuver.time[0]), maneuver.dt,
                       self._read(maneuver, self.signals.inputs.names), initial)

    # ------------------------------------------------------------ simulation
    def expand(self, batch: np.ndarray, records: list[Record]):
        """Model parameters (B, p) and initial states (M, B, n) of B estimated vectors ψ."""
        theta = np.tile(self._theta, (batch.shape[0], 1))
        theta[:, self._free] = batch[:, :len(self._free)]
        states = np.stack([np.tile(r.initial_state, (batch.shape[0], 1)) for r in records])
        if self._estimated:
            if not self._maneuver_names:
                raise StructureError("the initial states are estimated per maneuver: give the "
                                     "model its maneuvers first, model.for_maneuvers(maneuvers)")
            names = [r.name for r in records]
            unknown = sorted(set(names) - set(self._maneuver_names))
            if unknown:
                raise StructureError(f"maneuver {unknown[0]!r} has no estimated initial state; "
                                     f"the model was built for {', '.join(self._maneuver_names)}")
            per_maneuver = batch[:, len(self._free):].reshape(
                batch.shape[0], len(self._maneuver_names), len(self._estimated))
            for i, name in enumerate(names):
                states[i][:, self._estimated] = per_maneuver[:, self._maneuver_names.index(name)]
        return theta, states

    def _groups(self, records):
        """Indices of the records sharing a sample time."""
        groups: dict[float, list[int]] = {}
        for i, r in enumerate(records):
            groups.setdefault(round(r.dt, 12), []).append(i)
        return groups.values()

    def stacked(self, records, members, theta, states):
        """Time-major inputs (N, R, m), t0 (R,), x0 (R, n) and θ (R, p) of R = members × B
        rows; shorter maneuvers hold their last input to the longest one's length."""
        n = max(records[i].inputs.shape[0] for i in members)
        b = theta.shape[0]
        inputs = np.concatenate([
            np.repeat(np.pad(records[i].inputs, ((0, n - records[i].inputs.shape[0]), (0, 0)),
                             mode="edge")[:, None, :], b, axis=1) for i in members], axis=1)
        t0 = np.repeat([records[i].t0 for i in members], b)
        x0 = np.concatenate([states[i] for i in members])
        return inputs, t0, x0, np.tile(theta, (len(members), 1))

    def _outputs(self, t0, dt, states, inputs, theta, jacobians=False):
        """Outputs (N, R, ny) at every sample, from one call on all samples stacked."""
        n, rows = states.shape[:2]
        t = (t0[None, :] + dt * np.arange(n)[:, None]).reshape(-1)
        flat = (t, states.reshape(n * rows, -1), inputs.reshape(n * rows, -1),
                np.broadcast_to(theta, (n,) + theta.shape).reshape(n * rows, -1))
        if jacobians:
            h_x, h_theta = self.model.output_jacobians(*flat)
            return (np.reshape(h_x, (n, rows) + np.shape(h_x)[1:]),
                    np.reshape(h_theta, (n, rows) + np.shape(h_theta)[1:]))
        with np.errstate(all="ignore"):
            return np.reshape(self.model.outputs(*flat), (n, rows, -1))

    def _simulate_batch(self, batch: np.ndarray, maneuvers: ManeuverSet) -> list[np.ndarray]:
        """Outputs (N_i, B, ny) per maneuver for B estimated vectors ψ (batch (B, P))."""
        records = self.records(maneuvers)
        theta, states = self.expand(batch, records)
        result = [None] * len(records)
        b = batch.shape[0]
        for members in self._groups(records):
            inputs, t0, x0, rows_theta = self.stacked(records, members, theta, states)
            dt = records[members[0]].dt
            x = integrate(self.model.derivatives, t0, dt, x0, inputs, rows_theta,
                          maneuvers.hold, self.integration)
            y = self._outputs(t0, dt, x, inputs, rows_theta)
            for j, i in enumerate(members):
                result[i] = y[:records[i].inputs.shape[0], j * b:(j + 1) * b]
        return result

    # ------------------------------------------------------------ sensitivities
    def _finite_difference_sensitivities(self, values, maneuvers):
        lower, upper = self.bounds()
        h = self.step * np.maximum(np.abs(values), 1.0)
        eye = np.eye(values.size)
        up = np.minimum(values + h, upper)
        if self.method == "central":
            down = np.maximum(values - h, lower)
        else:
            up = np.where(values + h > upper, values - h, up)
            down = values
        batch = np.vstack([values, values + eye * (up - values),
                           values + eye * (down - values)])
        width = up - down
        outputs, sens = [], []
        p = values.size
        for y in self._simulate_batch(batch, maneuvers):
            outputs.append(y[:, 0])
            sens.append((y[:, 1:1 + p] - y[:, 1 + p:]) / width[None, :, None])
        return outputs, sens

    def _exact_sensitivities(self, values, maneuvers):
        records = self.records(maneuvers)
        theta, states = self.expand(values[None, :], records)
        p_free, p = len(self._free), values.size
        theta_tangent = np.zeros((self._theta.size, p))
        theta_tangent[self._free, np.arange(p_free)] = 1.0
        outputs, sens = [None] * len(records), [None] * len(records)
        for members in self._groups(records):
            inputs, t0, x0, rows_theta = self.stacked(records, members, theta, states)
            x0_tangent = np.zeros(x0.shape + (p,))
            for j, i in enumerate(members):
                first = p_free + len(self._estimated) * (
                    self._maneuver_names.index(records[i].name) if self._estimated else 0)
                for k, state in enumerate(self._estimated):
                    x0_tangent[j, state, first + k] = 1.0
            dt = records[members[0]].dt
            x, s = integrate_with_tangents(self.model.derivatives,
                                           self.model.derivative_jacobians, t0, dt, x0,
                                           x0_tangent, inputs, rows_theta, theta_tangent,
                                           maneuvers.hold, self.integration)
            y = self._outputs(t0, dt, x, inputs, rows_theta)
            h_x, h_theta = self._outputs(t0, dt, x, inputs, rows_theta, jacobians=True)
            dy = h_x @ s + h_theta @ theta_tangent             # (N, R, ny, P)
            for j, i in enumerate(members):
                n = records[i].inputs.shape[0]
                outputs[i] = y[:n, j]
                sens[i] = dy[:n, j].transpose(0, 2, 1)
        return outputs, sens


def maneuver_columns(maneuver: Maneuver, signals: ModelSignals
                     ) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """A maneuver's channels by name (extra channels included), and the units of those its
    unit system fixes: its outputs, by the helicopter channel's kind or the kind ``signals``
    declare (controls and extra channels carry whatever unit the data have)."""
    system = unit_system(maneuver.units)
    declared = {s.name: s.kind for s in signals.all}
    kinds = {c: CHANNEL_KINDS.get(c, declared.get(c)) for c in maneuver.output_names}
    names = maneuver.channel_names + tuple(maneuver.extra_channels)
    return ({c: maneuver.channel(c) for c in names},
            {c: system.unit_of(kind) for c, kind in kinds.items()
             if kind not in (None, "control")})
