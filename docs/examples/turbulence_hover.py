"""Output error against filter error with gust states on hover data flown in turbulence.

The helisim truth model is trimmed in hover and flown through the 16 identification multisteps
(3211 and 2311, both directions, every control) twice with the same seed: in still air and in
Dryden turbulence (``moderate`` by default: σ_u = σ_v = 2.65 m/s, σ_w = 1.54 m/s, L_u = L_v =
154 m, L_w = 30.5 m, rotational gusts from the 9.8 m rotor span, convected at 5 m/s; ``light``
halves the σ; docs/truth-model.md). Each set is fitted with the hybrid rotor-body structure
(docs/hybrid.md), built on the still-air 6-DoF output-error fit (in turbulence that fit loses
the roll axis, and a hybrid built on it has no valid start), by output error and by filter
error with gust states on u, v, w (acting through the derivatives) and Gauss-Markov
disturbances on the p, q, r equations (the rotational gusts), their sizes and correlation
times started at the declared turbulence (:data:`DECLARED`). ``--from-still`` starts the
turbulent filter-error fit at the still-air output-error solution of the hybrid instead (a
diagnostic: whether the likelihood's optimum lies near it).

The key derivatives are the hybrid's quasi-steady ones (its flap tilts residualised, e.g.
L_p = τ_f·L_beta1s), compared with the truth model's residualised 6-DoF linearisation, in the
fit's Cramér-Rao bounds (CR, propagated through the residualisation) and in %. Run from the
repository root::

    python docs/examples/turbulence_hover.py [--turbulence light|moderate] [--seed N] [--quick]
                                             [--from-still] [--cutoff HZ [--decimate N]]
                                             [--hold zoh|foh] [--cyclic-delay S] [--two-stage]
                                             [--update-every] [--truth T]
                                             [--structure hybrid|six-dof]
                                             [--heave-disturbance] [--sigma SU SV SW]
                                             [--actuator-lag S] [--turbulent-only]
                                             [--longest-correlation T_w=3,...]
                                             [--amplitude AXIS=PERCENT ...]

``--quick`` shortens the records to 60 %. ``--cutoff HZ`` fits both estimators to the records
low-passed at HZ (zero phase) and kept at every N-th sample (:mod:`rotorid.resampling`; N by
default the largest whose Nyquist frequency is at least HZ, which keeps the sensor noise
white): the band the hybrid describes, without the coning, inflow and actuator dynamics above
it that the filter's one-step innovations otherwise weigh. ``--hold foh`` interpolates the
(decimated) inputs linearly between samples instead of holding them. ``--cyclic-delay S`` fixes
a delay of S s on the hybrid's four cyclic flap derivatives (:data:`FLAP_CONTROL_DELAYS`).
``--update-every`` (with ``--cutoff``) keeps every low-passed sample
(:func:`rotorid.resampling.low_passed`) for filter error, which takes its measurement update at
every N-th sample only (its ``update_every``) and steps its model through the samples between
with their recorded inputs: no hold assumption; output error still fits the decimated records.
``--truth linear`` or ``linear-rotor`` flies the maneuvers with the truth model's linearisation
(the rotor, inflow and actuator states residualised, or kept;
:func:`rotorid_helisim.linear_truth.source_flown_by`) through the same loops, gusts and sensors:
a truth without the nonlinearity, and for ``linear`` one the six-dof structure
(``--structure six-dof``) represents exactly. ``--truth hybrid`` flies the hybrid that output
error fits to the ``linear-rotor`` truth's still-air records (:func:`hybrid_truth`): one the
hybrid structure represents exactly, as near the rotor as it gets; its key derivatives are that
hybrid's own. ``--heave-disturbance`` gives filter error a
Gauss-Markov acceleration on the w equation in place of the w gust, started at the declared
vertical gust through the hover heave damping (:data:`DECLARED_HEAVE`). ``--sigma SU SV SW``
flies the translational gusts at those intensities (m/s, the preset's scale lengths) with the
rotational gusts made negligible (a 1000 m span), to see one gust component at a time.
``--actuator-lag S`` passes every recorded input through a first-order lag of S s before the
fits (:func:`rotorid.actuators.lagged_inputs`): the actuators' dynamics as known, in place of
the stick. ``--turbulent-only`` leaves the still-air fits out (the still-air records still
give the hybrid its start). ``--two-stage`` replaces every input by its least-squares
projection on the recorded multistep of its maneuver's axis (:func:`two_stage_inputs`), which
removes the stabilising loops' answer to the turbulence from the inputs (a diagnostic of
closed-loop bias). ``--amplitude coll=12 ...`` flies the multisteps of the named axes at those
amplitudes (% of travel, still air and turbulence alike; the built-in ones are long 5, lat 3,
coll 6, ped 6): inputs sized for the turbulence. ``--longest-correlation T_w=3`` limits
filter error's correlation times named (its ``longest_correlation``; with
``--heave-disturbance``, T_w is the heave disturbance's). docs/estimation.md, "Hover in moderate
turbulence", gives what each setting measured.
"""

