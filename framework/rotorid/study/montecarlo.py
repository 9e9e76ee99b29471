"""Monte Carlo check of the Cramér-Rao bounds.

A case's final estimation (the selected structure with its delays, its parameters from the
study's start) is repeated on data sets that differ only in their measurement-noise seed.
Per parameter the runs give the sample mean and standard deviation; each run also reports its
own Cramér-Rao bound. If the bounds are honest, the standard deviation equals the mean bound
(ratio ≈ 1) and the ±2·CR interval of a run contains the centre in about 95 % of the runs. See
docs/montecarlo.md for what the numbers mean, and why bounds from coloured residuals are
optimistic.

* :func:`monte_carlo`: the runs of one structure on data from any ``data(seed)`` factory;
* :func:`case_monte_carlo`: the same for a flight case, reusing (or first running) its study;
* :class:`WhiteNoise`: a factory adding Gaussian white noise to noise-free maneuvers;
* :class:`PreparedRealisations`: a factory's sets passed through a preparation (decimation).
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import DataError, IdentifiabilityWarning
from rotorid.executors import failure_error, run_tasks
from rotorid.frozen import readonly_array
from rotorid.io import atomic_write, jsonable
from rotorid.model.structure import ModelStructure
from rotorid.plugin.manager import create

#: Half-width of the interval whose coverage is reported, in Cramér-Rao bounds.
INTERVAL = 2.0
#: Probability that a Gaussian lies within ±2σ.
NOMINAL_COVERAGE = math.erf(INTERVAL / math.sqrt(2.0))


@attrs.frozen(eq=False)
class WhiteNoise:
    """Noisy copies of noise-free maneuvers: Gaussian white noise with standard deviation
    ``sigma`` (n_outputs,) per output channel, drawn from ``numpy.random.default_rng(seed)``."""

    clean: ManeuverSet
    sigma: np.ndarray = attrs.field(converter=readonly_array)

    def __call__(self, seed: int) -> ManeuverSet:
        rng = np.random.default_rng(seed)
        return ManeuverSet([m.with_outputs(m.outputs + rng.standard_normal(m.outputs.shape)
                                           * self.sigma) for m in self.clean],
                           hold=self.clean.hold)


@attrs.frozen(eq=False)
class PreparedRealisations:
    """A data factory ``data(seed)`` whose sets go through ``prepare(ManeuverSet) ->
    ManeuverSet`` (a case's :meth:`~rotorid.study.case.FlightCase.identification_records`,
    a :func:`functools.partial` of :func:`rotorid.resampling.decimated`); picklable when both
    are, so it runs in process pools."""

    data: Callable[[int], ManeuverSet]
    prepare: Callable[[ManeuverSet], ManeuverSet]

    def __call__(self, seed: int) -> ManeuverSet:
        return self.prepare(self.data(seed))


@attrs.frozen(eq=False)
class MonteCarloResult:
    """The runs of a Monte Carlo (immutable); statistics are per parameter, shape (P,).

    ``estimates`` and ``cramer_rao`` are (N, P) over the N finished runs (seeds in ``seeds``);
    ``truth`` holds the true values where known (NaN elsewhere; for the truth model its
    linearisation, which a reduced model with delays need not match); ``reference`` the
    estimate the runs repeat (the study's, NaN if none).
    """

    case: str
    parameter_names: tuple[str, ...] = attrs.field(converter=tuple)
    seeds: tuple[int, ...] = attrs.field(converter=tuple)
    estimates: np.ndarray = attrs.field(converter=readonly_array)
    cramer_rao: np.ndarray = attrs.field(converter=readonly_array)
    converged: np.ndarray = attrs.field(converter=lambda v: np.asarray(v, dtype=bool))
    truth: np.ndarray = attrs.field(converter=readonly_array)
    reference: np.ndarray = attrs.field(converter=readonly_array)
    failures: Mapping[int, str] = attrs.field(factory=dict, converter=dict)
    units: str = "flight-test"

    @property
    def runs(self) -> int:
        return len(self.seeds)

    def converged_runs(self) -> "MonteCarloResult":
        """The same Monte Carlo over the runs whose estimation converged: the bound of a run
        stopped at its iteration limit belongs to no optimum."""
        keep = self.converged
        return attrs.evolve(self, seeds=[s for s, k in zip(self.seeds, keep) if k],
                            estimates=self.estimates[keep], cramer_rao=self.cramer_rao[keep],
                            converged=keep[keep])

    @property
    def mean(self) -> np.ndarray:
        """Sample mean of the estimates."""
        return self.estimates.mean(axis=0)

    @property
    def std(self) -> np.ndarray:
        """Sample standard deviation of the estimates (N − 1 in the denominator)."""
        return self.estimates.std(axis=0, ddof=1)

    @property
    def mean_cramer_rao(self) -> np.ndarray:
        """Mean of the runs' Cramér-Rao bounds."""
        return self.cramer_rao.mean(axis=0)

    @property
    def ratio(self) -> np.ndarray:
        """Sample standard deviation over mean Cramér-Rao bound: 1 for honest bounds; NaN
        where a run's bound is infinite (a diverged run claims no spread to compare)."""
        bound = self.mean_cramer_rao
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(np.isfinite(bound), self.std / bound, np.nan)

    def coverage(self, centre: str = "mean") -> np.ndarray:
        """Fraction of runs whose ±2·CR interval contains the sample ``"mean"`` or the
        ``"truth"`` (NaN where the truth is unknown); about 0.954 for honest bounds."""
        if centre not in ("mean", "truth"):
            raise DataError(f"coverage centre must be 'mean' or 'truth', got {centre!r}")
        target = self.mean if centre == "mean" else self.truth
        inside = np.abs(self.estimates - target) <= INTERVAL * self.cramer_rao
        return np.where(np.isfinite(target), inside.mean(axis=0), np.nan)

    @property
    def ratio_band(self) -> float:
        """Two standard errors of a sample-std ratio from N Gaussian runs, ≈ 2/√(2(N−1))."""
        return 2.0 / math.sqrt(2.0 * max(self.runs - 1, 1))

    @property
    def coverage_band(self) -> float:
        """Two binomial standard errors of a coverage of N runs at the nominal 0.954."""
        return 2.0 * math.sqrt(NOMINAL_COVERAGE * (1 - NOMINAL_COVERAGE) / max(self.runs, 1))

    def summary(self) -> dict:
        """Per parameter: mean, std, mean CR, ratio, coverages, truth; and the overall figures."""
        ratio, coverage_mean = self.ratio, self.coverage("mean")
        columns = {"mean": self.mean, "std": self.std, "mean_cramer_rao": self.mean_cramer_rao,
                   "ratio": ratio, "coverage_mean": coverage_mean,
                   "coverage_truth": self.coverage("truth"), "truth": self.truth,
                   "reference": self.reference}
        rows = {name: {key: float(column[i]) for key, column in columns.items()}
                for i, name in enumerate(self.parameter_names)}
        finite = np.isfinite(ratio)
        return jsonable({
            "case": self.case, "runs": self.runs, "converged": int(self.converged.sum()),
            "failed": len(self.failures), "units": self.units,
            "interval_cramer_rao": INTERVAL, "nominal_coverage": NOMINAL_COVERAGE,
            "median_ratio": float(np.median(ratio[finite])) if finite.any() else None,
            "mean_coverage_mean": float(np.nanmean(coverage_mean)),
            "ratio_band": self.ratio_band, "coverage_band": self.coverage_band,
            "parameters": rows})

    def as_dict(self) -> dict:
        """The ``montecarlo.json`` record: the summary and every run."""
        return {**self.summary(), "seeds": list(self.seeds),
                "parameter_names": list(self.parameter_names),
                "estimates": jsonable(self.estimates.tolist()),
                "cramer_rao": jsonable(self.cramer_rao.tolist()),
                "run_converged": self.converged.tolist(),
                "failures": {str(k): v for k, v in self.failures.items()}}

    def report(self) -> str:
        """Text table: per parameter mean, std, mean CR, std/CR and the 2-CR coverages; the
        median std/CR over the converged runs too when some did not converge."""
        lines = [f"Monte Carlo of case {self.case}: {self.runs} runs "
                 f"({int(self.converged.sum())} converged, {len(self.failures)} failed), "
                 f"units {self.units}",
                 f"{'parameter':<12}{'mean':>12}{'std':>11}{'mean CR':>11}{'std/CR':>8}"
                 f"{'cov(mean)':>10}{'cov(truth)':>11}{'truth':>11}"]
        summary = self.summary()
        for name, row in summary["parameters"].items():
            lines.append(f"{name:<12}{_cell(row['mean'], 12)}{_cell(row['std'], 11)}"
                         f"{_cell(row['mean_cramer_rao'], 11)}{_cell(row['ratio'], 8, '.2f')}"
                         f"{_cell(row['coverage_mean'], 10, '.0%')}"
                         f"{_cell(row['coverage_truth'], 11, '.0%')}"
                         f"{_cell(row['truth'], 11)}")
        lines.append(f"median std/CR {_cell(summary['median_ratio'], 0, '.2f').strip()} "
                     f"(honest: 1 ± {self.ratio_band:.2f}); mean coverage around the mean "
                     f"{summary['mean_coverage_mean']:.1%} (honest: {NOMINAL_COVERAGE:.1%} ± "
                     f"{self.coverage_band:.1%})")
        if 1 < self.converged.sum() < self.runs:
            converged = self.converged_runs().summary()
            lines.append(f"over the {converged['runs']} converged runs only: median std/CR "
                         f"{_cell(converged['median_ratio'], 0, '.2f').strip()}")
        return "\n".join(lines)


def _cell(value, width: int, spec: str = ".4g") -> str:
    return f"{'—' if value is None else format(value, spec):>{width}}"


# ----------------------------------------------------------------- runs
def estimate_run(structure: ModelStructure, data: Callable[[int], ManeuverSet], seed: int,
                 estimator: str, options: Mapping, start) -> tuple:
    """One Monte Carlo run (a task): ``(parameter names, values, cramer_rao, converged)`` on
    ``data(seed)``."""
    maneuvers = data(seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        result = create("estimators", estimator, **options).estimate(structure, maneuvers,
                                                                     start=start)
    return result.parameter_names, result.values, result.cramer_rao, result.converged


def monte_carlo(structure: ModelStructure, data: Callable[[int], ManeuverSet],
                seeds: Sequence[int], *, estimator: str = "output-error",
                estimator_options: Mapping | None = None, start=None,
                truth: Mapping[str, float] | None = None, reference=None, executor=None,
                case: str = "") -> MonteCarloResult:
    """Estimate ``structure`` on ``data(seed)`` for every seed, through ``executor``.

    Args:
        structure: the model structure (with its delays) every run estimates.
        data: ``data(seed) -> ManeuverSet``; must pickle for a process pool or Dask.
        seeds: one run per seed.
        estimator, estimator_options: the estimator plugin and its options.
        start: start values of every run (name → value or a vector; default the structure's).
        truth: true values by name, where known.
        reference: the estimate being checked (vector), e.g. the study's; NaN if ``None``.
        executor: ``None``, ``"process"`` or an Executor (see :mod:`rotorid.executors`).

    The result covers every parameter the estimator estimates (the filter error's noise
    parameters too). Failed runs are recorded in ``failures`` and left out of the statistics;
    if every run fails, :class:`~rotorid.errors.StudyError` names them.
    """
    options = dict(estimator_options or {})
    tasks = {int(s): ((structure, data, int(s), estimator, options, start), {}) for s in seeds}
    label = f"case {case} run with seed {{}}".format
    results, failures = run_tasks(estimate_run, tasks, executor, label=label)
    if not results:
        raise failure_error("Monte Carlo runs", results, failures, "no directory", label)
    names = next(iter(results.values()))[0]
    truth_vector = [float((truth or {}).get(n, np.nan)) for n in names]
    return MonteCarloResult(
        case, names, tuple(results), [r[1] for r in results.values()],
        [r[2] for r in results.values()], [r[3] for r in results.values()], truth_vector,
        np.full(len(names), np.nan) if reference is None else reference, failures,
        structure.units.name)


def case_monte_carlo(case, runs: int, out_dir: str | Path, *, seed: int | None = None,
                     executor=None, progress=None) -> MonteCarloResult:
    """Monte Carlo of a flight case's final estimation.

    The case's data source must generate data: besides ``case_data`` it has the optional
    ``noise_realisations(settings, directory)``, which returns a picklable
    ``data(seed) -> ManeuverSet`` of the case's identification maneuvers with that noise seed.
    The case's study result in ``out_dir/<case>`` is reused when it is there (it is run
    first otherwise, without figures). Each run regenerates the case's data with noise seed
    ``seed + k`` (k = 0 … runs − 1; ``seed`` defaults to the case's own, so run 0 repeats
    the study's data) and repeats the final estimation: the selected structure with its
    delays, from the study's start values of the structure's parameters; what an estimator
    starts from its data (filter error's noise parameters, output biases, initial states) each
    run starts from its own data, as the study's selected fit did (its final fit continued
    from that one's noise model, :mod:`rotorid.estimation.continuation`). Writes
    ``montecarlo.json`` and the figure ``montecarlo.png``/``.svg`` into ``out_dir/<case>``.
    """
    from rotorid.study.pipeline import run_case

    if runs < 2:
        raise DataError(f"a Monte Carlo needs at least 2 runs to estimate a spread, got {runs}")
    source = create("data-sources", case.data_source)
    if not hasattr(source, "noise_realisations"):
        raise DataError(f"case {case.name}: a Monte Carlo regenerates the data with new noise, "
                        f"which the {case.data_source!r} data source cannot do; use generated "
                        f"data (a source with noise_realisations, docs/plugins.md)")
    study = run_case(case, out_dir, resume=True, progress=progress)
    directory = Path(out_dir) / case.name
    data = source.noise_realisations(case.data_settings, directory / "montecarlo-data")
    data = PreparedRealisations(data, case.identification_records)   # as the study's fits
    first = int(case.data.get("seed", 0) if seed is None else seed)
    structure, estimate = study.structures["with delays"], study.estimates["with delays"]
    start = {name: float(value) for name, value in zip(estimate.parameter_names, estimate.start)
             if name in structure.parameter_names}
    result = monte_carlo(
        structure, data, range(first, first + runs),
        estimator=case.estimator, estimator_options=case.estimator_options,
        start=start, truth=study.truth_derivatives, reference=estimate.values,
        executor=executor, case=case.name)
    write_monte_carlo(result, directory)
    return result


def write_monte_carlo(result: MonteCarloResult, directory: str | Path) -> Path:
    """Write ``montecarlo.json`` in ``directory`` (its figure:
    :func:`rotorid.report.plots.montecarlo.plot_monte_carlo`); returns its path."""
    return atomic_write(Path(directory) / "montecarlo.json",
                        json.dumps(result.as_dict(), indent=1, allow_nan=False))
