"""Flight condition and the linear model structure.

A structure has the shape of its template (:mod:`rotorid.model.templates`): states, controls,
outputs, equations and known terms. The default is the paper's coupled helicopter rigid-body
model about straight trimmed flight (``six-dof``); other templates are its ``longitudinal`` or
``lateral`` subset, fixed-wing small-perturbation models, or a model file's own declaration.
The six-dof model::

    states   x = [u w q theta v p phi r]
    controls u = [long lat coll ped]
    outputs  y = [ax az q theta ay p phi r]

    u' = ΣX·z − W0·q + V0·r − g·cosΘ0·θ
    v' = ΣY·z − U0·r + W0·p + g·cosΘ0·cosΦ0·φ − g·sinΘ0·sinΦ0·θ
    w' = ΣZ·z − V0·p + U0·q − g·cosΦ0·sinΘ0·θ − g·sinΦ0·cosΘ0·φ
    p' = ΣL·z     q' = ΣM·z     r' = ΣN·z        (L, N inertia-coupled)
    θ' = q·cosΦ0 − r·sinΦ0
    φ' = p + q·sinΦ0·tanΘ0 + r·cosΦ0·tanΘ0
    ax = ΣX·z     ay = ΣY·z     az = ΣZ·z

``ΣX·z`` sums the X derivatives times their state or control, each possibly delayed. The
template builds the known gravity and kinematic terms in the structure's unit system, with the
deg↔rad factors folded in. Estimable quantities are the free derivatives and free delays; they
form the parameter vector in :attr:`ModelStructure.parameter_names` order.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Mapping

import attrs
import numpy as np

from rotorid.errors import StructureError
from rotorid.frozen import readonly_array
from rotorid.model.derivatives import (
    DEFAULT_DELAY_UPPER,
    Delay,
    Derivative,
    Sign,
    delayed_derivative,
    parse_name,
)
from rotorid.model.signals import ModelSignals
from rotorid.model.templates import (
    CONTROLS,
    OUTPUTS,
    SIX_DOF,
    STATES,
    KnownTerms,
    StructureTemplate,
    structure_template,
)
from rotorid.units import FLIGHT_TEST, FOOT, KNOT, UnitSystem, unit_system

#: The paper's delayed derivatives (τ1 … τ8).
PAPER_DELAYED = ("L_p", "L_q", "L_long", "L_lat", "M_p", "M_q", "M_long", "M_lat")


def _finite_float(instance, attribute, value):
    if not math.isfinite(value):
        raise StructureError(f"flight condition: {attribute.name} must be finite, got {value!r}")


#: Highest airspeed of a flight condition, kt: beyond any rotorcraft, tiltrotors included, so
#: that a value in the wrong unit is refused.
MAX_AIRSPEED_KT = 400.0


@attrs.frozen
class FlightCondition:
    """Trim point of the linear model, in SI: body velocities in m/s, attitudes in rad.

    Use :meth:`from_airspeed` for level flight at a given airspeed and trim attitude.
    """

    u0: float = attrs.field(default=0.0, converter=float, validator=_finite_float)
    v0: float = attrs.field(default=0.0, converter=float, validator=_finite_float)
    w0: float = attrs.field(default=0.0, converter=float, validator=_finite_float)
    theta0: float = attrs.field(default=0.0, converter=float, validator=_finite_float)
    phi0: float = attrs.field(default=0.0, converter=float, validator=_finite_float)

    def __attrs_post_init__(self):
        if self.airspeed_kt > MAX_AIRSPEED_KT:
            raise StructureError(
                f"flight condition: airspeed {self.airspeed_kt:.6g} kt is beyond any rotorcraft "
                f"(at most {MAX_AIRSPEED_KT:g} kt); give airspeed_kt in kt or the body "
                f"velocities in m/s (u0_mps) or ft/s (u0_fps)"
            )
        for name in ("theta0", "phi0"):
            angle = getattr(self, name)
            if abs(angle) >= math.pi / 2:
                raise StructureError(
                    f"flight condition: {name} = {math.degrees(angle):.4g}° ({angle:.4g} rad) "
                    f"is not within ±90°; check its unit: FlightCondition takes rad, a model "
                    f"file's {name}_deg and from_airspeed({name}_deg=...) take deg")

    @classmethod
    def from_airspeed(cls, airspeed_kt: float = 0.0, theta0_deg: float = 0.0,
                      phi0_deg: float = 0.0) -> "FlightCondition":
        """Level flight at ``airspeed_kt`` with the fuselage pitched ``theta0_deg``.

        In level flight the velocity vector is horizontal, so U0 = V·cosΘ0 and W0 = V·sinΘ0
        (zero sideslip, V0 = 0).
        """
        if not math.isfinite(airspeed_kt) or airspeed_kt < 0:
            raise StructureError(f"airspeed must be a finite number ≥ 0 kt, got {airspeed_kt!r}")
        speed = airspeed_kt * KNOT
        theta0 = math.radians(theta0_deg)
        return cls(speed * math.cos(theta0), 0.0, speed * math.sin(theta0), theta0,
                   math.radians(phi0_deg))

    @classmethod
    def from_mapping(cls, settings: Mapping) -> "FlightCondition":
        """Build from a model file's ``[condition]`` table.

        Keys: ``airspeed_kt`` or body velocities ``u0_mps v0_mps w0_mps`` / ``u0_fps v0_fps
        w0_fps``; attitudes ``theta0_deg phi0_deg``.
        """
        known = {"airspeed_kt", "theta0_deg", "phi0_deg", "u0_mps", "v0_mps", "w0_mps",
                 "u0_fps", "v0_fps", "w0_fps"}
        unknown = set(settings) - known
        if unknown:
            raise StructureError(
                f"[condition]: unknown key(s) {sorted(unknown)}; known: {sorted(known)}"
            )
        theta = settings.get("theta0_deg", 0.0)
        phi = settings.get("phi0_deg", 0.0)
        body = [k for k in settings if k[:2] in ("u0", "v0", "w0")]
        if "airspeed_kt" in settings:
            if body:
                raise StructureError("[condition]: give airspeed_kt or body velocities, not both")
            return cls.from_airspeed(settings["airspeed_kt"], theta, phi)
        velocity = {}
        for axis in ("u0", "v0", "w0"):
            si, ft = settings.get(f"{axis}_mps"), settings.get(f"{axis}_fps")
            if si is not None and ft is not None:
                raise StructureError(f"[condition]: give {axis}_mps or {axis}_fps, not both")
            velocity[axis] = si if si is not None else (ft * FOOT if ft is not None else 0.0)
        return cls(theta0=math.radians(theta), phi0=math.radians(phi), **velocity)

    @property
    def airspeed_kt(self) -> float:
        """Total airspeed in knots."""
        return math.sqrt(self.u0**2 + self.v0**2 + self.w0**2) / KNOT

    def airspeed_text(self, units: str = "flight-test", decimals: int = 1) -> str:
        """The airspeed in the unit system's speed: ``"70.0 kt"`` (flight-test units) or
        ``"36.0 m/s"`` (``units = "si"``)."""
        if unit_system(units).name == "si":
            return f"{self.airspeed_kt * KNOT:.{decimals}f} m/s"
        return f"{self.airspeed_kt:.{decimals}f} kt"

    def describe(self, units: str = "flight-test") -> str:
        """One-line summary, e.g. ``70.0 kt, Θ0 = 1.2°, Φ0 = -1.5°`` (the airspeed in m/s
        for ``units = "si"``)."""
        return (f"{self.airspeed_text(units)}, Θ0 = {math.degrees(self.theta0):.2f}°, "
                f"Φ0 = {math.degrees(self.phi0):.2f}°")


def _unique_derivatives(instance, attribute, value):
    seen = set()
    for d in value:
        if not isinstance(d, Derivative):
            raise StructureError(f"structure derivatives must be Derivative objects, got {d!r}")
        if d.name in seen:
            raise StructureError(f"derivative {d.name} is declared twice in the structure")
        seen.add(d.name)


@attrs.frozen
class TermTable:
    """The derivative terms of a structure evaluated at one parameter vector.

    Every array has one entry per derivative of the structure (free and fixed), shape ``(K,)``:

    - ``equation``: row in the state vector (index into the structure's states) the term drives;
    - ``source``: column in ``[x; u]`` (0 … n−1 the n states, n … n+m−1 the m controls);
    - ``gain``: derivative value; ``delay``: delay in s (0 where none);
    - ``output``: row in the structure's outputs that also reads the term (a specific force,
      a state derivative), −1 if none; ``weight``: the term's weight in that output (0 if none).
    """

    equation: np.ndarray
    source: np.ndarray
    gain: np.ndarray
    delay: np.ndarray
    output: np.ndarray
    weight: np.ndarray


@functools.lru_cache(maxsize=256)
def _known_terms(template: StructureTemplate, condition: FlightCondition,
                 units: UnitSystem) -> KnownTerms:
    """The known terms, computed once per template, condition and units: every simulation,
    discretisation and frequency response of a fit asks for them."""
    terms = template.known_terms(condition, units)
    return KnownTerms(*(readonly_array(getattr(terms, f.name))
                        for f in attrs.fields(KnownTerms)))


@attrs.frozen
class ModelStructure:
    """A frozen linear model structure: flight condition, derivatives, unit system and
    template (the states, controls and outputs; ``six-dof`` by default).

    Build a fully populated structure with :meth:`populated` (:meth:`six_dof` for the
    paper's), then shape it with :meth:`without`, :meth:`fixing`, :meth:`with_delays` and
    :meth:`with_initial`; each returns a new structure.
    """

    condition: FlightCondition
    derivatives: tuple[Derivative, ...] = attrs.field(converter=tuple,
                                                      validator=_unique_derivatives)
    units: UnitSystem = attrs.field(default=FLIGHT_TEST, converter=unit_system)
    template: StructureTemplate = attrs.field(default=SIX_DOF, converter=structure_template)

    def __attrs_post_init__(self):
        for derivative in self.derivatives:
            self.template.check(derivative)

    # ----------------------------------------------------------------- constructors
    @classmethod
    def populated(cls, condition: FlightCondition, template: str | StructureTemplate = SIX_DOF,
                  units: str | UnitSystem = FLIGHT_TEST,
                  signs: Mapping[str, str] | None = None) -> "ModelStructure":
        """The fully populated structure of ``template``: every derivative of its force and
        moment equations over its velocity and rate states and its controls, free, starting
        at zero (60 for ``six-dof``, 15 for ``longitudinal`` and ``lateral``).

        ``signs`` optionally attaches sign priors, e.g. ``{"L_p": "negative"}``.
        """
        template = structure_template(template)
        signs = dict(signs or {})
        derivatives = [Derivative(name, sign=signs.pop(name, Sign.NONE))
                       for name in template.derivative_names()]
        if signs:
            raise StructureError(f"sign priors given for derivatives the {template.name} "
                                 f"template does not have: {sorted(signs)}")
        return cls(condition, derivatives, units, template)

    @classmethod
    def six_dof(cls, condition: FlightCondition, units: str | UnitSystem = FLIGHT_TEST,
                signs: Mapping[str, str] | None = None) -> "ModelStructure":
        """The paper's fully populated structure (:meth:`populated` with ``six-dof``)."""
        return cls.populated(condition, SIX_DOF, units, signs)

    # ----------------------------------------------------------------- signals
    @property
    def states(self) -> tuple[str, ...]:
        return self.template.states

    @property
    def controls(self) -> tuple[str, ...]:
        return self.template.controls

    @property
    def read_controls(self) -> tuple[str, ...]:
        """The controls the model reads: those of a derivative (free or fixed) or of a known
        output term; the data need not hold the others."""
        variables = {d.variable for d in self.derivatives}
        direct = np.any(self.known_terms().d != 0, axis=0)
        return tuple(c for j, c in enumerate(self.controls) if c in variables or direct[j])

    @property
    def outputs(self) -> tuple[str, ...]:
        return self.template.outputs

    @property
    def signals(self) -> ModelSignals:
        """States, inputs and outputs as named signals in the structure's units."""
        return self.template.signals(self.units)

    # ----------------------------------------------------------------- lookup
    @property
    def names(self) -> tuple[str, ...]:
        """Names of every derivative in the structure, free and fixed."""
        return tuple(d.name for d in self.derivatives)

    def derivative(self, name: str) -> Derivative:
        """The derivative called ``name``; a clear error lists what the structure has."""
        for d in self.derivatives:
            if d.name == name:
                return d
        self.template.check(Derivative(name))  # names the template cannot hold at all
        raise StructureError(
            f"derivative {name} is not in this structure ({len(self.derivatives)} derivatives: "
            f"{', '.join(self.names)})"
        )

    @property
    def free_derivatives(self) -> tuple[Derivative, ...]:
        return tuple(d for d in self.derivatives if not d.fixed)

    @property
    def free_delays(self) -> tuple[Derivative, ...]:
        """Derivatives whose delay is estimated."""
        return tuple(d for d in self.derivatives if d.delay is not None and not d.delay.fixed)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Estimated parameters: free derivatives, then free delays (``tau_<name>``)."""
        return (tuple(d.name for d in self.free_derivatives)
                + tuple(d.delay_name for d in self.free_delays))

    @property
    def n_parameters(self) -> int:
        return len(self.free_derivatives) + len(self.free_delays)

    @property
    def n_states(self) -> int:
        return len(self.states)

    @property
    def n_controls(self) -> int:
        return len(self.controls)

    @property
    def n_outputs(self) -> int:
        return len(self.outputs)

    @property
    def equation_rows(self) -> tuple[int, ...]:
        """Rows of the state vector that derivative terms can drive (the force and moment
        equations), in state order."""
        driven = {state for _, state in self.template.equations}
        return tuple(i for i, name in enumerate(self.states) if name in driven)

    def is_delay(self) -> np.ndarray:
        """Boolean mask over :attr:`parameter_names`: True for delays."""
        return np.array([False] * len(self.free_derivatives) + [True] * len(self.free_delays),
                        dtype=bool)

    # ----------------------------------------------------------------- editing
    def without(self, *names: str) -> "ModelStructure":
        """Return the structure with the named derivatives removed (their value becomes 0)."""
        for name in names:
            self.derivative(name)
        drop = set(names)
        return attrs.evolve(self, derivatives=[d for d in self.derivatives if d.name not in drop])

    def replacing(self, derivative: Derivative) -> "ModelStructure":
        """Return the structure with ``derivative`` replacing the one of the same name,
        or appended when the structure does not have it yet."""
        if derivative.name in self.names:
            items = [derivative if d.name == derivative.name else d for d in self.derivatives]
        else:
            items = [*self.derivatives, derivative]
        return attrs.evolve(self, derivatives=items)

    def fixing(self, name: str, value: float) -> "ModelStructure":
        """Return the structure with derivative ``name`` fixed at ``value``."""
        return self.replacing(self.derivative(name).fixed_at(value))

    def with_delays(self, names: Iterable[str] = PAPER_DELAYED, initial: float = 0.0,
                    upper: float | None = None, missing: str = "skip") -> "ModelStructure":
        """Return the structure with a free delay on each named derivative.

        ``missing="skip"`` ignores names the structure no longer has (the paper adds delays
        only to the derivatives that survived reduction); ``"error"`` rejects them.
        """
        if missing not in ("skip", "error"):
            raise StructureError("missing must be 'skip' or 'error'")
        structure = self
        for name in names:
            if name not in self.names:
                if missing == "error":
                    self.derivative(name)
                continue
            structure = structure.replacing(
                attrs.evolve(self.derivative(name), delay=Delay(initial, upper)))
        return structure

    def without_delay(self, name: str) -> "ModelStructure":
        """Return the structure with the delay of derivative ``name`` removed."""
        derivative = self.derivative(name)
        if derivative.delay is None:
            raise StructureError(f"derivative {name} has no delay to remove")
        return self.replacing(attrs.evolve(derivative, delay=None))

    def with_initial(self, values: Mapping[str, float]) -> "ModelStructure":
        """Return the structure with new initial values (derivatives by name, delays by
        ``tau_<name>``)."""
        structure = self
        for key, value in values.items():
            delayed = delayed_derivative(key)
            if delayed is not None:
                d = structure.derivative(delayed)
                if d.delay is None:
                    raise StructureError(f"{key}: derivative {d.name} has no delay")
                new = attrs.evolve(d, delay=attrs.evolve(d.delay, initial=value))
            else:
                new = attrs.evolve(structure.derivative(key), initial=value)
            structure = structure.replacing(new)
        return structure

    # ----------------------------------------------------------------- parameters
    def initial_values(self) -> np.ndarray:
        """Initial parameter vector, shape ``(n_parameters,)``."""
        return np.array([d.initial for d in self.free_derivatives]
                        + [d.delay.initial for d in self.free_delays], dtype=float)

    def bounds(self, enforce_signs: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the parameter vector, each shape ``(n_parameters,)``.

        Delays are bounded below by 0 and above by their ``upper`` (by default
        :data:`~rotorid.model.derivatives.DEFAULT_DELAY_UPPER`); derivatives are
        unbounded unless ``enforce_signs`` turns their sign priors into bounds.
        """
        lower, upper = [], []
        for d in self.free_derivatives:
            lo, hi = -np.inf, np.inf
            if enforce_signs and d.sign is Sign.NEGATIVE:
                hi = 0.0
            if enforce_signs and d.sign is Sign.POSITIVE:
                lo = 0.0
            lower.append(lo)
            upper.append(hi)
        for d in self.free_delays:
            lower.append(0.0)
            upper.append(DEFAULT_DELAY_UPPER if d.delay.upper is None else d.delay.upper)
        return np.array(lower, dtype=float), np.array(upper, dtype=float)

    def as_vector(self, values) -> np.ndarray:
        """Parameter vector from an array or a name→value mapping (missing names take their
        initial value). Rejects wrong lengths, unknown names and non-finite values."""
        if isinstance(values, Mapping):
            unknown = set(values) - set(self.parameter_names)
            if unknown:
                raise StructureError(
                    f"values for unknown or non-free parameter(s) {sorted(unknown)}; "
                    f"free parameters: {', '.join(self.parameter_names)}"
                )
            vector = self.initial_values()
            index = {n: i for i, n in enumerate(self.parameter_names)}
            for name, value in values.items():
                vector[index[name]] = float(value)
        else:
            vector = np.array(values, dtype=float)
            if vector.shape != (self.n_parameters,):
                raise StructureError(
                    f"parameter vector has shape {vector.shape}; this structure has "
                    f"{self.n_parameters} free parameters ({', '.join(self.parameter_names)})"
                )
        if not np.all(np.isfinite(vector)):
            bad = [n for n, v in zip(self.parameter_names, vector) if not np.isfinite(v)]
            raise StructureError(f"non-finite parameter value(s): {', '.join(bad)}")
        return vector

    def as_mapping(self, values) -> dict[str, float]:
        """Name→value mapping of a parameter vector."""
        return dict(zip(self.parameter_names, self.as_vector(values).tolist()))

    # ----------------------------------------------------------------- matrices
    def known_terms(self) -> KnownTerms:
        """The template's known A0, C0, D0 and W at this condition, in this structure's units
        (:class:`~rotorid.model.templates.KnownTerms`, read-only arrays)."""
        return _known_terms(self.template, self.condition, self.units)

    def known_state_matrix(self) -> np.ndarray:
        """The known terms of A (gravity, kinematics …), shape (n, n)."""
        return self.known_terms().a

    def known_output_matrix(self) -> np.ndarray:
        """The known part of C (outputs that are states, the flow angles α and β …), shape (p, n)."""
        return self.known_terms().c

    def known_feedthrough(self) -> np.ndarray:
        """The known part of D, shape (p, m) (zero for the shipped templates)."""
        return self.known_terms().d

    def equation_of(self, derivative: Derivative) -> str:
        """The state whose equation ``derivative`` drives (e.g. ``q`` for ``M_long``)."""
        return self.template.equation_of(derivative)

    def is_control(self, derivative: Derivative) -> bool:
        """True when ``derivative`` multiplies a control (``M_long``), not a state (``M_q``)."""
        return derivative.variable in self.controls

    def terms(self, values=None) -> TermTable:
        """Every derivative term at the parameter vector ``values`` (default: initial)."""
        vector = self.initial_values() if values is None else self.as_vector(values)
        free = {n: v for n, v in zip(self.parameter_names, vector)}
        sources = self.states + self.controls
        measured = self.known_terms().measured
        # Looked up once per call: every derivative fits the template (checked when built).
        rows = {letter: self.states.index(state) for letter, state in self.template.equations}
        readers = [np.flatnonzero(measured[:, row]) for row in range(self.n_states)]
        equation, source, gain, delay, output, weight = [], [], [], [], [], []
        for d in self.derivatives:
            letter, variable = parse_name(d.name)
            row = rows[letter]
            equation.append(row)
            source.append(sources.index(variable))
            gain.append(d.initial if d.fixed else free[d.name])
            if d.delay is None:
                delay.append(0.0)
            else:
                delay.append(d.delay.initial if d.delay.fixed else free[d.delay_name])
            reader = readers[row]
            output.append(int(reader[0]) if reader.size else -1)
            weight.append(float(measured[reader[0], row]) if reader.size else 0.0)
        as_int = lambda x: np.array(x, dtype=int)  # noqa: E731
        return TermTable(as_int(equation), as_int(source), np.array(gain, dtype=float),
                         np.array(delay, dtype=float), as_int(output),
                         np.array(weight, dtype=float))

    def matrices(self, values=None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """A (n×n), B (n×m), C (p×n), D (p×m) with every delay set to zero."""
        table = self.terms(values)
        n = self.n_states
        known = self.known_terms()
        a, c, d = known.a.copy(), known.c.copy(), known.d.copy()
        b = np.zeros((n, self.n_controls))
        for eq, src, gain, out, weight in zip(table.equation, table.source, table.gain,
                                              table.output, table.weight):
            target, column = (a, src) if src < n else (b, src - n)
            target[eq, column] += gain
            if out >= 0:
                (c if src < n else d)[out, column] += weight * gain
        return a, b, c, d

    def describe(self) -> str:
        """Short summary: condition, units, counts."""
        n_fixed = len(self.derivatives) - len(self.free_derivatives)
        return (f"ModelStructure({self.template.name}, {self.condition.describe()}, "
                f"{self.units.name} units, "
                f"{len(self.free_derivatives)} free derivatives, {n_fixed} fixed, "
                f"{len(self.free_delays)} free delays)")
