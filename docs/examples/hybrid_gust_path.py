"""Can the hybrid rotor-body structure carry the truth's response to a lateral gust?

The truth model's hover linearisation with its rotor, inflow and actuator states kept
(:class:`rotorid_helisim.linear_truth.LinearisedPlant`, ``rotor=True``) gives the frequency
responses of the eight outputs to the four sticks and to the lateral gust v_g, which acts as
−A's column of v (the aerodynamics see v − v_g). The hybrid structure's gust response is formed
the same way, as the filter-error estimator's gust (``gusts = ["v"]``) enters it. The hybrid is
fitted by least squares to the stick responses alone, and to the stick and gust responses
together (complex, each output/input pair relative to its largest magnitude, 0.02–25 rad/s),
started at the truth's own hybrid derivatives; its quasi-steady key derivatives (flap tilts
residualised) are then compared with the truth's 6-DoF ones.

If the fit to both keeps the key derivatives near the truth, the structure can describe the
gust path, and a filter-error fit that misses them on turbulent data misses for another reason
(docs/estimation.md, "The lateral gust's path"). Run from the repository root::

    python docs/examples/hybrid_gust_path.py
"""

from __future__ import annotations

import numpy as np
import scipy.optimize
from rotorid import FlightCondition, ModelStructure
from rotorid.model.hybrid import hybrid_from_six_dof, quasi_steady_derivatives
from rotorid.simulation.transfer import frequency_response
from rotorid.study.truth import truth_derivatives
from rotorid.units import SI, channel_scale
from rotorid_helisim.linear_truth import LinearisedPlant
from rotorid_helisim.source import HelisimSource

KEY = ("L_p", "M_q", "L_lat", "M_long", "N_r", "N_ped", "Z_w", "Z_coll")
#: Frequencies of the fit, rad/s: the phugoid to the top of the identification band.
OMEGA = np.geomspace(0.02, 25.0, 30)
#: Column of the lateral gust in the truth's gust vector (u, v, w, p, q, r).
LATERAL_GUST = 1


def truth_responses(plant: LinearisedPlant, outputs, units, omega=OMEGA) -> np.ndarray:
    """(F, 8, 5) responses of the truth's ``outputs`` to the sticks (per %) and to v_g, in
    ``units`` (the gust per unit of velocity)."""
    inputs = np.hstack([plant.b, plant.g[:, [LATERAL_GUST]]])
    feedthrough = np.hstack([plant.d, plant.h[:, [LATERAL_GUST]]])
    identity = np.eye(plant.n_states)
    response = np.array([plant.c @ np.linalg.solve(1j * w * identity - plant.a, inputs)
                         + feedthrough for w in omega])
    response *= channel_scale(outputs, units, SI)[None, :, None]
    response[:, :, -1] /= channel_scale(("v",), units, SI)[0]
    return response


def hybrid_responses(hybrid: ModelStructure, values, omega=OMEGA) -> np.ndarray:
    """(F, p, m + 1) responses of ``hybrid`` at ``values`` to its controls (delays exact) and to
    a gust on v: −A's column of v through the states, −C's through the derivative terms."""
    a, _, c, _ = hybrid.matrices(values)
    v = hybrid.states.index("v")
    derivative_reading = c[:, v] - hybrid.known_output_matrix()[:, v]
    identity = np.eye(hybrid.n_states)
    gust = np.array([-c @ np.linalg.solve(1j * w * identity - a, a[:, v]) - derivative_reading
                     for w in omega])
    return np.concatenate([frequency_response(hybrid, values, omega), gust[:, :, None]], axis=2)


def relative_errors(hybrid: ModelStructure, values, target: np.ndarray) -> np.ndarray:
    """(F, p, m + 1) complex errors of the hybrid's responses, each output/input pair relative
    to the truth's largest magnitude on it."""
    return (hybrid_responses(hybrid, values) - target) / np.abs(target).max(axis=0)


def misfit(errors: np.ndarray, columns) -> float:
    """RMS magnitude of ``errors`` over the input ``columns``."""
    return float(np.sqrt(np.mean(np.abs(errors[:, :, columns]) ** 2)))


def fitted(hybrid: ModelStructure, start: np.ndarray, target: np.ndarray,
           columns) -> np.ndarray:
    """The hybrid's parameters (delays within their bounds) whose responses fit ``target``'s
    input ``columns`` best in :func:`relative_errors`, from ``start``."""
    lower, upper = hybrid.bounds()

    def residuals(values):
        error = relative_errors(hybrid, values, target)[:, :, columns]
        return np.concatenate([error.real.ravel(), error.imag.ravel()])

    return scipy.optimize.least_squares(residuals, np.clip(start, lower, upper),
                                        bounds=(lower, upper), max_nfev=2000).x


def main() -> dict:
    source = HelisimSource()
    trim = source.trim(0.0)
    plant = LinearisedPlant.about(source.plant, trim, rotor=True)
    attitude = [np.degrees(trim.state[source.plant.index[name]]) for name in ("theta", "phi")]
    condition = FlightCondition.from_airspeed(0.0, *attitude)
    six_dof = ModelStructure.six_dof(condition)
    truth = truth_derivatives(source, condition, six_dof)
    hybrid = hybrid_from_six_dof(six_dof, six_dof.as_vector(truth))
    start = hybrid.initial_values()          # its quasi-steady form is the truth's 6-DoF
    target = truth_responses(plant, hybrid.outputs, hybrid.units)
    fits = {"start": start,
            "sticks": fitted(hybrid, start, target, [0, 1, 2, 3]),
            "sticks + v_g": fitted(hybrid, start, target, [0, 1, 2, 3, 4])}
    print(f"{'':8}{'truth':>9}" + "".join(f"{name:>20}" for name in fits))
    table = {"truth": {key: truth[key] for key in KEY}}
    for name, values in fits.items():
        errors = relative_errors(hybrid, values, target)
        table[name] = {**dict(zip(KEY, quasi_steady_derivatives(hybrid, values, six_dof, KEY))),
                       "misfit sticks": misfit(errors, [0, 1, 2, 3]),
                       "misfit v_g": misfit(errors, [4])}
    for key in KEY:
        print(f"{key:8}{truth[key]:9.3f}" + "".join(
            f"{table[name][key]:12.3f} {100 * (table[name][key] / truth[key] - 1):+5.0f} %"
            for name in fits))
    for row in ("misfit sticks", "misfit v_g"):
        print(f"{row:17}" + "".join(f"{table[name][row]:20.3f}" for name in fits))
    return table


if __name__ == "__main__":
    main()
