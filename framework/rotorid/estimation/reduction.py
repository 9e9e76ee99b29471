"""Stepwise model reduction (the framework owns the loop; criteria are plugins).

The paper's procedure: converge the fully populated structure, remove the one parameter the
criteria point at, restart the remaining parameters from their initial values, repeat, and
watch the RMSE. Criteria are asked in order; the first that proposes a removal wins
(insensitivity first, then Cramér-Rao bounds). With ``continue_to_zero`` the loop goes on once
the criteria are satisfied, removing by the last criterion's ranking, until no derivative is
left: that gives the RMSE-versus-removals curve.

Selection rules:

* ``"lowest-rmse"`` (the paper's): the structure with the lowest RMSE on the path (the first
  one, should two be equal).
* ``"parsimonious"``: the most reduced structure whose RMSE is within ``rmse_tolerance``
  (relative) of the lowest. With an estimator that reaches the optimum from any start, the
  RMSE is flat while redundant parameters go and rises once necessary ones do; the tolerance
  reads "lowest" as "lowest, up to estimation noise" and removes more.
* ``"first-rise"``: the structure before the first step whose RMSE rises by more than
  ``rmse_tolerance`` over its predecessor.

``ReductionPath.selections()`` gives the step every rule selects, whichever was chosen.

A removal that leaves a structure the estimator refuses (an :class:`EstimationError`: e.g. a
mode filter error's Riccati equation cannot stabilise) ends the path at the step before it;
``ReductionPath.stopped`` says which removal and why, and the rules select among the steps
reached.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence

import attrs
import numpy as np

from rotorid.errors import EstimationError, PluginError
from rotorid.estimation.continuation import continued_start
from rotorid.estimation.estimate import Estimate
from rotorid.model.structure import ModelStructure
from rotorid.plugin.contracts import Removal
from rotorid.plugin.returns import returned

RULES = ("lowest-rmse", "parsimonious", "first-rise")


@attrs.frozen(eq=False)
class ReductionStep:
    """One structure on the reduction path and its estimate.

    ``removal`` is what was removed to get here (``None`` for the full structure).
    """

    index: int
    removal: Removal | None
    estimate: Estimate
    structure: ModelStructure

    @property
    def n_parameters(self) -> int:
        return len(self.structure.parameter_names)

    @property
    def rmse(self) -> float:
        return self.estimate.rmse

    @property
    def cost(self) -> float:
        return self.estimate.cost

    def summary(self) -> dict:
        removal = self.removal
        return {"step": self.index, "n_parameters": self.n_parameters,
                "removed": None if removal is None else removal.parameter,
                "criterion": None if removal is None else removal.criterion,
                "metric": None if removal is None else _finite(removal.metric),
                "metric_unit": None if removal is None else removal.unit,
                "reason": None if removal is None else removal.reason,
                "rmse": self.rmse, "cost": self.cost,
                "iterations": self.estimate.iterations, "converged": self.estimate.converged}


def _finite(value: float):
    return float(value) if np.isfinite(value) else None


@attrs.frozen(eq=False)
class ReductionPath:
    """Every step of a reduction and the structure the selection rule picked."""

    steps: tuple[ReductionStep, ...] = attrs.field(converter=tuple)
    rule: str = "lowest-rmse"
    rmse_tolerance: float = 0.01
    #: why the path ended before the criteria were satisfied ("" when it did not)
    stopped: str = ""

    @property
    def selected_index(self) -> int:
        return self.index_by_rule(self.rule)

    def index_by_rule(self, rule: str) -> int:
        """The step ``rule`` (one of :data:`RULES`) selects, with this path's tolerance."""
        rmse = np.array([s.rmse for s in self.steps])
        if rule == "lowest-rmse":
            return int(np.argmin(rmse))
        if rule == "parsimonious":
            within = np.flatnonzero(rmse <= rmse.min() * (1.0 + self.rmse_tolerance))
            return int(within.max())
        if rule == "first-rise":
            for k in range(1, len(self.steps)):
                if rmse[k] > rmse[k - 1] * (1.0 + self.rmse_tolerance):
                    return k - 1
            return len(self.steps) - 1
        raise EstimationError(f"unknown selection rule {rule!r}; use {', '.join(RULES)}")

    def selections(self) -> dict[str, int]:
        """Rule → the step it selects on this path (every rule of :data:`RULES`)."""
        return {rule: self.index_by_rule(rule) for rule in RULES}

    @property
    def selected(self) -> ReductionStep:
        return self.steps[self.selected_index]

    @property
    def removed(self) -> tuple[str, ...]:
        """Parameters removed up to the selected structure, in order."""
        return tuple(s.removal.parameter for s in self.steps[1: self.selected_index + 1])

    def rmse_curve(self) -> tuple[np.ndarray, np.ndarray]:
        """Number of removed parameters (K,) and RMSE (K,)."""
        return (np.arange(len(self.steps)), np.array([s.rmse for s in self.steps]))


