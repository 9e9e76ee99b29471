"""A custom estimator plugin: equation error by linear least squares, with Cramér-Rao bounds.

rotorid chooses its estimator by name from plugins. This script writes one, registers it with
rotorid's plugin manager at run time and uses it twice: directly on a maneuver set, and as the
estimator of a flight case (``[estimator] name = "ls-equation-error"``), where the framework's
reduction loop, selection rule and verification run around it unchanged.

The estimator. Each force/moment equation of the 6-DoF structure is one linear regression::

    ax = Σ X_j·z_j      ay = Σ Y_j·z_j      az = Σ Z_j·z_j        (accelerometers, measured)
    ṗ  = Σ L_j·z_j      q̇  = Σ M_j·z_j      ṙ  = Σ N_j·z_j        (rates differentiated)

over the states and controls z = (u w q θ v p φ r, long lat coll ped). The rates and
attitudes are measured; u, v, w are reconstructed by integrating the force equations
(:func:`rotorid.estimation.equation_error.reconstructed_states`). Each equation is written per sample
interval: the rate's change over dt against the interval's mean states and the control held
over it. That is exact for zero-order-hold controls, where a central difference of the rates
would smear every control step over two samples. Per equation k with regressor matrix
X_k and residual variance σ_k², the estimate is θ_k = (X_kᵀX_k)⁻¹X_kᵀy_k and the information
matrix is F_k = X_kᵀX_k/σ_k²; :meth:`rotorid.Estimate.from_fit` turns the block-diagonal F
into Cramér-Rao bounds, insensitivities and correlations, exactly as for the built-in
output-error estimator. The cost is det R of the equation residuals, the RMSE their root mean
square (ft/s² and deg/s² in flight-test units).

It is fast (one least-squares solve per equation, no simulation) but biased: the regressors
carry sensor noise and integration drift. Use it for a first look at data or as a start;
the paper's output-error estimator gives the final model. Fixed delays shift their regressor;
free delays are refused (equation error cannot estimate them here), so the case below adds
none.

The plugin. A registration hook returns descriptors::

    class EquationErrorPlugin:
        @rotorid.hookimpl
        def rotorid_estimators(self):
            return [rotorid.PluginDescriptor("ls-equation-error", EquationErrorEstimator, "...")]

Register it at run time with ``rotorid.register_plugin(EquationErrorPlugin())``
(done by :func:`registered_plugin` below), or, in a package of your own, declare the module
holding the hook as an entry point and it is found on installation (docs/plugins.md)::

    [project.entry-points.rotorid]
    my_estimators = "my_package.plugin"

Run it from the repository root::

    python docs/examples/custom_estimator.py results/custom-estimator

It flies the truth model in hover twice (about 10 s), fits the 60-derivative structure by
equation error and by output error for comparison, then runs a quick hover case with the new
estimator (reduction stopped by the criteria); about 30 s on 2 cores in all.
"""

from __future__ import annotations

import argparse
import contextlib
import time
import tomllib
from pathlib import Path

import attrs
import numpy as np
import rotorid
from rotorid.errors import EstimationError
from rotorid.estimation.equation_error import reconstructed_states
from rotorid.estimation.estimate import Estimate
from rotorid.model.structure import CONTROLS, STATES, ModelStructure
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import Study
from rotorid.study.result import KEY_DERIVATIVES, CaseResult
from rotorid.study.truth import truth_derivatives

NAME = "ls-equation-error"
#: Measured left-hand side of each equation: a specific force, or a rate to differentiate.
LEFT_SIDE = {"X": "ax", "Y": "ay", "Z": "az", "L": "p", "M": "q", "N": "r"}
EQUATION_NAMES = ("ax", "ay", "az", "p_dot", "q_dot", "r_dot")


# ----------------------------------------------------------------- the estimator
def _interval_mean(signal: np.ndarray) -> np.ndarray:
    """Mean over each sample interval by the trapezoid rule, shape (N-1,)."""
    return 0.5 * (signal[:-1] + signal[1:])


def _left_side(letter: str, maneuver) -> np.ndarray:
    """Per sample interval: the mean specific force, or the rate's change over dt."""
    measured = maneuver.channel(LEFT_SIDE[letter])
    if letter in "XYZ":
        return _interval_mean(measured)
    return np.diff(measured) / np.diff(maneuver.time)


