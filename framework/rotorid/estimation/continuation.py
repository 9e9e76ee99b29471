"""Start values of a refit that continues from an earlier fit of the same estimator.

A warm-started reduction step, the delayed fit and each delay-profile point refit a structure
close to one already fitted, on the same records. They start from that fit's derivatives and
delays, and also from its values of the estimator's own parameters (filter error's process
noise, disturbances, gusts and measurement noise): left to their default starts those would
restart from the data, and a filter-error refit of the very same structure can then settle
in another, less likely optimum of its noise model (a study's "with delays" model, refitted
without any delay, ended at 3.3 times the cost of the fit it started from). The records' own
parameters (output biases, initial states) restart from the data as usual.
"""

from __future__ import annotations

from rotorid.estimation.estimate import Estimate
from rotorid.estimation.result_file import RECORD_PARAMETER_PREFIXES
from rotorid.model.structure import ModelStructure


def continued_start(estimate: Estimate, fitted: ModelStructure,
                    refitted: ModelStructure) -> dict[str, float]:
    """Name → start value for a fit of ``refitted`` from ``estimate`` (a fit of ``fitted``):
    its values of the parameters ``refitted`` shares with it and of the estimator's own
    parameters (neither ``fitted``'s nor a record's ``bias_``/``x0_``)."""
    shared = set(refitted.parameter_names)
    structure = set(fitted.parameter_names)
    return {name: value for name, value in estimate.as_mapping().items()
            if name in shared or (name not in structure
                                  and not name.startswith(RECORD_PARAMETER_PREFIXES))}
