"""Frequency-domain model verification: the sweep comparison against envelopes.

The verification error of an identified model is the paper's eq. 19,
``ε(jω) = H_model(jω) / H_truth(jω)``: the ratio of the model's response to the truth's,
both estimated from the same sweeps with identical processing (or the model's evaluated
analytically). ``ε`` is held against envelopes (MUAD, AEE, the mismatch cost J), which are
plugins of the ``rotorid_validation_envelopes`` family (contract
:class:`rotorid.plugin.contracts.ValidationEnvelope`; the values they return are in
:mod:`rotorid.verification.envelopes`). :func:`verify_model` runs the whole comparison for an
identified model.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import attrs
import numpy as np

from rotorid.data import INPUT_CHANNELS, OUTPUT_CHANNELS
from rotorid.errors import VerificationError
from rotorid.plugin.contracts import ValidationEnvelope
from rotorid.verification.frequency import (
    FrequencyResponse,
    apparent_response,
    default_windows,
    log_grid,
    lowest_frequency,
    moving_inputs,
    response_from_maneuvers,
)
from rotorid.verification.envelopes import EnvelopeCheck, _finite_or_none, _readonly
from rotorid.verification.metrics import TimeDomainMetrics, time_domain_metrics

#: Default coherence threshold of the checks (the paper's and the project's strict value).
COHERENCE_THRESHOLD = 0.8
#: Model-to-truth output RMS ratio above which a simulated sweep counts as drifting.
DRIFT_RATIO = 10.0
#: Growth of the unstable mode over the longest sweep above which the model's open-loop
#: simulation counts as drifting: it is compared through its apparent response instead
#: (see :func:`verify_model`).
DRIFT_LIMIT = 100.0
#: The paper's verification pairs (figs. 4, 5, 12, 14): ``output/input``.
PAPER_PAIRS = ("q/long", "p/long", "q/lat", "p/lat", "r/coll", "az/coll", "r/ped", "ay/ped")
#: The paper's envelopes on ``ε``: MUAD, the AEE tables and the mismatch cost J.
PAPER_ENVELOPES = ("muad", "aee", "mismatch-cost")


def parse_pair(pair: str) -> tuple[str, str]:
    """``"q/long"`` → ``("q", "long")`` (output, input); the error lists the valid names."""
    parts = str(pair).strip().split("/")
    if (len(parts) != 2 or parts[0] not in OUTPUT_CHANNELS
            or parts[1] not in INPUT_CHANNELS):
        raise VerificationError(
            f"unknown response pair {pair!r}; write OUTPUT/INPUT with OUTPUT one of "
            f"{', '.join(OUTPUT_CHANNELS)} and INPUT one of {', '.join(INPUT_CHANNELS)}, "
            f"e.g. 'q/long'")
    return parts[0], parts[1]


def envelopes_by_name(names: Sequence[str], manager=None, **options
                      ) -> dict[str, ValidationEnvelope]:
    """Build registered envelopes by name (``rotorid plugins --family validation-envelopes``)
    from ``manager`` (default the current plugin manager)."""
    from rotorid.plugin.manager import create

    return {name: create("validation-envelopes", name, manager, **options) for name in names}


# ----------------------------------------------------------------- sweep comparison
class _FrozenMapping(Mapping):
    """A read-only mapping that, unlike ``types.MappingProxyType``, pickles (results travel
    between processes when a study runs on an executor)."""

    def __init__(self, mapping):
        self._items = dict(mapping)

    def __getitem__(self, key):
        return self._items[key]

    def __iter__(self):
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._items!r})"


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
        checks: envelope name → check of ``ε = model/truth`` (the paper's eq. 19), selected
            by the truth's coherence.
        analytic_checks: envelope name → check of ``ε = analytic/conditioned``, selected by
            the partial coherence.
    """

    pair: str
    maneuvers: tuple[str, ...]
    truth: FrequencyResponse
    model: FrequencyResponse
    conditioned: FrequencyResponse | None
    analytic: np.ndarray | None = attrs.field(
        converter=lambda a: None if a is None else _readonly(a, complex))
    checks: Mapping[str, EnvelopeCheck] = attrs.field(converter=_FrozenMapping)
    analytic_checks: Mapping[str, EnvelopeCheck] = attrs.field(converter=_FrozenMapping)
    output_rms_ratio: float = float("nan")
    model_source: str = "simulated"      # or "apparent" (see compare_sweeps)

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

    def input_coherence(self, threshold: float = COHERENCE_THRESHOLD) -> float | None:
        """Median coherence of the pair's input with the conditioning inputs over the points
        where the partial coherence reaches ``threshold``; None if not conditioned.

        Above about 0.5 the conditioned responses are unreliable (Tischler & Remple). The
        median is used because coherence estimated from few averages is biased upwards
        (about 1/n_d for independent inputs), so single points overstate the correlation."""
        if self.conditioned is None or not self.conditioned.conditioned_on:
            return None
        values = self.conditioned.input_coherence
        with np.errstate(invalid="ignore"):
            used = values[self.conditioned.coherence >= threshold]
        used = used[np.isfinite(used)]
        return float(np.median(used)) if used.size else None

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
        return {"notes": list(self.notes), "pairs": [p.summary() for p in self.pairs],
                "average_cost": self.average_cost(),
                "average_cost_analytic": self.average_cost(analytic=True),
                "time_domain": self.time_metrics.summary()}

    def report(self) -> str:
        lines = [f"note: {note}" for note in self.notes]
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
                    lines.append(f"  [{label}] {check.report()}")
        average = self.average_cost()
        if average is not None:
            lines.append(f"J_ave (simulated) = {average:.1f}")
        lines.append(self.time_metrics.report())
        return "\n".join(lines)