from __future__ import annotations

import argparse
import time
import warnings

import attrs
import numpy as np
import rotorid
from rotorid import FlightCondition, ModelStructure
from rotorid.actuators import lagged_inputs
from rotorid.cli.arguments import correlation_limits
from rotorid.data import HOLDS
from rotorid.errors import IdentifiabilityWarning
from rotorid.estimation.profiles import fixing_delay
from rotorid.model.hybrid import (FLAP_CONTROL_DELAYS, hybrid_from_six_dof,
                                  quasi_steady_derivatives)
from rotorid.resampling import decimated, low_passed, white_noise_factor
from rotorid.simulation.simulator import lagged_sources
from rotorid_helisim.linear_truth import (TRUTHS, LinearisedPlant, linearised_trim,
                                          source_flown_by)
from rotorid_helisim.source import HelisimSource
from rotorid.study.truth import truth_derivatives
from rotorid_signals.signals import Multistep

KEY = ("L_p", "M_q", "L_lat", "M_long", "N_r", "N_ped", "Z_w", "Z_coll")
#: The filter-error noise model: gusts through the derivatives, rotational disturbances.
FILTER_ERROR = {"process_noise": (), "gusts": ("u", "v", "w"), "disturbances": ("q", "p", "r"),
                "max_iterations": 100}
#: Starts from the declared moderate turbulence: gust sizes in ft/s and correlation times
#: L/(5 m/s); the rotational disturbances a few deg/s² with the rotational gusts' 2.5 s.
DECLARED = {"G_u": 8.7, "Tg_u": 31.0, "G_v": 8.7, "Tg_v": 31.0, "G_w": 5.0, "Tg_w": 6.0,
            "D_p": 12.0, "T_p": 2.5, "D_q": 3.0, "T_q": 2.5, "D_r": 3.0, "T_r": 2.5}
#: ``--heave-disturbance``'s starts in place of the w gust's: the declared vertical gust
#: (5 ft/s, 6 s) through a hover heave damping of 0.3 1/s (the still-air fits' Z_w) as an
#: acceleration in ft/s². Left to the estimator's own start (a tenth of az's noise), the
#: disturbance collapsed to white noise on some flights, a likelihood several times lower.
DECLARED_HEAVE = {"D_w": 1.5, "T_w": 6.0}
#: Rotor span (m) of ``--sigma``'s gust field: rotational gusts scale down with the span.
NO_ROTATION_SPAN = 1000.0
#: What ``--truth hybrid`` fits its hybrid to (in still air) before flying it.
HYBRID_TRUTH_OF = "linear-rotor"
#: Size of each setting's gusts relative to moderate turbulence (docs/truth-model.md).
INTENSITY = {"light": 0.5, "moderate": 1.0}


def declared(turbulence: str, heave_disturbance: bool = False) -> dict[str, float]:
    """:data:`DECLARED` for ``turbulence``, with ``heave_disturbance`` its w gust's starts
    replaced by :data:`DECLARED_HEAVE`: the sizes scaled, the correlation times kept."""
    starts = ({**{n: v for n, v in DECLARED.items() if not n.endswith("_w")}, **DECLARED_HEAVE}
              if heave_disturbance else DECLARED)
    return {name: value * (INTENSITY[turbulence] if name[0] in "GD" else 1.0)
            for name, value in starts.items()}


