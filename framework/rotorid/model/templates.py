"""Structure templates: the states, inputs, outputs, equations and known terms of a linear model.

A template fixes the shape of a :class:`~rotorid.model.structure.ModelStructure`: its states,
controls (inputs) and outputs in the order of its arrays, its *equations* (derivative letter →
the state whose equation the letter's derivatives drive), the *variables* a derivative may
multiply, and its *known terms*. The linear model is::

    ẋ = A0·x + Σ_terms                 (each term: derivative × variable, possibly delayed)
    y = C0·x + D0·u + W·Σ_terms        (W: weight of each equation's term sum in each output)

so an accelerometer reads the force derivatives' sum (W = 1 on its equation), ``q_dot`` the
pitch equation's, and ``alpha``'s gains on u and w are known C0 coefficients. :class:`KnownTerms` holds
A0, C0, D0 and W for one flight condition and unit system. A known control term is a fixed
derivative (``[derivatives.M_elevator] fixed = …``). Each equation's term sum may be read by
one output at most (the sensitivities' fast path relies on it).

Shipped templates (rigid body about straight trimmed flight; known gravity and kinematic terms
in the structure's unit system, :func:`rigid_body_terms`):

* ``six-dof`` (the paper's, default): states ``u w q theta v p phi r``, controls
  ``long lat coll ped``, outputs ``ax az q theta ay p phi r``; 60 derivatives;
* ``longitudinal`` / ``lateral``: the helicopter's longitudinal (``u w q theta``; ``long coll``;
  ``ax az q theta``) and lateral-directional (``v p phi r``; ``lat ped``; ``ay p phi r``)
  subsets, 15 derivatives each;
* ``fixed-wing-longitudinal``: states ``u w q theta``, controls ``elevator throttle``, outputs
  ``u alpha q theta q_dot ax az`` (Δα = (u0·Δw − w0·Δu)/(u0² + w0²), w/U0 at α0 = 0;
  ``u`` the body-axis velocity, not the airspeed), 15 derivatives;
* ``fixed-wing-lateral``: states ``v p phi r``, controls ``aileron rudder``, outputs
  ``beta p phi r ay`` (Δβ = Δv/V0), 15 derivatives;
* ``hybrid``: the six-dof model plus the rotor's tip-path-plane tilts ``beta1c beta1s`` as
  first-order states driven by the equations ``Bc`` and ``Bs``, with the known rate feedback
  β̇1c = q, β̇1s = p (docs/hybrid.md); 96 derivatives. ``hybrid-flap`` measures the tilts
  (outputs ``beta1c beta1s`` after the body's);
* ``hybrid-inflow``: the hybrid model plus coning ``beta0`` and the uniform induced velocity
  ``vi`` as first-order states (equations ``B0`` and ``Vi``); 140 derivatives.
  ``hybrid-inflow-flap`` measures ``beta0 beta1c beta1s``.

A subset's known terms are the six-dof's rows and columns of its states, so a subset is the
six-dof model with the other axes' states held at trim. A model file may also declare a template
of its own (:class:`DeclaredTerms`, :mod:`rotorid.model.modelfile`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import attrs
import numpy as np

from rotorid.errors import StructureError
from rotorid.model.derivatives import (
    CONTROL_VARIABLES,
    DELAY_PREFIX,
    EQUATION_OF_LETTER,
    FORCE_MOMENT_LETTERS,
    STATE_VARIABLES,
    Derivative,
)
from rotorid.model.signals import ModelSignals, Signal, SignalSet
from rotorid.units import CHANNEL_KINDS, KIND_DIMENSIONS, UnitSystem

STATES = ("u", "w", "q", "theta", "v", "p", "phi", "r")
CONTROLS = CONTROL_VARIABLES
OUTPUTS = ("ax", "az", "q", "theta", "ay", "p", "phi", "r")
#: The velocity whose equation's term sum (specific force) each accelerometer output reads.
ACCELEROMETER_EQUATION = {"ax": "u", "ay": "v", "az": "w"}
#: Prefix of an output that reads a state's derivative (``q_dot`` reads q̇'s term sum).
DERIVATIVE_SUFFIX = "_dot"


@attrs.frozen(eq=False)
class KnownTerms:
    """The known coefficients of a structure at one condition, in its units.

    Attributes:
        a: A0, (n, n); c: C0, (p, n); d: D0, (p, m);
        measured: W, (p, n): ``measured[j, i]`` weights state i's derivative-term sum in
            output j.
    """

    a: np.ndarray
    c: np.ndarray
    d: np.ndarray
    measured: np.ndarray


def _tuple_of_names(value) -> tuple[str, ...]:
    return tuple(str(v) for v in value)


def _pairs(value) -> tuple[tuple[str, str], ...]:
    """A mapping (or pairs) as hashable (key, value) pairs in their order."""
    items = value.items() if isinstance(value, Mapping) else value
    return tuple((str(k), str(v)) for k, v in items)


@attrs.frozen
class StructureTemplate:
    """The shape of a linear structure: signals, equations, variables and known terms.

    Attributes:
        name: template name (``six-dof`` …, or a declared model's own).
        states, controls, outputs: signal names in array order.
        summary: one line for listings.
        equations: (letter, state) pairs: each derivative letter and the state whose equation
            it drives, in the order of a fully populated structure (a mapping is accepted).
        variables: states and controls a derivative may multiply, in the order of a fully
            populated structure.
        kinds: (signal, kind) pairs: the physical kind of every signal
            (:data:`rotorid.units.KIND_DIMENSIONS`); the unit system turns it into a unit.
        known: ``known(template, condition, units) -> KnownTerms``.
        control_units: (control, unit) pairs for controls recorded in a stated unit (``deg``,
            ``N``); a control without one is in % of travel. Unit systems never rescale them.
    """

    name: str
    states: tuple[str, ...] = attrs.field(converter=_tuple_of_names)
    controls: tuple[str, ...] = attrs.field(converter=_tuple_of_names)
    outputs: tuple[str, ...] = attrs.field(converter=_tuple_of_names)
    summary: str
    equations: tuple[tuple[str, str], ...] = attrs.field(converter=_pairs)
    variables: tuple[str, ...] = attrs.field(converter=_tuple_of_names)
    kinds: tuple[tuple[str, str], ...] = attrs.field(converter=_pairs)
    known: Callable
    control_units: tuple[tuple[str, str], ...] = attrs.field(default=(), converter=_pairs)

    def __attrs_post_init__(self):
        where = f"template {self.name!r}"
        for role, names in (("state", self.states), ("control", self.controls),
                            ("output", self.outputs)):
            bad = [n for n in names if not n.isidentifier()]
            twice = sorted({n for n in names if names.count(n) > 1})
            if bad or twice:
                raise StructureError(f"{where}: {role} names must be distinct identifiers "
                                     f"(got {', '.join(bad + twice)})")
        if set(self.controls) & (set(self.states) | set(self.outputs)):
            raise StructureError(f"{where}: a control cannot also be a state or an output "
                                 f"({', '.join(sorted(set(self.controls) & set(self.states + self.outputs)))})")
        for letter, state in self.equations:
            if not letter.isidentifier() or "_" in letter or letter + "_" == DELAY_PREFIX:
                raise StructureError(f"{where}: equation letter {letter!r} must be an "
                                     f"identifier without underscores, not 'tau'")
            if state not in self.states:
                raise StructureError(f"{where}: equation {letter} drives {state!r}, which is "
                                     f"not a state ({', '.join(self.states)})")
        driven = [state for _, state in self.equations]
        if len(set(driven)) != len(driven):
            raise StructureError(f"{where}: two equation letters drive the same state; give "
                                 f"each state at most one letter")
        unknown = [v for v in self.variables if v not in self.states + self.controls]
        if unknown:
            raise StructureError(f"{where}: derivative variables {', '.join(unknown)} are not "
                                 f"states or controls")
        missing = [n for n in self.states + self.controls + self.outputs
                   if n not in self.kind_of]
        strange = sorted({kind for _, kind in self.kinds if kind not in KIND_DIMENSIONS})
        if strange:
            raise StructureError(f"{where}: unknown signal kind {strange[0]!r}; use one of "
                                 f"{', '.join(KIND_DIMENSIONS)}")
        if missing:
            raise StructureError(f"{where}: no physical kind for {', '.join(missing)}; give each "
                                 f"signal a kind (velocity, angle, rate, acceleration, "
                                 f"angular-acceleration or control)")

    @property
    def letters(self) -> tuple[str, ...]:
        """Equation letters (e.g. X Z M)."""
        return tuple(letter for letter, _ in self.equations)

    @property
    def kind_of(self) -> dict[str, str]:
        """Signal name → physical kind."""
        return dict(self.kinds)

    def equation_of(self, derivative: Derivative) -> str:
        """The state whose equation ``derivative`` drives."""
        self.check(derivative)
        return dict(self.equations)[derivative.letter]

    def derivative_names(self) -> tuple[str, ...]:
        """Every derivative of the fully populated structure, equation by equation."""
        return tuple(f"{k}_{v}" for k in self.letters for v in self.variables)

    def check(self, derivative: Derivative) -> None:
        """Raise when ``derivative`` drives an equation or reads a variable the template lacks."""
        if derivative.letter not in self.letters or derivative.variable not in self.variables:
            shape = (f"the declared structure {self.name}"
                     if isinstance(self.known, DeclaredTerms) else f"the {self.name} template")
            fix = ("correct its name, or declare the equation or signal it needs in "
                   "[structure]" if isinstance(self.known, DeclaredTerms)
                   else "remove it or choose a template that has it")
            raise StructureError(
                f"derivative {derivative.name} does not fit {shape} (equations "
                f"{' '.join(self.letters)}; variables {' '.join(self.variables)}); {fix}")

    def signals(self, units: UnitSystem) -> ModelSignals:
        """The states, inputs and outputs as named signals in the unit system ``units``."""
        kinds, stated = self.kind_of, dict(self.control_units)

        def signal_set(names):
            return SignalSet(Signal(n, stated.get(n) or units.unit_of(kinds[n]), kinds[n])
                             for n in names)

        return ModelSignals(signal_set(self.states), signal_set(self.controls),
                            signal_set(self.outputs))

    def known_terms(self, condition, units: UnitSystem) -> KnownTerms:
        """A0, C0, D0 and W at ``condition`` in ``units``, shapes checked."""
        terms = self.known(self, condition, units)
        n, m, p = len(self.states), len(self.controls), len(self.outputs)
        for label, array, shape in (("A0", terms.a, (n, n)), ("C0", terms.c, (p, n)),
                                    ("D0", terms.d, (p, m)), ("W", terms.measured, (p, n))):
            if np.shape(array) != shape or not np.all(np.isfinite(array)):
                raise StructureError(f"template {self.name!r}: known {label} must be finite "
                                     f"with shape {shape}, got {np.shape(array)}")
        for column in np.flatnonzero(np.count_nonzero(terms.measured, axis=0) > 1):
            readers = [self.outputs[j] for j in np.flatnonzero(terms.measured[:, column])]
            raise StructureError(f"template {self.name!r}: outputs {', '.join(readers)} all "
                                 f"read {self.states[column]}'s derivative terms; one output "
                                 f"per state derivative: keep one of them")
        return terms


# ----------------------------------------------------------------- rigid-body known terms
def _rigid_body_a(condition, units: UnitSystem) -> np.ndarray:
    """Gravity and kinematic terms of the six-dof rigid body over :data:`STATES`, (8, 8)."""
    c = condition
    k = units.radian_per_angle
    g = units.g
    scale = units.length_per_metre
    u0, v0, w0 = c.u0 * scale, c.v0 * scale, c.w0 * scale
    st, ct = math.sin(c.theta0), math.cos(c.theta0)
    sp, cp = math.sin(c.phi0), math.cos(c.phi0)
    i = {s: n for n, s in enumerate(STATES)}
    a = np.zeros((len(STATES), len(STATES)))
    a[i["u"], i["q"]] = -w0 * k
    a[i["u"], i["r"]] = v0 * k
    a[i["u"], i["theta"]] = -g * ct * k
    a[i["v"], i["r"]] = -u0 * k
    a[i["v"], i["p"]] = w0 * k
    a[i["v"], i["phi"]] = g * ct * cp * k
    a[i["v"], i["theta"]] = -g * st * sp * k
    a[i["w"], i["p"]] = -v0 * k
    a[i["w"], i["q"]] = u0 * k
    a[i["w"], i["theta"]] = -g * cp * st * k
    a[i["w"], i["phi"]] = -g * sp * ct * k
    a[i["theta"], i["q"]] = cp
    a[i["theta"], i["r"]] = -sp
    a[i["phi"], i["p"]] = 1.0
    a[i["phi"], i["q"]] = sp * st / ct
    a[i["phi"], i["r"]] = cp * st / ct
    return a


def _flow_angle_gains(name: str, template: str, condition, units: UnitSystem) -> dict:
    """The flow angle ``name``'s small-perturbation gains on the body velocities about the
    trim's (u0, v0, w0), in angle unit per length unit/s: α = atan(w/u) gives
    Δα = (u0·Δw − w0·Δu)/(u0² + w0²), β = asin(v/V) at v0 = 0 gives Δβ = Δv/V0."""
    scale = units.length_per_metre
    u0, v0, w0 = condition.u0 * scale, condition.v0 * scale, condition.w0 * scale
    if u0 <= 0.0:
        velocity = {"alpha": "w", "beta": "v"}[name]
        raise StructureError(f"template {template!r}: output {name} from {velocity} needs "
                             f"forward flight (U0 > 0); give the [condition] an airspeed")
    angle = units.angle_per_radian
    if name == "alpha":
        square = u0**2 + w0**2
        return {"w": angle * u0 / square, "u": -angle * w0 / square}
    return {"v": angle / math.sqrt(u0**2 + v0**2 + w0**2)}


def rigid_body_terms(template: StructureTemplate, condition, units: UnitSystem) -> KnownTerms:
    """The rigid body's known terms for ``template``'s states (a subset of :data:`STATES`).

    A0: the six-dof gravity and kinematic terms; outputs named like a state read it; ``ax``,
    ``ay``, ``az`` read the X, Y, Z term sums (specific forces); ``<state>_dot`` reads that
    state's term sum; ``alpha`` and ``beta`` are the flow angles' small perturbations about
    the trim's velocities (:func:`_flow_angle_gains`; w/U0 and v/U0 at α0 = 0; in the unit
    system's angle unit; U0 must not be 0).
    """
    rows = [STATES.index(s) for s in template.states]
    a = _rigid_body_a(condition, units)[np.ix_(rows, rows)]
    n, m, p = len(template.states), len(template.controls), len(template.outputs)
    c, measured = np.zeros((p, n)), np.zeros((p, n))
    for row, name in enumerate(template.outputs):
        state = ACCELEROMETER_EQUATION.get(name)
        if name.endswith(DERIVATIVE_SUFFIX):
            state = name[: -len(DERIVATIVE_SUFFIX)]
        if state is not None and state in template.states:
            measured[row, template.states.index(state)] = 1.0
        elif name in template.states:
            c[row, template.states.index(name)] = 1.0
        elif name in ("alpha", "beta"):
            for state, gain in _flow_angle_gains(name, template.name, condition, units).items():
                if state in template.states:
                    c[row, template.states.index(state)] = gain
        else:
            raise StructureError(f"template {template.name!r}: no rigid-body output equation "
                                 f"for {name!r}")
    return KnownTerms(a, c, np.zeros((p, m)), measured)


def _rigid_body_template(name, states, controls, outputs, summary) -> StructureTemplate:
    equations = {k: s for k, s in EQUATION_OF_LETTER.items() if s in states}
    variables = tuple(v for v in STATE_VARIABLES if v in states) + tuple(controls)
    ordered = sorted(equations.items(), key=lambda item: FORCE_MOMENT_LETTERS.index(item[0]))
    return StructureTemplate(name, states, controls, outputs, summary, ordered, variables,
                             {s: CHANNEL_KINDS[s] for s in states + controls + outputs},
                             rigid_body_terms)


SIX_DOF = _rigid_body_template("six-dof", STATES, CONTROLS, OUTPUTS,
                               "coupled 6-DoF helicopter rigid body (the paper's model)")
LONGITUDINAL = _rigid_body_template("longitudinal", ("u", "w", "q", "theta"), ("long", "coll"),
                                    ("ax", "az", "q", "theta"),
                                    "helicopter longitudinal axes: surge, heave and pitch")
LATERAL = _rigid_body_template("lateral", ("v", "p", "phi", "r"), ("lat", "ped"),
                               ("ay", "p", "phi", "r"),
                               "helicopter lateral-directional axes: sway, roll and yaw")
FIXED_WING_LONGITUDINAL = _rigid_body_template(
    "fixed-wing-longitudinal", ("u", "w", "q", "theta"), ("elevator", "throttle"),
    ("u", "alpha", "q", "theta", "q_dot", "ax", "az"),
    "fixed-wing longitudinal small perturbations (alpha about the trim's u0, w0)")
FIXED_WING_LATERAL = _rigid_body_template(
    "fixed-wing-lateral", ("v", "p", "phi", "r"), ("aileron", "rudder"),
    ("beta", "p", "phi", "r", "ay"),
    "fixed-wing lateral-directional small perturbations (beta = v/V0)")


# ----------------------------------------------------------------- hybrid rotor-body model
#: Tip-path-plane tilts of the ``hybrid`` template (docs/hybrid.md): β1c forward, β1s left.
FLAP_STATES = ("beta1c", "beta1s")
#: Letters of the flap equations: ``Bc`` drives β̇1c, ``Bs`` drives β̇1s.
FLAP_EQUATIONS = (("Bc", "beta1c"), ("Bs", "beta1s"))
#: Known rate feedback: the disc keeps its orientation in space, so relative to the shaft it
#: tilts at the body rate, β̇1c = q + …, β̇1s = p + … (derived in docs/hybrid.md).
RATE_FEEDBACK = (("beta1c", "q"), ("beta1s", "p"))
#: Coning (angle, up) and the uniform induced velocity through the disc (velocity, down the
#: shaft) of the ``hybrid-inflow`` templates (docs/hybrid.md, "Coning and inflow").
CONING_INFLOW_STATES = ("beta0", "vi")
#: Letters of the coning and inflow equations: ``B0`` drives β̇0, ``Vi`` drives v̇i.
CONING_INFLOW_EQUATIONS = (("B0", "beta0"), ("Vi", "vi"))


def hybrid_terms(template: StructureTemplate, condition, units: UnitSystem) -> KnownTerms:
    """The six-dof rigid body's known terms, the flap's rate feedback, and a rotor output
    (``beta1c`` …) reading its state; the coning and inflow equations have no known term."""
    body = rigid_body_terms(SIX_DOF, condition, units)
    states, outputs = template.states, template.outputs
    n, p = len(states), len(outputs)
    rows = [states.index(s) for s in STATES]
    body_outputs = [outputs.index(y) for y in OUTPUTS]
    a, c, measured = np.zeros((n, n)), np.zeros((p, n)), np.zeros((p, n))
    a[np.ix_(rows, rows)] = body.a
    c[np.ix_(body_outputs, rows)] = body.c
    measured[np.ix_(body_outputs, rows)] = body.measured
    for flap, rate in RATE_FEEDBACK:
        a[states.index(flap), states.index(rate)] = 1.0
    for row, name in enumerate(outputs[len(OUTPUTS):], start=len(OUTPUTS)):
        c[row, states.index(name)] = 1.0
    return KnownTerms(a, c, np.zeros((p, len(template.controls))), measured)


def _hybrid_template(name: str, rotor_states: tuple[str, ...],
                     rotor_equations: tuple[tuple[str, str], ...],
                     measured: tuple[str, ...], summary: str) -> StructureTemplate:
    """A hybrid template: the six-dof body, the rotor states with their equations, and the
    body's outputs followed by the ``measured`` rotor states."""
    states = STATES + rotor_states
    return StructureTemplate(
        name, states, CONTROLS, OUTPUTS + measured, summary,
        SIX_DOF.equations + rotor_equations, STATE_VARIABLES + rotor_states + CONTROLS,
        SIX_DOF.kinds + tuple((s, CHANNEL_KINDS[s]) for s in rotor_states), hybrid_terms)


HYBRID = _hybrid_template(
    "hybrid", FLAP_STATES, FLAP_EQUATIONS, (),
    "six-dof rigid body with first-order tip-path-plane flapping (docs/hybrid.md)")
HYBRID_FLAP = _hybrid_template(
    "hybrid-flap", FLAP_STATES, FLAP_EQUATIONS, FLAP_STATES,
    "the hybrid model with the tip-path-plane tilts measured (docs/hybrid.md)")
HYBRID_INFLOW = _hybrid_template(
    "hybrid-inflow", FLAP_STATES + CONING_INFLOW_STATES,
    FLAP_EQUATIONS + CONING_INFLOW_EQUATIONS, (),
    "the hybrid model with coning and uniform inflow states (docs/hybrid.md)")
HYBRID_INFLOW_FLAP = _hybrid_template(
    "hybrid-inflow-flap", FLAP_STATES + CONING_INFLOW_STATES,
    FLAP_EQUATIONS + CONING_INFLOW_EQUATIONS, ("beta0",) + FLAP_STATES,
    "the coning/inflow hybrid model with coning and tip-path-plane tilts measured "
    "(docs/hybrid.md)")

TEMPLATES = {t.name: t for t in (SIX_DOF, LONGITUDINAL, LATERAL, FIXED_WING_LONGITUDINAL,
                                 FIXED_WING_LATERAL, HYBRID, HYBRID_FLAP, HYBRID_INFLOW,
                                 HYBRID_INFLOW_FLAP)}


# ----------------------------------------------------------------- declared templates
@attrs.frozen
class DeclaredTerms:
    """Known terms written out as coefficients in a model file, independent of the condition.

    Attributes:
        state_terms: (state, source, value): ``ẋ_state += value · source``, the source a state
            (a known control term is a fixed derivative instead).
        output_terms: (output, source, value): ``y_output += value · source``, the source a
            state, a control or ``d(state)`` (the state's full derivative ẋ).
    """

    state_terms: tuple[tuple[str, str, float], ...] = attrs.field(
        converter=lambda rows: tuple((str(a), str(b), float(c)) for a, b, c in rows))
    output_terms: tuple[tuple[str, str, float], ...] = attrs.field(
        converter=lambda rows: tuple((str(a), str(b), float(c)) for a, b, c in rows))

    def __call__(self, template: StructureTemplate, condition, units: UnitSystem) -> KnownTerms:
        states, controls, outputs = template.states, template.controls, template.outputs
        n, m, p = len(states), len(controls), len(outputs)
        a = np.zeros((n, n))
        for state, source, value in self.state_terms:
            if source in controls:
                raise StructureError(f"template {template.name!r}: a known term of {state} "
                                     f"on control {source} is a fixed derivative; declare it "
                                     f"in [derivatives] with fixed = {value}")
            a[_position(states, state, "state", template),
              _position(states, source, "state", template)] += value
        cd, measured = np.zeros((p, n + m)), np.zeros((p, n))
        for output, source, value in self.output_terms:
            row = _position(outputs, output, "output", template)
            if source.startswith("d(") and source.endswith(")"):
                state = _position(states, source[2:-1], "state", template)
                cd[row, :n] += value * a[state]
                measured[row, state] += value
            else:
                column = _position(states + controls, source, "state, control or d(state)",
                                   template)
                cd[row, column] += value
        return KnownTerms(a, cd[:, :n], cd[:, n:], measured)


def _position(names, name, role, template) -> int:
    if name not in names:
        raise StructureError(f"template {template.name!r}: {name!r} is not a {role} "
                             f"({', '.join(names)})")
    return names.index(name)


def structure_template(template: str | StructureTemplate) -> StructureTemplate:
    """The template called ``template`` (or ``template`` itself); unknown names raise."""
    if isinstance(template, StructureTemplate):
        return template
    try:
        return TEMPLATES[str(template)]
    except KeyError:
        raise StructureError(f"unknown structure template {template!r}; use one of "
                             f"{', '.join(TEMPLATES)}, or declare states, controls and outputs "
                             f"in the model file's [structure] table") from None