def primary_axis(maneuver) -> str:
    """The input axis a sweep excites: ``metadata['axis']``, else the input of largest RMS."""
    axis = maneuver.metadata.get("axis")
    if axis is not None:
        if axis not in INPUT_CHANNELS:
            raise VerificationError(f"maneuver {maneuver.name!r}: metadata axis {axis!r} is "
                                    f"not an input ({', '.join(INPUT_CHANNELS)})")
        return axis
    centred = maneuver.inputs - maneuver.inputs.mean(axis=0)
    return INPUT_CHANNELS[int(np.argmax(np.sqrt(np.mean(centred ** 2, axis=0))))]


def sweep_omega_min(maneuver) -> float | None:
    """The lowest frequency a sweep's signal excites, rad/s, when its metadata records it
    (``omega_min``, or ``signal.omega_min`` as the input-signal plugins write it)."""
    metadata = maneuver.metadata
    signal = metadata.get("signal")
    value = metadata.get("omega_min",
                         signal.get("omega_min") if isinstance(signal, Mapping) else None)
    if value is None:
        return None
    try:
        value = float(value)
    except (TypeError, ValueError):
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        raise VerificationError(f"maneuver {maneuver.name!r}: metadata omega_min must be the "
                                f"sweep's lowest frequency in rad/s (> 0), got "
                                f"{metadata.get('omega_min', value)!r}")
    return value


def default_omega(sweeps, n: int = 200, upper: float = 20.0) -> np.ndarray:
    """Log grid from the lowest frequency the data support to ``upper`` rad/s or a fifth of
    the Nyquist frequency, whichever is lower.

    The lower end is the longest default window's lowest frequency (4π/(T_rec/2)), raised to
    the lowest frequency the sweeps excite where their metadata records it
    (:func:`sweep_omega_min`): below it the inputs' spectra hold only the window's leakage of
    the lowest sweep frequency, not excitation at the nominal one.
    """
    shortest = min(m.duration for m in sweeps)
    dt = max(m.dt for m in sweeps)
    low = lowest_frequency(default_windows(shortest)[0])
    excited = [w for w in (sweep_omega_min(m) for m in sweeps) if w is not None]
    if excited:
        low = max(low, min(excited))
    return log_grid(low, min(upper, 0.2 * np.pi / dt), n)


