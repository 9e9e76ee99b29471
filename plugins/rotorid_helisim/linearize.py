"""Linearisation of the truth model about a trim by central differences.

* ``full=True``: rigid body (Padfield order u w q θ v p φ r) + flap (β0 β1c β1s and rates) +
  inflow states (main and tail rotor); heading and actuators are left out, the controls are the
  blade angles themselves. The main rotor's uniform inflow is the induced velocity
  ``vi`` = λ0·ΩR (down the shaft, in the unit system's velocity unit), the state of the
  ``hybrid-inflow`` template (docs/hybrid.md); harmonic and tail-rotor inflow stay ratios.
* ``full=False``: the 6-DoF model with the rotor and inflow states residualised (quasi-static),
  A = A_bb − A_br·A_rr⁻¹·A_rb and B = B_b − A_br·A_rr⁻¹·B_r (reference §2.6). This is Padfield's
  form: ṗ and ṙ rows inertia-coupled (primed), A including the gravity and kinematic terms.

Units: ``"si"`` gives m/s, rad, rad/s and controls per rad of blade angle (θ0, θ1s, θ1c, θ0T);
``"flight-test"`` gives ft/s, deg, deg/s and controls per % of stick travel (long, lat, coll, ped)
through the stick mixing (rotor angles in deg and deg/s, ``vi`` in ft/s, inflow ratios
unchanged).
"""

from __future__ import annotations

import attrs
import numpy as np
from rotorid.errors import StructureError
from rotorid.model.residualisation import residualise
from rotorid.units import (
    FLIGHT_TEST,
    SI,
    channel_scale,
    convert_state_space,
    unit_system,
)

from .model import ROTOR, Bo105Model
from .parameters import BLADE_ANGLES, STICKS
from .trim import Trim

#: Rigid-body states in Padfield's (and the identified model's) order.
PADFIELD_STATES = ("u", "w", "q", "theta", "v", "p", "phi", "r")

#: Central-difference step per state kind (SI).
_STEPS = {"u": 1e-2, "v": 1e-2, "w": 1e-2, "p": 1e-3, "q": 1e-3, "r": 1e-3, "phi": 1e-3,
          "theta": 1e-3, "beta0": 1e-4, "beta1c": 1e-4, "beta1s": 1e-4, "beta0_dot": 1e-3,
          "beta1c_dot": 1e-3, "beta1s_dot": 1e-3}
_INFLOW_STEP = 1e-5
_BLADE_STEP = 1e-4


@attrs.frozen(eq=False)
class LinearModel:
    """ẋ = A·x + B·u about a trim.

    Attributes:
        states: state names (rows/columns of A).
        controls: control names (columns of B).
        A: (n, n); B: (n, m).
        eigenvalues: (n,) eigenvalues of A, sorted by real part then imaginary part.
        units: ``"si"`` or ``"flight-test"``.
        airspeed_kt: trim airspeed.
        full: whether the rotor and inflow states are kept.
    """

    states: tuple
    controls: tuple
    A: np.ndarray
    B: np.ndarray
    eigenvalues: np.ndarray
    units: str
    airspeed_kt: float
    full: bool

    def derivative(self, row: str, column: str) -> float:
        """Entry of A or B by state/control names, e.g. ``derivative("q", "u")`` for M_u."""
        i = self.states.index(row)
        if column in self.states:
            return float(self.A[i, self.states.index(column)])
        if column in self.controls:
            return float(self.B[i, self.controls.index(column)])
        raise StructureError(f"unknown column {column!r}; states {self.states}, "
                             f"controls {self.controls}")

    def as_dict(self) -> dict:
        """JSON-ready: states, controls, A, B (nested lists), eigenvalues as [re, im] pairs."""
        return {
            "airspeed_kt": self.airspeed_kt,
            "units": self.units,
            "full": self.full,
            "states": list(self.states),
            "controls": list(self.controls),
            "A": self.A.tolist(),
            "B": self.B.tolist(),
            "eigenvalues": [[float(e.real), float(e.imag)] for e in self.eigenvalues],
        }


