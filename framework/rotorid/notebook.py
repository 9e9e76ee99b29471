"""Short text and HTML summaries of rotorid's values, for ``repr`` and Jupyter notebooks.

Each value shows what it is in one line (its ``__repr__``) and, in a notebook, a small table
(``_repr_html_``): never its arrays. The functions take the objects by duck typing, so this
module imports none of them.
"""

from __future__ import annotations

import html
import math

import numpy as np

from rotorid.progress import counted
from rotorid.units import unit_system

#: Maneuver names listed in a set's one-line summary before "…".
LISTED_NAMES = 4


def html_table(caption: str, header, rows) -> str:
    """An HTML table with a caption; every cell is escaped."""
    def cells(tag, values):
        return "".join(f"<{tag}>{html.escape(str(v))}</{tag}>" for v in values)

    body = "".join(f"<tr>{cells('td', row)}</tr>" for row in rows)
    return (f"<table><caption style='text-align:left'>{html.escape(caption)}</caption>"
            f"<thead><tr>{cells('th', header)}</tr></thead><tbody>{body}</tbody></table>")


def _number(value, digits: int = 4) -> str:
    return "–" if value is None or not math.isfinite(value) else f"{value:.{digits}g}"


def _pct(value) -> str:
    return "inf" if not math.isfinite(value) else f"{value:.1f}"


# ----------------------------------------------------------------- estimates
def estimate_summary(estimate) -> str:
    """``Estimate(output-error, 9 parameters incl. 1 delay, converged after 4 iterations,
    RMSE 0.0652, det R 1.45e-10)``; other estimators' cost is named ``cost`` (filter error's
    exp(2L/N), the frequency-response estimator's J)."""
    delays = int(np.sum(estimate.is_delay))
    state = "converged" if estimate.converged else f"not converged ({estimate.stop_reason})"
    return (f"Estimate({estimate.estimator}, {len(estimate.parameter_names)} parameters"
            + (f" incl. {counted(delays, 'delay')}" if delays else "")
            + f", {state} after {counted(estimate.iterations, 'iteration')}, RMSE "
              f"{_number(estimate.rmse)}, "
              f"{'det R' if estimate.estimator == 'output-error' else 'cost'} "
              f"{_number(estimate.cost, 3)})")


def estimate_html(estimate) -> str:
    """The summary and the parameter table: value, Cramér-Rao bound, normalised CR and
    insensitivity in %."""
    rows = [(name, _number(value, 6), _number(bound), _pct(cr), _pct(insensitivity))
            for name, value, bound, cr, insensitivity in zip(
                estimate.parameter_names, estimate.values, estimate.cramer_rao,
                estimate.cramer_rao_pct, estimate.insensitivity_pct)]
    return html_table(f"{estimate_summary(estimate)}; {estimate.units} units, delays in s",
                      ("parameter", "value", "CR bound", "CR %", "insens. %"), rows)


# ----------------------------------------------------------------- maneuvers
def _described(metadata) -> str:
    """The scalar metadata as ``key=value`` pairs (nested settings left out)."""
    return "".join(f", {key}={value}" for key, value in metadata.items()
                   if isinstance(value, (str, int, float, bool)))


def maneuver_summary(maneuver) -> str:
    """``Maneuver('doublet_long', 10 s, 500 samples at 50 Hz, flight-test units, kind=doublet)``."""
    return (f"Maneuver({maneuver.name!r}, {maneuver.duration:.4g} s, {maneuver.n_samples} "
            f"samples at {1.0 / maneuver.dt:.4g} Hz, {maneuver.units} units"
            f"{_described(maneuver.metadata)})")


def maneuver_html(maneuver, channels) -> str:
    """The summary and, per channel (``channels``: names of ``time``, inputs, outputs), its
    unit, minimum and maximum."""
    units = unit_system(maneuver.units)
    rows = []
    for name in channels:
        values = maneuver.channel(name)
        unit = "s" if name == "time" else units.label(name)
        rows.append((name, unit, _number(float(values.min())), _number(float(values.max()))))
    return html_table(maneuver_summary(maneuver), ("channel", "unit", "min", "max"), rows)


def maneuver_set_summary(maneuvers) -> str:
    """``ManeuverSet(4 maneuvers: a, b, c, d; 2000 samples, zoh hold, flight-test units)``."""
    names = list(maneuvers.names)
    listed = ", ".join(names[:LISTED_NAMES]) + (", …" if len(names) > LISTED_NAMES else "")
    return (f"ManeuverSet({counted(len(names), 'maneuver')}: {listed}; "
            f"{maneuvers.n_samples} samples, {maneuvers.hold} hold, {maneuvers.units} units)")


def maneuver_set_html(maneuvers) -> str:
    """The summary and one row per maneuver: kind, axis, duration, samples."""
    rows = [(m.name, m.metadata.get("kind", ""), m.metadata.get("axis", ""),
             f"{m.duration:.4g}", m.n_samples) for m in maneuvers]
    return html_table(maneuver_set_summary(maneuvers),
                      ("maneuver", "kind", "axis", "duration s", "samples"), rows)


# ----------------------------------------------------------------- study results
def case_result_summary(result) -> str:
    """``CaseResult('hover', 45 parameters at step 15 of 15; RMSE no delays 0.2763, with
    delays 0.2350)``."""
    path = result.path
    rmse = ", ".join(f"{result.model_name(label)} {_number(result.estimates[label].rmse)}"
                     for label in result.models)
    return (f"CaseResult({result.name!r}, {path.selected.n_parameters} "
            f"parameters at step {path.selected_index} of {len(path.steps) - 1}; RMSE {rmse})")


def case_result_html(result) -> str:
    """The summary and one row per model: parameters, delays, RMSE, det R, J_ave."""
    rows = []
    for label in result.models:
        estimate, verification = result.estimates[label], result.verification.get(label)
        cost = None if verification is None else verification.average_cost()
        rows.append((result.model_name(label), len(estimate.parameter_names),
                     int(np.sum(estimate.is_delay)),
                     _number(estimate.rmse), _number(estimate.cost, 3), _number(cost)))
    return html_table(case_result_summary(result),
                      ("model", "parameters", "delays", "RMSE", "det R", "J_ave"), rows)