def compare_sweeps(sweeps, model_outputs: Sequence[np.ndarray],
                   pairs: Sequence[str] = PAPER_PAIRS,
                   envelopes: Mapping[str, ValidationEnvelope] | None = None, *,
                   analytic=None, omega=None, windows=None,
                   conditioning: str | Sequence[str] = "auto",
                   model_response: str = "simulated") -> VerificationResult:
    """Compare a model's simulated sweeps with the recorded ones, pair by pair.

    Args:
        sweeps: :class:`~rotorid.data.ManeuverSet` of verification sweeps (truth outputs).
        model_outputs: the model's outputs for the same inputs, one (N_i, 8) array per sweep.
        pairs: ``output/input`` names; each uses the sweeps whose axis is its input.
        envelopes: name → envelope; default MUAD, AEE and mismatch cost from the plugins.
        analytic: optional callable ``omega -> (M, 8, 4)`` complex model response.
        omega: frequency grid in rad/s; default :func:`default_omega` of the sweeps.
        windows: window lengths in s; default from the shortest sweep.
        conditioning: inputs the truth's response is conditioned on for the analytic
            comparison: ``"auto"`` (every other input that moved, see
            :func:`rotorid.verification.frequency.moving_inputs`), ``"none"``, or explicit input names.
        model_response: ``"simulated"``: the model's single-input response is estimated from
            ``model_outputs``; ``"apparent"``: it is formed from the analytic responses and
            the recorded inputs' cross-spectra (:func:`rotorid.verification.frequency.apparent_response`;
            needs ``analytic``), for models whose simulation drifts.

    Both comparisons use single-input responses of truth and model: the model is driven by
    every recorded input, so the other inputs affect both sides alike.
    """
    if model_response not in ("simulated", "apparent"):
        raise VerificationError(f"model_response must be 'simulated' or 'apparent', got "
                                f"{model_response!r}")
    if model_response == "apparent" and analytic is None:
        raise VerificationError("model_response='apparent' needs the analytic model response "
                                "(analytic=lambda omega: frequency_response(...))")
    parsed = [(name, *parse_pair(name)) for name in pairs]
    if not parsed:
        raise VerificationError("no response pairs given; e.g. pairs=['q/long', 'p/long']")
    if envelopes is None:
        envelopes = envelopes_by_name(PAPER_ENVELOPES)
    if len(model_outputs) != len(sweeps):
        raise VerificationError(f"{len(model_outputs)} model output arrays for {len(sweeps)} "
                                f"sweeps; simulate every sweep")
    axes = [primary_axis(m) for m in sweeps]
    omega = default_omega(sweeps) if omega is None else np.asarray(omega, dtype=float)
    full = None if analytic is None else analytic(omega)
    results = []
    for name, output, control in parsed:
        chosen = [i for i, axis in enumerate(axes) if axis == control]
        if not chosen:
            raise VerificationError(f"pair {name}: no sweep excites {control!r}; the sweeps "
                                    f"excite {', '.join(sorted(set(axes)))}")
        subset = sweeps.select(lambda m, names={sweeps[i].name for i in chosen}:
                               m.name in names)
        if isinstance(conditioning, str) and conditioning == "auto":
            others = moving_inputs(subset, control)
        elif isinstance(conditioning, str) and conditioning == "none":
            others = ()
        else:
            others = tuple(c for c in conditioning if c != control)
        if model_response == "apparent":
            model, truth = apparent_response(subset, control, output, omega,
                                             full[:, OUTPUT_CHANNELS.index(output)],
                                             windows=windows)
        else:
            truth = response_from_maneuvers(subset, control, output, omega, windows=windows)
            model = response_from_maneuvers(subset, control, output, omega, windows=windows,
                                            outputs=[model_outputs[i] for i in chosen])
        with np.errstate(divide="ignore", invalid="ignore"):
            error = model.response / truth.response
            checks = {n: e.check(error, truth.coherence, omega) for n, e in envelopes.items()}
        conditioned, analytic_pair, analytic_checks = None, None, {}
        if full is not None:
            conditioned = truth if not others else response_from_maneuvers(
                subset, control, output, omega, windows=windows, conditioned_on=others)
            analytic_pair = full[:, OUTPUT_CHANNELS.index(output), INPUT_CHANNELS.index(control)]
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = analytic_pair / conditioned.response
                analytic_checks = {n: e.check(ratio, conditioned.coherence, omega)
                                   for n, e in envelopes.items()}
        ratio = _rms_ratio([model_outputs[i] for i in chosen], [sweeps[i] for i in chosen],
                           OUTPUT_CHANNELS.index(output))
        results.append(PairVerification(name, subset.names, truth, model, conditioned,
                                        analytic_pair, checks, analytic_checks, ratio,
                                        model_response))
    notes = [f"{p.pair}: the model's {p.pair.split('/')[0]} has {p.output_rms_ratio:.3g} times "
             f"the truth's RMS on these sweeps; its open-loop simulation drifts (unstable "
             f"model?), so the simulated comparison of this pair is not meaningful"
             for p in results
             if model_response == "simulated" and p.output_rms_ratio > DRIFT_RATIO]
    return VerificationResult(results, time_domain_metrics(sweeps, model_outputs), notes)