def _sorted_eigenvalues(a):
    eig = np.linalg.eigvals(a)
    return eig[np.lexsort((eig.imag, eig.real))]


def jacobians(model: Bo105Model, trim: Trim):
    """Central-difference Jacobians of the full model at ``trim``.

    Returns (names, A, B): the state names kept (Padfield rigid body, rotor, inflow), A (n, n)
    and B (n, 4) per rad of blade angle (θ0, θ1s, θ1c, θ0T).
    """
    names = PADFIELD_STATES + ROTOR + tuple(n for n in model.state_names
                                            if n.startswith("lambda"))
    columns = [model.index[n] for n in names] + [model.index[n] for n in BLADE_ANGLES]
    steps = np.array([_STEPS.get(n, _INFLOW_STEP) for n in names] + [_BLADE_STEP] * 4)
    n_col = len(columns)
    x = np.repeat(np.asarray(trim.state, dtype=float)[None, :], 2 * n_col, axis=0)
    rows = np.arange(n_col)
    x[rows, columns] += steps
    x[n_col + rows, columns] -= steps
    stick = np.repeat(np.asarray(trim.stick, dtype=float)[None, :], 2 * n_col, axis=0)
    dx = model.derivatives(x, stick)[:, [model.index[n] for n in names]]
    jac = ((dx[:n_col] - dx[n_col:]) / (2.0 * steps[:, None])).T
    n = len(names)
    return names, jac[:, :n], jac[:, n:]


#: The full model's name of the main rotor's uniform inflow, as an induced velocity.
INDUCED_VELOCITY = "vi"


def _state_scale(names, target, tip_speed: float):
    """Per-state factors from the model's states (SI, λ0 as a ratio) to ``target``: rigid
    body through rotorid.units, rotor angles as angles, ``vi`` = λ0·ΩR as a velocity."""
    rigid = [n for n in names if n in PADFIELD_STATES]
    scale = dict(zip(rigid, channel_scale(rigid, target)))
    for n in names:
        if n == INDUCED_VELOCITY:
            scale[n] = tip_speed * target.length_per_metre
        elif n not in scale:
            scale[n] = target.angle_per_radian if n.startswith("beta") else 1.0
    return np.array([scale[n] for n in names])


def linearize(model: Bo105Model, trim: Trim, full: bool = False, units: str = "si") -> LinearModel:
    """Linear model about ``trim`` (see the module docstring for the forms and units).

    Args:
        model: the truth model that was trimmed.
        trim: from :func:`~.trim.trim`.
        full: keep the flap and inflow states (True) or residualise them (False).
        units: ``"si"`` (per rad of blade angle) or ``"flight-test"`` (per % stick).
    """
    system = unit_system(units)
    if tuple(trim.state_names) != model.state_names:
        raise StructureError("linearize: the trim belongs to a model with other states "
                             "(different inflow option); trim this model first")
    names, a, b = jacobians(model, trim)
    if not full:
        a, b = residualise(a, b, names, PADFIELD_STATES)
        names = PADFIELD_STATES
    controls = BLADE_ANGLES
    if system is FLIGHT_TEST:
        b = b @ model.config.mixing.matrix  # per % stick
        controls = STICKS
    if full:
        names = tuple(INDUCED_VELOCITY if n == "lambda0" else n for n in names)
        s = _state_scale(names, system, model.config.tip_speed)
        a = a * s[:, None] / s[None, :]
        b = b * s[:, None]
    elif system is FLIGHT_TEST:
        a, b = convert_state_space(a, b, names, controls, system, SI)
    eigenvalues = _sorted_eigenvalues(a)
    for array in (a, b, eigenvalues):
        array.setflags(write=False)
    return LinearModel(states=tuple(names), controls=tuple(controls), A=a, B=b,
                       eigenvalues=eigenvalues, units=system.name,
                       airspeed_kt=trim.airspeed_kt, full=bool(full))
