"""The paper's hover study with the Study API: identify, reduce, add delays, verify.

This script runs the built-in ``hover`` flight case (``rotorid/cases/hover.toml``) end to end
and prints what the paper reports for it:

1. the data: the nonlinear Bo-105-class truth model (the ``helisim`` data source) trimmed in
   hover and flown with 3211/2311 multisteps on every control (identification) and one
   frequency sweep per control (verification), with sensor noise;
2. the reduction path: starting from the fully populated 60-derivative structure, one
   parameter is removed per step (normalised insensitivity > 10 %, then Cramér-Rao bound
   > 20 %) and the rest re-estimated; the structure with the lowest RMSE is selected;
3. the time delays on the surviving rotor-affected derivatives (L_p … M_lat), estimated with
   the other parameters in a final refinement (undetermined ones are dropped);
4. the key derivatives (M_w, L_v, N_v, Z_w, M_u, X_u, X_v, Y_u, Y_v) beside the truth model's
   own 6-DoF linearisation;
5. the verification: time-domain RMSE on the identification data, and for every sweep pair
   (``q/long``, ``p/long`` …) whether the error ε = H_model/H_truth stays inside the MUAD and
   AEE envelopes where the coherence is at least 0.8, for the models without and with delays.

Run it from the repository root::

    python docs/examples/study_hover.py results/hover-example --quick

``--quick`` (or the environment variable ``ROTORID_QUICK=1``) runs the case's reduced but
honest variant (records shortened to 60 %, reduction stopped by the criteria instead of being
continued to zero parameters): about 40 s on 2 cores with the figures and the report, as
``rotorid study hover --quick``.
Without it the full paper setup runs (full-length records, reduction to zero parameters):
about 1.5 minutes plus the figures. ``--seed`` changes the sensor noise, ``--resume``
reuses the reduction steps a previous run of the same configuration left in the output
directory, ``--no-figures`` skips the figures and the HTML report.

Everything is written under ``<out>/hover/``: the maneuvers (``data/``), one JSON file per
reduction step (``steps/``), ``delays.json``, ``result.json``, the paper's figures
(``figures/``: RMSE versus removals, 2311 time histories, sweep errors against the envelopes),
the Appendix-B tables (``tables/``) and ``report.html``; ``<out>/report.html`` links the
cases. Units are the paper's flight-test units: ft/s, ft/s², deg, deg/s, % of control travel;
delays in s.

``docs/examples/study_forward.py`` reuses the functions below for the 70 kt case.
"""

from __future__ import annotations

import argparse
import math
import os
from collections import defaultdict

from rotorid.report.html import StudyReport
from rotorid.study.case import FlightCase
from rotorid.study.pipeline import Study
from rotorid.study.result import MODELS, CaseResult

#: Envelopes whose pass/fail the summary shows per pair.
ENVELOPES = ("muad", "aee")


def quick_requested(flag: bool) -> bool:
    """``--quick`` given, or ``ROTORID_QUICK`` set to a true value in the environment."""
    return flag or os.environ.get("ROTORID_QUICK", "").lower() in ("1", "true", "yes")


def build_case(name: str, quick: bool, seed: int | None = None) -> FlightCase:
    """A built-in case (``hover`` or ``forward``), its quick variant, another noise seed."""
    case = FlightCase.load(name)
    if quick:
        case = case.quick()
    if seed is not None:
        case = case.with_seed(seed)
    return case


def run_study(case: FlightCase, out_dir, figures: bool = True,
              resume: bool = False) -> CaseResult:
    """Run one case through the Study (progress lines go to stderr); return its result."""
    study = Study([case], out_dir, resume=resume,
                  report_writer=StudyReport() if figures else None)
    return study.run()[case.name]


def reduction_table(result: CaseResult) -> str:
    """One line per reduction step; the selected step is marked with ``◀``."""
    path = result.path
    lines = [f"Reduction path ({len(path.steps)} steps, rule {path.rule}, "
             f"RMSE tolerance {path.rmse_tolerance:.0%})",
             f"  {'step':>4}  {'removed':<9}{'criterion':<14}{'metric %':>9}"
             f"{'params':>8}{'RMSE':>9}"]
    for step in path.steps:
        removal = step.removal
        removed, criterion, metric = ("—", "(full)", "") if removal is None else (
            removal.parameter, removal.criterion, f"{removal.metric:.1f}")
        mark = "  ◀ selected" if step.index == path.selected_index else ""
        lines.append(f"  {step.index:>4}  {removed:<9}{criterion:<14}{metric:>9}"
                     f"{step.n_parameters:>8}{step.rmse:>9.4f}{mark}")
    return "\n".join(lines)


def structure_summary(result: CaseResult) -> str:
    """The selected derivatives grouped by force/moment, and the removed ones."""
    selected = result.structures["no delays"]
    groups = defaultdict(list)
    for name in selected.names:
        groups[name.split("_")[0]].append(name)
    lines = [f"Selected structure: {len(selected.names)} derivatives "
             f"({len(result.path.removed)} removed)"]
    lines += [f"  {letter}: {', '.join(groups[letter])}" for letter in "XYZLMN"
              if groups[letter]]
    lines.append(f"  removed, in order: {', '.join(result.path.removed) or 'none'}")
    return "\n".join(lines)