def _regressor(derivative, signals: dict, time_: np.ndarray, hold: str) -> np.ndarray:
    """The variable a derivative multiplies, shifted by its (fixed) delay, per interval.

    Trapezoid means, except a control held constant over the interval (zero-order hold) in
    the moment equations: there it is its value at the start of the interval.
    """
    signal = signals[derivative.variable]
    if derivative.delay is not None and derivative.delay.initial > 0.0:
        signal = np.interp(time_ - derivative.delay.initial, time_, signal, left=0.0)
    if hold == "zoh" and derivative.letter in "LMN" and derivative.variable in CONTROLS:
        return signal[:-1]
    return _interval_mean(signal)


@attrs.frozen
class EquationErrorEstimator:
    """Equation-error estimator (see the module docstring); implements the Estimator protocol.

    Args:
        min_excitation: regressors whose standard deviation is below this are left at zero
            and reported with an infinite Cramér-Rao bound (a variable the data never moved).
    """

    name = NAME
    min_excitation: float = 1e-9

    def estimate(self, model, maneuvers, *, start=None) -> Estimate:
        """Fit ``model`` (a :class:`ModelStructure`) to ``maneuvers``. ``start`` is recorded
        but not needed: a linear least-squares problem has one solution."""
        structure = self._checked(model)
        signals = [self._signals(structure, m) for m in maneuvers]
        names = structure.parameter_names
        values = np.zeros(len(names))
        information = np.zeros((len(names), len(names)))
        residuals = []
        for letter in LEFT_SIDE:
            columns, residual, info = self._equation(structure, letter, maneuvers, signals)
            for local, (index, value) in enumerate(columns):
                values[index] = value
                information[index, [i for i, _ in columns]] = info[local]
            residuals.append(residual)
        residuals = np.column_stack(residuals)         # (intervals of all maneuvers, 6)
        # The builder derives the bounds, R, det R, the RMSE and the sign checks.
        units = structure.units
        return Estimate.from_fit(
            structure, values, information, [residuals], estimator=NAME,
            start=structure.initial_values() if start is None else structure.as_vector(start),
            output_names=EQUATION_NAMES,
            output_units=(units.unit_of("acceleration"),) * 3
            + (units.unit_of("angular-acceleration"),) * 3, iterations=1,
            stop_reason="linear least squares: closed-form solution",
            notes=("equation error: values are biased by noise on the regressors",))

    @staticmethod
    def _checked(model) -> ModelStructure:
        if not isinstance(model, ModelStructure):
            raise EstimationError(f"{NAME} fits model structures only, got "
                                  f"{type(model).__name__}")
        if model.free_delays:
            raise EstimationError(
                f"{NAME} cannot estimate delays (free delays on "
                f"{', '.join(d.name for d in model.free_delays)}); fix them "
                f"(Delay(value, fixed=True)) or use the output-error estimator")
        return model

    @staticmethod
    def _signals(structure: ModelStructure, maneuver) -> dict:
        """Every state and control of one maneuver by name (structure units)."""
        states = reconstructed_states(structure, maneuver)
        signals = {name: states[:, i] for i, name in enumerate(STATES)}
        signals.update({c: maneuver.channel(c) for c in structure.controls})
        return signals

    def _equation(self, structure, letter, maneuvers, signals):
        """Solve one equation. Returns ([(parameter index, value)], residual (N,), F_k)."""
        members = [d for d in structure.derivatives if d.letter == letter]

        def column(d):
            return np.concatenate([_regressor(d, s, m.time, maneuvers.hold)
                                   for m, s in zip(maneuvers, signals)])

        target = np.concatenate([_left_side(letter, m) for m in maneuvers])
        for d in (d for d in members if d.fixed):
            target = target - d.initial * column(d)
        free = [d for d in members if not d.fixed]
        if not free:
            return [], target, np.zeros((0, 0))
        design = np.column_stack([column(d) for d in free])
        moved = design.std(axis=0) > self.min_excitation
        solution = np.zeros(len(free))
        solution[moved], *_ = np.linalg.lstsq(design[:, moved], target, rcond=None)
        residual = target - design @ solution
        variance = residual @ residual / max(len(residual) - int(moved.sum()), 1)
        info = design.T @ design / variance
        info[~moved, :] = info[:, ~moved] = 0.0          # no information on what never moved
        index = structure.parameter_names.index
        return [(index(d.name), v) for d, v in zip(free, solution)], residual, info


