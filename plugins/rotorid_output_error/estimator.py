"""The ``output-error`` estimator: options, start strategy, horizon continuation, statistics.

Deviation from the paper's plain procedure (documented in docs/estimation.md): by default the
fit does not start Levenberg-Marquardt from zero on the full records. When the structure
declares no start information (every initial value zero), start values come from an
equation-error fit; when that start is zero, unstable or diverges on the full records, the
fit first runs on growing initial portions of the maneuvers (``horizons``, in s). Both keep the
intermediate simulations of unstable hover dynamics bounded, so the iteration neither stalls
nor diverges; a stable, well-started fit goes straight to the full records. ``start=
"initial"`` and ``horizons=()`` restore the paper's procedure.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping

import attrs
import numpy as np
from rotorid import blas
from rotorid.data import ManeuverSet
from rotorid.errors import DataWarning, EstimationError, SimulationDivergedError
from rotorid.estimation.coloured_residuals import coloured_covariance
from rotorid.estimation.estimate import Estimate
from rotorid.estimation.fit_notes import (fast_modes_note, held_delay_note, outlying_maneuvers,
                                          smooth_inputs_note)
from rotorid.estimation.models import (
    LinearModel,
    as_model,
    gauss_newton_products,
    measured_outputs,
    output_sensitivities,
)
from rotorid.estimation.whiteness import coloured_text
from rotorid.model.derivatives import delayed_derivative
from rotorid.model.structure import ModelStructure
from rotorid.plugin.manager import notify
from rotorid.units import rmse_reference_factors

from .augment import WithInitialStates, WithOutputBiases
from .levenberg_marquardt import Problem, Settings, run

NAME = "output-error"
#: An output whose residual RMS after the fit is below this fraction of its own RMS is
#: reproduced exactly: noise-free data, whose R rests on the floor.
EXACT_FRACTION = 1e-6
START_STRATEGIES = ("auto", "initial", "equation-error")
#: Growth rate (1/s, largest real part of A's eigenvalues) above which a start model counts as
#: unstable, so that the fit goes through the horizons first.
UNSTABLE_GROWTH_RATE = 1e-6


def _check_choice(options):
    def check(instance, attribute, value):
        if value not in options:
            raise EstimationError(f"{attribute.name} must be one of {', '.join(options)}, "
                                  f"got {value!r}")
    return check


@attrs.frozen
class OutputErrorEstimator:
    """Maximum-likelihood output-error estimator.

    Args:
        max_iterations: iteration limit of the final (full-record) run.
        cost_tolerance: stop when det R changes by less than this (relative).
        step_tolerance: stop when no parameter changes by more than this (relative).
        noise: ``"full"`` covariance R (default) or ``"diagonal"``.
        outputs: outputs used in the cost (default all of the model's).
        weights: optional output name → weight multiplying its residual.
        enforce_signs: use the sign priors as bounds.
        output_biases: estimate one constant bias per maneuver and output.
        initial_states: estimate the initial perturbation state of every maneuver
            (``x0_<maneuver>_<state>``, structure units; model structures only), starting
            from each maneuver's ``initial_state`` or trim.
        start: ``"auto"`` (equation error when every initial value is zero, else the
            initial values), ``"initial"`` or ``"equation-error"``.
        horizons: durations (s) of the initial portions fitted before the full records.
        coloured_residuals: Cramér-Rao bounds (and correlations) for the residuals' own
            correlation in time (:mod:`rotorid.estimation.coloured_residuals`) in place of
            the white-residual ones; the estimate is the same.

    Every accepted iteration is reported through the ``rotorid_estimation_iteration`` hook
    (stage ``"3 s"``, ``"6 s"``, … or ``"full"``).
    """

    name = NAME
    max_iterations: int = 50
    cost_tolerance: float = 1e-7
    step_tolerance: float = 1e-9
    noise: str = attrs.field(default="full", validator=_check_choice(("full", "diagonal")))
    outputs: tuple[str, ...] | None = attrs.field(
        default=None, converter=lambda v: None if v is None else tuple(v))
    weights: Mapping[str, float] | None = None
    enforce_signs: bool = False
    output_biases: bool = False
    initial_states: bool = False
    start: str = attrs.field(default="auto", validator=_check_choice(START_STRATEGIES))
    horizons: tuple[float, ...] = attrs.field(default=(3.0, 6.0), converter=tuple)
    coloured_residuals: bool = False

    # ----------------------------------------------------------------- public
    def estimate(self, model, maneuvers: ManeuverSet, *, start=None) -> Estimate:
        """Fit ``model`` (a ModelStructure or any identifiable model) to ``maneuvers``.

        ``start`` overrides the start values (vector in parameter order or name mapping).
        """
        with blas.single_threaded():
            return self._estimate_single_threaded(model, maneuvers, start)

    def _estimate_single_threaded(self, model, maneuvers, start) -> Estimate:
        base = (LinearModel(model, enforce_signs=self.enforce_signs)
                if isinstance(model, ModelStructure) else as_model(model))
        start_values, start_note = self._start_values(base, maneuvers, start)
        fitted = base
        if self.initial_states:
            if not isinstance(base, LinearModel):
                raise EstimationError("initial_states=True needs a model structure; a model of "
                                      "one's own can declare its initial states as parameters")
            fitted = WithInitialStates(base, maneuvers.names)
            start_values = np.concatenate([start_values, fitted.start_states(maneuvers)])
        if self.output_biases:
            fitted = WithOutputBiases(fitted, maneuvers.names)
            start_values = np.concatenate(
                [start_values, np.zeros(len(fitted.parameter_names) - start_values.size)])
        columns, weights = self._output_selection(fitted)
        notes = [start_note] if start_note else []
        result, start_values = self._best_of_starts(base, fitted, maneuvers, columns, weights,
                                                    start_values, notes)
        if np.array_equal(result.values, np.clip(start_values, *fitted.bounds())):
            result = attrs.evolve(result, converged=False, stop_reason=(
                "no step moved the parameters from their start values: " + result.stop_reason))
        elif result.iterations == 0:
            result = attrs.evolve(result, converged=True, stop_reason=(
                "the earlier stages already reached the minimum of the full records"))
        measured = measured_outputs(fitted, maneuvers, columns)
        _warn_exact_outputs(result, measured, weights,
                            [fitted.output_names[c] for c in columns], self.noise)
        estimate = self._estimate(fitted, base, result, start_values, notes,
                                  sum(m.n_samples for m in maneuvers), columns)
        return self._residual_statistics(estimate, base, fitted, maneuvers, measured, columns,
                                         weights)

    # ----------------------------------------------------------------- steps
    def _best_of_starts(self, base, fitted, maneuvers, columns, weights, start_values, notes):
        """Fit from ``start_values``; fall back to the model's initial values when that
        start makes the simulation diverge or ends above the cost of the initial values
        (a local minimum worse than doing nothing), and to the equation-error start when
        the initial values themselves diverge (``start="auto"``). Returns the result and
        its start."""
        fallback = np.clip(fitted.initial_values(), *fitted.bounds())
        try:
            result = self._run_stages(base, fitted, maneuvers, columns, weights, start_values,
                                      notes)
        except SimulationDivergedError:
            found = self._restart(base, fitted, maneuvers, start_values, fallback)
            if found is None:
                raise
            restart, label = found
            notes.append(f"the start values gave no finite cost; restarted from {label}")
            return (self._run_stages(base, fitted, maneuvers, columns, weights, restart, notes),
                    restart)
        if np.array_equal(np.clip(start_values, *fitted.bounds()), fallback):
            return result, start_values
        problem = _problem(fitted, maneuvers, columns, weights, Settings(noise=self.noise))
        if result.cost <= problem.evaluate(fallback)[0]:
            return result, start_values
        notes.append("the fit from the start values ended above the cost of the initial "
                      "values; refitted from the initial values")
        try:
            retry = self._run_stages(base, fitted, maneuvers, columns, weights, fallback, notes)
        except SimulationDivergedError:
            return result, start_values
        return (retry, fallback) if retry.cost < result.cost else (result, start_values)

    def _restart(self, base, fitted, maneuvers, start_values, initial):
        """Where a fit whose ``start_values`` diverged starts again, and its name: the
        ``initial`` values when the start was something else, else (``start="auto"``) the
        equation-error start of ``base`` with the record parameters' starts kept; None when
        there is neither."""
        if not np.array_equal(np.clip(start_values, *fitted.bounds()), initial):
            return initial, "the initial values"
        if self.start == "auto" and hasattr(base, "start_values"):
            n_base = len(base.parameter_names)
            restart = np.concatenate([base.start_values(maneuvers), start_values[n_base:]])
            return np.clip(restart, *fitted.bounds()), "the equation-error start"
        return None

    def _run_stages(self, base, fitted, maneuvers, columns, weights, values, notes):
        """Horizon continuation where it helps (:meth:`_horizons_help`), then the full
        records; returns the last run's result.

        A stage whose start (the previous stage's result) diverges on its longer records
        starts again from the values the continuation began with; a continuation that ends
        above the cost of those values on the full records is replaced by the full records'
        fit from them (:meth:`_not_above_start`).
        """
        first = values
        horizons = self._stages(maneuvers)
        reason, evaluated = (self._horizons_help(base, fitted, maneuvers, columns, weights,
                                                 values) if horizons else (None, None))
        if reason:
            notes.append(f"horizons {', '.join(f'{h:g} s' for h in horizons)} first (fitted "
                         f"on each record's first seconds before the whole records, so that "
                         f"the simulation stays near the data): {reason}")
        stages = [(h, Settings(max_iterations=15, cost_tolerance=1e-4, noise=self.noise))
                  for h in (horizons if reason else ())]
        stages.append((None, Settings(self.max_iterations, self.cost_tolerance,
                                      self.step_tolerance, noise=self.noise)))
        for horizon, settings in stages:
            portion = maneuvers if horizon is None else ManeuverSet(
                [m.head(horizon) for m in maneuvers], hold=maneuvers.hold)
            label = "full" if horizon is None else f"{horizon:g} s"
            try:
                result = self._run(fitted, portion, columns, weights, values, settings, label,
                                   final_information=horizon is None,
                                   start_evaluation=evaluated)
            except SimulationDivergedError:
                if values is first:
                    raise
                notes.append(f"stage {label}: the previous stage's values diverge on the "
                             f"longer records; restarted the stage from the start values")
                result = self._run(fitted, portion, columns, weights, first, settings, label,
                                   final_information=horizon is None)
            values = result.values
            if horizon is not None:
                notes.append(f"horizon {label}: {result.iterations} iterations, "
                             f"RMSE {result.rmse:.4g}")
        if reason:
            result = self._not_above_start(fitted, maneuvers, columns, weights, first, result,
                                           stages[-1][1], notes)
        return result

    def _not_above_start(self, fitted, maneuvers, columns, weights, first, result, settings,
                         notes):
        """``result`` of a horizon continuation begun at ``first``, or, when it ends above
        the cost of ``first`` on the full records (the short records led the fit where the
        full ones fit worse than its start), the full records' fit straight from ``first``."""
        problem = _problem(fitted, maneuvers, columns, weights, Settings(noise=self.noise))
        start_cost = problem.evaluate(first)[0]
        if not np.isfinite(start_cost) or result.cost <= start_cost:
            return result
        notes.append("the horizons ended above the start values' cost on the full records; "
                     "refitted the full records from the start values")
        return self._run(fitted, maneuvers, columns, weights, first, settings, "full")

    def _horizons_help(self, base, fitted, maneuvers, columns, weights, values):
        """Why the fit of ``fitted`` (``base`` with any record parameters) from ``values``
        goes through the horizons first, or None when it goes straight to the full records:
        the horizons help a zero start, a start model that is unstable (``base``'s optional
        ``growth_rate`` above :data:`UNSTABLE_GROWTH_RATE`) and a start whose simulation of
        the full records diverges; on a stable, well-started fit they only cost iterations.

        Also returns the start's evaluation on the full records (``Problem.evaluate``) when
        it was simulated and the fit may start from it (``values`` within the bounds), else
        None."""
        own = values[:len(base.parameter_names)]         # the base model's, then the records'
        derivatives = np.array([delayed_derivative(n) is None for n in base.parameter_names],
                               dtype=bool)
        if not np.any(own[derivatives]):
            return "zero start", None
        if hasattr(base, "growth_rate"):
            rate = base.growth_rate(own)
            if rate > UNSTABLE_GROWTH_RATE:
                return f"the start model is unstable (growth rate {rate:.3g} 1/s)", None
        problem = _problem(fitted, maneuvers, columns, weights, Settings(noise=self.noise))
        evaluation = problem.evaluate(values)
        if not np.isfinite(evaluation[0]):
            return "the start diverges on the full records", None
        within = np.array_equal(np.clip(values, *fitted.bounds()), values)
        return None, evaluation if within else None

    def _start_values(self, model, maneuvers, start):
        names = tuple(model.parameter_names)
        if start is not None:
            if isinstance(start, Mapping):
                unknown = set(start) - set(names)
                if unknown:
                    raise EstimationError(f"start values for unknown parameters {sorted(unknown)}")
                vector = model.initial_values().copy()
                for name, value in start.items():
                    vector[names.index(name)] = float(value)
            else:
                vector = np.asarray(start, dtype=float).copy()
                if vector.shape != (len(names),):
                    raise EstimationError(f"start has shape {vector.shape}; the model has "
                                          f"{len(names)} parameters")
            return vector, None
        initial = model.initial_values()
        derivative_part = np.array([delayed_derivative(n) is None for n in names], dtype=bool)
        wants_ee = self.start == "equation-error" or (
            self.start == "auto" and not np.any(initial[derivative_part]))
        if wants_ee and hasattr(model, "start_values"):
            return model.start_values(maneuvers), "start values from equation error"
        if self.start == "equation-error":
            raise EstimationError(f"{type(model).__name__} offers no equation-error start; "
                                  "use start='initial' or pass start values")
        return initial, None

    def _stages(self, maneuvers):
        shortest = min(m.duration for m in maneuvers)
        return [h for h in self.horizons if 0 < h < shortest]

    def _output_selection(self, model):
        names = tuple(model.output_names)
        chosen = self.outputs or names
        unknown = [n for n in chosen if n not in names]
        if unknown:
            raise EstimationError(f"unknown output(s) {unknown}; outputs: {', '.join(names)}")
        weights = dict(self.weights or {})
        unknown = [n for n in weights if n not in chosen]
        if unknown:
            raise EstimationError(f"weights for unused output(s) {unknown}")
        columns = [names.index(n) for n in chosen]
        return columns, np.array([float(weights.get(n, 1.0)) for n in chosen])

    def _run(self, model, maneuvers, columns, weights, start, settings, stage,
             final_information: bool = True, start_evaluation=None):
        problem = _problem(model, maneuvers, columns, weights, settings)

        def progress(record):
            notify("rotorid_estimation_iteration", estimator=NAME, stage=stage,
                   iteration=record.iteration, cost=record.cost, rmse=record.rmse,
                   lm_lambda=record.lm_lambda)

        return run(problem, start, model.bounds(), progress, final_information,
                   start_evaluation)

    def _estimate(self, fitted, base, result, start, notes, n_samples, columns):
        """The estimate of ``result``: the run's own cost (weighted, floored R) and RMSE."""
        names = tuple(fitted.parameter_names)
        lower, upper = fitted.bounds()
        at_bound = tuple(n for n, v, lo, hi in zip(names, result.values, lower, upper)
                         if (np.isfinite(lo) and v <= lo) or (np.isfinite(hi) and v >= hi))
        structure = getattr(base, "structure", None)
        selected = _SelectedOutputs(fitted, columns)
        return Estimate.from_fit(
            fitted, result.values, result.information, estimator=NAME, start=start,
            noise_covariance=result.noise_covariance, cost=result.cost, rmse=result.rmse,
            n_samples=n_samples, output_names=selected.output_names,
            output_units=selected.output_units, residual_rms=result.residual_rms,
            cost_history=result.cost_history, rmse_history=result.rmse_history,
            iterations=result.iterations, converged=result.converged,
            stop_reason=result.stop_reason, at_bound=at_bound,
            fixed=getattr(base, "fixed", {}), signs=getattr(base, "signs", {}),
            units=structure.units.name if structure is not None else "model",
            notes=tuple(notes))

    def _residual_statistics(self, estimate, base, fitted, maneuvers, measured, columns,
                             weights):
        """``estimate`` with notes on its residuals (maneuvers that stand out, residuals that
        are not white), on delays the zero-order hold hides, and, with
        :attr:`coloured_residuals`, its bounds and correlations for the residuals'
        correlation; ``measured`` are the fitted outputs ``columns`` per maneuver."""
        selected = _SelectedOutputs(fitted, columns)
        residuals = [z - y for z, y in
                     zip(measured, selected.simulate(estimate.values, maneuvers))]
        structure = getattr(base, "structure", None)
        notes = [note for note in (
            outlying_maneuvers(residuals, maneuvers.names, estimate.noise_covariance),
            None if structure is None else held_delay_note(structure, maneuvers.hold),
            smooth_inputs_note(maneuvers),
            None if structure is None else fast_modes_note(
                structure, estimate.restricted(structure.parameter_names).values,
                maneuvers[0].dt))
            if note is not None]
        coloured = coloured_text(residuals, selected.output_names, maneuvers[0].dt,
                                 "residuals")
        if not self.coloured_residuals:
            if coloured is not None:
                notes.append(f"{coloured}; the Cramér-Rao bounds assume white residuals and "
                             f"understate the scatter: coloured_residuals = true (identify "
                             f"--coloured-residuals) widens them for that correlation")
            return attrs.evolve(estimate, notes=(*estimate.notes, *notes))
        _, sensitivities = output_sensitivities(fitted, estimate.values, maneuvers)
        sensitivities = [s[:, :, columns] for s in sensitivities]
        weighting = weights[:, None] * np.linalg.inv(estimate.noise_covariance) * weights
        covariance, lags = coloured_covariance(sensitivities, residuals, weighting,
                                               np.asarray(estimate.information))
        bounds = np.sqrt(np.maximum(np.diag(covariance), 0.0))
        bounds = np.where(np.isfinite(estimate.cramer_rao), bounds, np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            correlation = np.clip(np.nan_to_num(covariance / np.outer(bounds, bounds)), -1, 1)
        finite = np.isfinite(bounds) & (estimate.cramer_rao > 0)
        factor = float(np.median(bounds[finite] / estimate.cramer_rao[finite])) \
            if finite.any() else 1.0
        note = (f"Cramér-Rao bounds for coloured residuals (Morelli & Klein), the residuals' "
                f"correlation taken over {lags} lags ({lags * maneuvers[0].dt:.3g} s): "
                f"{factor:.2f} times the white-residual bounds (median)")
        return attrs.evolve(estimate, cramer_rao=bounds, correlation=correlation,
                            notes=(*estimate.notes, *notes, note))


def _problem(model, maneuvers, columns, weights, settings) -> Problem:
    """The run's problem on the outputs ``columns`` of ``model``, its RMSE counted in the
    outputs' reference units when they have them (:func:`rotorid.units.rmse_reference_factors`)."""
    selected = _SelectedOutputs(model, columns)
    measured = measured_outputs(model, maneuvers, columns)
    return Problem(selected, maneuvers, measured, weights, settings,
                   rmse_scale=rmse_reference_factors(selected.output_units))


def _warn_exact_outputs(result, measured, weights, names, noise: str) -> None:
    """A :class:`DataWarning` naming the outputs the fit reproduces exactly (residual RMS
    below :data:`EXACT_FRACTION` of the output's RMS) and the largest such ratio; its fix
    suits the ``noise`` setting (``"full"`` or ``"diagonal"``)."""
    n = sum(z.shape[0] for z in measured)
    signal = np.sqrt(sum(np.sum((z * weights) ** 2, axis=0) for z in measured) / n)
    ratio = np.sqrt(np.diag(result.noise_covariance)) / np.maximum(signal, 1e-300)
    exact = np.flatnonzero(ratio < EXACT_FRACTION)
    if not exact.size:
        return
    if exact.size == len(names):        # nothing to leave out: the records are noise-free
        fix = "the values are the model's that generated the records; bounds need noisy records"
    else:
        fix = (f"{'use --noise diagonal or ' if noise == 'full' else ''}leave them out with "
               f"--outputs")
    warnings.warn(f"the fit reproduces the outputs {', '.join(repr(names[k]) for k in exact)} "
                  f"exactly (residual RMS at most {ratio[exact].max():.2g} of the output's "
                  f"RMS): noise-free data? Their R is held at its floor, so the Cramér-Rao "
                  f"bounds mean nothing; {fix}", DataWarning, stacklevel=3)


class _SelectedOutputs:
    """A model restricted to some of its outputs (for excluded outputs)."""

    def __init__(self, model, columns):
        self.model = model
        self.columns = list(columns)
        self.parameter_names = model.parameter_names
        self.output_names = tuple(model.output_names[c] for c in self.columns)
        units = tuple(getattr(model, "output_units", ()))
        self.output_units = tuple(units[c] for c in self.columns) if units else ()

    def simulate(self, values, maneuvers):
        return [y[:, self.columns] for y in self.model.simulate(values, maneuvers)]

    def gauss_newton(self, values, maneuvers, residuals, weighting):
        """The products of the selected outputs: residuals and weighting embedded in all
        outputs (zero weight on the others)."""
        n_all = len(self.model.output_names)
        embedded_weighting = np.zeros((n_all, n_all))
        embedded_weighting[np.ix_(self.columns, self.columns)] = weighting
        embedded = []
        for e in residuals:
            full = np.zeros((e.shape[0], n_all))
            full[:, self.columns] = e
            embedded.append(full)
        return gauss_newton_products(self.model, values, maneuvers, embedded,
                                     embedded_weighting)
