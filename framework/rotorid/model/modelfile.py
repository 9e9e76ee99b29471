"""Model files: a flight condition and a model structure declared in TOML.

Example (flight-test units; derivative values in the structure's units)::

    units = "flight-test"            # or "si"

    [condition]                      # airspeed_kt, or u0_mps/v0_mps/w0_mps (or *_fps)
    airspeed_kt = 0.0
    theta0_deg = 0.0
    phi0_deg = 0.0

    [structure]
    template = "six-dof"             # or "longitudinal", "lateral" (rotorid.model.templates)
    populate = "all"                 # all of the template's derivatives (60 for six-dof),
                                     # free, starting at 0; or "none"
    remove = ["X_v", "Y_p"]          # only with populate = "all"

    [derivatives.L_lat]              # settings of one derivative (added when populate = "none")
    initial = 1.0                    # start value
    sign = "positive"                # sign prior: "negative", "positive" or "none"
    delay = { initial = 0.05 }       # or a number (initial, s); keys initial, upper, fixed

    [derivatives.M_w]
    fixed = 0.0                      # a known value, not estimated

    [channels]                       # the data's own column names (optional)
    Q_degps = { signal = "q", unit = "deg/s" }
    DELE = { signal = "long", unit = "%", scale = -1.0, offset = 0.0 }

A structure of one's own is declared instead of a template (signals as ``name = "kind"`` in
array order; kinds: velocity, angle, rate, acceleration, angular-acceleration, control; the unit
system gives each kind its unit)::

    [structure]
    name = "short-period"
    states = { alpha = "angle", q = "rate" }
    controls = { elevator = "control" }
    outputs = { alpha = "angle", q = "rate", q_dot = "angular-acceleration", az = "acceleration" }
    equations = { Z = "alpha", M = "q" }     # derivative letter → the state it drives
    variables = ["alpha", "q", "elevator"]   # optional: default every state and control
    populate = "all"                         # Z_alpha Z_q Z_elevator M_alpha M_q M_elevator

    [structure.known]                        # ẋ_state += value · state
    alpha = { q = 1.0 }

    [structure.output_equations]             # y += value · (state, control or d(state));
    q_dot = { "d(q)" = 1.0 }                 # an output named like a state reads it
    az = { "d(alpha)" = 50.0, q = -50.0 }    # by default

:func:`load_model` reads a file, :func:`parse_model` an already parsed mapping,
:func:`load_channel_map` the file's ``[channels]`` table (for the data files' readers),
:func:`save_model` writes a structure back (atomically) so that loading it gives an equal
structure.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path

import attrs

from rotorid.errors import DataFileError, RotoridError
from rotorid.io import atomic_write, read_toml
from rotorid.model.derivatives import Derivative
from rotorid.model.signals import ChannelMap
from rotorid.model.structure import FlightCondition, ModelStructure
from rotorid.units import FLIGHT_TEST, canonical_unit, unit_fits_kind, units_of_kind
from rotorid.model.templates import SIX_DOF, TEMPLATES, DeclaredTerms, StructureTemplate

POPULATE = ("all", "none")
_TOP_KEYS = ("units", "condition", "structure", "derivatives", "channels")
_STRUCTURE_KEYS = ("template", "populate", "remove")
_DECLARATION_KEYS = ("name", "states", "controls", "outputs", "equations", "variables", "known",
                     "output_equations")
_DERIVATIVE_KEYS = ("initial", "sign", "delay", "fixed")
_DELAY_KEYS = {"initial": "number", "upper": "number", "fixed": "boolean"}


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _require(kind: str, value, where: str):
    ok = {"number": _is_number(value), "boolean": isinstance(value, bool),
          "string": isinstance(value, str), "table": isinstance(value, Mapping)}[kind]
    if not ok:
        raise DataFileError(f"{where} must be a {kind}, got {value!r}")
    return value


def _check_keys(table: Mapping, known, where: str) -> None:
    unknown = [key for key in table if key not in known]
    if unknown:
        raise DataFileError(f"{where}: unknown key {unknown[0]!r}; known keys: "
                            f"{', '.join(known)}")


def _delay(value, where: str):
    if value is None or _is_number(value):
        return value
    _require("table", value, where)
    _check_keys(value, _DELAY_KEYS, where)
    for key, kind in _DELAY_KEYS.items():
        if key in value:
            _require(kind, value[key], f"{where}.{key}")
    return dict(value)


def _derivative(name: str, settings, where: str) -> Derivative:
    _require("table", settings, where)
    _check_keys(settings, _DERIVATIVE_KEYS, where)
    if "fixed" in settings and "initial" in settings:
        raise DataFileError(f"{where}: give 'initial' (a start value) or 'fixed' (a known "
                            f"value), not both")
    value = settings.get("fixed", settings.get("initial", 0.0))
    _require("number", value, f"{where}.{'fixed' if 'fixed' in settings else 'initial'}")
    sign = _require("string", settings.get("sign", "none"), f"{where}.sign")
    return Derivative(name, initial=value, sign=sign, fixed="fixed" in settings,
                      delay=_delay(settings.get("delay"), f"{where}.delay"))


def _structure(mapping: Mapping, source: str) -> ModelStructure:
    _require("table", mapping, f"{source}: a model file")
    if "data" in mapping:
        raise DataFileError(f"{source}: a study case file (it has a [data] table), not a "
                            f"model file: run it with `rotorid study {source} --out DIR`, or "
                            f"give `rotorid identify` a model file (keys "
                            f"{', '.join(_TOP_KEYS)})")
    _check_keys(mapping, _TOP_KEYS, source)
    units = _require("string", mapping.get("units", "flight-test"), f"{source}: units")
    if "condition" not in mapping:
        raise DataFileError(f"{source}: missing [condition] table (e.g. airspeed_kt = 0.0)")
    condition = _require("table", mapping["condition"], f"{source}: [condition]")
    for key, value in condition.items():
        _require("number", value, f"{source}: [condition] {key}")
    settings = _require("table", mapping.get("structure", {}), f"{source}: [structure]")
    _check_keys(settings, _STRUCTURE_KEYS + _DECLARATION_KEYS, f"{source}: [structure]")
    if "states" in settings:
        if "template" in settings:
            raise DataFileError(f"{source}: [structure] give a template or declare states, "
                                f"controls and outputs, not both")
        template = _declared_template(settings, f"{source}: [structure]")
    else:
        stray = [key for key in _DECLARATION_KEYS if key in settings]
        if stray:
            raise DataFileError(f"{source}: [structure] {stray[0]} belongs to a declared "
                                f"structure; declare states, controls and outputs too")
        template = _require("string", settings.get("template", SIX_DOF.name),
                            f"{source}: [structure] template")
        if template not in TEMPLATES:
            raise DataFileError(f"{source}: [structure] template = {template!r}; use "
                                f"{' or '.join(map(repr, TEMPLATES))}, or declare states, "
                                f"controls and outputs")
    populate = _require("string", settings.get("populate", "all"),
                        f"{source}: [structure] populate")
    if populate not in POPULATE:
        raise DataFileError(f"{source}: [structure] populate = {populate!r}; use "
                            f"{' or '.join(map(repr, POPULATE))}")
    remove = settings.get("remove", [])
    if not isinstance(remove, list) or not all(isinstance(n, str) for n in remove):
        raise DataFileError(f"{source}: [structure] remove must be a list of derivative names")
    twice = sorted({n for n in remove if remove.count(n) > 1})
    if twice:
        raise DataFileError(f"{source}: [structure] remove lists {', '.join(twice)} twice")
    declared = _require("table", mapping.get("derivatives", {}), f"{source}: [derivatives]")
    derivatives = [_derivative(name, value, f"{source}: [derivatives.{name}]")
                   for name, value in declared.items()]
    channels = _channel_map(mapping, source)
    if isinstance(template, str):
        template = _recorded_control_units(TEMPLATES[template], channels)
    condition = FlightCondition.from_mapping(condition)
    if populate == "none":
        if remove:
            raise DataFileError(f"{source}: [structure] remove needs populate = 'all'; "
                                f"with 'none', declare only the derivatives you want")
        return ModelStructure(condition, derivatives, units, template)
    both = sorted(set(remove) & set(declared))
    if both:
        raise DataFileError(f"{source}: {', '.join(both)} both removed and declared in "
                            f"[derivatives]; keep one")
    structure = ModelStructure.populated(condition, template, units).without(*remove)
    for derivative in derivatives:
        structure = structure.replacing(derivative)
    return structure


def _signals(settings: Mapping, key: str, where: str) -> dict[str, str]:
    table = _require("table", settings.get(key), f"{where} {key}")
    if not table:
        raise DataFileError(f"{where} {key} is empty; declare at least one, e.g. "
                            f'{key} = {{ q = "rate" }}')
    for name, kind in table.items():
        _require("string", kind, f"{where} {key}.{name} (its kind)")
    return dict(table)


def _control_unit(name: str, value: str, where: str) -> str:
    """A declared control's unit: ``"control"`` (% of travel) or a unit label of a travel, a
    deflection or a force."""
    try:
        unit = canonical_unit(value)
    except RotoridError:
        unit = None
    if unit is None or not unit_fits_kind(unit, "control"):
        raise DataFileError(f"{where} controls.{name} = {value!r}: give \"control\" (% of "
                            f"travel) or the unit the data record it in, one of "
                            f"{', '.join(units_of_kind('control'))}")
    return unit


def _coefficients(table, where: str) -> list[tuple[str, str, float]]:
    rows = []
    for target, terms in _require("table", table, where).items():
        for source, value in _require("table", terms, f"{where}.{target}").items():
            rows.append((target, source, _require("number", value,
                                                  f"{where}.{target}.{source}")))
    return rows


def _declared_template(settings: Mapping, where: str) -> StructureTemplate:
    """A template declared in ``[structure]`` (see the module docstring)."""
    for key in ("states", "controls", "outputs", "equations"):
        if key not in settings:
            raise DataFileError(f"{where}: a declared structure needs {key} "
                                f"(see docs/concepts.md, Declared structures)")
    states = _signals(settings, "states", where)
    controls = _signals(settings, "controls", where)
    outputs = _signals(settings, "outputs", where)
    control_units = {name: _control_unit(name, value, where) for name, value in controls.items()
                     if value != "control"}
    controls = {name: "control" for name in controls}
    kinds = {**outputs, **controls, **states}
    clash = [n for n in outputs if n in states and outputs[n] != states[n]]
    if clash:
        raise DataFileError(f"{where}: {clash[0]} is a state of kind {states[clash[0]]} and an "
                            f"output of kind {outputs[clash[0]]}; give it one kind")
    equations = _require("table", settings["equations"], f"{where} equations")
    for letter, state in equations.items():
        _require("string", state, f"{where} equations.{letter}")
    variables = settings.get("variables", list(states) + list(controls))
    if not isinstance(variables, list) or not all(isinstance(v, str) for v in variables):
        raise DataFileError(f"{where} variables must be a list of state and control names")
    output_terms = _coefficients(settings.get("output_equations", {}),
                                 f"{where} output_equations")
    written = {row[0] for row in output_terms}
    output_terms += [(name, name, 1.0) for name in outputs if name in states and
                     name not in written]
    known = DeclaredTerms(_coefficients(settings.get("known", {}), f"{where} known"),
                          output_terms)
    name = _require("string", settings.get("name", "declared"), f"{where} name")
    template = StructureTemplate(name, tuple(states), tuple(controls), tuple(outputs),
                                 f"declared in the model file ({len(states)} states)",
                                 equations, variables, kinds, known, control_units)
    silent = [o for o in outputs if o not in {row[0] for row in output_terms}]
    if silent:
        raise DataFileError(f"{where}: output {silent[0]} has no output equation; write one in "
                            f"[structure.output_equations] (e.g. {silent[0]} = "
                            f'{{ "d({next(iter(states))})" = 1.0 }})')
    template.known_terms(None, FLIGHT_TEST)  # names in the coefficients, one reader per state
    return template


def _recorded_control_units(template: StructureTemplate, channels: ChannelMap
                            ) -> StructureTemplate:
    """``template`` with each control the channel map links recorded in the link's unit
    (``deg``, ``N``, ``%`` …): controls are never converted, so the model's control
    derivatives, tables, figures and exports are per that unit."""
    stated = {link.signal: link.unit for link in channels.links
              if link.signal in template.controls}
    if not stated:
        return template
    return attrs.evolve(template, control_units={**dict(template.control_units), **stated})


def _channel_map(mapping: Mapping, source: str) -> ChannelMap:
    table = _require("table", mapping.get("channels", {}), f"{source}: [channels]")
    return ChannelMap.from_mapping(table, source)


def parse_model(mapping: Mapping, source: str = "<string>") -> ModelStructure:
    """The structure declared by a parsed model file (see the module docstring).

    ``source`` names the file in error messages. Unknown keys, wrong types and contradictory
    settings raise :class:`~rotorid.errors.DataFileError` naming the key and the source.
    """
    try:
        return _structure(mapping, source)
    except DataFileError:
        raise
    except RotoridError as error:
        raise _naming(source, error) from None


def _naming(source: str, error: Exception) -> DataFileError:
    """``error`` as a :class:`DataFileError` that names ``source`` once (errors of the
    channel map name it already)."""
    message = str(error)
    return DataFileError(message if message.startswith(f"{source}:") else f"{source}: {message}")


def _read(path: str | os.PathLike) -> Mapping:
    return read_toml(path, "model file")


def case_model(case: Mapping, condition: Mapping, units: str, source: str) -> ModelStructure:
    """The structure a case's settings declare: its ``structure`` and ``derivatives`` tables
    and its ``data`` table's ``channels`` (a case file's, or a study result's ``case``), as
    a model file at the ``[condition]`` table ``condition`` in ``units``."""
    data = case.get("data") if isinstance(case.get("data"), Mapping) else {}
    return parse_model({"units": units, "condition": dict(condition),
                        "structure": dict(case.get("structure") or {}),
                        "derivatives": dict(case.get("derivatives") or {}),
                        "channels": dict(data.get("channels") or {})}, source)


def load_model(path: str | os.PathLike) -> ModelStructure:
    """The structure declared by the TOML model file ``path``."""
    return parse_model(_read(path), source=str(Path(path)))


def load_channel_map(path: str | os.PathLike) -> ChannelMap:
    """The ``[channels]`` table of the model file ``path`` (empty without one): data column →
    channel, unit, scale and offset, as :class:`~rotorid.model.signals.ChannelMap`."""
    try:
        return _channel_map(_read(path), str(Path(path)))
    except DataFileError:
        raise
    except RotoridError as error:
        raise _naming(str(Path(path)), error) from None


# ----------------------------------------------------------------- writing
def _number(value: float) -> str:
    return repr(float(value))


def _degrees(radians: float) -> float:
    """A degree value that converts back to exactly ``radians`` where one exists (it does for
    every attitude that was itself given in degrees), so saved files load back unchanged."""
    guess = math.degrees(radians)
    for candidate in (guess, math.nextafter(guess, math.inf), math.nextafter(guess, -math.inf)):
        if math.radians(candidate) == radians:
            return candidate
    return guess


def _derivative_lines(derivative: Derivative) -> list[str]:
    lines = [f"[derivatives.{derivative.name}]"]
    if derivative.fixed:
        lines.append(f"fixed = {_number(derivative.initial)}")
    elif derivative.initial != 0.0:
        lines.append(f"initial = {_number(derivative.initial)}")
    if derivative.sign.value != "none":
        lines.append(f'sign = "{derivative.sign.value}"')
    delay = derivative.delay
    if delay is not None:
        fields = [f"initial = {_number(delay.initial)}"]
        if delay.upper is not None:
            fields.append(f"upper = {_number(delay.upper)}")
        if delay.fixed:
            fields.append("fixed = true")
        lines.append(f"delay = {{ {', '.join(fields)} }}")
    return lines


def _inline(pairs) -> str:
    return "{ " + ", ".join(f'"{k}" = {v}' for k, v in pairs) + " }"


def _template_lines(template: StructureTemplate) -> list[str]:
    """``template = "…"`` for a shipped template, else the whole declaration."""
    if TEMPLATES.get(template.name) == template:
        return [f'template = "{template.name}"']
    kinds = {**template.kind_of, **dict(template.control_units)}
    known: DeclaredTerms = template.known
    lines = [f'name = "{template.name}"']
    for key, names in (("states", template.states), ("controls", template.controls),
                       ("outputs", template.outputs)):
        lines.append(f"{key} = " + _inline((n, f'"{kinds[n]}"') for n in names))
    lines.append("equations = " + _inline((k, f'"{s}"') for k, s in template.equations))
    lines.append("variables = [" + ", ".join(f'"{v}"' for v in template.variables) + "]")
    for key, rows in (("known", known.state_terms), ("output_equations", known.output_terms)):
        grouped: dict[str, list] = {}
        for target, source, value in rows:
            grouped.setdefault(target, []).append((source, _number(value)))
        lines.append(f"{key} = {{ " + ", ".join(f'"{target}" = {_inline(pairs)}'
                                               for target, pairs in grouped.items()) + " }")
    return lines


def format_model(structure: ModelStructure) -> str:
    """The model file text of ``structure``: its template, ``populate = "all"`` with a
    ``remove`` list when its derivatives keep the template's order, else ``populate = "none"``
    with every derivative listed; derivative tables only where settings differ from the
    defaults."""
    c = structure.condition
    lines = [f"# rotorid model: {structure.describe()}",
             f'units = "{structure.units.name}"', "", "[condition]",
             f"u0_mps = {_number(c.u0)}", f"v0_mps = {_number(c.v0)}",
             f"w0_mps = {_number(c.w0)}", f"theta0_deg = {_number(_degrees(c.theta0))}",
             f"phi0_deg = {_number(_degrees(c.phi0))}", "", "[structure]",
             *_template_lines(structure.template)]
    full = structure.template.derivative_names()
    kept = set(structure.names)
    if [n for n in full if n in kept] == list(structure.names):
        lines.append('populate = "all"')
        removed = [f'"{n}"' for n in full if n not in kept]
        rows = [", ".join(removed[i:i + 8]) for i in range(0, len(removed), 8)]
        lines.append("remove = [" + "".join(f"\n    {row}," for row in rows)
                     + ("\n]" if rows else "]"))
        listed = [d for d in structure.derivatives if d != Derivative(d.name)]
    else:
        lines.append('populate = "none"')
        listed = list(structure.derivatives)
    for derivative in listed:
        lines += ["", *_derivative_lines(derivative)]
    return "\n".join(lines) + "\n"


def save_model(structure: ModelStructure, path: str | os.PathLike) -> Path:
    """Write ``structure`` to the TOML model file ``path`` atomically; return the path."""
    return atomic_write(path, format_model(structure))
