"""The method's rules on small constructed cases with hand-computed answers: the statistics of
an information matrix, the criteria's default thresholds and order, the continue-to-zero
ranking, the selection rule, and the Levenberg-Marquardt acceptance and bound rules."""

import math
import warnings

import attrs
import numpy as np
import pytest
import rotorid
from rotorid import Derivative, FlightCondition, Maneuver, ManeuverSet, ModelStructure
from rotorid.data import OUTPUT_CHANNELS
from rotorid.errors import EstimationError, IdentifiabilityWarning
from rotorid.estimation.estimate import Estimate, statistics
from rotorid.estimation.reduction import ReductionPath, ReductionStep, reduce
from rotorid.estimation.steps import bounded_step
from rotorid_output_error.levenberg_marquardt import Settings, run

HOVER = FlightCondition.from_airspeed(0.0)


def estimate_of(information, values, names, rmse=1.0):
    """An estimate whose statistics come from ``information`` at ``values``."""
    stats = statistics(information, names)
    n = len(names)
    return Estimate(estimator="constructed", parameter_names=names, values=values,
                    start=np.zeros(n), cramer_rao=stats.cramer_rao,
                    insensitivity=stats.insensitivity, correlation=stats.correlation,
                    information=information, noise_covariance=np.eye(8),
                    output_names=OUTPUT_CHANNELS, cost=1.0, rmse=rmse,
                    cost_history=(1.0,), rmse_history=(rmse,), iterations=1, converged=True,
                    stop_reason="constructed", n_samples=100)


# ----------------------------------------------------------------- statistics
def test_statistics_of_a_two_parameter_information_matrix_by_hand():
    # F = [[4, 2], [2, 2]], det F = 4, F⁻¹ = [[0.5, −0.5], [−0.5, 1]]:
    #   CR = sqrt(diag F⁻¹) = (1/√2, 1); I = 1/sqrt(diag F) = (1/2, 1/√2);
    #   r12 = −0.5 / (1/√2 · 1) = −1/√2 (F's own normalised entry is +1/√2).
    # At Θ = (2, −5): CR % = (100/(2√2), 20), I % = (25, 100/(5√2)).
    estimate = estimate_of(np.array([[4.0, 2.0], [2.0, 2.0]]), [2.0, -5.0], ("M_q", "M_u"))
    np.testing.assert_allclose(estimate.cramer_rao, [1 / math.sqrt(2), 1.0], rtol=1e-12)
    np.testing.assert_allclose(estimate.insensitivity, [0.5, 1 / math.sqrt(2)], rtol=1e-12)
    np.testing.assert_allclose(estimate.correlation,
                               [[1.0, -1 / math.sqrt(2)], [-1 / math.sqrt(2), 1.0]], rtol=1e-12)
    np.testing.assert_allclose(estimate.cramer_rao_pct, [25 * math.sqrt(2), 20.0], rtol=1e-12)
    np.testing.assert_allclose(estimate.insensitivity_pct, [25.0, 10 * math.sqrt(2)],
                               rtol=1e-12)


def test_a_parameter_estimated_at_zero_has_infinite_normalised_measures():
    estimate = estimate_of(np.diag([4.0, 1.0]), [0.0, 1.0], ("M_q", "M_u"))
    assert estimate.cramer_rao_pct[0] == np.inf and estimate.insensitivity_pct[0] == np.inf
    assert estimate.cramer_rao_pct[1] == pytest.approx(100.0)


def test_a_non_finite_information_matrix_names_its_parameters():
    f = np.diag([4.0, np.inf, 1.0])
    with pytest.raises(EstimationError, match="not finite in the rows of M_u: the "
                                              "sensitivities overflow"):
        statistics(f, ("M_q", "M_u", "L_p"))
    with pytest.raises(EstimationError, match=r"must be a 3×3 array, got shape \(2, 2\)"):
        statistics(np.eye(2), ("M_q", "M_u", "L_p"))


