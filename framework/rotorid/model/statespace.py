"""An identified model as a named state-space system: A, B, C, D with signal names and units.

:func:`state_space` assembles ``ẋ = A x + B u``, ``y = C x + D u`` from a structure and its
parameter values and keeps only what the model can produce: the controls that drive a state or
an output, the states those controls reach and the outputs that depend on them. A decoupled
longitudinal model thus has the states ``u w q theta``, not eight states of which four are
spurious integrators at s = 0.

Delays are kept as data (:class:`DelayedTerm`: which derivative, which equation, which signal,
how long). With ``pade_order = n`` each distinct delayed signal also gets an n-th order Padé
approximation of ``e^(−sτ)`` as extra states, so that the system alone reproduces the delayed
model's response up to about ``ω ≈ n/τ``; without it, A, B, C, D are the model with every
delay set to zero.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import attrs
import numpy as np

from rotorid.errors import StructureError
from rotorid.frozen import readonly_array
from rotorid.model.derivatives import delay_parameter
from rotorid.model.structure import ModelStructure


def _readonly(value) -> np.ndarray:
    return readonly_array(np.asarray(value, dtype=float) + 0.0)   # + 0.0: no negative zeros


@attrs.frozen
class DelayedTerm:
    """One delayed derivative term: ``equation``'s derivative ``derivative`` acts on
    ``source`` (a state or control) ``seconds`` late."""

    derivative: str
    equation: str
    source: str
    seconds: float


@attrs.frozen
class RecordedChannel:
    """How a signal is read from the recorded data: ``signal = factor · column + offset`` in
    the signal's unit (a channel map's scale, offset and unit conversion in one, e.g. a stick
    recorded in inches read in %, and the trim the identification records had removed, so
    that the signal is the model's perturbation)."""

    signal: str
    column: str
    factor: float
    offset: float


def recorded_channels(channel_map, units: Mapping[str, str],
                      trim: Mapping[str, float] | None = None) -> tuple[RecordedChannel, ...]:
    """The links of ``channel_map`` (:class:`rotorid.model.signals.ChannelMap`) for the
    signals of ``units`` (name → the system's unit), as :class:`RecordedChannel`s; a control
    whose unit does not convert (% of travel, a unit of one's own) keeps the link's. ``trim``
    (signal → value in the system's unit) is taken off each offset; a trimmed signal without
    a link is read from the column of its own name."""
    from rotorid.errors import SignalError
    from rotorid.units import conversion_factor

    trim = {k: float(v) for k, v in (trim or {}).items() if k in units}
    found = []
    for link in channel_map.links:
        if link.signal not in units:
            continue
        try:
            unit_factor = conversion_factor(link.unit, units[link.signal])
        except SignalError:
            unit_factor = 1.0
        found.append(RecordedChannel(link.signal, link.column, link.scale * unit_factor,
                                     link.offset * unit_factor - trim.get(link.signal, 0.0)))
    linked = {channel.signal for channel in found}
    found += [RecordedChannel(name, name, 1.0, -value) for name, value in trim.items()
              if name not in linked]
    return tuple(found)


