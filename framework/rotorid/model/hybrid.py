"""The hybrid rotor-body model built on a 6-DoF model, and its start values (docs/hybrid.md).

With the flap equations β̇1c = q − β1c/τ + ΣBc·z and β̇1s = p − β1s/τ + ΣBs·z (no
cross-coupling), the disc settles quasi-statically at β1c = τ·(q + ΣBc·z) and
β1s = τ·(p + ΣBs·z). The rotor's part of the body's equations follows the disc. Moving, in
each of :data:`DISC_EQUATIONS` (E), the 6-DoF model's rate derivatives onto the disc tilt and,
for each variable z of :data:`FLAPPING`, the roll and pitch derivatives into the flap
equations,

    E_beta1c = E_q/τ   E_beta1s = E_p/τ
    [[L_q, L_p], [M_q, M_p]]·[Bc_z, Bs_z]ᵀ = [L_z, M_z]ᵀ

with the direct E_z − E_q·Bc_z − E_p·Bs_z left in the force and yaw equations, therefore gives
a hybrid model whose quasi-steady form is the 6-DoF model itself: a hybrid fit started there
begins where the 6-DoF fit ended.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rotorid.errors import StructureError
from rotorid.model.residualisation import derivatives_of, residualise
from rotorid.model.structure import ModelStructure

#: What the hybrid model adds to a 6-DoF structure: the flap equations' own damping and
#: cross-coupling, the hub moments per disc tilt, and (:func:`hybrid_from_six_dof`) the
#: other equations' terms on the disc tilt and the flap equations' terms on the controls and
#: velocities.
FLAP_DERIVATIVES = ("Bc_beta1c", "Bc_beta1s", "Bs_beta1c", "Bs_beta1s")
DISC_MOMENTS = ("L_beta1c", "L_beta1s", "M_beta1c", "M_beta1s")
#: Sign priors of the flap damping and the on-axis hub moments (docs/hybrid.md).
SIGNS = {"Bc_beta1c": "negative", "Bs_beta1s": "negative", "L_beta1s": "negative",
         "M_beta1c": "negative"}
#: What a reduction keeps (:func:`rotorid.estimation.reduction.reduce`, ``keep``): without its
#: flap damping and on-axis hub moments the disc is no rotor.
REQUIRED = tuple(SIGNS)
#: Equations whose rotor part follows the disc tilt: the rotor's in-plane forces (the thrust
#: tilts with the disc) and its moments (the yaw equation's through the product of inertia).
#: Not Z: to first order the thrust does not change with the tilt.
DISC_EQUATIONS = ("X", "Y", "L", "M", "N")
#: The disc equations that keep a direct part of their terms on :data:`FLAPPING` (the flap
#: equations' terms are solved from the roll and pitch ones).
DIRECT_PART = ("X", "Y", "N")
#: Each disc tilt and the body rate it follows (its known term in the flap equation).
TILT_RATES = (("beta1c", "q"), ("beta1s", "p"))
#: Variables that tilt the disc: the cyclic controls, and the velocities (the flapback on u
#: and w, the flapping's dihedral on v). Their roll and pitch moments act through the disc.
FLAPPING = ("long", "lat", "u", "v", "w")
#: The body's direct derivatives the hybrid model leaves out: the disc equations' rate
#: derivatives (the disc carries the rotor's rate damping; with a direct M_q beside it,
#: q/δ_long determines only M_beta1c·Bc_long, 1/τ − M_q and M_q/τ + M_beta1c, so τ trades
#: with M_q) and the roll and pitch derivatives of :data:`FLAPPING` (they trade with the flap
#: equations' terms and the actuator delays).
DIRECT_DERIVATIVES = (tuple(f"{e}_{rate}" for e in DISC_EQUATIONS for _, rate in TILT_RATES)
                      + tuple(f"{e}_{z}" for e in ("L", "M") for z in FLAPPING))
#: Derivatives that carry a delay for the actuators between stick and blade angle.
FLAP_CONTROL_DELAYS = ("Bc_long", "Bc_lat", "Bs_long", "Bs_lat")
#: Upper bound of those delays, s.
FLAP_DELAY_UPPER = 0.1
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
        :data:`DIRECT_DERIVATIVES`, with the force and yaw equations' terms on
        :data:`FLAPPING` reduced by what the disc carries, and the disc-tilt and flap terms
        above.
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
    start.update({f"{e}_{tilt}": value(f"{e}_{rate}") / tau
                  for e in DISC_EQUATIONS for tilt, rate in TILT_RATES})
    start.update({"Bc_beta1c": -1.0 / tau, "Bs_beta1s": -1.0 / tau})
    for z in FLAPPING:
        flap_c, flap_s = np.linalg.solve(rates, [value(f"L_{z}"), value(f"M_{z}")])
        start[f"Bc_{z}"], start[f"Bs_{z}"] = float(flap_c), float(flap_s)
        for e in DIRECT_PART:
            start[f"{e}_{z}"] = (value(f"{e}_{z}") - value(f"{e}_q") * flap_c
                                 - value(f"{e}_p") * flap_s)
    return start


def hybrid_from_six_dof(structure: ModelStructure, values,
                        flap_time_constant: float = DEFAULT_FLAP_TIME_CONSTANT,
                        delay_upper: float | None = FLAP_DELAY_UPPER,
                        template: str = "hybrid") -> ModelStructure:
    """The hybrid structure of a 6-DoF structure and its estimate, started at
    :func:`hybrid_start`.

    It holds the 6-DoF structure's derivatives but :data:`DIRECT_DERIVATIVES` (delays
    dropped); :data:`FLAP_DERIVATIVES` and :data:`DISC_MOMENTS` with the :data:`SIGNS` priors;
    each disc equation's term on a disc tilt whose rate (:data:`TILT_RATES`) it had a
    derivative of; both flap equations' terms on each control and velocity that has a roll or
    pitch derivative in ``structure`` (the collective's and the pedal's start at 0); the force
    and yaw equations' direct terms on each of :data:`FLAPPING` the disc now carries part of;
    and, unless ``delay_upper`` is ``None``, the delays of :func:`with_flap_delays` (up to
    ``delay_upper`` s).

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
    populated = ModelStructure.populated(structure.condition, template, structure.units, SIGNS)
    hybrid = populated.without(*(n for n in populated.names
                                 if n not in _hybrid_names(set(structure.names),
                                                           structure.controls)))
    for derivative in structure.derivatives:
        if derivative.fixed and derivative.name in hybrid.names:
            hybrid = hybrid.fixing(derivative.name, derivative.initial)
    start = hybrid_start(six_dof, flap_time_constant)
    hybrid = hybrid.with_initial({n: v for n, v in start.items() if n in hybrid.parameter_names})
    return hybrid if delay_upper is None else with_flap_delays(hybrid, delay_upper)