def delay_summary(result: CaseResult) -> str:
    """Estimated delays with Cramér-Rao bounds, in brackets the truth model's equivalent delays
    (``rotorid.verification.equivalent_delays``), and the delays dropped as undetermined."""
    estimate = result.estimates["with delays"]
    truth = {} if result.truth_delays is None else result.truth_delays.delays
    lines = ["Time delays (s)" + ("   [truth model's equivalent delay]" if truth else "")]
    for i, name in enumerate(estimate.parameter_names):
        if name.startswith("tau_"):
            line = (f"  {name[4:]:<8}{estimate.values[i]:7.3f} ± "
                    f"{estimate.cramer_rao[i]:.3f} (Cramér-Rao)")
            if name[4:] in truth:
                line += f"   [{truth[name[4:]]:.3f}]"
            lines.append(line)
    if result.dropped_delays:
        lines.append(f"  dropped (undetermined): {', '.join(result.dropped_delays)}")
    return "\n".join(lines)


def _number(value: float | None) -> str:
    return f"{'—':>10}" if value is None else f"{value:>10.4g}"


def key_derivative_table(result: CaseResult) -> str:
    """Identified key derivatives (model with delays) beside the truth's linearisation."""
    source = ("truth-model linearisation" if result.truth_derivatives is not None
              else "no truth model for these data")
    lines = [f"Key derivatives (identified with delays / {source})",
             f"  {'name':<6}{'identified':>10}{'truth':>10}  sign"]
    for name, row in result.key_derivatives().items():
        identified, truth = row["identified"], row["truth_linearisation"]
        if identified is None:
            verdict = "removed"
        elif truth is None:
            verdict = ""
        else:
            verdict = "agrees" if math.copysign(1, identified) == math.copysign(1, truth) \
                else "DIFFERS"
        lines.append(f"  {name:<6}{_number(identified)}{_number(truth)}  {verdict}")
    return "\n".join(lines)


def _status(check) -> str:
    """``pass 162/162``: status, points inside / points with coherence ≥ 0.8."""
    if check.passed is None:
        return "n/a" if check.status == "not available" else check.status
    return f"{'pass' if check.passed else 'FAIL'} {check.n_inside}/{check.n_used}"


def verification_table(result: CaseResult) -> str:
    """Time-domain RMSE and the envelope status of every sweep pair, for both models."""
    lines = ["Verification",
             "  time domain, identification data: " + ", ".join(
                 f"RMSE {label} {result.time_metrics[label].rmse:.3f}" for label in MODELS)]
    if not result.verification:
        lines.append("  no verification sweeps in the data")
        return "\n".join(lines)
    columns = [(label, env) for label in MODELS for env in ENVELOPES]
    lines.append(f"  {'':<9}" + "".join(f"{label:>30}" for label in MODELS))
    lines.append(f"  {'pair':<9}" + "".join(f"{env.upper():>15}" for _, env in columns))
    for pair in result.case.pairs:
        cells = [_status(result.verification[label][pair].checks[env])
                 for label, env in columns]
        lines.append(f"  {pair:<9}" + "".join(f"{cell:>15}" for cell in cells))
    lines.append("  (points inside the envelope / points with coherence ≥ 0.8; "
                 "n/a: envelope has no breakpoints)")
    return "\n".join(lines)


def print_summary(result: CaseResult) -> None:
    """Everything above, in the order of the paper."""
    condition = result.condition
    variant = " (quick variant)" if result.case.is_quick else ""
    print(f"Case {result.name}{variant}: {result.case.description}; "
          f"trim {condition.describe()}")
    print(f"  {len(result.identification)} identification maneuvers, "
          f"{0 if result.verification_data is None else len(result.verification_data)} "
          f"verification sweeps; " + ", ".join(f"{k} {v:.0f} s"
                                                 for k, v in result.seconds.items()))
    for section in (reduction_table, structure_summary, delay_summary, key_derivative_table,
                    verification_table):
        print()
        print(section(result))


def parse_arguments(argv=None, case: str = "hover") -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=f"The paper's {case} study (rotorid Study).")
    parser.add_argument("out", nargs="?", default=f"results/{case}-example",
                        help="results directory (default: %(default)s)")
    parser.add_argument("--quick", action="store_true",
                        help="reduced but honest run (also: ROTORID_QUICK=1)")
    parser.add_argument("--seed", type=int, default=None, help="sensor-noise seed")
    parser.add_argument("--no-figures", dest="figures", action="store_false",
                        help="skip the figures and the HTML report")
    parser.add_argument("--resume", action="store_true",
                        help="reuse finished reduction steps found in the results directory")
    return parser.parse_args(argv)


def main(argv=None, case: str = "hover") -> CaseResult:
    args = parse_arguments(argv, case)
    flight_case = build_case(case, quick_requested(args.quick), args.seed)
    result = run_study(flight_case, args.out, figures=args.figures, resume=args.resume)
    print_summary(result)
    print(f"\nResults: {os.path.join(args.out, flight_case.name, 'result.json')}")
    if args.figures:
        print(f"Report: {os.path.join(args.out, 'report.html')}")
    return result


if __name__ == "__main__":
    main()