# ----------------------------------------------------------------- the plugin
class EquationErrorPlugin:
    """A rotorid plugin providing the ``ls-equation-error`` estimator."""

    @rotorid.hookimpl
    def rotorid_estimators(self):
        return [rotorid.PluginDescriptor(
            NAME, EquationErrorEstimator,
            "equation error: one linear least-squares fit per equation, Cramér-Rao bounds")]


@contextlib.contextmanager
def registered_plugin():
    """Register the plugin with rotorid's plugin manager for the duration of the block
    (checked like an installed plugin)."""
    plugin = EquationErrorPlugin()
    name = rotorid.register_plugin(plugin, name="docs-example-equation-error")
    try:
        yield plugin
    finally:
        rotorid.get_plugin_manager().unregister(name=name)


# ----------------------------------------------------------------- using it
def hover_data(seed: int = 0):
    """Multisteps of the truth model in hover (one direction, shortened records), the trim
    condition and the data source (for the truth model's linearisation)."""
    source = rotorid.create("data-sources", "helisim")
    data = source.generate({"condition": "hover", "seed": seed, "kinds": ["3211", "2311"],
                            "directions": [1], "duration_scale": 0.6})
    trim = data[0].metadata
    condition = rotorid.FlightCondition.from_airspeed(0.0, trim["trim_theta_deg"],
                                                      trim["trim_phi_deg"])
    return data, condition, source


def compare_estimators(data, condition, source) -> dict:
    """Fit the 60-derivative structure with the new estimator and with output error."""
    structure = ModelStructure.six_dof(condition)
    estimates, seconds = {}, {}
    for name in (NAME, "output-error"):
        clock = time.perf_counter()
        estimates[name] = rotorid.create("estimators", name).estimate(structure, data)
        seconds[name] = time.perf_counter() - clock
    print(estimates[NAME].report())
    truth = truth_derivatives(source, condition, structure)
    print(f"\nKey derivatives: {NAME} ({seconds[NAME]:.2f} s), output-error "
          f"({seconds['output-error']:.1f} s), truth-model linearisation")
    for key in KEY_DERIVATIVES:
        ee, oe = (estimates[n].value(key) for n in (NAME, "output-error"))
        print(f"  {key:<5}{ee:>11.4g}{oe:>11.4g}{truth[key]:>11.4g}")
    return estimates


CASE = f"""
name = "hover-equation-error"
description = "Hover, truth model, identified by equation error"

[data]
source = "helisim"
condition = "hover"
duration_scale = 0.6

[estimator]
name = "{NAME}"

[reduction]
continue_to_zero = false
# A least-squares fit's residual RMSE can only grow as derivatives go, so the lowest RMSE is
# always the full structure; the tolerance rule selects past the growth that is noise.
rule = "parsimonious"

[delays]
derivatives = []    # equation error does not estimate delays
"""


def run_case_with_plugin(out_dir, seed: int = 0) -> CaseResult:
    """The flight case above, run by the Study with the new estimator."""
    case = FlightCase.from_mapping(tomllib.loads(CASE), "custom_estimator.py").with_seed(seed)
    result = Study([case], out_dir, resume=False).run()[case.name]
    path = result.path
    print(f"\nCase {case.name}: {len(path.steps)} reduction steps, selected step "
          f"{path.selected_index} with {path.selected.n_parameters} derivatives "
          f"(removed {', '.join(path.removed)})")
    for label, metrics in result.time_metrics.items():
        print(f"  simulated output RMSE on the identification data ({label}): "
              f"{metrics.rmse:.3f}")
    estimate = result.estimates["with delays"]
    for key in ("M_q", "L_p", "N_r", "M_long", "L_lat"):
        if key in estimate.parameter_names:
            i = estimate.index(key)
            print(f"  {key:<7}{estimate.values[i]:>9.4g} ± {estimate.cramer_rao[i]:.2g} "
                  f"(Cramér-Rao, {estimate.cramer_rao_pct[i]:.1f} %)")
    return result


def parse_arguments(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description="A custom estimator plugin at work.")
    parser.add_argument("out", nargs="?", default="results/custom-estimator",
                        help="results directory of the case (default: %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="sensor-noise seed")
    return parser.parse_args(argv)


def main(argv=None) -> tuple[dict, CaseResult]:
    args = parse_arguments(argv)
    with registered_plugin():
        print(f"estimators: {', '.join(rotorid.registry('estimators'))}\n")
        data, condition, source = hover_data(args.seed)
        estimates = compare_estimators(data, condition, source)
        result = run_case_with_plugin(Path(args.out), args.seed)
    return estimates, result


if __name__ == "__main__":
    main()
