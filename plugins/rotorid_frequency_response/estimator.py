"""The ``frequency-response`` estimator: a model structure fitted to measured frequency
responses by minimising Tischler's mismatch cost J summed over the response pairs.

Statistics follow Tischler & Remple (ch. 11, the frequency-response method's accuracy
metrics): the information matrix is the Gauss-Newton approximation of the Hessian of the cost
without the factor 20 of J,

    M = (2/n_l) Σ_l Σ_k (∂ε/∂θ)ᵀ W (∂ε/∂θ) = JᵀJ / 10

(ε the dB/deg errors, W = W_γ·diag(W_g, W_p), J the Jacobian of the residual vector of
:mod:`.cost`), and :func:`rotorid.estimation.estimate.statistics` turns it into Cramér-Rao
bounds sqrt((M⁻¹)_ii) and insensitivities 1/sqrt(M_ii), so the reduction criteria apply
unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence

import attrs
import numpy as np
from rotorid import blas
from rotorid.data import ManeuverSet
from rotorid.errors import EstimationError
from rotorid.estimation.equation_error import equation_error_start
from rotorid.estimation.estimate import Estimate
from rotorid.model.statespace import state_space
from rotorid.model.structure import ModelStructure
from rotorid.plugin.manager import notify
from rotorid.verification.envelopes import MISMATCH_COST_GUIDELINE
from rotorid.verification.frequency import FrequencyResponse
from rotorid_envelopes.cost import COST_THRESHOLD

from .cost import MismatchProblem
from .levenberg_marquardt import RunResult, Settings, run
from .pairs import PairData, pair_data, sweep_pair_data

NAME = "frequency-response"
START_STRATEGIES = ("auto", "initial", "equation-error")
#: The factor between JᵀJ of the residual vector and Tischler's Hessian approximation.
HESSIAN_SCALE = 10.0
#: σ of the log-normal factors that vary the gains of the random starts.
START_SPREAD = 0.5
#: A default pair's coherent J points must span at least this ratio of frequencies.
MIN_COHERENT_SPAN = 2.0


def _check_start(instance, attribute, value):
    if value not in START_STRATEGIES:
        raise EstimationError(f"start must be one of {', '.join(START_STRATEGIES)}, got "
                              f"{value!r}")


def _check_starts(instance, attribute, value):
    if isinstance(value, bool) or not (isinstance(value, int) and value >= 1):
        raise EstimationError(f"starts must be a whole number ≥ 1, got {value!r}")


def varied_starts(model: ModelStructure, start: np.ndarray, count: int, seed: int
                  ) -> list[np.ndarray]:
    """``start`` (P,) and ``count − 1`` random variations of it: every gain multiplied by
    e^(σξ), ξ standard normal and σ = ``START_SPREAD`` (signs and zeros kept); the delays
    keep their start values (a random delay of a few tenths of a second turns the phase by
    more than 180° within the J band and starts the fit where J cannot guide it)."""
    rng = np.random.default_rng(seed)
    gain = ~model.is_delay()
    varied = [np.asarray(start, dtype=float)]
    for _ in range(count - 1):
        values = varied[0].copy()
        values[gain] *= np.exp(START_SPREAD * rng.standard_normal(int(np.sum(gain))))
        varied.append(values)
    return varied


@attrs.frozen
class FrequencyResponseEstimator:
    """State-space fit to frequency responses (CIFER's method).

    Args:
        pairs: ``output/input`` pairs to fit; default every output over every swept input.
            Pairs without a coherent frequency (γ² ≥ ``threshold``) are left out with a note.
        n_points: J points per pair (log-spaced over its coherent range).
        threshold: coherence bounding each pair's range and its kept points.
        band: (lowest, highest) frequency in rad/s a pair's range may reach; default the
            whole coherent range. A 6-DoF model has no rotor modes: limit its band below
            them (about 10 rad/s for a hingeless rotor).
        max_iterations, cost_tolerance, step_tolerance: Levenberg-Marquardt stopping rules
            (tolerances relative).
        enforce_signs: use the derivatives' sign priors as bounds.
        start: ``"auto"`` (equation error on the sweeps when every initial derivative is
            zero, else the initial values), ``"initial"`` or ``"equation-error"``.
        starts: fits from the start values and from ``starts − 1`` random variations of
            them (:func:`varied_starts`, drawn with ``seed``); the lowest J wins among the
            fits whose model has no unstable pole above the J band
            (:func:`unstable_poles_above`). The cost of a structure with many weakly
            determined parameters has many local minima.

    Every accepted iteration is reported through the ``rotorid_estimation_iteration`` hook
    (stage ``""``, cost J, rmse sqrt(J_ave/20)).
    """

    name = NAME
    pairs: tuple[str, ...] | None = attrs.field(
        default=None, converter=lambda v: None if v is None else tuple(v))
    n_points: int = 20
    threshold: float = COST_THRESHOLD
    band: tuple[float, float] = attrs.field(default=(0.0, np.inf), converter=tuple)
    max_iterations: int = 500
    cost_tolerance: float = 1e-6
    step_tolerance: float = 1e-10
    enforce_signs: bool = False
    start: str = attrs.field(default="auto", validator=_check_start)
    starts: int = attrs.field(default=1, validator=_check_starts)
    seed: int = 0

    def fit_data(self, data) -> tuple[PairData | str, ...]:
        """What :meth:`estimate` matches, from a :class:`ManeuverSet` of sweeps (see
        :mod:`.pairs`) or from measured :class:`FrequencyResponse` objects of the model's
        own responses (conditioned, or of a model): one :class:`PairData` per pair, or the
        pair's name when it has no coherent frequency. Compute it once and pass it to
        repeated fits (a reduction)."""
        if isinstance(data, ManeuverSet):
            found = sweep_pair_data(data, self.pairs, self.n_points, self.threshold, self.band)
            return found if self.pairs is not None else broad_pairs(found)
        return tuple(pair_data(r, self.n_points, self.threshold, self.band) or r.pair
                     for r in self._chosen(data))

    def estimate(self, model: ModelStructure, data, *, start=None) -> Estimate:
        """Fit ``model`` to ``data``: a :class:`ManeuverSet` of sweeps, measured
        :class:`FrequencyResponse` objects, or the result of :meth:`fit_data`.

        ``start`` overrides the start values (vector in parameter order or name mapping).
        """
        if not isinstance(model, ModelStructure):
            raise EstimationError(f"the {NAME} estimator fits a ModelStructure (its analytic "
                                  f"response); got {type(model).__name__}")
        maneuvers = data if isinstance(data, ManeuverSet) else None
        fitted, notes = self._usable(self._prepared(data))
        start_values, start_note = self._start_values(model, maneuvers, start)
        notes = [note for note in (start_note,) if note] + notes
        problem = MismatchProblem(model, fitted)
        bounds = self._bounds(model)
        initial = problem.evaluate(np.clip(start_values, *bounds))
        if not np.isfinite(initial.cost):
            silent = [p.pair for p, cost in zip(fitted, initial.pair_costs)
                      if not np.isfinite(cost)]
            raise EstimationError(f"the start model has no response on {', '.join(silent)}; "
                                  f"give start values that couple those pairs or leave the "
                                  f"pairs out (pairs=...)")

        def progress(iteration, cost, lam):
            notify("rotorid_estimation_iteration", estimator=NAME, stage="",
                   iteration=iteration, cost=cost, rmse=_equivalent_db(cost, len(fitted)),
                   lm_lambda=lam)

        settings = Settings(self.max_iterations, self.cost_tolerance, self.step_tolerance)
        starts, results = varied_starts(model, start_values, self.starts, self.seed), []
        with blas.single_threaded():
            for values in starts:
                if np.isfinite(problem.evaluate(np.clip(values, *bounds), jacobian=False).cost):
                    results.append(run(problem, values, bounds, settings, progress))
                else:
                    results.append(None)       # a random start without a response
        best, selection_notes = best_start(model, results, max(p.omega.max() for p in fitted))
        notes += selection_notes
        return self._estimate(model, fitted, results[best], starts[best], problem.n_points,
                              notes)

    def pair_costs(self, model: ModelStructure, values, data) -> dict[str, float]:
        """J per pair of ``model`` at ``values`` (vector or name mapping) on ``data`` (as
        for :meth:`estimate`): e.g. a time-domain estimate judged on the same responses."""
        fitted, _ = self._usable(self._prepared(data))
        mismatch = MismatchProblem(model, fitted).evaluate(model.as_vector(values),
                                                           jacobian=False)
        return dict(zip((p.pair for p in fitted), mismatch.pair_costs))

    # ----------------------------------------------------------------- steps
    def _prepared(self, data) -> tuple[PairData | str, ...]:
        if not isinstance(data, ManeuverSet):
            data = list(data)
            if data and all(isinstance(p, (PairData, str)) for p in data):
                return tuple(data)
        return self.fit_data(data)

    def _chosen(self, responses: Sequence[FrequencyResponse]) -> list[FrequencyResponse]:
        responses = list(responses)
        if not all(isinstance(r, FrequencyResponse) for r in responses):
            raise EstimationError(f"the {NAME} estimator fits a ManeuverSet of sweeps or a "
                                  f"sequence of FrequencyResponse objects")
        if self.pairs is None:
            return responses
        by_pair = {r.pair: r for r in responses}
        missing = [p for p in self.pairs if p not in by_pair]
        if missing:
            raise EstimationError(f"no response given for pair(s) {', '.join(missing)}; "
                                  f"given: {', '.join(by_pair)}")
        return [by_pair[p] for p in self.pairs]

    def _usable(self, prepared) -> tuple[list[PairData], list[str]]:
        fitted = [p for p in prepared if isinstance(p, PairData) and p.omega.size]
        empty = [p if isinstance(p, str) else p.pair for p in prepared
                 if not (isinstance(p, PairData) and p.omega.size)]
        if not fitted:
            raise EstimationError(f"no pair has a frequency with coherence ≥ "
                                  f"{self.threshold:g}; check that the sweeps excite the "
                                  f"chosen pairs")
        described = [name if " (" in name else
                     f"{name} (no frequency with γ² ≥ {self.threshold:g})" for name in empty]
        notes = [f"pairs left out: {', '.join(described)}"] if empty else []
        return fitted, notes

    def _bounds(self, model: ModelStructure):
        return model.bounds(enforce_signs=self.enforce_signs)

    def _start_values(self, model: ModelStructure, maneuvers, start):
        if start is not None:
            return model.as_vector(start), None
        initial = model.initial_values()
        zero = not np.any(initial[~model.is_delay()])
        if self.start == "equation-error" or (self.start == "auto" and zero):
            if maneuvers is None:
                raise EstimationError("equation-error start values need the sweeps; pass the "
                                      "ManeuverSet, start values or a structure with initial "
                                      "values")
            return equation_error_start(model, maneuvers), "start values from equation error"
        return initial, None

    def _estimate(self, model: ModelStructure, pairs: Sequence[PairData], result: RunResult,
                  start, n_points: int, notes) -> Estimate:
        names = model.parameter_names
        lower, upper = self._bounds(model)
        costs = result.mismatch.pair_costs
        jacobian = result.mismatch.jacobian
        return Estimate.from_fit(
            model, result.values, jacobian.T @ jacobian / HESSIAN_SCALE, estimator=NAME,
            start=start, noise_covariance=np.diag(costs),
            output_names=tuple(p.pair for p in pairs), output_units=(),
            cost=result.mismatch.cost, rmse=_equivalent_db(result.mismatch.cost, len(pairs)),
            rmse_basis="sqrt(J_ave/20): the uniform magnitude error in dB that alone gives "
                       "the mean mismatch cost, dimensionless",
            cost_history=result.cost_history,
            rmse_history=tuple(_equivalent_db(c, len(pairs)) for c in result.cost_history),
            iterations=result.iterations, converged=result.converged,
            stop_reason=result.stop_reason, n_samples=n_points,
            at_bound=tuple(n for n, v, lo, hi in zip(names, result.values, lower, upper)
                           if (np.isfinite(lo) and v <= lo) or (np.isfinite(hi) and v >= hi)),
            notes=(*notes, "J per pair: " + ", ".join(
                f"{p.pair} {c:.1f}" for p, c in zip(pairs, costs)),
                   *_poorly_fitted(pairs, costs)))


def broad_pairs(found: Sequence[PairData | str]) -> tuple[PairData | str, ...]:
    """``found`` with each pair coherent over less than :data:`MIN_COHERENT_SPAN` in
    frequency replaced by its name and that range (left out of the default pairs: its J
    points would all weigh one frequency), unless no broader pair is left."""
    usable = [p for p in found if isinstance(p, PairData) and p.omega.size]
    narrow = {p.pair for p in usable if p.omega.max() < MIN_COHERENT_SPAN * p.omega.min()}
    if len(narrow) == len(usable):
        return tuple(found)
    return tuple(f"{p.pair} (coherent over {p.omega.min():.3g}–{p.omega.max():.3g} rad/s "
                 f"only, less than a factor {MIN_COHERENT_SPAN:g}; name it in pairs to fit it)"
                 if isinstance(p, PairData) and p.pair in narrow else p for p in found)


def _poorly_fitted(pairs: Sequence[PairData], costs) -> list[str]:
    """A note naming the pairs whose J exceeds the guideline for any pair (Tischler: 200 for
    a few pairs), which pull the derivatives the other pairs determine."""
    limit = MISMATCH_COST_GUIDELINE["few_pairs_max"]
    poor = [(p.pair, c) for p, c in zip(pairs, costs) if c > limit]
    if not poor or len(poor) == len(pairs):
        return []
    listed = ", ".join(f"{pair} (J {cost:.0f})" for pair, cost in poor)
    kept = ", ".join(p.pair for p, c in zip(pairs, costs) if c <= limit)
    return [f"pairs the structure does not fit (J above {limit:g}, the guideline for any "
            f"pair): {listed}; they pull the derivatives the other pairs determine: fit without "
            f"them (pairs = [{kept}]; identify --pairs) or extend the structure"]


def unstable_poles_above(structure: ModelStructure, values, omega_max: float) -> np.ndarray:
    """The eigenvalues (rad/s) of the model's delay-free dynamics matrix in the right
    half-plane with modulus above ``omega_max`` (rad/s), fastest first.

    The J points cannot determine such a pole: below its modulus a real pole at +a looks like
    a gain and a lag of about 1/a s, which a fit uses in place of the rotor's lag, while the
    model's time response diverges within about 1/a s.
    """
    poles = np.linalg.eigvals(state_space(structure, values).a)
    fast = poles[(poles.real > 0) & (np.abs(poles) > omega_max)]
    return fast[np.argsort(-np.abs(fast))]


def best_start(model: ModelStructure, results, omega_max: float) -> tuple[int, list[str]]:
    """The index of the lowest-J run whose model has no unstable pole above ``omega_max``
    (the lowest-J run when every one has), and the notes on the choice."""
    ran = [k for k, r in enumerate(results) if r is not None]
    fast = {k: unstable_poles_above(model, results[k].values, omega_max) for k in ran}
    admissible = [k for k in ran if not fast[k].size] or ran
    best = min(admissible, key=lambda k: results[k].mismatch.cost)
    notes = []
    if len(results) > 1:
        notes.append(f"best of {len(results)} starts: start {best} "
                     f"({'the start values' if best == 0 else 'varied'}); J per start: "
                     + ", ".join("—" if r is None else f"{r.mismatch.cost:.1f}"
                                 + (" (unstable pole above the band)" if fast[k].size else "")
                                 for k, r in enumerate(results)))
    if fast[best].size:
        notes.append(f"the model has unstable poles above the J band ({omega_max:.3g} rad/s): "
                     + ", ".join(f"{p:.4g}" for p in fast[best]) + " rad/s; the J points "
                     "cannot determine them and its time response diverges: fit the "
                     "delays the structure lacks or end the band lower")
    return best, notes


def _equivalent_db(cost: float, n_pairs: int) -> float:
    """sqrt(J_ave/20): the uniform magnitude error in dB that alone gives J_ave."""
    return float(np.sqrt(cost / (20.0 * n_pairs)))