def _settings(seed: int, quick: bool, amplitude=None) -> dict:
    """The helisim source's settings of the hover identification set (``amplitude``: the
    multisteps' amplitudes by axis, % of travel, in place of the built-in ones)."""
    return {"condition": "hover", "kinds": ["3211", "2311"], "seed": seed,
            "duration_scale": 0.6 if quick else 1.0, "amplitude": dict(amplitude or {})}


def still_air(source, seed: int, quick: bool, amplitude=None):
    """The still-air identification set flown by ``source`` and its hover trim condition."""
    still = source.generate(_settings(seed, quick, amplitude))
    first = still[0].metadata
    return still, FlightCondition.from_airspeed(0.0, first["trim_theta_deg"],
                                                first["trim_phi_deg"])


def data_sets(turbulence, seed: int, quick: bool, source=None, amplitude=None):
    """(still air, turbulent) identification sets flown by ``source`` (a helisim source; by
    default the truth model) in ``turbulence`` (a preset name or a table of the helisim
    source's turbulence settings), the hover trim condition and the truth model's data
    source."""
    source = source_flown_by("nonlinear") if source is None else source
    still, condition = still_air(source, seed, quick, amplitude)
    turbulent = source.generate({**_settings(seed, quick, amplitude), "turbulence": turbulence})
    return still, turbulent, condition, rotorid.create("data-sources", "helisim")


def hybrid_truth(seed: int, quick: bool, amplitude=None):
    """A helisim source flying the hybrid structure that output error fits to still-air
    records of :data:`HYBRID_TRUTH_OF` (a truth of exactly the hybrid's form, delays dropped,
    as near that rotor as the hybrid gets; :meth:`LinearisedPlant.of_structure`), and that
    hybrid's quasi-steady key derivatives by name."""
    rotor = source_flown_by(HYBRID_TRUTH_OF)
    still, condition = still_air(rotor, seed, quick, amplitude)
    six_dof = ModelStructure.six_dof(condition)
    hybrid = hybrid_from_six_dof(six_dof, fit("output-error", six_dof, still).values)
    values = fit("output-error", hybrid, still).values
    plant = LinearisedPlant.of_structure(hybrid, values, rotor.trim(0.0).stick)
    truth = quasi_steady_derivatives(hybrid, values, six_dof, KEY)
    return HelisimSource(plant=plant, trimmer=linearised_trim), dict(zip(KEY, truth))


def fit(name: str, structure, maneuvers, start=None, **options):
    estimator = rotorid.create("estimators", name, **options)
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        estimate = estimator.estimate(structure, maneuvers, start=start)
    print(f"  {name} {structure.template.name}: {time.perf_counter() - started:.0f} s, "
          f"{estimate.iterations} iterations, converged {estimate.converged}", flush=True)
    return estimate


#: The two-stage projection's filter spans the excitation this far back and ahead, s.
PROJECTION_SPAN = (3.0, 0.5)


def with_cyclic_delay(hybrid: ModelStructure, delay: float) -> ModelStructure:
    """``hybrid`` with every one of :data:`FLAP_CONTROL_DELAYS` delayed by ``delay`` s,
    fixed."""
    structure = hybrid.with_delays(FLAP_CONTROL_DELAYS, initial=delay)
    for name in FLAP_CONTROL_DELAYS:
        structure = fixing_delay(structure, f"tau_{name}", delay)
    return structure


def _excitation(maneuver) -> np.ndarray:
    """The multistep the pilot model flew in ``maneuver`` (its metadata), at its samples."""
    settings = {k: v for k, v in maneuver.metadata["signal"].items() if k != "type"}
    return Multistep(**settings)(maneuver.time - maneuver.time[0])


def _shifted(signal: np.ndarray, back: int, ahead: int) -> np.ndarray:
    """(N, back + ahead + 1): ``signal`` delayed by −ahead … back samples, zero outside."""
    taps = [(lag, 0) for lag in range(-ahead, back + 1)]
    return lagged_sources(signal[:, None, None], taps)[:, 0, :]


