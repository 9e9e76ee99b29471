"""Parameters of each maneuver in the filter: initial states and output biases.

A record's initial state is the filter's start x̃_0; by default it is the record's own (its
measured initial values, zero for the disturbance and gust states). Estimated, it is one
parameter per maneuver and filter state (``x0_<maneuver>_<state>``, a disturbance state named
``d_<state>``, a gust ``g_<state>``). A slow gust is nearly a constant over a record, and a
filter started at zero gust reads its first seconds wrongly; its initial value is then the
thing to estimate. An output bias is a constant per maneuver and output
(``bias_<maneuver>_<output>``, the output's unit) added to the model's output: the filter
subtracts it from the measurement before it corrects.

Their sensitivities need no complex step. With the closed-loop step A = Φ(I − KH) and ΦK of
the predictor form (:mod:`.kalman`), the same for every maneuver,

    ∂x̃_n/∂x0 = Aⁿ E          ∂ν_n/∂x0 = −H Aⁿ E                (E selects the states)
    ∂x̃_n+1/∂b = A ∂x̃_n − ΦK   ∂ν_n/∂b = −I − H ∂x̃_n,  ∂x̃_0/∂b = 0

so one recursion over the longest record gives the pattern Z_n (p, q) of every maneuver,
which reads it up to its own length. B does not depend on them.
"""

from __future__ import annotations

import attrs
import numpy as np
from rotorid.errors import EstimationError
from rotorid.model.parameter_units import rate_unit
from rotorid.model.structure import ModelStructure


def filter_state_names(kept: tuple[str, ...], disturbances: tuple[str, ...],
                       gusts: tuple[str, ...]) -> tuple[str, ...]:
    """Names of the filter states an initial value can be given for: the structure's states
    the outputs see (``kept``), then ``d_<state>`` per disturbance and ``g_<state>`` per
    gust."""
    return kept + tuple(f"d_{s}" for s in disturbances) + tuple(f"g_{s}" for s in gusts)


def initial_state_option(value) -> bool | tuple[str, ...]:
    """The ``initial_states`` option as given: a bool, or the names as a tuple."""
    if isinstance(value, bool):
        return value
    return (value,) if isinstance(value, str) else tuple(value)


def chosen_initial_states(option, available: tuple[str, ...],
                          structure_states: tuple[str, ...]) -> tuple[str, ...]:
    """The filter states whose initial values are estimated: none (False), all ``available``
    (True) or the named ones, checked, in the order of ``available``."""
    names = initial_state_option(option)
    if names is False:
        return ()
    if names is True:
        return available
    unknown = [n for n in names if n not in available]
    if unknown:
        unseen = [n for n in unknown if n in structure_states]
        reason = (f"{', '.join(unseen)} no output sees (its initial value changes no "
                  f"innovation); " if unseen else "")
        raise EstimationError(f"initial_states names {', '.join(unknown)}: {reason}the "
                              f"filter's states are {', '.join(available)}")
    return tuple(n for n in available if n in names)


@attrs.frozen(eq=False)
class ManeuverParameters:
    """The per-maneuver parameters of one problem.

    Attributes:
        maneuvers: the maneuvers' names, in the records' order.
        states: filter states with estimated initial values (:func:`filter_state_names`).
        state_columns: their columns in the filter's companion state, counted from the
            kept structure states (non-negative) or from the end (the coloured states,
            negative).
        outputs: the outputs with estimated biases (all or none).
    """

    maneuvers: tuple[str, ...]
    states: tuple[str, ...]
    state_columns: tuple[int, ...]
    outputs: tuple[str, ...]

    @classmethod
    def of(cls, maneuvers, available: tuple[str, ...], n_coloured: int, states,
           output_names: tuple[str, ...], biases: bool) -> "ManeuverParameters":
        n_kept = len(available) - n_coloured
        columns = tuple(i if i < n_kept else i - len(available)
                        for i in (available.index(s) for s in states))
        return cls(tuple(maneuvers), tuple(states), columns,
                   tuple(output_names) if biases else ())

    @property
    def per_maneuver(self) -> int:
        """Parameters per maneuver, q."""
        return len(self.states) + len(self.outputs)

    @property
    def size(self) -> int:
        return self.per_maneuver * len(self.maneuvers)

    @property
    def names(self) -> tuple[str, ...]:
        """Per maneuver its initial values, then its biases."""
        return tuple(name for m in self.maneuvers
                     for name in ([f"x0_{m}_{s}" for s in self.states]
                                  + [f"bias_{m}_{o}" for o in self.outputs]))

    def units(self, structure: ModelStructure) -> dict[str, str]:
        """Each parameter's unit: a state's, a disturbance's acceleration unit, an output's."""
        signals = structure.signals

        def unit(state: str) -> str:
            if state.startswith("d_"):
                return rate_unit(signals.states[state[2:]].unit)
            return signals.states[state[2:] if state.startswith("g_") else state].unit

        units = {f"x0_{m}_{s}": unit(s) for m in self.maneuvers for s in self.states}
        outputs = dict(zip(structure.outputs, signals.outputs.units))
        units.update({f"bias_{m}_{o}": outputs[o] for m in self.maneuvers for o in self.outputs})
        return units

    def start(self, x0: np.ndarray, kept_indices: np.ndarray) -> np.ndarray:
        """Start values: each record's initial value of the kept structure states (``x0``
        (M, n) over the structure's states), zero for the coloured states and the biases."""
        start = np.zeros((len(self.maneuvers), self.per_maneuver))
        for j, column in enumerate(self.state_columns):
            if column >= 0:
                start[:, j] = x0[:, kept_indices[column]]
        return start.ravel()

    def split(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(initial values (M, k), biases (M, p_b)) of the per-maneuver part of a vector."""
        values = np.asarray(values, dtype=float).reshape(len(self.maneuvers), self.per_maneuver)
        return values[:, : len(self.states)], values[:, len(self.states):]

    def filter_start(self, values, default: np.ndarray) -> np.ndarray:
        """The filter's start x̃_0 (M, S): ``default`` with the estimated initial values."""
        start = np.array(default, dtype=float)
        initial, _ = self.split(values)
        start[:, list(self.state_columns)] = initial
        return start

    def output_biases(self, values, n_outputs: int) -> np.ndarray:
        """Biases (M, p) of every output (zero where none is estimated)."""
        _, biases = self.split(values)
        return biases if self.outputs else np.zeros((len(self.maneuvers), n_outputs))

    def patterns(self, closed_loop: np.ndarray, output: np.ndarray, correction: np.ndarray,
                 n_samples: int) -> np.ndarray:
        """Z (N, p, q): the innovations' sensitivity at sample n to one maneuver's parameters
        (module docstring), from A = ``closed_loop`` (S, S), H = ``output`` (p, S) and
        ΦK = ``correction`` (S, p)."""
        size, n_y = closed_loop.shape[0], output.shape[0]
        select = np.zeros((size, len(self.states)))
        select[list(self.state_columns), np.arange(len(self.states))] = 1.0
        bias_rows = list(range(n_y)) if self.outputs else []
        states = np.concatenate([select, np.zeros((size, len(bias_rows)))], axis=1)
        forcing = np.concatenate([np.zeros((size, len(self.states))),
                                  -correction[:, bias_rows]], axis=1)
        direct = np.zeros((n_y, self.per_maneuver))
        direct[bias_rows, len(self.states) + np.arange(len(bias_rows))] = -1.0
        patterns = np.empty((n_samples, n_y, self.per_maneuver))
        for n in range(n_samples):
            patterns[n] = direct - output @ states
            states = closed_loop @ states + forcing
        return patterns
