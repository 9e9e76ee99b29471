"""The hybrid rotor-body model built on a 6-DoF model, and its start values (docs/hybrid.md).

With the flap equations β̇1c = q − β1c/τ + ΣBc·u and β̇1s = p − β1s/τ + ΣBs·u (no
cross-coupling), the disc settles quasi-statically at β1c = τ·(q + ΣBc·u) and
β1s = τ·(p + ΣBs·u). Moving the 6-DoF model's roll and pitch rate derivatives and its cyclic
controls' roll and pitch derivatives onto the disc tilt,

    L_beta1c = L_q/τ   L_beta1s = L_p/τ   M_beta1c = M_q/τ   M_beta1s = M_p/τ
    [[L_q, L_p], [M_q, M_p]]·[Bc_c, Bs_c]ᵀ = [L_c, M_c]ᵀ   for each cyclic control c

therefore gives a hybrid model whose quasi-steady form is the 6-DoF model itself: a hybrid
fit started there begins where the 6-DoF fit ended.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rotorid.errors import StructureError
from rotorid.model.structure import ModelStructure

#: What the hybrid model adds to a 6-DoF structure: the flap equations' own damping and
#: cross-coupling, the hub moments per disc tilt, and (:func:`hybrid_from_six_dof`) the
#: controls into flapping.
FLAP_DERIVATIVES = ("Bc_beta1c", "Bc_beta1s", "Bs_beta1c", "Bs_beta1s")
DISC_MOMENTS = ("L_beta1c", "L_beta1s", "M_beta1c", "M_beta1s")
#: Sign priors of the flap damping and the on-axis hub moments (docs/hybrid.md).
SIGNS = {"Bc_beta1c": "negative", "Bs_beta1s": "negative", "L_beta1s": "negative",
         "M_beta1c": "negative"}
#: The cyclic controls: they tilt the disc, and act on roll and pitch only through it.
CYCLIC = ("long", "lat")
#: The body's direct roll and pitch derivatives the hybrid model leaves out: the rates' (the
#: disc tilt carries the rotor's rate damping; with a direct M_q beside it, q/δ_long determines
#: only M_beta1c·Bc_long, 1/τ − M_q and M_q/τ + M_beta1c, so τ trades with M_q) and the cyclic
#: controls' (they trade with the controls into flapping and the actuator delays).
DIRECT_DERIVATIVES = ("L_p", "L_q", "M_p", "M_q", "L_long", "L_lat", "M_long", "M_lat")
#: Derivatives that carry a delay for the actuators between stick and blade angle.
FLAP_CONTROL_DELAYS = ("Bc_long", "Bc_lat", "Bs_long", "Bs_lat")
#: The templates of the hybrid model without coning and inflow: flap states unmeasured, measured.
FLAP_TEMPLATES = ("hybrid", "hybrid-flap")
#: Start of the flap time constant when nothing better is known, s (hingeless rotors: 0.05–0.1).
DEFAULT_FLAP_TIME_CONSTANT = 0.07


def hybrid_start(six_dof: Mapping[str, float],
                 flap_time_constant: float = DEFAULT_FLAP_TIME_CONSTANT) -> dict[str, float]:
    """Hybrid derivative values whose quasi-steady model is ``six_dof``.

    Args:
        six_dof: 6-DoF derivative values by name (absent names are 0), in the hybrid's units.
        flap_time_constant: τ in s, > 0.
    Returns:
        Values by hybrid derivative name: the 6-DoF's derivatives but
        :data:`DIRECT_DERIVATIVES` unchanged, and the disc-tilt terms above.
    """
    tau = float(flap_time_constant)
    if not np.isfinite(tau) or tau <= 0.0:
        raise StructureError(f"flap time constant must be a positive number of seconds, "
                             f"got {flap_time_constant!r}")
    value = lambda name: float(six_dof.get(name, 0.0))  # noqa: E731
    rates = np.array([[value("L_q"), value("L_p")], [value("M_q"), value("M_p")]])
    if abs(np.linalg.det(rates)) < 1e-12 * max(np.abs(rates).max() ** 2, 1e-300):
        raise StructureError(
            "hybrid start: the 6-DoF model's roll and pitch rate derivatives [[L_q, L_p], "
            "[M_q, M_p]] are singular, so its cyclic derivatives cannot be moved onto the "
            "disc tilt; keep L_p and M_q in the 6-DoF model the start comes from")
    start = {n: v for n, v in six_dof.items() if n not in DIRECT_DERIVATIVES}
    start.update({"L_beta1c": rates[0, 0] / tau, "L_beta1s": rates[0, 1] / tau,
                  "M_beta1c": rates[1, 0] / tau, "M_beta1s": rates[1, 1] / tau,
                  "Bc_beta1c": -1.0 / tau, "Bs_beta1s": -1.0 / tau})
    for control in CYCLIC:
        flap = np.linalg.solve(rates, [value(f"L_{control}"), value(f"M_{control}")])
        start[f"Bc_{control}"], start[f"Bs_{control}"] = float(flap[0]), float(flap[1])
    return start


def hybrid_from_six_dof(structure: ModelStructure, values,
                        flap_time_constant: float = DEFAULT_FLAP_TIME_CONSTANT,
                        delay_upper: float | None = 0.1,
                        template: str = "hybrid") -> ModelStructure:
    """The hybrid structure of a 6-DoF structure and its estimate, started at
    :func:`hybrid_start`.

    It holds the 6-DoF structure's derivatives but :data:`DIRECT_DERIVATIVES` (delays
    dropped), :data:`FLAP_DERIVATIVES` and :data:`DISC_MOMENTS` with the :data:`SIGNS` priors,
    both flap equations' derivative on each control that has a roll or pitch derivative in
    ``structure`` (the collective's and the pedal's start at 0), and, unless ``delay_upper`` is
    ``None``, a free delay (0 … ``delay_upper`` s) on each of :data:`FLAP_CONTROL_DELAYS`.

    Args:
        structure: a ``six-dof`` structure; values: its parameter vector or mapping.
        flap_time_constant: τ of the start in s.
        template: ``hybrid``, or ``hybrid-flap`` for data that measure the tip-path-plane
            tilts (extra channels ``beta1c beta1s``).
    """
    if structure.template.name != "six-dof":
        raise StructureError(f"the hybrid model is built on a six-dof structure, got the "
                             f"{structure.template.name} template")
    if template not in FLAP_TEMPLATES:
        raise StructureError(f"a hybrid model built on a six-dof model uses one of the "
                             f"templates {', '.join(FLAP_TEMPLATES)}, not {template!r}")
    six_dof = {d.name: d.initial for d in structure.derivatives if d.fixed}
    six_dof.update(structure.as_mapping(values))
    controls = [c for c in structure.controls
                if {f"L_{c}", f"M_{c}"} & set(structure.names)]
    keep = ((set(structure.names) - set(DIRECT_DERIVATIVES)) | set(FLAP_DERIVATIVES)
            | set(DISC_MOMENTS)
            | {f"{letter}_{c}" for letter in ("Bc", "Bs") for c in controls})
    populated = ModelStructure.populated(structure.condition, template, structure.units, SIGNS)
    hybrid = populated.without(*(n for n in populated.names if n not in keep))
    for derivative in structure.derivatives:
        if derivative.fixed and derivative.name in hybrid.names:
            hybrid = hybrid.fixing(derivative.name, derivative.initial)
    start = hybrid_start(six_dof, flap_time_constant)
    hybrid = hybrid.with_initial({n: v for n, v in start.items() if n in hybrid.parameter_names})
    if delay_upper is None:
        return hybrid
    return hybrid.with_delays(FLAP_CONTROL_DELAYS, upper=delay_upper, missing="skip")
