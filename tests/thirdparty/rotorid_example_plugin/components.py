"""The components; each follows its contract in docs/plugins.md."""

from __future__ import annotations

import attrs
import numpy as np
import rotorid
from rotorid.verification.envelopes import error_db_deg, status_of, validate_check_inputs

#: The model the source flies (flight-test units, hover).
TRUTH = {"M_q": -3.0, "M_long": 0.8, "L_p": -6.0, "L_lat": 2.5}
#: Output noise, one standard deviation per output (ax az q θ ay p φ r).
NOISE = np.array([0.02, 0.02, 0.05, 0.02, 0.02, 0.05, 0.02, 0.05])
DT = 0.02
SETTINGS = {"seed", "duration", "sweep_duration"}


@attrs.frozen
class SimulatedSource:
    """Doublets (identification) and chirps (verification) on long and lat stick, flown on
    :data:`TRUTH` with output noise. Settings: ``seed``, ``duration`` and ``sweep_duration``
    (s)."""

    def case_data(self, settings, directory) -> rotorid.CaseData:
        unknown = set(settings) - SETTINGS
        if unknown:
            raise rotorid.DataError(f"example-simulated: unknown settings {sorted(unknown)}; "
                                    f"known: {sorted(SETTINGS)}")
        condition = rotorid.FlightCondition.from_airspeed(0.0)
        structure = rotorid.ModelStructure(condition,
                                           [rotorid.Derivative(n) for n in TRUTH])
        rng = np.random.default_rng(int(settings.get("seed", 0)))
        doublets = [self._maneuver(f"doublet_{axis}", _doublet(settings.get("duration", 12.0)),
                                   axis, "doublet") for axis in ("long", "lat")]
        chirps = [self._maneuver(f"chirp_{axis}", _chirp(settings.get("sweep_duration", 40.0)),
                                 axis, "sweep") for axis in ("long", "lat")]

        def flown(maneuvers):
            blank = rotorid.ManeuverSet(maneuvers)
            outputs = rotorid.simulate(structure, structure.as_vector(TRUTH), blank)
            return rotorid.ManeuverSet([m.with_outputs(y + rng.normal(size=y.shape) * NOISE)
                                        for m, y in zip(blank, outputs)])

        return rotorid.CaseData(flown(doublets), flown(chirps), condition)

    @staticmethod
    def _maneuver(name, signal, axis, kind) -> rotorid.Maneuver:
        time = np.arange(signal.size) * DT
        inputs = np.zeros((signal.size, 4))
        inputs[:, rotorid.CONTROLS.index(axis)] = signal
        return rotorid.Maneuver(name, time, inputs, np.zeros((signal.size, 8)),
                                metadata={"axis": axis, "kind": kind})


def _doublet(duration: float) -> np.ndarray:
    signal = np.zeros(int(round(duration / DT)))
    signal[50:100], signal[100:150] = 5.0, -5.0
    return signal


def _chirp(duration: float) -> np.ndarray:
    """A linear chirp from 0.5 to 12 rad/s, 3 % of travel, with 2 s of trim at each end."""
    t = np.arange(0.0, duration, DT)
    omega = 0.5 + (12.0 - 0.5) * t / duration
    quiet = np.zeros(int(round(2.0 / DT)))
    return np.concatenate([quiet, 3.0 * np.sin(np.cumsum(omega) * DT), quiet])


@attrs.frozen
class FlatEnvelope:
    """A bounds-kind envelope: |ε| within ±6 dB and its phase within ±45° everywhere."""

    name: str = "example-flat"
    kind: str = "bounds"
    provenance: str = "A test envelope. Not from any standard"
    verified: bool = False
    threshold: float = 0.8

    def bounds(self, omega) -> rotorid.EnvelopeBounds:
        ones = np.ones_like(np.asarray(omega, dtype=float))
        return rotorid.EnvelopeBounds(self.name, omega, -6.0 * ones, 6.0 * ones, -45.0 * ones,
                                      45.0 * ones, np.zeros(ones.shape, dtype=bool))

    def check(self, error, coherence, omega) -> rotorid.EnvelopeCheck:
        return rotorid.check_bounds(self, error, coherence, omega)


@attrs.frozen
class GainCost:
    """A cost-kind envelope: the mean squared magnitude error (dB²) over the points whose
    coherence reaches the threshold; passes at or below ``limit``."""

    limit: float = 10.0
    name: str = "example-gain-cost"
    kind: str = "cost"
    provenance: str = "A test cost. Mean squared gain error"
    verified: bool = False
    threshold: float = 0.6

    def bounds(self, omega) -> rotorid.EnvelopeBounds:
        ones = np.ones_like(np.asarray(omega, dtype=float))
        gain = np.sqrt(self.limit)
        return rotorid.EnvelopeBounds(self.name, omega, -gain * ones, gain * ones,
                                      -180.0 * ones, 180.0 * ones,
                                      np.zeros(ones.shape, dtype=bool))

    def check(self, error, coherence, omega) -> rotorid.EnvelopeCheck:
        error, coherence, omega = validate_check_inputs(error, coherence, omega)
        magnitude, phase = error_db_deg(error)
        used = (coherence >= self.threshold) & np.isfinite(error)
        cost = float(np.mean(magnitude[used] ** 2)) if used.any() else None
        passed = None if cost is None else cost <= self.limit
        margin = np.sqrt(self.limit) - np.abs(magnitude)
        return rotorid.EnvelopeCheck(
            envelope=self.name, provenance=self.provenance, verified=self.verified,
            omega=omega, magnitude_db=magnitude, phase_deg=phase, coherence=coherence,
            used=used, inside=margin >= 0, extrapolated=np.zeros(omega.shape, dtype=bool),
            margin_db=margin, margin_deg=180.0 - np.abs(phase), threshold=self.threshold,
            passed=passed, status=status_of(passed, self.verified), cost=cost)


@attrs.frozen
class LargestBound:
    """Removes the derivative of largest normalised Cramér-Rao bound above ``threshold`` (%)."""

    threshold: float = 25.0
    name: str = "example-largest-bound"

    def rank(self, estimate: rotorid.Estimate) -> rotorid.Removal | None:
        candidates = [p for p in estimate if not p.name.startswith("tau_")]
        if not candidates:
            return None
        worst = max(candidates, key=lambda p: p.cramer_rao_pct)
        return rotorid.Removal(worst.name, self.name, worst.cramer_rao_pct, self.threshold,
                               f"normalised Cramér-Rao bound {worst.cramer_rao_pct:.1f} %")

    def propose(self, estimate: rotorid.Estimate) -> rotorid.Removal | None:
        removal = self.rank(estimate)
        return removal if removal is not None and removal.metric > self.threshold else None


@attrs.frozen
class WrappedOutputError:
    """The built-in output error (any of its options), reporting under its own name."""

    options: dict = attrs.field(factory=dict)
    name: str = "example-output-error"

    def __init__(self, **options):
        self.__attrs_init__(dict(options))

    def estimate(self, structure, maneuvers, *, start=None) -> rotorid.Estimate:
        inner = rotorid.create("estimators", "output-error", **self.options)
        fit = inner.estimate(structure, maneuvers, start=start)
        return rotorid.Estimate.from_fit(
            structure, fit.values, fit.information, estimator=self.name, start=fit.start,
            noise_covariance=fit.noise_covariance, cost=fit.cost, rmse=fit.rmse,
            n_samples=fit.n_samples, cost_history=fit.cost_history,
            rmse_history=fit.rmse_history, iterations=fit.iterations,
            converged=fit.converged, stop_reason=fit.stop_reason)