def _rms_ratio(model_outputs, maneuvers, column: int) -> float:
    """RMS of the model's output over RMS of the recorded one (means removed)."""
    def rms(arrays):
        centred = [a - a.mean() for a in arrays]
        return float(np.sqrt(np.mean(np.concatenate(centred) ** 2)))

    truth = rms([m.outputs[:, column] for m in maneuvers])
    model = rms([np.asarray(y)[:, column] for y in model_outputs])
    return model / truth if truth > 0 else float("inf")


def verify_model(structure, values, sweeps, pairs: Sequence[str] = PAPER_PAIRS,
                 envelopes: Mapping[str, ValidationEnvelope] | Sequence[str] | None = None,
                 segment: float | None = None, manager=None, **options) -> VerificationResult:
    """Verify an identified model on sweeps not used for identification.

    Simulates ``structure`` at ``values`` (vector, name→value mapping or None) on the
    recorded inputs of every sweep (:func:`rotorid.simulation.simulator.simulate`, with the sweeps'
    input hold), estimates truth and model responses with identical processing and holds
    ``ε = H_model/H_truth`` against the envelopes; also compares the analytic response with
    exact delays (:func:`rotorid.simulation.transfer.frequency_response`) with the truth's conditioned
    response. ``envelopes`` may be envelope objects by name or registered envelope names.

    An unstable model (the hover phugoid is unstable) cannot follow a long sweep open loop
    when its unstable mode grows more than :data:`DRIFT_LIMIT`-fold over the longest sweep
    (σ·T > ln 100 for the largest unstable real part σ): its simulation drifts away from the
    data. For such a model the frequency comparison uses its *apparent* response instead
    (:func:`rotorid.verification.frequency.apparent_response`: the analytic responses combined through the
    recorded inputs' cross-spectra, which is what a single-input estimate from its simulation
    would give if it did not drift), and the time-domain metrics come from a simulation in
    segments of 2/σ s (at least 5 s) restarted from the data (:func:`segmented_simulation`).
    A slower instability is simulated in one piece. ``segment`` given explicitly simulates in
    segments of that length and uses the simulated comparison. The result's notes say which
    was done. Envelope names are built from ``manager`` (default the current plugin
    manager). Other keyword options go to :func:`compare_sweeps`.
    """
    from rotorid.simulation.simulator import simulate
    from rotorid.simulation.transfer import frequency_response

    if envelopes is not None and not isinstance(envelopes, Mapping):
        envelopes = envelopes_by_name(tuple(envelopes), manager)
    eigenvalues = np.linalg.eigvals(structure.matrices(values)[0])
    growth = float(np.max(eigenvalues.real))
    longest = max(m.duration for m in sweeps)
    notes = _stability_notes(eigenvalues, growth * longest)
    drifts = growth * longest > math.log(DRIFT_LIMIT)
    comparison = "apparent" if drifts and segment is None else "simulated"
    if segment is None and drifts:
        segment = max(5.0, 2.0 / growth)
        notes.append(f"the model's unstable mode grows e^{growth * longest:.0f}-fold over the "
                     f"longest sweep: frequency responses compared through its apparent "
                     f"response (analytic responses and the recorded inputs' cross-spectra); "
                     f"time-domain metrics from segments of {segment:.1f} s restarted from "
                     f"the measured and reconstructed state")
    elif segment is not None:
        notes.append(f"the model was simulated in segments of {segment:.1f} s, each restarted "
                     f"from the measured and reconstructed state")
    outputs = (simulate(structure, values, sweeps) if segment is None
               else segmented_simulation(structure, values, sweeps, segment))
    result = compare_sweeps(
        sweeps, outputs, pairs, envelopes,
        analytic=lambda omega: frequency_response(structure, values, omega),
        model_response=comparison, **options)
    return attrs.evolve(result, notes=[*notes, *result.notes])