@pytest.mark.parametrize("gap, flagged", [(1e-9, False), (1e-11, True)])
def test_nearly_dependent_parameters_are_named_and_get_infinite_bounds(gap, flagged):
    # F = [[1, 1 − gap, 0], [1 − gap, 1, 0], [0, 0, 1]]: eigenvalues 2 − gap, gap and 1, so a
    # condition number of about 2/gap against the limit 10¹⁰.
    f = np.array([[1.0, 1.0 - gap, 0.0], [1.0 - gap, 1.0, 0.0], [0.0, 0.0, 1.0]])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        stats = statistics(f, ("M_q", "M_u", "L_p"))
    named = [w for w in caught if issubclass(w.category, IdentifiabilityWarning)]
    assert stats.cramer_rao[2] == pytest.approx(1.0)
    if flagged:
        assert stats.unidentifiable == (("M_q", "M_u"),) and len(named) == 1
        assert "M_q + M_u" in str(named[0].message)
        assert np.all(np.isinf(stats.cramer_rao[:2]))
    else:
        assert stats.unidentifiable == () and not named
        # (F⁻¹)₁₁ = 1/(1 − (1 − gap)²) ≈ 1/(2 gap)
        assert stats.cramer_rao[0] == pytest.approx(1 / math.sqrt(2 * gap), rel=1e-6)


# ----------------------------------------------------------------- criteria
def test_default_thresholds_are_the_papers():
    assert rotorid.create("reduction-criteria", "insensitivity").threshold == 10.0
    assert rotorid.create("reduction-criteria", "cramer-rao").threshold == 20.0


@pytest.mark.parametrize("name, threshold", [("insensitivity", 10.0), ("cramer-rao", 20.0)])
def test_a_criterion_removes_above_its_threshold_only(name, threshold):
    # One parameter, F = 1/σ², Θ = 1: CR = I = σ, both normalised measures 100·σ %.
    criterion = rotorid.create("reduction-criteria", name)
    for pct, removed in ((threshold * 1.01, True), (threshold, False), (threshold * 0.99, False)):
        estimate = estimate_of(np.array([[(100.0 / pct) ** 2]]), [1.0], ("L_p",))
        proposal = criterion.propose(estimate)
        assert (proposal is not None) == removed, pct
        if removed:
            assert proposal.metric == pytest.approx(pct) and proposal.threshold == threshold


# ----------------------------------------------------------------- reduction loop
# Three derivatives, Θ = 1 each. M_q and M_u are measured well but nearly together:
#   F = [[100, 99, 0], [99, 101, 0], [0, 0, 4]]
#   I % = 100/√F_ii = (10, 9.95, 50): insensitivity ranks L_p worst;
#   the 2×2 block has det 299, so its inverse's diagonal is (101, 100)/299 and
#   CR % = (58.1, 57.8, 50): the Cramér-Rao bound ranks M_q worst.
INFORMATION = {("M_q", "M_q"): 100.0, ("M_u", "M_u"): 101.0, ("M_q", "M_u"): 99.0,
               ("L_p", "L_p"): 4.0}
NAMES = ("M_q", "M_u", "L_p")


class ConstructedEstimator:
    """Returns the statistics of :data:`INFORMATION` restricted to the structure's
    parameters; the RMSE grows by 0.1 per removed parameter. Records the starts it is given."""

    name = "constructed"

    def __init__(self):
        self.starts = []

    def estimate(self, structure, maneuvers, *, start=None):
        self.starts.append(start)
        names = structure.parameter_names
        f = np.array([[INFORMATION.get((a, b), INFORMATION.get((b, a), 0.0)) for b in names]
                      for a in names])
        return estimate_of(f, np.ones(len(names)), names,
                           rmse=1.0 + 0.1 * (len(NAMES) - len(names)))


def _reduction(criteria, continue_to_zero, estimator=None, **options):
    """The parameters removed, in order."""
    structure = ModelStructure(HOVER, [Derivative(n) for n in NAMES])
    t = np.arange(10) * 0.02
    maneuvers = ManeuverSet([Maneuver("still", t, np.zeros((10, 4)), np.zeros((10, 8)))])
    path = reduce(structure, maneuvers, estimator or ConstructedEstimator(), criteria,
                  continue_to_zero=continue_to_zero, **options)
    return [step.removal.parameter for step in path.steps[1:]]


def test_criteria_are_asked_in_order_the_first_proposal_wins():
    insensitivity = rotorid.create("reduction-criteria", "insensitivity")
    cramer_rao = rotorid.create("reduction-criteria", "cramer-rao")
    # Both propose (L_p at 50 % > 10 %, M_q at 58.1 % > 20 %): the first criterion wins.
    assert _reduction([insensitivity, cramer_rao], False)[0] == "L_p"
    assert _reduction([cramer_rao, insensitivity], False)[0] == "M_q"


