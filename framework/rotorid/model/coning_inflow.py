"""The coning/inflow hybrid model built on a hybrid model, and its start values
(docs/hybrid.md, "Coning and inflow").

Two first-order states join the hybrid model: the coning β0 (up) and the uniform induced
velocity vi through the disc (down the shaft). Their equations and the heave equation read

    β̇0 = B0_beta0·β0 + B0_vi·vi + B0_w·w + ΣB0_c·c (+ B0_u·u)
    v̇i = Vi_vi·vi + Vi_beta0·β0 + Vi_w·w (+ Vi_u·u)
    ẇ  = … + Z_beta0·β0 + Z_vi·vi              (Z_coll left out: the collective acts through
                                                the coning)

The blade sees the induced velocity and the climb rate only as their difference, and the
hand derivation gives B0_vi = −4/(3R) for any Lock number and flap stiffness: it is fixed,
and it fixes the scale of the unmeasured induced velocity (as the known rate feedback fixes
the tilts'). The start below makes the model's quasi-steady form (β0 and vi residualised)
exactly the hybrid model it is built on:

    B0_beta0 = −1/τβ   B0_w = k   B0_vi = −k   B0_coll = k·Z_coll/Z_w   (k = 4/(3R))
    Vi_vi = −1/τλ      Vi_w = 1/(2τλ)           Z_w, Z_vi = −Z_w, Z_beta0 = Z_w/(τβ·k)

(the hybrid's Z_w and Z_coll), so vi settles at w/2 (the momentum-theory ratio of hover) and
the coning carries the collective's heave response.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from rotorid.errors import StructureError
from rotorid.model.structure import ModelStructure
from rotorid.units import UnitSystem

#: The coning/inflow template of each hybrid template (flap tilts unmeasured, measured).
CONING_INFLOW_TEMPLATES = {"hybrid": "hybrid-inflow", "hybrid-flap": "hybrid-inflow-flap"}
#: What the coning/inflow model adds to a hybrid structure.
CONING_DERIVATIVES = ("B0_u", "B0_w", "B0_beta0", "B0_vi", "B0_long", "B0_lat", "B0_coll")
INFLOW_DERIVATIVES = ("Vi_u", "Vi_w", "Vi_beta0", "Vi_vi")
HEAVE_DERIVATIVES = ("Z_beta0", "Z_vi")
#: Derivatives that carry a delay for the actuators between stick and blade angle.
CONING_CONTROL_DELAYS = ("B0_coll",)
#: Sign priors (docs/hybrid.md): the coning and inflow lags, collective up cones the rotor
#: up, more coning (thrust) drives more inflow and pulls the aircraft up.
SIGNS = {"B0_beta0": "negative", "B0_coll": "positive", "Vi_vi": "negative",
         "Vi_beta0": "positive", "Z_beta0": "negative"}
#: Start of the first-order coning lag, s (8/(λβ²·γ·Ω): 0.011 s for the Bo-105).
DEFAULT_CONING_TIME_CONSTANT = 0.012
#: Start of the uniform inflow's lag, s ((8/3π)/(4·λ0·Ω) in hover: 0.097 s for the Bo-105).
DEFAULT_INFLOW_TIME_CONSTANT = 0.09


def coning_gain(rotor_radius: float, units: UnitSystem) -> float:
    """k = 4/(3R): the coning rate per unit of climb rate minus induced velocity, in
    ``units`` (deg/s per ft/s, or rad/s per m/s), for a rotor of radius ``rotor_radius`` m."""
    radius = float(rotor_radius)
    if not math.isfinite(radius) or radius <= 0.0:
        raise StructureError(f"rotor radius must be a positive number of metres, got "
                             f"{rotor_radius!r}")
    return 4.0 / (3.0 * radius) * units.angle_per_radian / units.length_per_metre


def coning_inflow_start(hybrid: Mapping[str, float], gain: float,
                        coning_time_constant: float = DEFAULT_CONING_TIME_CONSTANT,
                        inflow_time_constant: float = DEFAULT_INFLOW_TIME_CONSTANT
                        ) -> dict[str, float]:
    """Coning, inflow and heave start values whose quasi-steady model is ``hybrid``.

    Args:
        hybrid: the hybrid model's derivative values by name (absent names are 0).
        gain: k of :func:`coning_gain`, in the hybrid's units.
        coning_time_constant, inflow_time_constant: τβ and τλ in s, > 0.
    Returns:
        Values of :data:`CONING_DERIVATIVES`, :data:`INFLOW_DERIVATIVES`,
        :data:`HEAVE_DERIVATIVES` and ``Z_w`` (module docstring).
    """
    for label, value in (("coning", coning_time_constant), ("inflow", inflow_time_constant)):
        if not math.isfinite(value) or value <= 0.0:
            raise StructureError(f"{label} time constant must be a positive number of "
                                 f"seconds, got {value!r}")
    z_w, z_coll = float(hybrid.get("Z_w", 0.0)), float(hybrid.get("Z_coll", 0.0))
    if not z_w < 0.0:
        raise StructureError(f"coning/inflow start: the hybrid model's heave damping Z_w is "
                             f"{z_w:g}; the start puts the rotor's part of it on the coning and "
                             f"needs Z_w < 0, so keep Z_w in the hybrid model it comes from")
    start = dict.fromkeys(CONING_DERIVATIVES + INFLOW_DERIVATIVES, 0.0)
    start.update({"B0_beta0": -1.0 / coning_time_constant, "B0_w": gain, "B0_vi": -gain,
                  "B0_coll": gain * z_coll / z_w, "Vi_vi": -1.0 / inflow_time_constant,
                  "Vi_w": 0.5 / inflow_time_constant, "Z_w": z_w, "Z_vi": -z_w,
                  "Z_beta0": z_w / (coning_time_constant * gain)})
    return start


def coning_inflow_from_hybrid(structure: ModelStructure, values, rotor_radius: float,
                              coning_time_constant: float = DEFAULT_CONING_TIME_CONSTANT,
                              inflow_time_constant: float = DEFAULT_INFLOW_TIME_CONSTANT,
                              delay_upper: float | None = 0.1) -> ModelStructure:
    """The coning/inflow structure of a hybrid structure and its values, started at
    :func:`coning_inflow_start`.

    It holds the hybrid structure's derivatives as they are (fixed ones, sign priors and
    delays kept; estimates as start values) but ``Z_coll``, and the coning, inflow and heave
    derivatives above with the :data:`SIGNS` priors, ``B0_vi`` fixed at −4/(3R), and, unless
    ``delay_upper`` is ``None``, a free delay (0 … ``delay_upper`` s, start 0) on each of
    :data:`CONING_CONTROL_DELAYS`, as on the controls into flapping.

    Args:
        structure: a ``hybrid`` or ``hybrid-flap`` structure; values: its parameter vector or
            mapping.
        rotor_radius: R in m.
    """
    name = structure.template.name
    if name not in CONING_INFLOW_TEMPLATES:
        raise StructureError(f"the coning/inflow model is built on a hybrid structure "
                             f"({', '.join(CONING_INFLOW_TEMPLATES)}), got the {name} template")
    hybrid = {d.name: d.initial for d in structure.derivatives if d.fixed}
    hybrid.update(structure.as_mapping(values))
    gain = coning_gain(rotor_radius, structure.units)
    start = coning_inflow_start(hybrid, gain, coning_time_constant, inflow_time_constant)
    populated = ModelStructure.populated(structure.condition, CONING_INFLOW_TEMPLATES[name],
                                         structure.units, SIGNS)
    added = CONING_DERIVATIVES + INFLOW_DERIVATIVES + HEAVE_DERIVATIVES
    extended = populated.without(*(n for n in populated.names if n not in added))
    for derivative in structure.derivatives:
        if derivative.name != "Z_coll":
            extended = extended.replacing(derivative)
    extended = extended.fixing("B0_vi", start.pop("B0_vi"))
    initial = {**hybrid, **start}
    extended = extended.with_initial({n: float(v) for n, v in initial.items()
                                      if n in extended.parameter_names})
    if delay_upper is None:
        return extended
    return extended.with_delays(CONING_CONTROL_DELAYS, upper=delay_upper)
