"""Monte Carlo check of the Cramér-Rao bounds: honest on white noise, optimistic on coloured
noise by the expected factor, identical through a process pool, failures kept apart."""

import json
import re

import attrs
import numpy as np
import pytest
import rotorid
from rotorid import Derivative, FlightCondition, ManeuverSet, ModelStructure
from rotorid.errors import DataError, StudyError
from rotorid.study.montecarlo import (
    NOMINAL_COVERAGE,
    WhiteNoise,
    case_monte_carlo,
    monte_carlo,
    write_monte_carlo,
)
from scipy.signal import lfilter
from test_output_error import SMALL_TRUTH, doublet_maneuvers, with_outputs
from test_reduction_study import files_case

NAMES = ("M_u", "M_q", "M_long", "X_u", "X_long", "L_p", "L_lat")
SIGMA = np.array([0.2, 0.2, 0.3, 0.1, 0.2, 0.3, 0.1, 0.2])


@pytest.fixture(scope="module")
def problem():
    """A linear pitch/roll model, its true values and noise-free doublet responses."""
    structure = ModelStructure(FlightCondition.from_airspeed(0.0),
                               [Derivative(n) for n in NAMES])
    truth = {n: SMALL_TRUTH[n] for n in NAMES}
    clean = with_outputs(structure, structure.as_vector(truth), doublet_maneuvers(n=400))
    return structure, truth, clean


class ColouredNoise:
    """First-order autoregressive noise of standard deviation σ and pole ``pole``."""

    def __init__(self, clean, sigma, pole):
        self.clean, self.sigma, self.pole = clean, sigma, pole

    def __call__(self, seed):
        rng = np.random.default_rng(seed)
        maneuvers = []
        for m in self.clean:
            white = rng.standard_normal(m.outputs.shape) * self.sigma * np.sqrt(1 - self.pole**2)
            maneuvers.append(m.with_outputs(m.outputs + lfilter([1.0], [1.0, -self.pole], white,
                                                                 axis=0)))
        return ManeuverSet(maneuvers)


def run(problem, data, seeds, **options):
    structure, truth, _ = problem
    return monte_carlo(structure, data, seeds, estimator_options={"horizons": ()}, start=truth,
                       truth=truth, **options)


def test_bounds_are_honest_for_white_noise(problem):
    result = run(problem, WhiteNoise(problem[2], SIGMA), range(150))
    assert result.converged.all()
    # 150 runs: a sample-std ratio has a standard error of about 6 %.
    assert np.all(np.abs(result.ratio - 1.0) < 0.2), result.ratio
    assert abs(np.median(result.ratio) - 1.0) < 0.1
    coverage = result.coverage("truth")
    assert abs(coverage.mean() - NOMINAL_COVERAGE) < 0.03, coverage
    assert np.all(np.abs(result.mean - result.truth) < 3 * result.std / np.sqrt(150) + 1e-12)


def test_bounds_are_optimistic_for_coloured_noise_by_the_autoregressive_factor(problem):
    # For noise with pole a and slowly varying sensitivities the variance grows by (1+a)/(1-a)
    # over white noise of the same σ: √3 ≈ 1.73 at a = 0.5, which the bounds do not see.
    result = run(problem, ColouredNoise(problem[2], SIGMA, 0.5), range(80))
    assert np.all((result.ratio > 1.4) & (result.ratio < 2.1)), result.ratio
    assert result.coverage("truth").mean() < 0.85


def test_runs_are_identical_in_a_process_pool_and_failures_are_kept_apart(problem):
    data = WhiteNoise(problem[2], SIGMA)
    serial = run(problem, data, range(4))
    pooled = run(problem, data, range(4), executor="process")
    assert pooled.seeds == serial.seeds == (0, 1, 2, 3)
    assert np.array_equal(pooled.estimates, serial.estimates)
    assert np.array_equal(pooled.cramer_rao, serial.cramer_rao)

    def broken(seed):
        if seed == 2:
            raise DataError("no data for seed 2")
        return data(seed)

    partial = run(problem, broken, range(4))
    assert partial.seeds == (0, 1, 3)
    assert "seed 2" in partial.failures[2] and "no data for seed 2" in partial.failures[2]
    assert np.array_equal(partial.estimates, serial.estimates[[0, 1, 3]])
    with pytest.raises(StudyError, match="3 of 3 Monte Carlo runs failed") as caught:
        run(problem, lambda seed: broken(2), range(3))
    told = str(caught.value)                         # one reason, told once, for all three
    assert told.count("no data for seed 2") == 1
    assert re.search(r"seed 0, case \S* ?run with seed 1, case \S* ?run with seed 2: "
                     r"DataError: no data for seed 2", told), told