def _propose(criteria, estimate: Estimate, continue_to_zero: bool) -> Removal | None:
    """The first criterion's removal (the last one's ranking with ``continue_to_zero``),
    checked: a :class:`Removal` of one of ``estimate``'s parameters, or None."""
    calls = [(criterion, "propose") for criterion in criteria]
    if continue_to_zero:
        calls.append((criteria[-1], "rank"))
    for criterion, method in calls:
        call = f"reduction criterion {type(criterion).__name__}: {method}"
        removal = returned(getattr(criterion, method)(estimate), (Removal, type(None)), call)
        if removal is not None:
            if removal.parameter not in estimate.parameter_names:
                raise PluginError(f"{call} proposed {removal.parameter!r}, which is not one "
                                  f"of the candidates ({', '.join(estimate.parameter_names)})"
                                  f"; fix the criterion")
            return removal
    return None


def reduce(structure: ModelStructure, maneuvers, estimator, criteria: Sequence, *,
           continue_to_zero: bool = False, warm_start: bool = False, rule: str = "lowest-rmse",
           rmse_tolerance: float = 0.01, keep: Collection[str] = (),
           finished: Sequence[ReductionStep] = (),
           on_step: Callable[[ReductionStep], None] | None = None,
           case: str = "", manager=None) -> ReductionPath:
    """Run the reduction loop.

    Args:
        structure: the starting (usually fully populated) structure, without delays.
        maneuvers: identification maneuvers.
        estimator: an estimator plugin object (``estimate(structure, maneuvers, start=...)``).
        criteria: reduction-criterion objects, asked in order.
        continue_to_zero: keep removing after the criteria are satisfied (until only
            ``keep`` is left).
        warm_start: restart from the previous values instead of the initial values (a
            documented speed-up; the paper restarts from the initial values).
        keep: derivatives never proposed for removal (e.g. the hybrid model's flap damping
            and hub moments, :data:`rotorid.model.hybrid.REQUIRED`); each must be one of the
            structure's free derivatives.
        finished: steps already computed (resume); they must be a prefix of this run.
        on_step: called after every step (progress, persistence); the
            ``rotorid_reduction_step`` hook fires too, with ``case``.
        manager: the plugin manager notified (and current while the estimator runs);
            default the current one (:func:`rotorid.plugin.manager.current_manager`).
    """
    from rotorid.plugin.manager import notify, using

    def record(step: ReductionStep) -> None:
        steps.append(step)
        notify("rotorid_reduction_step", case=case, step=step)
        if on_step is not None:
            on_step(step)

    if rule not in RULES:
        raise EstimationError(f"unknown selection rule {rule!r}; use {', '.join(RULES)}")
    if not criteria:
        raise EstimationError("model reduction needs at least one criterion")
    if structure.free_delays:
        raise EstimationError("reduce the structure without delays; the delays are added "
                              "after selection (the paper's two-step approach)")
    strange = set(keep) - {d.name for d in structure.free_derivatives}
    if strange:
        raise EstimationError(f"reduction: {', '.join(sorted(strange))} to keep but not free "
                              f"derivatives of the structure; keep only its free derivatives")
    with using(manager):
        steps = list(finished)
        if not steps:
            record(ReductionStep(0, None, _fitted(estimator, structure, maneuvers), structure))
        while candidates := [d.name for d in steps[-1].structure.free_derivatives
                             if d.name not in keep]:
            last = steps[-1]
            # the criteria see the candidates only, never an estimator's own parameters
            # (filter error's noise F_* and R_*)
            removal = _propose(criteria, last.estimate.restricted(candidates), continue_to_zero)
            if removal is None:
                break
            reduced = last.structure.without(removal.parameter)
            start = None
            if warm_start:
                start = continued_start(last.estimate, last.structure, reduced)
            try:
                estimate = (_fitted(estimator, reduced, maneuvers, start)
                            if reduced.parameter_names else _empty_estimate(reduced,
                                                                            maneuvers))
            except EstimationError as error:
                return ReductionPath(steps, rule, rmse_tolerance, stopped=(
                    f"stopped at step {last.index}: removing {removal.parameter} "
                    f"({removal.criterion} {removal.metric_text}) leaves a structure the "
                    f"estimator cannot fit ({error})"))
            record(ReductionStep(len(steps), removal, estimate, reduced))
        return ReductionPath(steps, rule, rmse_tolerance)


def _fitted(estimator, structure: ModelStructure, maneuvers, start=None) -> Estimate:
    """``estimator``'s estimate of ``structure``, checked to be an :class:`Estimate`."""
    return returned(estimator.estimate(structure, maneuvers, start=start), Estimate,
                    f"estimator {type(estimator).__name__}: estimate")


def _empty_estimate(structure: ModelStructure, maneuvers) -> Estimate:
    """The 'estimate' of a structure with no parameter left: its plain simulation."""
    from rotorid.simulation.simulator import simulate

    outputs = simulate(structure, None, maneuvers)
    residuals = [m.columns(structure.outputs) - y for m, y in zip(maneuvers, outputs)]
    return Estimate.from_fit(structure, [], np.zeros((0, 0)), residuals, estimator="none",
                             stop_reason="no parameter left", cost_history=(),
                             rmse_history=())