@attrs.frozen(eq=False)
class NamedStateSpace:
    """``ẋ = A x + B u``, ``y = C x + D u`` with named signals (immutable).

    Shapes: ``a`` (n, n), ``b`` (n, m), ``c`` (p, n), ``d`` (p, m) for n ``states``, m
    ``inputs`` and p ``outputs``. ``units`` maps every signal name to its unit label (the
    structure's unit system, e.g. ``deg/s``; controls in ``%``). ``delays`` lists every delayed
    term; ``pade_order`` is the order of their realisation among the states, 0 when the
    matrices ignore them. ``channels`` says how the inputs and outputs are read from the
    recorded data, where a channel map links them (:meth:`with_channels`).
    """

    a: np.ndarray = attrs.field(converter=_readonly)
    b: np.ndarray = attrs.field(converter=_readonly)
    c: np.ndarray = attrs.field(converter=_readonly)
    d: np.ndarray = attrs.field(converter=_readonly)
    states: tuple[str, ...] = attrs.field(converter=tuple)
    inputs: tuple[str, ...] = attrs.field(converter=tuple)
    outputs: tuple[str, ...] = attrs.field(converter=tuple)
    units: Mapping[str, str] = attrs.field(converter=dict)
    unit_system: str
    delays: tuple[DelayedTerm, ...] = attrs.field(default=(), converter=tuple)
    pade_order: int = 0
    channels: tuple[RecordedChannel, ...] = attrs.field(default=(), converter=tuple)

    def with_channels(self, channel_map, trim: Mapping[str, float] | None = None
                      ) -> "NamedStateSpace":
        """This system with the links of ``channel_map`` that read its inputs and outputs,
        less ``trim`` (signal → value in the system's units, :func:`recorded_channels`)."""
        units = {n: self.units[n] for n in self.inputs + self.outputs}
        return attrs.evolve(self, channels=recorded_channels(channel_map, units, trim))

    def __repr__(self) -> str:
        delays = (f", {len(self.delays)} delays" + (f" (Padé order {self.pade_order})"
                                                   if self.pade_order else " (not realised)")
                  if self.delays else "")
        return (f"NamedStateSpace({len(self.states)} states {' '.join(self.states)}; inputs "
                f"{' '.join(self.inputs)}; outputs {' '.join(self.outputs)}; "
                f"{self.unit_system} units{delays})")

    def to_scipy(self):
        """The system as a :class:`scipy.signal.StateSpace` (which keeps no names)."""
        from scipy import signal

        return signal.StateSpace(self.a, self.b, self.c, self.d)

    def as_dict(self) -> dict:
        """JSON-ready record: matrices as nested lists, signals with their units, delays."""
        def signals(names):
            return [{"name": n, "unit": self.units[n]} for n in names]

        return {"unit_system": self.unit_system,
                "states": signals(self.states), "inputs": signals(self.inputs),
                "outputs": signals(self.outputs),
                "A": self.a.tolist(), "B": self.b.tolist(), "C": self.c.tolist(),
                "D": self.d.tolist(),
                "delays": [attrs.asdict(term) for term in self.delays],
                "pade_order": self.pade_order,
                "channels": [attrs.asdict(channel) for channel in self.channels]}


def pade_realisation(seconds: float, order: int):
    """State-space realisation (A, B, C, D) of the [order/order] Padé approximation of
    ``e^(−s·seconds)``, shapes (n, n), (n, 1), (1, n), (1, 1).

    The realisation is built for ``σ = s·seconds`` and rescaled in time, so that its states
    carry the unit of the delayed signal and its coefficients stay of order one for any delay.
    """
    from scipy import signal

    if order < 1 or not seconds > 0:
        raise StructureError(f"a Padé realisation needs order ≥ 1 and a delay > 0 s, got "
                             f"order {order} and {seconds!r} s")
    coefficients = [math.factorial(2 * order - k) * math.factorial(order)
                    / (math.factorial(2 * order) * math.factorial(k)
                       * math.factorial(order - k)) for k in range(order + 1)]
    numerator = [c * (-1) ** k for k, c in enumerate(coefficients)][::-1]
    denominator = coefficients[::-1]
    a, b, c, d = signal.tf2ss(numerator, denominator)
    return a / seconds, b / seconds, c, d


def state_space(structure: ModelStructure, values=None, *, pade_order: int = 0
                ) -> NamedStateSpace:
    """The model at ``values`` as a :class:`NamedStateSpace` of the signals it can produce.

    Args:
        structure: the identified structure; values: parameter vector, name → value mapping
            (delays as ``tau_<derivative>``) or None for the initial values.
        pade_order: 0 keeps the delays as data only; n ≥ 1 adds an n-th order Padé
            realisation per delayed signal (states ``tau_<derivative>_1 … _n``).
    Raises:
        StructureError: no control drives a state or an output.
    """
    if pade_order < 0:
        raise StructureError(f"pade_order must be 0 (delays as data) or a positive order, got "
                             f"{pade_order}")
    table = structure.terms(values)
    delays = tuple(DelayedTerm(d.name, structure.equation_of(d), d.variable, float(tau))
                   for d, tau in zip(structure.derivatives, table.delay) if tau > 0)
    a, b, c, d, names = _assemble(structure, table, pade_order)
    states, controls, outputs = structure.states, structure.controls, structure.outputs
    columns = [j for j in range(len(controls)) if np.any(b[:, j]) or np.any(d[:, j])]
    if not columns:
        raise StructureError("no control drives a state or an output of this model; give it "
                             "control derivatives (X_long, M_long …)")
    rows, kept = _produced(a, b, c, d, columns)
    units = {signal.name: signal.unit for signal in structure.signals.all}
    units.update({name: units[source] for name, source in names[len(states):]})
    return NamedStateSpace(
        a[np.ix_(rows, rows)], b[np.ix_(rows, columns)], c[np.ix_(kept, rows)],
        d[np.ix_(kept, columns)], [names[i][0] for i in rows], [controls[j] for j in columns],
        [outputs[i] for i in kept], units, structure.units.name, delays, pade_order)