def test_record_report_and_figure(problem, tmp_path):
    result = run(problem, WhiteNoise(problem[2], SIGMA), range(5))
    assert write_monte_carlo(result, tmp_path) == tmp_path / "montecarlo.json"
    record = json.loads((tmp_path / "montecarlo.json").read_text())
    assert record["runs"] == 5 and record["parameter_names"] == list(NAMES)
    row = record["parameters"]["L_p"]
    i = NAMES.index("L_p")
    assert row["std"] == pytest.approx(result.std[i])
    assert row["ratio"] == pytest.approx(result.std[i] / result.cramer_rao[:, i].mean())
    assert row["reference"] is None and row["truth"] == SMALL_TRUTH["L_p"]
    report = result.report()
    assert "std/CR" in report and all(name in report for name in NAMES)


def test_the_figure_turns_logarithmic_for_a_far_off_ratio(problem):
    from rotorid.report.plots.montecarlo import plot_monte_carlo

    result = run(problem, WhiteNoise(problem[2], SIGMA), range(5))
    assert plot_monte_carlo(result).axes[0].get_yscale() == "linear"
    bounds = result.cramer_rao.copy()
    bounds[:, NAMES.index("L_p")] /= 90.0            # one ratio 90 times the others
    far = attrs.evolve(result, cramer_rao=bounds)
    top = plot_monte_carlo(far).axes[0]
    assert top.get_yscale() == "log"
    assert top.get_ylim()[1] > 90 * far.ratio[NAMES.index("M_q")]


def test_converged_runs_keep_the_statistics_of_those_runs_only(problem):
    result = run(problem, WhiteNoise(problem[2], SIGMA), range(4))
    marked = attrs.evolve(result, converged=[True, False, True, True])
    kept = marked.converged_runs()
    assert kept.seeds == (0, 2, 3) and kept.converged.all()
    np.testing.assert_array_equal(kept.std, result.estimates[[0, 2, 3]].std(axis=0, ddof=1))
    np.testing.assert_array_equal(kept.mean_cramer_rao,
                                  result.cramer_rao[[0, 2, 3]].mean(axis=0))
    median = np.median(kept.ratio)
    assert f"over the 3 converged runs only: median std/CR {median:.2f}" in marked.report()
    assert "converged runs only" not in result.report()


def test_helisim_noise_realisations_equal_data_generated_with_that_seed(tmp_path):
    source = rotorid.create("data-sources", "helisim")
    settings = {"condition": "hover", "duration_scale": 0.3, "axes": ["long", "ped"],
                "directions": [1]}
    direct, _ = source.generate_into({**settings, "kinds": ["3211"], "seed": 5},
                                     tmp_path / "direct")
    realisations = source.noise_realisations(
        {**settings, "identification": ["3211"], "verification": ["sweep"]}, tmp_path / "clean")
    again, other = realisations(5), realisations(6)
    assert again.names == direct.names
    for a, b, c in zip(direct, again, other):
        assert np.array_equal(a.outputs, b.outputs) and np.array_equal(a.inputs, b.inputs)
        assert not np.array_equal(a.outputs, c.outputs)


def test_case_monte_carlo_needs_generated_data_and_two_runs(tmp_path, problem):
    case = files_case(tmp_path, problem[2])
    with pytest.raises(DataError, match="cannot do; use generated data"):
        case_monte_carlo(case, 3, tmp_path / "out")
    with pytest.raises(DataError, match="at least 2 runs"):
        case_monte_carlo(case, 1, tmp_path / "out")


def test_flying_only_the_identification_maneuvers_gives_the_same_maneuvers(tmp_path):
    """case_monte_carlo flies only the identification kinds: each maneuver is its own row of
    the batch and its noise is seeded by its name, so it equals the full set's."""
    source = rotorid.create("data-sources", "helisim")
    settings = {"condition": "hover", "duration_scale": 0.3, "seed": 4, "axes": ["long"],
                "directions": [1]}
    everything, _ = source.generate_into(settings, tmp_path / "all")
    multisteps, _ = source.generate_into({**settings, "kinds": ["3211", "2311"]},
                                         tmp_path / "multisteps")
    by_name = {m.name: m for m in everything}
    assert len(multisteps) < len(everything)
    for m in multisteps:
        assert np.array_equal(by_name[m.name].outputs, m.outputs)
        assert np.array_equal(by_name[m.name].inputs, m.inputs)
