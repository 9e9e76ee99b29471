"""Frequency-domain comparison of a model's sweeps with the recorded ones, against envelopes.

The verification error of an identified model is the paper's eq. 19,
``ε(jω) = H_model(jω) / H_truth(jω)``: the ratio of the model's response to the truth's,
both estimated from the same sweeps with identical processing (or the model's evaluated
analytically). ``ε`` is held against envelopes (MUAD, AEE, the mismatch cost J), which are
plugins of the ``rotorid_validation_envelopes`` family (contract
:class:`rotorid.plugin.contracts.ValidationEnvelope`; the values they return are in
:mod:`rotorid.verification.envelopes`). :func:`compare_sweeps` compares given model outputs;
:func:`rotorid.verification.verify.verify_model` simulates an identified model and compares it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import VerificationError
from rotorid.frozen import FrozenMapping, readonly_array
from rotorid.plugin.contracts import ValidationEnvelope
from rotorid.plugin.manager import create
from rotorid.plugin.returns import returned
from rotorid.verification.band import DEFAULT_BAND, VerificationBand
from rotorid.verification.envelopes import (
    MISMATCH_COST_GUIDELINE,
    MISMATCH_COST_GUIDELINE_TEXT,
    EnvelopeCheck,
    _finite_or_none,
)
from rotorid.verification.frequency import (
    FrequencyResponse,
    apparent_response,
    default_windows,
    influential_inputs,
    log_grid,
    lowest_frequency,
    moving_inputs,
    response_from_maneuvers,
)
from rotorid.verification.metrics import TimeDomainMetrics, time_domain_metrics
from rotorid.verification.pairs import (default_pairs, lowest_swept_frequency, parse_pair,
                                        sweeps_exciting)

#: Coherence of a pair's input with the conditioning inputs above which its conditioned
#: response is unreliable (Tischler & Remple): the analytic comparison skips such points.
INPUT_COHERENCE_LIMIT = 0.5
#: Model-to-truth output RMS ratio above which a simulated sweep counts as drifting.
DRIFT_RATIO = 10.0
#: The paper's envelopes on ``ε``: MUAD, the AEE tables and the mismatch cost J.
PAPER_ENVELOPES = ("muad", "aee", "mismatch-cost")
#: How the model's single-input response is formed (see :func:`compare_sweeps`).
MODEL_RESPONSES = ("simulated", "apparent")


def envelopes_by_name(names: Sequence[str], manager=None,
                      band: VerificationBand = DEFAULT_BAND) -> dict[str, ValidationEnvelope]:
    """Build registered envelopes by name (``rotorid plugins --family validation-envelopes``)
    from ``manager`` (default the current plugin manager), each counting the points of
    ``band`` (its factory receives ``threshold=band.coherence``)."""
    return {name: create("validation-envelopes", name, manager, threshold=band.coherence)
            for name in names}


def check_envelope_thresholds(envelopes: Mapping[str, ValidationEnvelope],
                              band: VerificationBand) -> None:
    """Refuse envelopes whose coherence threshold is not the band's: every verdict counts the
    same points."""
    for name, envelope in envelopes.items():
        if envelope.threshold != band.coherence:
            raise VerificationError(
                f"envelope {name!r} counts points with γ² ≥ {envelope.threshold:g} but the "
                f"verification band is {band.describe()}: build it with "
                f"threshold={band.coherence:g}, or pass a band with coherence="
                f"{envelope.threshold:g}")


# ----------------------------------------------------------------- results
@attrs.frozen(eq=False)
class PairVerification:
    """Verification of one ``output/input`` pair on the sweeps of its input axis.

    Attributes:
        pair: ``"q/long"`` style name.
        maneuvers: names of the sweeps pooled for this pair.
        truth: single-input response estimated from the recorded (truth) outputs.
        model: single-input response estimated from the model's simulation of the same
            recorded inputs, processed identically (same grid and windows), or the model's
            apparent response (``model_source``). Both include the effect of the other
            inputs that moved, alike, so no conditioning is needed.
        conditioned: the truth's response conditioned on the other inputs that moved (the
            conditioned response the analytic model response is compared with), or None.
        analytic: the model's analytic response (exact delays) on the grid, shape (M,), or
            None when not evaluated.
        checks: envelope name → check of ``ε = model/truth`` (the paper's eq. 19) on the
            points of ``band`` by the truth's coherence.
        analytic_checks: envelope name → check of ``ε = analytic/conditioned`` on the points
            of ``band`` by the partial coherence, where the input's coherence with the
            conditioning inputs is at most :data:`INPUT_COHERENCE_LIMIT`.
        band: the verification band every check of the pair counts points in.
    """

    pair: str
    maneuvers: tuple[str, ...]
    truth: FrequencyResponse
    model: FrequencyResponse
    conditioned: FrequencyResponse | None
    analytic: np.ndarray | None = attrs.field(
        converter=lambda a: None if a is None else readonly_array(a, complex))
    checks: Mapping[str, EnvelopeCheck] = attrs.field(converter=FrozenMapping)
    analytic_checks: Mapping[str, EnvelopeCheck] = attrs.field(converter=FrozenMapping)
    output_rms_ratio: float = float("nan")
    model_source: str = "simulated"      # or "apparent" (see compare_sweeps)
    band: VerificationBand = DEFAULT_BAND

    @property
    def omega(self) -> np.ndarray:
        return self.truth.omega

    @property
    def coherence(self) -> np.ndarray:
        """Coherence of the truth's single-input estimate, shape (M,)."""
        return self.truth.coherence

    @property
    def analytic_coherence(self) -> np.ndarray | None:
        """Partial coherence of the truth's conditioned estimate, shape (M,), or None."""
        return None if self.conditioned is None else self.conditioned.coherence

    @property
    def error(self) -> np.ndarray:
        """``ε = H_model/H_truth`` from the simulated sweeps, complex, shape (M,)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.model.response / self.truth.response

    @property
    def analytic_error(self) -> np.ndarray | None:
        """``ε = H_analytic/H_truth,conditioned``, complex, shape (M,), or None."""
        if self.analytic is None or self.conditioned is None:
            return None
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.analytic / self.conditioned.response

    @property
    def checked(self) -> np.ndarray:
        """Points of the band by the truth's coherence (the simulated checks'), shape (M,)."""
        return self.band.selects(self.omega, self.coherence)

    def input_coherence(self) -> float | None:
        """Median coherence of the pair's input with the conditioning inputs over the band's
        points by the partial coherence; None if not conditioned.

        Above about 0.5 the conditioned responses are unreliable (Tischler & Remple). The
        median is used because coherence estimated from few averages is biased upwards
        (about 1/n_d for independent inputs), so single points overstate the correlation."""
        if self.conditioned is None or not self.conditioned.conditioned_on:
            return None
        values = self.conditioned.input_coherence
        used = values[self.band.selects(self.omega, self.conditioned.coherence)]
        used = used[np.isfinite(used)]
        return float(np.median(used)) if used.size else None

    def checked_in(self, band: VerificationBand,
                   envelopes: Mapping[str, ValidationEnvelope]) -> "PairVerification":
        """The same responses checked against ``envelopes`` on the points of ``band``
        instead (nothing is estimated again)."""
        analytic_checks = ({} if self.analytic is None else
                           _envelope_checks(self.analytic, _reliable(self.conditioned),
                                            band, envelopes))
        return attrs.evolve(self, checks=_envelope_checks(self.model.response, self.truth,
                                                          band, envelopes),
                            analytic_checks=analytic_checks, band=band)

    def summary(self) -> dict:
        return {
            "pair": self.pair, "maneuvers": list(self.maneuvers),
            "conditioned_on": [] if self.conditioned is None else list(
                self.conditioned.conditioned_on),
            "input_coherence": self.input_coherence(),
            "output_rms_ratio": _finite_or_none(self.output_rms_ratio),
            "model_source": self.model_source,
            "windows_s": list(self.truth.windows),
            "omega_range_rad_s": [float(self.omega.min()), float(self.omega.max())],
            "band": self.band.as_dict(),
            "checks": {n: c.summary() for n, c in self.checks.items()},
            "analytic_checks": {n: c.summary() for n, c in self.analytic_checks.items()},
        }


@attrs.frozen(eq=False)
class VerificationResult:
    """Frequency-domain verification of one model on a set of sweeps, plus time metrics."""

    pairs: tuple[PairVerification, ...] = attrs.field(converter=tuple)
    time_metrics: TimeDomainMetrics
    notes: tuple[str, ...] = attrs.field(default=(), converter=tuple)

    def __getitem__(self, pair: str) -> PairVerification:
        item = self.get(pair)
        if item is None:
            raise VerificationError(f"pair {pair!r} was not verified; verified pairs: "
                                    f"{', '.join(p.pair for p in self.pairs)}")
        return item

    def get(self, pair: str) -> PairVerification | None:
        """The verification of ``pair``, or ``None`` when it was not verified."""
        return next((item for item in self.pairs if item.pair == pair), None)

    def checked_in(self, band: VerificationBand,
                   envelopes: Mapping[str, ValidationEnvelope]) -> "VerificationResult":
        """Every pair's responses checked against ``envelopes`` (counting γ² ≥
        ``band.coherence``) on the points of ``band`` instead
        (:meth:`PairVerification.checked_in`)."""
        check_envelope_thresholds(envelopes, band)
        return attrs.evolve(self, pairs=[p.checked_in(band, envelopes) for p in self.pairs])

    @property
    def band(self) -> VerificationBand:
        """The verification band of every pair (one comparison shares one band)."""
        return self.pairs[0].band if self.pairs else DEFAULT_BAND

    def average_cost(self, envelope: str = "mismatch-cost", analytic: bool = False
                     ) -> float | None:
        """``J_ave`` over the pairs that have a cost for ``envelope``; None if none has."""
        costs = [(p.analytic_checks if analytic else p.checks)[envelope].cost
                 for p in self.pairs
                 if envelope in (p.analytic_checks if analytic else p.checks)]
        costs = [c for c in costs if c is not None]
        return float(np.mean(costs)) if costs else None

    def summary(self) -> dict:
        """JSON-ready summary of every check and the time-domain metrics."""
        return {"notes": list(self.notes), "band": self.band.as_dict(),
                "pairs": [p.summary() for p in self.pairs],
                "average_cost": self.average_cost(),
                "average_cost_analytic": self.average_cost(analytic=True),
                "cost_guideline": MISMATCH_COST_GUIDELINE,
                "time_domain": self.time_metrics.summary()}

    def report(self) -> str:
        lines = [f"note: {note}" for note in self.notes]
        lines.append(f"verification band (every check): {self.band.describe()}")
        every = [c for p in self.pairs for checks in (p.checks, p.analytic_checks)
                 for c in checks.values()]
        absent = {c.envelope for c in every} - {c.envelope for c in every
                                                if c.status != "not available"}
        for name in sorted(absent):            # said once, not on every pair
            lines.append(next(c for c in every if c.envelope == name).report().replace(
                "not available, no point checked", "not available on any pair, no point checked"))
        for p in self.pairs:
            correlation = p.input_coherence()
            note = "" if correlation is None else (
                f", median input coherence with them {correlation:.2f}"
                + (" — too correlated, conditioned responses unreliable"
                   if correlation > 0.5 else ""))
            others = () if p.conditioned is None else p.conditioned.conditioned_on
            lines.append(f"{p.pair} ({len(p.maneuvers)} sweep(s); analytic comparison "
                         f"conditioned on {', '.join(others) or 'nothing'}{note})")
            for label, checks in (("simulated", p.checks), ("analytic", p.analytic_checks)):
                for check in checks.values():
                    if check.envelope not in absent:
                        lines.append(f"  [{label}] {check.report()}")
        average = self.average_cost()
        if average is not None:
            lines.append(f"J_ave (simulated) = {average:.1f}; guideline "
                         f"{MISMATCH_COST_GUIDELINE_TEXT}")
        lines.append(self.time_metrics.report())
        return "\n".join(lines)


def sweep_frequency(maneuver, bound: str = "omega_min") -> float | None:
    """The lowest (``bound = "omega_min"``) or highest (``"omega_max"``) frequency a sweep's
    signal excites, rad/s, when its metadata records it (under ``bound``, or
    ``signal.<bound>`` as the input-signal plugins write it)."""
    metadata = maneuver.metadata
    signal = metadata.get("signal")
    value = metadata.get(bound, signal.get(bound) if isinstance(signal, Mapping) else None)
    if value is None:
        return None
    try:
        value = float(value)
    except (TypeError, ValueError):
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        extreme = "lowest" if bound == "omega_min" else "highest"
        raise VerificationError(f"maneuver {maneuver.name!r}: metadata {bound} must be the "
                                f"sweep's {extreme} frequency in rad/s (> 0), got "
                                f"{metadata.get(bound, value)!r}")
    return value


def default_omega(sweeps, n: int = 200, upper: float = 20.0) -> np.ndarray:
    """Log grid from the lowest frequency the data support to ``upper`` rad/s (or the highest
    the sweeps excite where their metadata records it and that is higher), at most a fifth of
    the Nyquist frequency.

    The lower end is the longest default window's lowest frequency (4π/(T_rec/2)), raised to
    the lowest frequency the sweeps excite: recorded in their metadata
    (:func:`sweep_frequency`), else read from the input's slowest half cycle
    (:func:`rotorid.verification.pairs.lowest_swept_frequency`). Below it the inputs'
    spectra hold only the window's leakage of the lowest sweep frequency, not excitation at
    the nominal one.
    """
    shortest = min(m.duration for m in sweeps)
    dt = max(m.dt for m in sweeps)
    low = lowest_frequency(default_windows(shortest)[0])
    excited = [w for w in (sweep_frequency(m) or lowest_swept_frequency(m) for m in sweeps)
               if w is not None]
    if excited:
        low = max(low, min(excited))
    tops = [sweep_frequency(m, "omega_max") for m in sweeps]
    if all(top is not None for top in tops):
        upper = max(upper, min(tops))
    return log_grid(low, min(upper, 0.2 * np.pi / dt), n)


def compare_sweeps(sweeps, model_outputs: Sequence[np.ndarray],
                   pairs: Sequence[str] | None = None,
                   envelopes: Mapping[str, ValidationEnvelope] | None = None, *,
                   analytic=None, omega=None, windows=None,
                   conditioning: str | Sequence[str] = "auto",
                   model_response: str = "simulated",
                   on_pair: Callable[[PairVerification], None] | None = None,
                   band: VerificationBand = DEFAULT_BAND,
                   output_names: Sequence[str] | None = None,
                   input_names: Sequence[str] | None = None,
                   output_units: Sequence[str] = ()) -> VerificationResult:
    """Compare a model's simulated sweeps with the recorded ones, pair by pair.

    Args:
        sweeps: :class:`~rotorid.data.ManeuverSet` of verification sweeps (truth outputs).
        model_outputs: the model's outputs for the same inputs, one (N_i, ny) array per sweep,
            columns ``output_names``.
        pairs: ``output/input`` names of the model's outputs and inputs; each uses the sweeps
            whose axis is its input; default :func:`~rotorid.verification.pairs.default_pairs`.
        envelopes: name → envelope; default MUAD, AEE and mismatch cost from the plugins,
            built for ``band``; given envelopes must count γ² ≥ ``band.coherence``.
        analytic: optional callable ``omega -> (M, ny, m)`` complex model response (outputs
            ``output_names``, inputs ``input_names``).
        omega: frequency grid in rad/s; default :func:`default_omega` of the sweeps.
        windows: window lengths in s; default from the shortest sweep.
        conditioning: inputs the truth's response is conditioned on for the analytic
            comparison: ``"auto"`` (every other input that moved,
            :func:`rotorid.verification.frequency.moving_inputs`, or that the model says drives
            the output, :func:`rotorid.verification.frequency.influential_inputs`, over the
            band's range), ``"none"``, or explicit input names.
        model_response: ``"simulated"``: the model's single-input response is estimated from
            ``model_outputs``; ``"apparent"``: it is formed from the analytic responses and
            the recorded inputs' cross-spectra (:func:`rotorid.verification.frequency.apparent_response`;
            needs ``analytic``), for models whose simulation drifts.
        on_pair: called with each pair's verification as it is done (progress).
        band: the verification band: every check, simulated and analytic, counts only the
            points in its frequency range whose coherence reaches its threshold.
        output_names, input_names: the model's outputs and inputs (e.g. a structure's
            ``outputs`` and ``controls``); default the sweeps' own.
        output_units: the outputs' units (a structure's ``signals.outputs.units``): the
            time-domain RMSE and J_rms then count residuals in reference units
            (:func:`~rotorid.verification.metrics.time_domain_metrics`).

    Both comparisons use single-input responses of truth and model: the model is driven by
    every recorded input, so the other inputs affect both sides alike.
    """
    _check_model_response(model_response, analytic)
    output_names = tuple(sweeps.output_names if output_names is None else output_names)
    input_names = tuple(sweeps.input_names if input_names is None else input_names)
    names = list(default_pairs(output_names, input_names) if pairs is None else pairs)
    for name in names:
        parse_pair(name, output_names, input_names)   # every name checked before any work
    if not names:
        raise VerificationError("no response pairs given; e.g. pairs=['q/long', 'p/long']")
    if envelopes is None:
        envelopes = envelopes_by_name(PAPER_ENVELOPES, band=band)
    check_envelope_thresholds(envelopes, band)
    if len(model_outputs) != len(sweeps):
        raise VerificationError(f"{len(model_outputs)} model output arrays for {len(sweeps)} "
                                f"sweeps; simulate every sweep")
    omega = (default_omega(sweeps, upper=max(20.0, band.omega_max)) if omega is None
             else np.asarray(omega, dtype=float))
    comparison = _SweepComparison(
        sweeps, dict(zip(sweeps.names, model_outputs)), output_names, input_names, omega,
        None if analytic is None else analytic(omega), envelopes, windows, conditioning,
        model_response, band)
    results = []
    for name in names:
        results.append(comparison.pair(name))
        if on_pair is not None:
            on_pair(results[-1])
    return VerificationResult(results,
                              time_domain_metrics(sweeps, model_outputs, outputs=output_names,
                                                  units=output_units),
                              _drift_notes(results))


def _check_model_response(model_response: str, analytic) -> None:
    if model_response not in MODEL_RESPONSES:
        raise VerificationError(f"model_response must be 'simulated' or 'apparent', got "
                                f"{model_response!r}")
    if model_response == "apparent" and analytic is None:
        raise VerificationError("model_response='apparent' needs the analytic model response "
                                "(analytic=lambda omega: frequency_response(...))")


@attrs.frozen(eq=False)
class _SweepComparison:
    """What every pair of one :func:`compare_sweeps` call shares: the sweeps, the model's
    outputs on them (sweep name → (N_i, ny) array), the model's output and input names, the
    grid ω (M,), the analytic response (M, ny, m) or None, the envelopes, the processing
    options and the verification band."""

    sweeps: ManeuverSet
    model_outputs: Mapping[str, np.ndarray]
    output_names: tuple[str, ...]
    input_names: tuple[str, ...]
    omega: np.ndarray
    analytic: np.ndarray | None
    envelopes: Mapping[str, ValidationEnvelope]
    windows: object
    conditioning: str | Sequence[str]
    model_response: str
    band: VerificationBand

    def pair(self, name: str) -> PairVerification:
        """The verification of pair ``name`` (``output/input``) on the sweeps of its input."""
        output, control = parse_pair(name, self.output_names, self.input_names)
        subset = sweeps_exciting(self.sweeps, control, name)
        outputs = [self.model_outputs[m.name] for m in subset]
        model, truth = self._responses(subset, outputs, output, control)
        checks = _envelope_checks(model.response, truth, self.band, self.envelopes)
        conditioned, analytic, analytic_checks = self._analytic_comparison(
            subset, output, control, truth)
        column = self.output_names.index(output)
        ratio = _rms_ratio([y[:, column] for y in outputs], [m.channel(output) for m in subset])
        return PairVerification(name, subset.names, truth, model, conditioned, analytic,
                                checks, analytic_checks, ratio, self.model_response, self.band)

    def _responses(self, subset, outputs: list[np.ndarray], output: str, control: str
                   ) -> tuple[FrequencyResponse, FrequencyResponse]:
        """The model's and the truth's single-input responses of the pair; ``outputs`` are the
        model's on the ``subset`` of sweeps."""
        if self.model_response == "apparent":
            return apparent_response(subset, control, output, self.omega,
                                     self.analytic[:, self.output_names.index(output)],
                                     input_names=self.input_names, windows=self.windows)
        truth = response_from_maneuvers(subset, control, output, self.omega,
                                        windows=self.windows)
        model = response_from_maneuvers(subset, control, output, self.omega,
                                        windows=self.windows, outputs=outputs,
                                        output_names=self.output_names)
        return model, truth

    def _analytic_comparison(self, subset, output: str, control: str,
                             truth: FrequencyResponse):
        """The truth's conditioned response, the model's analytic response of the pair and
        their checks; ``(None, None, {})`` without an analytic response."""
        if self.analytic is None:
            return None, None, {}
        others = self._conditioning_inputs(subset, output, control)
        conditioned = truth if not others else response_from_maneuvers(
            subset, control, output, self.omega, windows=self.windows, conditioned_on=others)
        analytic = self.analytic[:, self.output_names.index(output),
                                 self.input_names.index(control)]
        return conditioned, analytic, _envelope_checks(analytic, _reliable(conditioned),
                                                       self.band, self.envelopes)

    def _conditioning_inputs(self, subset, output: str, control: str) -> tuple[str, ...]:
        if isinstance(self.conditioning, str) and self.conditioning == "auto":
            inside = (self.omega >= self.band.omega_min) & (self.omega <= self.band.omega_max)
            chosen = set(moving_inputs(subset, control)) | set(influential_inputs(
                subset, control, self.omega[inside],
                self.analytic[inside, self.output_names.index(output)], self.input_names))
            return tuple(n for n in subset.input_names if n in chosen)
        if isinstance(self.conditioning, str) and self.conditioning == "none":
            return ()
        return tuple(c for c in self.conditioning if c != control)