def segmented_simulation(structure, values, maneuvers, segment: float) -> list[np.ndarray]:
    """Outputs simulated in segments restarted from the data's state.

    Each maneuver is cut into segments of ``segment`` s (a remainder shorter than two samples
    joins the segment before it). A segment is simulated from the state at its start:
    measured q θ p φ r and u v w integrated from the measured specific forces
    (:func:`rotorid.estimation.equation_error.reconstructed_states`), and the segments are joined.
    Delayed terms see trim before each restart, and the reconstructed velocities carry
    integration error, so the restarts are approximate: on noise-free data of the model
    itself they reproduce its plain simulation to a few per cent (tested).
    Returns one (N_i, 8) array per maneuver.
    """
    from rotorid.data import Maneuver, ManeuverSet
    from rotorid.estimation.equation_error import reconstructed_states
    from rotorid.simulation.simulator import simulate

    if not segment > 0:
        raise VerificationError(f"segment must be a positive duration in s, got {segment!r}")
    pieces, counts = [], []              # counts: the number of pieces of each maneuver
    for m in maneuvers:
        states = reconstructed_states(structure, m)
        step = max(2, int(round(segment / m.dt)))
        starts = list(range(0, m.n_samples, step))
        if len(starts) > 1 and m.n_samples - starts[-1] < 2:
            starts.pop()
        for first, stop in zip(starts, starts[1:] + [m.n_samples]):
            pieces.append(Maneuver(f"{m.name}#{first}", m.time[first:stop],
                                   m.inputs[first:stop], m.outputs[first:stop],
                                   units=m.units, initial_state=states[first]))
        counts.append(len(starts))
    simulated = iter(simulate(structure, values, ManeuverSet(pieces, hold=maneuvers.hold)))
    return [np.concatenate([next(simulated) for _ in range(count)]) for count in counts]


def _stability_notes(eigenvalues: np.ndarray, growth_over_sweep: float) -> list[str]:
    """A note listing the unstable eigenvalues of A (delays set to zero), if any, and how
    much their mode grows over the longest sweep (``growth_over_sweep`` = σ·T)."""
    unstable = eigenvalues[eigenvalues.real > 1e-9]
    if not unstable.size:
        return []
    shown = ", ".join(f"{v.real:.3g}{v.imag:+.3g}j" for v in unstable if v.imag >= 0)
    return [f"the model is unstable (eigenvalues {shown} 1/s, delays ignored): its open-loop "
            f"response grows e^{growth_over_sweep:.1f}-fold over the longest sweep"]
