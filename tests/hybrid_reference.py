"""The 70 kt hybrid reference as a true model for tests: the truth model's full linearisation
reduced to the hybrid's states (docs/hybrid.md), its quasi-steady 6-DoF model, and open-loop
multisteps simulated with it. At 70 kt the model is stable, so open-loop records stay near
trim."""

from __future__ import annotations

import warnings

import attrs
import numpy as np
import rotorid
from hover_reference import multistep
from rotorid import FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.errors import IdentifiabilityWarning
from rotorid.model.residualisation import residualise
from rotorid.model.templates import HYBRID
from rotorid.simulation.simulator import simulate
from rotorid.model.residualisation import derivatives_of
from rotorid_helisim.linearize import PADFIELD_STATES, linearize

#: white-noise standard deviations per output (ft/s², deg/s, deg), ax az q θ ay p φ r
NOISE = np.array([0.1, 0.1, 0.1, 0.05, 0.1, 0.1, 0.05, 0.1])
#: white-noise standard deviation of a measured rotor state (deg, ft/s)
ROTOR_NOISE = 0.1
#: actuator-like delays of the true model on the controls into flapping, s
TRUE_DELAY = 0.03


def hybrid_reference(truth_model, trim, template=HYBRID
                     ) -> tuple[FlightCondition, np.ndarray, np.ndarray]:
    """(condition, A, B) of the reference over ``template``'s states at ``trim`` (every other
    state of the truth's full linearisation residualised), flight-test units."""
    full = linearize(truth_model, trim, full=True, units="flight-test")
    a, b = residualise(full.A, full.B, full.states, template.states)
    condition = FlightCondition.from_airspeed(trim.airspeed_kt, trim.theta_deg, trim.phi_deg)
    return condition, a, b


def six_dof_of(condition, a, b) -> tuple[ModelStructure, np.ndarray]:
    """The quasi-steady 6-DoF structure (every derivative) and values of a hybrid (A, B)."""
    structure = ModelStructure.six_dof(condition)
    a6, b6 = residualise(a, b, HYBRID.states, PADFIELD_STATES)
    return structure, structure.as_vector(derivatives_of(structure, a6, b6))


def open_loop_maneuvers(structure, values, seed, duration=10.0, dt=0.02, amplitude=2.0
                        ) -> ManeuverSet:
    """3211 and 2311 multisteps (0.15 s unit, ``amplitude`` % of travel) on every control, both
    directions, open loop, outputs with white noise :data:`NOISE`. Outputs beyond the body's
    eight (measured rotor states) become extra channels with noise :data:`ROTOR_NOISE`."""
    n = int(round(duration / dt)) + 1
    time = np.arange(n) * dt
    clean = []
    for axis, control in enumerate(structure.controls):
        for kind in ("3211", "2311"):
            for direction in (1, -1):
                inputs = np.zeros((n, 4))
                inputs[:, axis] = multistep(kind, direction, n, dt, amplitude, 0.15)
                clean.append(Maneuver(f"{kind}_{control}_{direction:+d}", time, inputs,
                                      np.zeros((n, 8))))
    clean = ManeuverSet(clean)
    rng = np.random.default_rng(seed)
    noise = np.concatenate([NOISE, np.full(structure.n_outputs - NOISE.size, ROTOR_NOISE)])
    noisy = []
    for maneuver, y in zip(clean, simulate(structure, values, clean)):
        y = y + rng.normal(size=y.shape) * noise
        rotor = dict(zip(structure.outputs[NOISE.size:], y[:, NOISE.size:].T))
        noisy.append(attrs.evolve(maneuver.with_outputs(y[:, :NOISE.size]),
                                  extra_channels=rotor))
    return ManeuverSet(noisy)


def true_values(structure, a, b) -> np.ndarray:
    """``structure``'s parameter vector read from the reference (A, B), every delay (the
    actuators') at :data:`TRUE_DELAY`."""
    truth = derivatives_of(structure, a, b)
    return structure.as_vector(
        {**{n: truth[n] for n in structure.parameter_names if n in truth},
         **{d.delay_name: TRUE_DELAY for d in structure.free_delays}})


def recovery(structure, maneuvers, truth: np.ndarray):
    """(estimate, errors in Cramér-Rao bounds) of an output-error fit of ``structure`` to
    ``maneuvers`` against the true parameter vector ``truth``; the fit must converge."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        estimate = rotorid.create("estimators", "output-error").estimate(structure, maneuvers)
    assert estimate.converged
    return estimate, (estimate.values - truth) / estimate.cramer_rao