class WithNoiseParameters(ConstructedEstimator):
    """Adds an estimator's own parameters to every estimate, as filter error adds F_* and R_*:
    far worse determined than any derivative."""

    def estimate(self, structure, maneuvers, *, start=None):
        own = super().estimate(structure, maneuvers, start=start)
        names = own.parameter_names + ("F_q", "R_q")
        information = np.zeros((len(names), len(names)))
        information[:-2, :-2] = own.information
        information[-2:, -2:] = np.eye(2) * 1e-6
        return estimate_of(information, np.ones(len(names)), names, rmse=own.rmse)


def test_reduction_removes_only_the_structures_derivatives():
    """Criteria see the structure's parameters only: an estimator's own parameters are never
    proposed, even by a criterion that takes any name, and their presence changes nothing."""
    plain = _reduction([rotorid.create("reduction-criteria", "cramer-rao")], True)
    assert _reduction([rotorid.create("reduction-criteria", "cramer-rao")], True,
                      estimator=WithNoiseParameters()) == plain

    class AnyName:
        def propose(self, estimate):
            worst = int(np.argmax(estimate.cramer_rao_pct))
            return rotorid.Removal(estimate.parameter_names[worst], "any", 1.0, 0.0, "worst")

    removed = _reduction([AnyName()], False, estimator=WithNoiseParameters())
    assert sorted(removed) == sorted(NAMES)


def test_continue_to_zero_removes_by_the_last_criteria_ranking():
    lenient = [rotorid.create("reduction-criteria", "insensitivity", threshold=1e6),
               rotorid.create("reduction-criteria", "cramer-rao", threshold=1e6)]
    assert _reduction(lenient, False) == []
    # Cramér-Rao ranks M_q first; without it the order would start with L_p.
    assert _reduction(lenient, True) == ["M_q", "L_p", "M_u"]


def test_kept_derivatives_are_never_proposed():
    """Cramér-Rao ranks M_q worst (58.1 %), but it is kept: M_u (57.8 %) goes first, and
    continuing to zero stops when only the kept derivative is left."""
    lenient = [rotorid.create("reduction-criteria", "cramer-rao", threshold=1e6)]
    assert _reduction(lenient, True, keep=("M_q",)) == ["M_u", "L_p"]
    with pytest.raises(EstimationError, match="N_r to keep but not free"):
        _reduction(lenient, True, keep=("N_r",))


def test_each_reduced_structure_restarts_from_the_initial_values():
    lenient = [rotorid.create("reduction-criteria", "cramer-rao", threshold=1e6)]
    cold = ConstructedEstimator()
    _reduction(lenient, True, cold)
    # The full structure and the two reduced ones with parameters left are estimated.
    assert cold.starts == [None, None, None]
    warm = ConstructedEstimator()
    _reduction(lenient, True, warm, warm_start=True)
    assert warm.starts == [None, {"M_u": 1.0, "L_p": 1.0}, {"M_u": 1.0}]


class RefusingWithout(ConstructedEstimator):
    """Refuses a structure without ``needed`` (as filter error refuses a structure whose
    Kalman filter does not exist)."""

    def __init__(self, needed: str):
        super().__init__()
        self.needed = needed

    def estimate(self, structure, maneuvers, *, start=None):
        if self.needed not in structure.parameter_names:
            raise EstimationError("no stabilising Kalman filter: a mode that does not decay "
                                  "moves no output")
        return super().estimate(structure, maneuvers, start=start)


def test_a_structure_the_estimator_refuses_ends_the_path_at_the_step_before():
    """Continuing to zero removes M_q, then L_p; without L_p the estimator refuses: the path
    ends at step 1 with the reason, and the rules select among the steps reached."""
    lenient = [rotorid.create("reduction-criteria", "cramer-rao", threshold=1e6)]
    structure = ModelStructure(HOVER, [Derivative(n) for n in NAMES])
    t = np.arange(10) * 0.02
    maneuvers = ManeuverSet([Maneuver("still", t, np.zeros((10, 4)), np.zeros((10, 8)))])
    path = reduce(structure, maneuvers, RefusingWithout("L_p"), lenient, continue_to_zero=True)
    assert [s.removal.parameter for s in path.steps[1:]] == ["M_q"]
    assert path.stopped.startswith("stopped at step 1: removing L_p (cramer-rao ")
    assert "no stabilising Kalman filter" in path.stopped
    assert path.selected_index == 0 and set(path.selections().values()) <= {0, 1}
    assert reduce(structure, maneuvers, ConstructedEstimator(), lenient).stopped == ""


