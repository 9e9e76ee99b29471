"""The frequency-domain fit beside the time-domain fit of a case (``[compare] frequency``).

For each identified model (no delays, with delays) the ``frequency-response`` estimator fits
the same structure to the verification sweeps' frequency responses from zero (equation-error
start values on the sweeps), the reverse of the paper, on the compared pairs and the
on-axis translational accelerations (:data:`TRANSLATIONAL_PAIRS`). Both estimates are then
judged on the same measures: Tischler's mismatch cost J per pair on the sweeps' measured
responses, and the time-domain metrics (RMSE, TIC) on the identification multisteps, both
from the plain simulation and, as frequency-domain practice verifies, with each multistep's
input biases and output reference shifts fitted to the fixed model
(:mod:`rotorid.verification.shifts`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import IdentifiabilityWarning
from rotorid.estimation.equation_error import equation_error_start
from rotorid.estimation.estimate import Estimate
from rotorid.model.structure import ModelStructure
from rotorid.plugin.manager import create
from rotorid.simulation.simulator import simulate
from rotorid.simulation.transfer import pair_response
from rotorid.verification.metrics import TimeDomainMetrics
from rotorid.verification.pairs import parse_pair, primary_axis
from rotorid.verification.shifts import simulate_with_shifts
from rotorid.verification.simulation_fit import fit_unless_diverging

#: The estimator the comparison fits with.
FREQUENCY_ESTIMATOR = "frequency-response"
#: The two estimates compared, by method.
METHODS = ("time", "frequency")
#: Starts of the frequency-domain fit (the equation-error start and varied ones).
FREQUENCY_STARTS = 24
#: Pairs the frequency-domain fit matches beside the compared ones: the on-axis
#: translational accelerations. They carry the speed derivatives and the slow translational
#: modes that the angular responses leave free and that dominate the multisteps.
TRANSLATIONAL_PAIRS = ("ax/long", "ay/lat")
#: Frequencies (rad/s) at which :func:`fitted_pairs` asks whether a model responds on a pair.
RESPONSE_CHECK_OMEGA = (0.5, 2.0, 8.0)


@attrs.frozen(eq=False)
class FrequencyComparison:
    """One model's time-domain estimate beside its frequency-domain fit.

    ``pair_costs`` is J per pair (dimensionless) by method; ``time_metrics`` the metrics on
    the identification multisteps by method, ``None`` where the model's simulation diverges;
    ``shifted_metrics`` the same after fitting each multistep's input biases and output
    reference shifts to the fixed model; ``seconds`` the frequency-domain fit's wall time in
    s, computing the responses included.
    """

    frequency_estimate: Estimate
    pair_costs: Mapping[str, Mapping[str, float]]
    time_metrics: Mapping[str, TimeDomainMetrics | None]
    shifted_metrics: Mapping[str, TimeDomainMetrics | None]
    seconds: float

    def summary(self) -> dict:
        """The ``result.json`` record: the frequency-domain estimate, J per pair and the
        multistep metrics of both methods, plain and with biases and shifts fitted (``null``
        for a diverging simulation); the fit's wall time goes to the record's ``timing``."""
        return {"frequency_estimate": self.frequency_estimate.as_dict(),
                "pair_costs": {m: dict(c) for m, c in self.pair_costs.items()},
                **{key: {m: None if v is None else v.summary() for m, v in metrics.items()}
                   for key, metrics in (("time_metrics", self.time_metrics),
                                        ("shifted_metrics", self.shifted_metrics))}}


def _metrics(structure: ModelStructure, values, multisteps: ManeuverSet,
             shifted: bool = False) -> TimeDomainMetrics | None:
    """Multistep metrics of ``structure`` at ``values``, from the plain simulation or, when
    ``shifted``, after the bias and shift fit; ``None`` when the model diverges."""
    fit = fit_unless_diverging(structure, values, multisteps,
                               _with_shifts if shifted else simulate)
    return None if fit is None else fit.metrics


def _with_shifts(structure: ModelStructure, values, multisteps: ManeuverSet):
    """The outputs after each multistep's input bias and output shift fit
    (:func:`~rotorid.verification.shifts.simulate_with_shifts`)."""
    return simulate_with_shifts(structure, values, multisteps).outputs


def fitted_pairs(structure: ModelStructure, values, sweeps: ManeuverSet, pairs
                 ) -> tuple[str, ...]:
    """``pairs`` and the :data:`TRANSLATIONAL_PAIRS` that ``sweeps`` excite and on which
    ``structure`` responds at ``values`` (a reduced structure may not couple them)."""
    axes = {primary_axis(m) for m in sweeps}

    def responds(pair: str) -> bool:
        output, control = parse_pair(pair)
        return (output in structure.outputs and control in structure.controls
                and np.any(pair_response(structure, values, RESPONSE_CHECK_OMEGA, output,
                                         control) != 0.0))

    return (*pairs, *(p for p in TRANSLATIONAL_PAIRS
                      if p not in pairs and parse_pair(p)[1] in axes and responds(p)))


def compare_frequency_fit(structure: ModelStructure, time_estimate: Estimate,
                          time_metrics: TimeDomainMetrics, sweeps: ManeuverSet,
                          multisteps: ManeuverSet, pairs, band_max: float
                          ) -> FrequencyComparison:
    """Fit ``structure`` to the ``pairs`` of ``sweeps`` and the translational pairs
    (:func:`fitted_pairs`; J points up to ``band_max`` rad/s) from equation-error start values
    on the sweeps and ``FREQUENCY_STARTS − 1`` variations of them, and compare it with
    ``time_estimate`` (whose metrics on the ``multisteps`` are ``time_metrics``)."""
    time_values = time_estimate.restricted(structure.parameter_names).values
    estimator = create("estimators", FREQUENCY_ESTIMATOR,
                       pairs=fitted_pairs(structure, time_values, sweeps, pairs),
                       band=(0.0, band_max), starts=FREQUENCY_STARTS)
    clock = time.perf_counter()
    fit_data = estimator.fit_data(sweeps)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        fitted = estimator.estimate(structure, fit_data,
                                    start=equation_error_start(structure, sweeps))
    seconds = time.perf_counter() - clock
    estimates = {"time": time_values, "frequency": fitted.values}
    return FrequencyComparison(
        fitted,
        {m: estimator.pair_costs(structure, estimates[m], fit_data) for m in METHODS},
        {"time": time_metrics,
         "frequency": _metrics(structure, fitted.values, multisteps)},
        {m: _metrics(structure, estimates[m], multisteps, shifted=True) for m in METHODS},
        seconds)