def responding_outputs(structure: ModelStructure, values=None) -> dict[str, tuple[str, ...]]:
    """Control → the outputs that respond to it at all; an output missing from a control's
    list is identically zero in the response to that control (a decoupled model)."""
    a, b, c, d, _ = _assemble(structure, structure.terms(values), 0)
    return {control: tuple(structure.outputs[i] for i in _produced(a, b, c, d, [j])[1])
            for j, control in enumerate(structure.controls)}


def _produced(a, b, c, d, columns) -> tuple[list[int], list[int]]:
    """The states the input ``columns`` reach and the outputs that depend on them."""
    rows = _reachable(a, b[:, columns])
    return rows, [i for i in range(c.shape[0]) if np.any(c[i, rows]) or np.any(d[i, columns])]


def _assemble(structure: ModelStructure, table, pade_order: int):
    """Full A, B, C, D (the structure's n states plus the Padé states) and (name, source) of
    every state."""
    n_states = structure.n_states
    known = structure.known_terms()
    a, c, d = known.a.copy(), known.c.copy(), known.d.copy()
    b = np.zeros((n_states, structure.n_controls))
    groups: dict[tuple[int, float], list] = {}
    for derivative, eq, src, gain, tau, out, weight in zip(
            structure.derivatives, table.equation, table.source, table.gain, table.delay,
            table.output, table.weight):
        if pade_order and tau > 0:
            groups.setdefault((int(src), float(tau)), []).append(
                (derivative.name, eq, gain, (out, weight)))
            continue
        _add(a, b, c, d, eq, src, (out, weight), gain, n_states, state_gain=None)
    names = [(s, s) for s in structure.states]
    sources = structure.states + structure.controls
    for (src, tau), terms in groups.items():
        fa, fb, fc, fd = pade_realisation(tau, pade_order)
        first = a.shape[0]
        label = "+".join(name for name, *_ in terms)
        names += [(f"{delay_parameter(label)}_{k}", sources[src])
                  for k in range(1, pade_order + 1)]
        a = np.pad(a, ((0, pade_order), (0, pade_order)))
        b = np.pad(b, ((0, pade_order), (0, 0)))
        c = np.pad(c, ((0, 0), (0, pade_order)))
        block = slice(first, first + pade_order)
        a[block, block] = fa
        if src < n_states:
            a[block, src] = fb[:, 0]
        else:
            b[block, src - n_states] = fb[:, 0]
        for _, eq, gain, out in terms:
            _add(a, b, c, d, eq, src, out, gain * fd[0, 0], n_states,
                 state_gain=(block, gain * fc[0]))
    return a, b, c, d, names


def _add(a, b, c, d, eq, src, reader, gain, n_states: int, state_gain) -> None:
    """Add a term ``gain·source`` to equation ``eq`` (and, weighted, to the output of
    ``reader = (output, weight)`` when the output is ≥ 0), plus ``state_gain = (columns, row)``
    on the Padé states of a delayed source; sources below ``n_states`` are states, the others
    controls."""
    out, weight = reader
    targets = [(a, b, eq, 1.0)] + ([(c, d, out, weight)] if out >= 0 else [])
    for states, controls, row, scale in targets:
        if src < n_states:
            states[row, src] += scale * gain
        else:
            controls[row, src - n_states] += scale * gain
        if state_gain is not None:
            states[row, state_gain[0]] += scale * state_gain[1]


def _reachable(a: np.ndarray, b: np.ndarray) -> list[int]:
    """Indices of the states reachable from the inputs through the nonzero pattern of A and B
    (structural controllability), in order."""
    reached = set(np.flatnonzero(np.any(b != 0, axis=1)).tolist())
    frontier = list(reached)
    while frontier:
        j = frontier.pop()
        for i in np.flatnonzero(a[:, j]).tolist():
            if i not in reached:
                reached.add(i)
                frontier.append(i)
    return sorted(reached)


__all__ = ["DelayedTerm", "NamedStateSpace", "pade_realisation", "responding_outputs",
           "state_space"]