def test_selection_rules_on_a_constructed_rmse_curve():
    structure = ModelStructure(HOVER, [Derivative(n) for n in NAMES])
    steps = [ReductionStep(k, None, estimate_of(np.eye(1), [1.0], ("L_p",), rmse=rmse),
                           structure) for k, rmse in enumerate((1.0, 1.009, 0.998, 1.3, 1.005))]
    # The lowest RMSE (the paper's rule): step 2.
    assert ReductionPath(steps, "lowest-rmse", 0.01).selected_index == 2
    # Within 1 % of the lowest (0.998 → 1.00798): steps 0, 2 and 4; the most reduced is 4.
    assert ReductionPath(steps, "parsimonious", 0.01).selected_index == 4
    # First rise by more than 1 % over the step before: step 3, so step 2 is selected.
    assert ReductionPath(steps, "first-rise", 0.01).selected_index == 2
    assert ReductionPath(steps, "first-rise", 0.01).selections() == {
        "lowest-rmse": 2, "parsimonious": 4, "first-rise": 2}


# ----------------------------------------------------------------- Levenberg-Marquardt
class ConstructedProblem:
    """One parameter with cost J(θ) and a Gauss-Newton model F = 1, G = −slope that always
    points towards larger θ."""

    def __init__(self, cost, slope=1.0):
        self.cost = cost
        self.slope = slope
        self.settings = Settings()
        self.n_samples = 1
        self.evaluated = []

    def evaluate(self, values):
        cost = float(self.cost(values[0]))
        self.evaluated.append((float(values[0]), cost))
        return cost, np.eye(1), [np.zeros((1, 1))], math.sqrt(cost)

    def gauss_newton(self, values, r, residuals):
        return np.eye(1), np.array([-self.slope])


def test_levenberg_marquardt_never_accepts_a_cost_increase():
    # The model promises a decrease but the cost rises by one part in 10¹² in that direction.
    problem = ConstructedProblem(lambda theta: 1.0 + 1e-12 * theta)
    result = run(problem, np.zeros(1), (np.full(1, -np.inf), np.full(1, np.inf)))
    assert result.values.tolist() == [0.0] and result.iterations == 0
    assert result.cost_history == (1.0,) and not result.converged
    tried = [theta for theta, _ in problem.evaluated[1:]]
    # Every rejection raises λ tenfold, so each trial step is shorter than the last.
    assert len(tried) == problem.settings.max_tries and np.all(np.diff(tried) < 0)


def test_levenberg_marquardt_accepted_costs_fall_strictly():
    problem = ConstructedProblem(lambda theta: 1.0 + (theta - 3.0) ** 2, slope=3.0)
    result = run(problem, np.zeros(1), (np.full(1, -np.inf), np.full(1, np.inf)))
    assert np.all(np.diff(result.cost_history) < 0)
    assert result.values[0] == pytest.approx(3.0, abs=1e-3)


def test_a_step_is_shortened_along_its_direction_to_stay_within_the_bounds():
    # F = I, G = (−2, −2): the free step is (2, 2); the first parameter may move by 0.5 only,
    # so the whole step is scaled by 1/4 (its direction kept).
    step = bounded_step(np.eye(2), np.array([-2.0, -2.0]), 0.0, np.array([0.5, 0.0]),
                         np.array([-np.inf, -np.inf]), np.array([1.0, np.inf]))
    np.testing.assert_allclose(step, [0.5, 0.5], rtol=1e-9)
    # At its bound and pushed outward, a parameter is frozen; the other takes its full step.
    step = bounded_step(np.eye(2), np.array([-2.0, -2.0]), 0.0, np.array([1.0, 0.0]),
                         np.array([-np.inf, -np.inf]), np.array([1.0, np.inf]))
    np.testing.assert_allclose(step, [0.0, 2.0], rtol=1e-9)
    # Projected instead: the first parameter stops at its bound, the other goes all the way.
    step = bounded_step(np.eye(2), np.array([-2.0, -2.0]), 0.0, np.array([0.5, 0.0]),
                         np.array([-np.inf, -np.inf]), np.array([1.0, np.inf]), shorten=False)
    np.testing.assert_allclose(step, [0.5, 2.0], rtol=1e-9)


def test_the_summary_names_the_cost_det_r_for_output_error_only():
    estimate = estimate_of(np.eye(1), [1.0], ("L_p",))
    assert "det R 1" in repr(attrs.evolve(estimate, estimator="output-error"))
    shown = repr(attrs.evolve(estimate, estimator="filter-error"))
    assert "det R" not in shown and ", cost 1)" in shown
