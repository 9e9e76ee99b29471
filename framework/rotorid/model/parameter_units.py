"""The units of a linear structure's parameters, from the signals they connect.

A derivative ``<letter>_<variable>`` adds ``value · variable`` to the rate of change of the
state its equation drives, so its unit is (unit of that state)/s per unit of the variable:
``L_p`` in 1/s, ``M_long`` in deg/s² per % (flight-test units), ``X_alpha`` in m/s² per rad
(SI). A delay is in s. Controls stay in the data's own unit: the one a declared structure
states for them (``deg``, ``N``), else % of travel for the helicopter's four stick channels
(the default data layout) and "control unit" for any other control.
"""

from __future__ import annotations

from rotorid.model.derivatives import CONTROL_VARIABLES

#: Unit of the helicopter's stick channels (``long lat coll ped``) in the default data layout.
HELICOPTER_CONTROL_UNIT = "%"
#: Unit of any other control: whatever the data record it in.
CONTROL_UNIT = "control unit"
#: Unit of a delay parameter.
DELAY_UNIT = "s"
_PER_SECOND = {0: "", 1: "/s", 2: "/s²", 3: "/s³"}


def control_unit(control: str) -> str:
    """The unit a control is reported in: ``%`` for the helicopter's, else ``control unit``."""
    return HELICOPTER_CONTROL_UNIT if control in CONTROL_VARIABLES else CONTROL_UNIT


def _split(unit: str) -> tuple[str, int]:
    """``"ft/s²"`` → (``"ft"``, 2): the unit as a base and a power of 1/s."""
    for power in (3, 2, 1):
        suffix = _PER_SECOND[power]
        if unit.endswith(suffix) and len(unit) > len(suffix):
            return unit[: -len(suffix)], power
    return unit, 0


def _joined(base: str, power: int) -> str:
    return base + _PER_SECOND[power]


def rate_unit(unit: str) -> str:
    """The unit of the rate of change of a signal in ``unit`` (``"ft/s"`` → ``"ft/s²"``)."""
    base, power = _split(unit)
    return _joined(base, power + 1)


def derivative_unit(state_unit: str, variable_unit: str) -> str:
    """Unit of a derivative driving a state in ``state_unit`` from a variable in
    ``variable_unit``: (state unit)/s per variable unit, shortened where the bases cancel
    (``"deg/s", "deg/s"`` → ``"1/s"``; ``"deg/s", "deg"`` → ``"1/s²"``)."""
    state_base, state_power = _split(state_unit)
    variable_base, variable_power = _split(variable_unit)
    if state_base == variable_base:
        power = state_power + 1 - variable_power
        return {0: "1", -1: "s"}.get(power) or f"1{_PER_SECOND[power]}"
    return f"{rate_unit(state_unit)} per {variable_unit}"


def structure_parameter_units(structure) -> dict[str, str]:
    """Name → unit of every derivative of ``structure`` (a
    :class:`~rotorid.model.structure.ModelStructure`) and of its free delays (s)."""
    signals = structure.signals
    units = {}
    for derivative in structure.derivatives:
        variable = derivative.variable
        stated = dict(structure.template.control_units).get(variable)
        variable_unit = (stated or control_unit(variable) if variable in structure.controls
                         else signals.states[variable].unit)
        driven = signals.states[structure.equation_of(derivative)].unit
        units[derivative.name] = derivative_unit(driven, variable_unit)
    units.update({d.delay_name: DELAY_UNIT for d in structure.free_delays})
    return units