def quasi_steady_derivatives(hybrid: ModelStructure, values, six_dof: ModelStructure,
                             names) -> np.ndarray:
    """The 6-DoF derivatives ``names`` of a hybrid model with its flap tilts residualised
    (β̇1c = β̇1s = 0, e.g. L_p = τ·L_beta1s), shape (len(names),).

    Args:
        hybrid: the hybrid structure; values: its parameter vector (delays ignored: a delay
            does not change a quasi-steady gain), or a longer vector that starts with it
            (an estimate's, noise parameters after it).
        six_dof: a six-dof structure over the hybrid's rigid-body states (its template names
            the derivatives).
        names: derivatives of the six-dof template, e.g. ``("L_p", "M_q")``.
    """
    a, b, _, _ = hybrid.matrices(np.asarray(values, dtype=float)[:hybrid.n_parameters])
    a, b = residualise(a, b, hybrid.states, six_dof.states)
    derivatives = derivatives_of(six_dof, a, b)
    return np.array([derivatives[name] for name in names])


def with_flap_delays(hybrid: ModelStructure,
                     upper: float = FLAP_DELAY_UPPER) -> ModelStructure:
    """``hybrid`` with a free delay (0 … ``upper`` s) on each of :data:`FLAP_CONTROL_DELAYS`
    it has."""
    return hybrid.with_delays(FLAP_CONTROL_DELAYS, upper=upper, missing="skip")


def _hybrid_names(six_dof: set[str], controls) -> set[str]:
    """The derivatives of the hybrid model built on a 6-DoF structure of these derivative
    names and controls (:func:`hybrid_from_six_dof`)."""
    tilting = [z for z in (*controls, "u", "v", "w") if {f"L_{z}", f"M_{z}"} & six_dof]
    disc = {e: [tilt for tilt, rate in TILT_RATES if f"{e}_{rate}" in six_dof]
            for e in DISC_EQUATIONS}
    return ((six_dof - set(DIRECT_DERIVATIVES)) | set(FLAP_DERIVATIVES) | set(DISC_MOMENTS)
            | {f"{e}_{tilt}" for e, tilts in disc.items() for tilt in tilts}
            | {f"{letter}_{z}" for letter in ("Bc", "Bs") for z in tilting}
            | {f"{e}_{z}" for e in DIRECT_PART if disc[e] for z in FLAPPING if z in tilting})