def _envelope_checks(response: np.ndarray, reference: FrequencyResponse,
                     band: VerificationBand, envelopes: Mapping[str, ValidationEnvelope]
                     ) -> dict[str, EnvelopeCheck]:
    """Every envelope's check of ``ε = response / reference`` (both on ``reference.omega``)
    on ``band``'s points by the reference's coherence (NaN outside the band's range)."""
    omega = reference.omega
    coherence = band.restrict(omega, reference.coherence)
    with np.errstate(divide="ignore", invalid="ignore"):
        error = response / reference.response
        return {n: returned(e.check(error, coherence, omega), EnvelopeCheck,
                            f"validation envelope {n!r}: check") for n, e in envelopes.items()}


def _reliable(conditioned: FrequencyResponse) -> FrequencyResponse:
    """``conditioned`` with zero coherence where its input is more than
    :data:`INPUT_COHERENCE_LIMIT` coherent with the conditioning inputs, so no check uses those
    points. Sweeps flown with stabilising loops make the other inputs nearly coherent with the
    swept one (0.93–1.00 at 70 kt over 1–10 rad/s); there conditioning does not even recover a
    noise-free linear model's own response from its simulation (docs/verification.md)."""
    if conditioned.input_coherence is None:
        return conditioned
    with np.errstate(invalid="ignore"):
        correlated = ~(conditioned.input_coherence <= INPUT_COHERENCE_LIMIT)
    return attrs.evolve(conditioned, coherence=np.where(correlated, 0.0,
                                                        conditioned.coherence))


def _drift_notes(results: Sequence[PairVerification]) -> list[str]:
    """A note for each simulated pair whose model output drifts (RMS ratio > DRIFT_RATIO)."""
    return [f"{p.pair}: the model's {p.pair.split('/')[0]} has {p.output_rms_ratio:.3g} times "
            f"the measured RMS on these sweeps; its open-loop simulation drifts (unstable "
            f"model?), so the simulated comparison of this pair is not meaningful"
            for p in results
            if p.model_source == "simulated" and p.output_rms_ratio > DRIFT_RATIO]


def _rms_ratio(model_outputs: Sequence[np.ndarray], measured: Sequence[np.ndarray]) -> float:
    """RMS of the model's output over RMS of the recorded one (means removed), each given as
    one (N_i,) array per sweep."""
    def rms(arrays):
        centred = [a - a.mean() for a in arrays]
        return float(np.sqrt(np.mean(np.concatenate(centred) ** 2)))

    truth = rms([np.asarray(z, dtype=float) for z in measured])
    model = rms([np.asarray(y, dtype=float) for y in model_outputs])
    return model / truth if truth > 0 else float("inf")