def two_stage_inputs(maneuvers):
    """``maneuvers`` with each input replaced by its projection on the excitation: per
    excited axis, one least-squares FIR filter (:data:`PROJECTION_SPAN`) from that axis's
    multistep to every input, over all the axis's records; each record starts at its own
    first input sample."""
    dt = maneuvers[0].dt
    back, ahead = (round(span / dt) for span in PROJECTION_SPAN)
    by_axis = {}
    for index, maneuver in enumerate(maneuvers):
        by_axis.setdefault(maneuver.metadata["axis"], []).append(index)
    projected = list(maneuvers)
    for indices in by_axis.values():
        regressors = np.vstack([_shifted(_excitation(maneuvers[i]), back, ahead)
                                for i in indices])
        inputs = np.vstack([maneuvers[i].inputs - maneuvers[i].inputs[0] for i in indices])
        fitted = regressors @ np.linalg.lstsq(regressors, inputs, rcond=None)[0]
        for i, part in zip(indices, np.split(fitted, np.cumsum(
                [maneuvers[i].n_samples for i in indices])[:-1])):
            projected[i] = attrs.evolve(maneuvers[i], inputs=maneuvers[i].inputs[0] + part)
    return attrs.evolve(maneuvers, maneuvers=projected)


def quasi_steady(six_dof: ModelStructure, structure: ModelStructure, estimate):
    """The key derivatives of the estimate of ``structure`` (a hybrid's with its flap tilts
    residualised, a six-dof one's as they are) and their Cramér-Rao bounds (the estimate's
    covariance through the residualisation)."""
    return estimate.propagated(lambda values: quasi_steady_derivatives(structure, values,
                                                                       six_dof, KEY))


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--turbulence", default="moderate", choices=tuple(INTENSITY))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--from-still", action="store_true")
    parser.add_argument("--cutoff", type=float,
                        help="Hz: fit records low-passed there and decimated")
    parser.add_argument("--decimate", type=int,
                        help="samples per kept sample, with --cutoff (default: the white-noise "
                             "factor, rotorid.resampling.white_noise_factor)")
    parser.add_argument("--hold", choices=HOLDS, default="zoh",
                        help="the inputs between samples: held (zoh) or interpolated (foh)")
    parser.add_argument("--cyclic-delay", type=float,
                        help="s: a fixed delay on the hybrid's four cyclic flap derivatives")
    parser.add_argument("--two-stage", action="store_true",
                        help="inputs projected on the recorded multisteps (closed-loop check)")
    parser.add_argument("--truth", default="nonlinear",
                        choices=tuple(t for t in TRUTHS if t != "linear-longitudinal")
                        + ("hybrid",),
                        help="what flies the maneuvers: the truth model, its linearisation "
                             "(rotor states residualised, or kept), or the hybrid fitted to "
                             "the rotor-kept one in still air")
    parser.add_argument("--structure", default="hybrid", choices=("hybrid", "six-dof"),
                        help="the structure fitted (six-dof: the rigid body alone)")
    parser.add_argument("--heave-disturbance", action="store_true",
                        help="filter error with a Gauss-Markov acceleration on the w equation "
                             "in place of the w gust")
    parser.add_argument("--sigma", type=float, nargs=3, metavar=("SU", "SV", "SW"),
                        help="m/s: the translational gusts' intensities in place of the "
                             "preset's, rotational gusts made negligible (1000 m span)")
    parser.add_argument("--actuator-lag", type=float, metavar="S",
                        help="s: every input through the actuators' first-order lag before "
                             "the fits (rotorid.actuators.lagged_inputs; the truth model's "
                             "actuators have 0.03 s)")
    parser.add_argument("--update-every", action="store_true",
                        help="with --cutoff: filter error on the low-passed records at full "
                             "rate, updating at every N-th sample (N as --decimate)")
    parser.add_argument("--amplitude", nargs="+", metavar="AXIS=PERCENT", default=(),
                        help="multistep amplitudes (%% of travel) in place of the built-in "
                             "ones, e.g. coll=12")
    parser.add_argument("--turbulent-only", action="store_true",
                        help="fit the turbulent records only (the still-air ones still give "
                             "the hybrid its start)")
    parser.add_argument("--longest-correlation", type=correlation_limits, default={},
                        metavar="T_w=3,...", help="filter error's longest correlation times "
                                                  "(its longest_correlation option)")
    args = parser.parse_args(argv)
    if args.update_every and args.cutoff is None:
        parser.error("--update-every needs --cutoff")
    if args.turbulent_only and args.from_still:
        parser.error("--from-still starts from the still-air fit, which --turbulent-only skips")

    try:
        amplitude = {axis: float(percent) for axis, percent in
                     (item.split("=") for item in args.amplitude)}
    except ValueError:
        parser.error(f"--amplitude takes AXIS=PERCENT items (long, lat, coll, ped), got "
                     f"{' '.join(args.amplitude)}")
    turbulence = args.turbulence if args.sigma is None else {
        "preset": args.turbulence, "sigma": list(args.sigma), "span": NO_ROTATION_SPAN}
    if args.truth == "hybrid":
        flown, truth = hybrid_truth(args.seed, args.quick, amplitude)
    else:
        flown, truth = source_flown_by(args.truth), None
    still, turbulent, condition, source = data_sets(turbulence, args.seed, args.quick, flown,
                                                  amplitude)
    if args.actuator_lag is not None:
        still, turbulent = (lagged_inputs(data, args.actuator_lag) for data in (still, turbulent))
    six_dof = ModelStructure.six_dof(condition)
    truth = truth or truth_derivatives(source, condition, six_dof)
    if args.structure == "six-dof":
        if args.cyclic_delay is not None:
            parser.error("--cyclic-delay acts on the hybrid's flap equations")
        structure = six_dof
    else:
        structure = hybrid_from_six_dof(six_dof, fit("output-error", six_dof, still).values)
        if args.cyclic_delay is not None:
            structure = with_cyclic_delay(structure, args.cyclic_delay)
    if args.two_stage:
        still, turbulent = (two_stage_inputs(data) for data in (still, turbulent))
    unfiltered, filter_options = (still, turbulent), dict(FILTER_ERROR)
    starts = declared(args.turbulence, args.heave_disturbance)
    if args.heave_disturbance:
        filter_options.update(gusts=("u", "v"), disturbances=("q", "p", "r", "w"))
    if args.longest_correlation:
        filter_options["longest_correlation"] = args.longest_correlation
    if args.cutoff is not None:
        still, turbulent = (decimated(data, args.decimate, args.cutoff)
                            for data in (still, turbulent))
    if args.update_every:
        filter_options["update_every"] = (args.decimate
                                          or white_noise_factor(unfiltered[0][0].dt, args.cutoff))
        for_filter = tuple(low_passed(data, args.cutoff) for data in unfiltered)
    else:
        for_filter = (still, turbulent)
    still, turbulent, *for_filter = (attrs.evolve(data, hold=args.hold)
                                     for data in (still, turbulent, *for_filter))
    columns, noise = {}, {}
    still_solution = None
    for (air, data), filtered in zip((("still", still), (args.turbulence, turbulent)),
                                     for_filter):
        if air == "still" and args.turbulent_only:
            continue
        output_error = fit("output-error", structure, data)
        columns[f"OE {air}"] = quasi_steady(six_dof, structure, output_error)
        start = starts
        if air == "still":
            still_solution = dict(zip(structure.parameter_names, output_error.values))
        elif args.from_still:
            start = {**still_solution, **start}
        filter_error = fit("filter-error", structure, filtered, start=start, **filter_options)
        columns[f"FE {air}"] = quasi_steady(six_dof, structure, filter_error)
        noise[air] = {n: filter_error.value(n) for n in filter_error.parameter_names
                      if n.split("_")[0] in ("D", "G", "T", "Tg", "R")}
        noise[air].update({f"OE R_{o}": r for o, r in
                           zip(structure.outputs, np.diag(output_error.noise_covariance))})
    print(f"\n{'':8}{'truth':>8}" + "".join(f"{name:>30}" for name in columns))
    table = {}
    for i, key in enumerate(KEY):
        row = f"{key:8}{truth[key]:8.3f}"
        for name, (values, bounds) in columns.items():
            error = values[i] - truth[key]
            table[(name, key)] = {"value": values[i], "cr": bounds[i],
                                  "percent": 100 * error / abs(truth[key]),
                                  "cr_off": error / bounds[i]}
            row += (f"{values[i]:9.3f} ±{bounds[i]:6.3f}{100 * error / abs(truth[key]):+5.0f} %"
                    f"{error / bounds[i]:+6.1f}")
        print(row)
    for air, values in noise.items():
        print(f"\n{air}: " + ", ".join(f"{n} {v:.4g}" for n, v in values.items()))
    return table


if __name__ == "__main__":
    main()
