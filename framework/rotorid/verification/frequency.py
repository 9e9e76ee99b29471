"""Frequency responses, coherence and random error from time histories.

The estimator follows CIFER practice (Tischler & Remple, *Aircraft and Rotorcraft System
Identification*, ch. 7–9; Bendat & Piersol, *Random Data*):

1. every record is cut into Hann-tapered segments of one window length with high overlap
   (80 % by default); each segment's mean is removed;
2. the windowed DFT of every segment is evaluated directly at the frequencies of a
   (logarithmic) grid, ``X(ω) = Δt Σ_n w[n] x[n] e^{−jωnΔt}``; for a uniform grid this is
   exactly what the chirp-z transform computes, for a log grid it is the same sum evaluated
   point by point;
3. the segment spectra of all records are averaged into the auto/cross spectral matrix
   ``G_ij = 2/(U T_win) · mean_k X_i* X_j`` (one-sided; ``U`` = mean square of the window);
4. for one output and ``n`` simultaneously active inputs the conditioned (MISO) responses are
   ``H = G_xx⁻¹ G_xy``; the partial coherence of each input with the output, the others
   removed, comes from the inverse of the full spectral matrix ``P = G⁻¹``:
   ``γ²_iy·rest = |P_iy|² / (P_ii P_yy)`` (for one input it is the ordinary coherence);
5. the normalised random error of ``|H|`` (≈ phase error in rad) is
   ``ε_r = sqrt(1 − γ²) / (|γ| sqrt(2 (n_d − q)))`` with ``n_d`` the number of independent
   averages of overlapped windows (Welch's formula) and ``q`` the number of conditioning inputs;
6. several window lengths are merged into one composite estimate: at each frequency the
   window estimates are averaged with weights ``1/ε_r²``; a window contributes only at
   frequencies with at least two periods inside it (``ω ≥ 4π/T_win``).

Frequencies are in rad/s, window lengths in s, responses in output unit per input unit.
scipy.signal provides the same spectra on FFT bins only; this module adds the log grid,
multi-record pooling, conditioning, random error and the composite.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import attrs
import numpy as np

from rotorid.blas import single_threaded
from rotorid.data import ManeuverSet
from rotorid.errors import VerificationError
from rotorid.frozen import readonly_array

#: Default overlap of consecutive windows (fraction of the window length).
DEFAULT_OVERLAP = 0.8
#: Default number of window lengths in the composite (Tischler & Remple §13.5).
DEFAULT_N_WINDOWS = 5
#: Ratio of the longest to the shortest default window.
DEFAULT_WINDOW_SPAN = 4.5
#: Periods of a frequency that must fit in a window for the window to estimate it.
PERIODS_PER_WINDOW = 2.0
#: Smallest random error used as a weight, so that noise-free data keep finite weights.
_ERROR_FLOOR = 1e-9


def log_grid(omega_min: float, omega_max: float, n: int = 200) -> np.ndarray:
    """``n`` log-spaced frequencies from ``omega_min`` to ``omega_max`` in rad/s, shape (n,)."""
    if not (np.isfinite(omega_min) and np.isfinite(omega_max) and 0 < omega_min < omega_max):
        raise VerificationError(f"frequency grid needs 0 < omega_min < omega_max, got "
                                f"{omega_min!r} and {omega_max!r} rad/s")
    if int(n) < 2:
        raise VerificationError(f"frequency grid needs at least 2 points, got {n}")
    return np.geomspace(omega_min, omega_max, int(n))


def default_windows(record_duration: float, n: int = DEFAULT_N_WINDOWS,
                    span: float = DEFAULT_WINDOW_SPAN) -> tuple[float, ...]:
    """CIFER-style window lengths in s for records of ``record_duration`` s.

    The longest window is half the record, the shortest ``1/span`` of that, ``n`` lengths
    geometrically spaced in between (a 90 s sweep gives 45, 31, 21, 15 and 10 s).
    """
    if not record_duration > 0:
        raise VerificationError(f"record duration must be positive, got {record_duration!r} s")
    longest = record_duration / 2.0
    if n == 1:
        return (longest,)
    return tuple(float(t) for t in np.geomspace(longest, longest / span, n))


def lowest_frequency(window: float) -> float:
    """Lowest frequency in rad/s a window of ``window`` s estimates (two periods inside it)."""
    return 2.0 * np.pi * PERIODS_PER_WINDOW / window


# ----------------------------------------------------------------- spectral matrix
@attrs.frozen(eq=False)
class Spectra:
    """Averaged auto/cross spectral matrix of several channels for one window length.

    Attributes:
        omega: frequencies in rad/s, shape (M,).
        matrix: one-sided spectral matrix, shape (M, C, C), ``G_ij ∝ E[X_i* X_j]`` in
            unit_i·unit_j per Hz (the scaling of ``scipy.signal.csd(..., scaling="density")``);
            Hermitian at each frequency.
        window: window length in s.
        n_segments: number of averaged segments over all records.
        n_effective: number of statistically independent averages (Welch's formula).
    """

    omega: np.ndarray = attrs.field(converter=readonly_array)
    matrix: np.ndarray = attrs.field(converter=lambda m: readonly_array(m, complex))
    window: float
    n_segments: int
    n_effective: float


def _hann(n: int) -> np.ndarray:
    """Periodic Hann window of ``n`` samples."""
    return 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)


def effective_averages(n_segments: int, taper: np.ndarray, hop: int) -> float:
    """Independent averages of ``n_segments`` overlapped segments (Welch 1967).

    ``n_d = n_seg / [1 + 2 Σ_j (1 − j/n_seg) ρ(j)²]`` with ``ρ(j)`` the normalised overlap
    correlation of the taper shifted by ``j`` hops.
    """
    length = taper.size
    energy = float(np.sum(taper ** 2))
    total = 0.0
    for j in range(1, n_segments):
        shift = j * hop
        if shift >= length:
            break
        rho = float(np.sum(taper[:length - shift] * taper[shift:])) / energy
        total += (1.0 - j / n_segments) * rho ** 2
    return n_segments / (1.0 + 2.0 * total)


def _segments(record: np.ndarray, length: int, hop: int) -> np.ndarray:
    """Mean-removed segments of one record, shape (K, C, length), contiguous."""
    starts = np.arange(0, record.shape[0] - length + 1, hop)
    index = starts[:, None] + np.arange(length)[None, :]
    segments = record[index]  # (K, length, C)
    segments = segments - segments.mean(axis=1, keepdims=True)
    return np.ascontiguousarray(np.transpose(segments, (0, 2, 1)))


def _accumulate(records, dt, length, hop, taper, kernel_cos, kernel_sin):
    """Sum of segment cross products over records, segment count and independent averages."""
    total = None
    n_segments, n_effective = 0, 0.0
    for record in records:
        record = np.asarray(record, dtype=float)
        if record.ndim != 2:
            raise VerificationError(f"records must have shape (N, C), got {record.shape}")
        if not np.all(np.isfinite(record)):
            raise VerificationError("a record contains NaN or infinite samples; clean it first")
        if record.shape[0] < length:
            continue
        segments = _segments(record, length, hop)
        flat = segments.reshape(-1, length)  # one matrix product for all segments/channels
        spectra = ((flat @ kernel_cos - 1j * (flat @ kernel_sin)) * dt).reshape(
            segments.shape[0], segments.shape[1], -1)  # (K, C, M)
        outer = np.einsum("kim,kjm->mij", spectra.conj(), spectra)
        total = outer if total is None else total + outer
        n_segments += segments.shape[0]
        n_effective += effective_averages(segments.shape[0], taper, hop)
    return total, n_segments, n_effective


def cross_spectra(records: Sequence[np.ndarray], dt: float, omega: np.ndarray, window: float,
                  overlap: float = DEFAULT_OVERLAP) -> Spectra:
    """Spectral matrix of the channels of several records on an arbitrary frequency grid.

    Args:
        records: arrays of shape (N_i, C), same channels in the same order, sample time ``dt``.
        dt: sample time in s.
        omega: frequencies in rad/s, shape (M,).
        window: Hann window length in s.
        overlap: fraction of the window shared by consecutive segments, in [0, 1).

    Records shorter than the window contribute nothing; if none is long enough the error says
    which window to shorten.
    """
    omega = np.asarray(omega, dtype=float)
    if omega.ndim != 1 or omega.size == 0 or np.any(~np.isfinite(omega)) or np.any(omega <= 0):
        raise VerificationError("omega must be a 1-D array of positive finite frequencies "
                                "in rad/s")
    if not 0.0 <= overlap < 1.0:
        raise VerificationError(f"overlap must be in [0, 1), got {overlap!r}")
    length = int(round(window / dt))
    if length < 8:
        raise VerificationError(f"window of {window} s is only {length} samples at dt = {dt} s; "
                                f"use a window of at least {8 * dt:.3g} s")
    hop = max(1, int(round(length * (1.0 - overlap))))
    taper = _hann(length)
    phase = np.outer(np.arange(length) * dt, omega)  # (L, M)
    kernel_cos, kernel_sin = np.cos(phase) * taper[:, None], np.sin(phase) * taper[:, None]
    with single_threaded():  # small products: one BLAS thread avoids core contention
        total, n_segments, n_effective = _accumulate(records, dt, length, hop, taper,
                                                     kernel_cos, kernel_sin)
    if total is None:
        longest = max((np.asarray(r).shape[0] for r in records), default=0) * dt
        raise VerificationError(f"no record is as long as the {window:.3g} s window (the "
                                f"longest is {longest:.3g} s); use windows of at most half "
                                f"the record length")
    scale = 2.0 / (float(np.mean(taper ** 2)) * length * dt) / n_segments
    return Spectra(omega, total * scale, float(length * dt), n_segments, n_effective)


# ----------------------------------------------------------------- responses
@attrs.frozen(eq=False)
class MisoEstimate:
    """Conditioned responses of one output to ``n`` inputs at one window length.

    Attributes:
        response: conditioned frequency responses, shape (M, n), complex.
        coherence: partial coherence of each input with the output, shape (M, n).
        multiple_coherence: coherence of the output with all inputs together, shape (M,).
        random_error: normalised random error of each response, shape (M, n).
        input_coherence: multiple coherence of each input with the other inputs, shape
            (M, n); zero for a single input. Above about 0.5 the inputs are too correlated
            for reliable conditioned responses (Tischler & Remple, ch. 9).
    """

    response: np.ndarray
    coherence: np.ndarray
    multiple_coherence: np.ndarray
    random_error: np.ndarray
    input_coherence: np.ndarray


def random_error(coherence: np.ndarray, n_effective: float, n_conditioning: int = 0
                 ) -> np.ndarray:
    """Normalised random error ``sqrt(1 − γ²)/(|γ| sqrt(2 (n_d − q)))`` (Bendat & Piersol).

    Infinite where the coherence is zero or the averages do not exceed the conditioning
    inputs.
    """
    dof = n_effective - n_conditioning
    coherence = np.clip(np.asarray(coherence, dtype=float), 0.0, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        error = np.sqrt(1.0 - coherence) / (np.sqrt(coherence) * np.sqrt(2.0 * max(dof, 0.0)))
    return np.where(np.isfinite(error), error, np.inf)


def miso_response(spectra: Spectra) -> MisoEstimate:
    """Conditioned responses of the **last** channel of ``spectra`` to all the others."""
    g = spectra.matrix
    n = g.shape[1] - 1
    if n < 1:
        raise VerificationError("spectra need at least one input and one output channel")
    power = np.einsum("mii->mi", g).real
    if np.any(power[:, :n] <= 0):
        channel = int(np.flatnonzero(np.any(power[:, :n] <= 0, axis=0))[0])
        raise VerificationError(f"input {channel} of the spectra has no power at some "
                                f"frequencies: it did not move; condition only on inputs that "
                                f"moved")
    # Work with the coherence matrix (unit diagonal): the results are scale invariant and
    # the conditioning test then detects only (nearly) proportional inputs. An output
    # without power (a model with no response on this pair) gets response and coherence 0.
    silent = power[:, n] <= 0
    scale = 1.0 / np.sqrt(np.where(power > 0, power, 1.0))
    scale[silent, n] = 0.0
    unit = g * scale[:, :, None] * scale[:, None, :]
    unit[silent, n, n] = 1.0
    if np.any(np.linalg.cond(unit[:, :n, :n]) > 1e10):
        raise VerificationError("the inputs are (nearly) proportional at some frequencies, so "
                                "their responses cannot be separated; condition only on "
                                "inputs that moved independently of the primary input")
    solved = np.linalg.solve(unit[:, :n, :n], unit[:, :n, n:])[..., 0]
    response = np.where(silent[:, None], 0.0, solved * scale[:, :n] / np.where(
        silent, 1.0, scale[:, n])[:, None])
    multiple = np.einsum("mi,mi->m", unit[:, :n, n].conj(), solved).real
    # A noise-free output (a simulated model) is fully coherent with the inputs, which makes
    # the full coherence matrix singular; a 1e-12 loading of its unit diagonal keeps the
    # inverse finite and gives partial coherences of 1 − O(1e-12) there.
    inverse = np.linalg.inv(unit + np.eye(n + 1) * 1e-12)
    diag = np.einsum("mii->mi", inverse).real
    partial = np.abs(inverse[:, :n, n]) ** 2 / (diag[:, :n] * diag[:, n:n + 1])
    partial = np.clip(partial, 0.0, 1.0)
    multiple = np.clip(multiple, 0.0, 1.0)
    error = random_error(partial, spectra.n_effective, n - 1)
    if n == 1:
        inputs = np.zeros_like(partial)
    else:
        inputs = np.clip(1.0 - 1.0 / np.einsum("mii->mi", np.linalg.inv(unit[:, :n, :n])).real,
                         0.0, 1.0)
    return MisoEstimate(response, partial, multiple, error, inputs)


def composite(estimates: Sequence[MisoEstimate], windows: Sequence[float], omega: np.ndarray
              ) -> MisoEstimate:
    """Merge window estimates into one, weighting each by ``1/ε_r²`` at every frequency.

    A window contributes only where ``ω ≥ 4π/T_win``; where all covering windows have zero
    coherence they count equally. The composite random error is the weighted mean of the
    window errors (the windows share data, so errors are not reduced as if independent).
    Frequencies no window covers are NaN.
    """
    omega = np.asarray(omega, dtype=float)
    covered = np.array([omega >= lowest_frequency(t) for t in windows])  # (W, M)
    errors = np.array([e.random_error for e in estimates])  # (W, M, n)
    weights = np.where(covered[..., None], 1.0 / np.maximum(errors, _ERROR_FLOOR) ** 2, 0.0)
    # Where every covering window has zero coherence, average the covering windows equally.
    weights = np.where((weights.sum(axis=0) == 0) & covered[..., None], 1.0, weights)
    total = weights.sum(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(total > 0, weights / total, np.nan)

    def merge(values):
        with np.errstate(invalid="ignore"):
            weighted = np.where(share > 0, share * np.asarray(values), 0.0)
        return np.where(total > 0, weighted.sum(axis=0), np.nan)

    multiple = np.array([e.multiple_coherence for e in estimates])[..., None]
    return MisoEstimate(
        response=merge([e.response for e in estimates]),
        coherence=merge([e.coherence for e in estimates]),
        multiple_coherence=merge(np.broadcast_to(multiple, share.shape))[:, 0],
        random_error=merge([e.random_error for e in estimates]),
        input_coherence=merge([e.input_coherence for e in estimates]),
    )


@attrs.frozen(eq=False)
class FrequencyResponse:
    """A frequency response estimated from time histories (or evaluated from a model).

    Attributes:
        input, output: channel names, e.g. ``"long"`` and ``"q"``.
        omega: frequencies in rad/s, shape (M,).
        response: complex response in output unit per input unit, shape (M,); NaN where no
            window covers the frequency.
        coherence: coherence, partial when ``conditioned_on`` is not empty, shape (M,).
        random_error: normalised random error of ``|response|``, shape (M,).
        conditioned_on: the other inputs removed by conditioning.
        windows: window lengths in s that formed the composite.
        n_effective: independent averages per window, same order as ``windows``.
        input_coherence: multiple coherence of ``input`` with the conditioning inputs,
            shape (M,), or None; conditioned responses are unreliable where it exceeds ~0.5.
    """

    input: str
    output: str
    omega: np.ndarray = attrs.field(converter=readonly_array)
    response: np.ndarray = attrs.field(converter=lambda r: readonly_array(r, complex))
    coherence: np.ndarray = attrs.field(converter=readonly_array)
    random_error: np.ndarray = attrs.field(converter=readonly_array)
    conditioned_on: tuple[str, ...] = attrs.field(default=(), converter=tuple)
    windows: tuple[float, ...] = attrs.field(default=(), converter=tuple)
    n_effective: tuple[float, ...] = attrs.field(default=(), converter=tuple)
    input_coherence: np.ndarray | None = attrs.field(
        default=None, converter=lambda c: None if c is None else readonly_array(c))

    @property
    def pair(self) -> str:
        """Pair name ``output/input``, e.g. ``"q/long"``."""
        return f"{self.output}/{self.input}"

    @property
    def magnitude_db(self) -> np.ndarray:
        """Magnitude in dB, shape (M,)."""
        with np.errstate(divide="ignore"):
            return 20.0 * np.log10(np.abs(self.response))

    @property
    def phase_deg(self) -> np.ndarray:
        """Phase in deg, unwrapped along frequency from its principal value, shape (M,)."""
        return unwrapped_phase_deg(self.response)


def unwrapped_phase_deg(response: np.ndarray) -> np.ndarray:
    """Phase in deg of a complex response along frequency, unwrapped; NaN points stay NaN."""
    response = np.asarray(response, dtype=complex)
    phase = np.full(response.shape, np.nan)
    finite = np.isfinite(response)
    phase[finite] = np.degrees(np.unwrap(np.angle(response[finite])))
    return phase


def estimate_responses(records: Sequence[np.ndarray], dt: float, input_names: Sequence[str],
                       output_name: str, omega: np.ndarray,
                       windows: Sequence[float] | None = None,
                       overlap: float = DEFAULT_OVERLAP) -> tuple[FrequencyResponse, ...]:
    """Composite conditioned responses of one output to several simultaneous inputs.

    Args:
        records: arrays of shape (N_i, n + 1): the ``n`` inputs then the output, sample time
            ``dt`` (s). Several records (repeated sweeps) are pooled segment by segment.
        input_names, output_name: channel names for the result.
        omega: frequencies in rad/s, shape (M,).
        windows: window lengths in s; default :func:`default_windows` of the shortest record.
        overlap: window overlap fraction.

    Returns one :class:`FrequencyResponse` per input, each conditioned on the other inputs.
    """
    records = [np.asarray(r, dtype=float) for r in records]
    if not records:
        raise VerificationError("no records given for the frequency response")
    n = len(input_names)
    for record in records:
        if record.ndim != 2 or record.shape[1] != n + 1:
            raise VerificationError(f"each record must have shape (N, {n + 1}) for inputs "
                                    f"{list(input_names)} and output {output_name!r}, got "
                                    f"{record.shape}")
    if windows is None:
        windows = default_windows(min(r.shape[0] for r in records) * dt)
    spectra = [cross_spectra(records, dt, omega, t, overlap) for t in windows]
    with single_threaded():
        estimates = [miso_response(s) for s in spectra]
    merged = composite(estimates, [s.window for s in spectra], omega)
    return tuple(
        FrequencyResponse(
            input=name, output=output_name, omega=omega, response=merged.response[:, i],
            coherence=merged.coherence[:, i], random_error=merged.random_error[:, i],
            conditioned_on=[o for o in input_names if o != name],
            windows=[s.window for s in spectra], n_effective=[s.n_effective for s in spectra],
            input_coherence=merged.input_coherence[:, i])
        for i, name in enumerate(input_names))


# ----------------------------------------------------------------- maneuver front end
def moving_inputs(maneuvers: ManeuverSet, primary: str, fraction: float = 0.05
                  ) -> tuple[str, ...]:
    """Inputs other than ``primary`` whose RMS (mean removed) exceeds ``fraction`` of the
    primary input's RMS in the pooled maneuvers: the candidates for conditioning."""
    names = maneuvers.input_names
    _check_channel(primary, names, "input")
    stacked = np.concatenate([m.inputs - m.inputs.mean(axis=0) for m in maneuvers])
    rms = np.sqrt(np.mean(stacked ** 2, axis=0))
    reference = rms[names.index(primary)]
    if reference <= 0:
        raise VerificationError(f"input {primary!r} does not move in these maneuvers; select "
                                f"the sweeps of that axis")
    return tuple(name for name, value in zip(names, rms)
                 if name != primary and value > fraction * reference)


def influential_inputs(maneuvers: ManeuverSet, primary: str, omega: np.ndarray,
                       model: np.ndarray, input_names: Sequence[str],
                       fraction: float = 0.05) -> tuple[str, ...]:
    """Inputs other than ``primary`` whose share of one output, as a model predicts it over
    ``omega``, exceeds ``fraction`` of the primary input's share in the pooled maneuvers.

    A small input can matter: a lateral stick at 3 % of a longitudinal sweep's RMS drives
    the roll rate as hard as the sweep does. Each input's share is
    ``sqrt(Σ_records Σ_ω |H_k(ω) U_k(ω)|²)``, ``U_k`` the record's DFT (mean removed) at the
    frequencies ``omega`` (rad/s, shape (M,)) and ``H_k`` the model's response of the output
    to input ``input_names[k]``, columns of ``model`` (M, m). Inputs the maneuvers lack are
    skipped."""
    _check_channel(primary, input_names, "input")
    names = [n for n in input_names if n in maneuvers.input_names]
    shares = dict.fromkeys(names, 0.0)
    for m in maneuvers:
        inputs = m.columns(names)
        kernel = np.exp(-1j * np.outer(omega, np.arange(m.n_samples) * m.dt))
        spectra = kernel @ (inputs - inputs.mean(axis=0))             # (M, len(names))
        for j, name in enumerate(names):
            column = model[:, list(input_names).index(name)]
            shares[name] += float(np.sum(np.abs(column * spectra[:, j]) ** 2))
    reference = shares.get(primary, 0.0)
    if not reference > 0:
        return ()
    return tuple(n for n in names
                 if n != primary and math.sqrt(shares[n] / reference) > fraction)


def _check_channel(name: str, channels: Sequence[str], kind: str) -> None:
    if name not in channels:
        raise VerificationError(f"unknown {kind} {name!r}; {kind}s: {', '.join(channels)}")


def response_from_maneuvers(maneuvers: ManeuverSet, input: str, output: str,
                            omega: np.ndarray, *, conditioned_on: Sequence[str] = (),
                            outputs: Sequence[np.ndarray] | None = None,
                            output_names: Sequence[str] | None = None,
                            windows: Sequence[float] | None = None,
                            overlap: float = DEFAULT_OVERLAP) -> FrequencyResponse:
    """Composite response ``output/input`` pooled over maneuvers, optionally conditioned.

    Args:
        maneuvers: the records (all must share one sample time).
        input, output: channel names (``"long"``, ``"q"``).
        omega: frequencies in rad/s, shape (M,).
        conditioned_on: other inputs to remove (see :func:`moving_inputs`).
        outputs: replacement output arrays, one (N_i, len(output_names)) per maneuver (e.g. a
            model's simulation of the same inputs); default the measured outputs.
        output_names: the columns of ``outputs`` (e.g. a structure's outputs); default the
            maneuvers' own outputs.
    """
    _check_channel(input, maneuvers.input_names, "input")
    for name in conditioned_on:
        _check_channel(name, maneuvers.input_names, "input")
    inputs = [input, *[c for c in conditioned_on if c != input]]
    records = _records(maneuvers, inputs, output, outputs, output_names)
    return estimate_responses(records, maneuvers[0].dt, inputs, output, omega, windows,
                              overlap)[0]


def _records(maneuvers: ManeuverSet, inputs: Sequence[str], output: str,
             outputs: Sequence[np.ndarray] | None = None,
             output_names: Sequence[str] | None = None) -> list[np.ndarray]:
    """Per maneuver, the ``inputs`` columns then the ``output`` column, shape (N_i, n + 1);
    the output from ``outputs`` (columns ``output_names``) when given."""
    dts = {round(m.dt, 9) for m in maneuvers}
    if len(dts) > 1:
        raise VerificationError(f"maneuvers have different sample times {sorted(dts)} s; "
                                f"resample them to one before estimating responses")
    names = tuple(maneuvers.output_names if output_names is None else output_names)
    _check_channel(output, names, "output")
    if outputs is None:
        outputs = [m.columns(names) for m in maneuvers]
    if len(outputs) != len(maneuvers):
        raise VerificationError(f"{len(outputs)} output arrays for {len(maneuvers)} maneuvers")
    records = []
    for m, y in zip(maneuvers, outputs):
        y = np.asarray(y, dtype=float)
        if y.shape != (m.n_samples, len(names)):
            raise VerificationError(f"outputs for maneuver {m.name!r} must have shape "
                                    f"({m.n_samples}, {len(names)}), got {y.shape}")
        records.append(np.column_stack([m.columns(inputs), y[:, names.index(output)]]))
    return records


def hold_response(omega: np.ndarray, dt: float, hold: str) -> np.ndarray:
    """Frequency response of the hold that turns input samples into the signal the aircraft
    sees, shape (M,): zero-order ``(1 − e^(−jωT))/(jωT)`` (half a sample of lag), first-order
    (linear interpolation) ``sinc²(ωT/2)`` (no lag)."""
    x = np.asarray(omega, dtype=float) * dt
    if hold == "zoh":
        return (1.0 - np.exp(-1j * x)) / (1j * x)
    if hold == "foh":
        return np.sinc(x / (2.0 * np.pi)) ** 2 + 0j
    raise VerificationError(f"unknown input hold {hold!r}; use 'zoh' or 'foh'")


def apparent_response(maneuvers: ManeuverSet, input: str, output: str, omega: np.ndarray,
                      model: np.ndarray, *, input_names: Sequence[str] | None = None,
                      windows: Sequence[float] | None = None,
                      overlap: float = DEFAULT_OVERLAP) -> tuple[FrequencyResponse,
                                                                 FrequencyResponse]:
    """A model's response as the single-input estimate ``output/input`` on these records
    sees it, beside the truth's single-input estimate from the recorded outputs.

    When the other inputs move with the primary one (stabilising loops), the single-input
    estimate of a linear system driven by all of them is ``Σ_k H_k · G_{u,u_k}/G_{u,u}``. This
    evaluates that sum per window from the recorded inputs' cross-spectra and the model's
    analytic responses ``H_k``, and merges the windows with the truth estimate's weights, so
    model and truth are processed identically. Nothing is simulated: an unstable model does
    not drift.

    Args:
        maneuvers: the records (one sample time).
        input, output: channel names (``"long"``, ``"q"``).
        omega: frequencies in rad/s, shape (M,).
        model: the model's responses of ``output`` to each of its inputs on ``omega``, shape
            (M, m) complex (e.g. from :func:`rotorid.simulation.transfer.frequency_response`).
        input_names: the model's inputs, the columns of ``model`` (default the maneuvers'
            inputs); each must be recorded, and ``input`` must be one of them.

    The analytic responses are those of the continuous model; the recorded inputs are
    samples of held signals, so each is multiplied by the frequency response of the records'
    hold (:func:`hold_response`), as the truth's and a simulation's estimates include it.

    Returns ``(model, truth)``; the model's carries the truth's coherence and random error.
    """
    names = tuple(maneuvers.input_names if input_names is None else input_names)
    _check_channel(input, names, "input")
    omega = np.asarray(omega, dtype=float)
    model = np.asarray(model, dtype=complex)
    if model.shape != (omega.size, len(names)):
        raise VerificationError(f"model responses must have shape ({omega.size}, "
                                f"{len(names)}), got {model.shape}")
    order = [input, *[c for c in names if c != input]]
    records = _records(maneuvers, order, output)
    if windows is None:
        windows = default_windows(min(r.shape[0] for r in records) * maneuvers[0].dt)
    gains = (model[:, [names.index(c) for c in order]]
             * hold_response(omega, maneuvers[0].dt, maneuvers.hold)[:, None])   # (M, m)
    truths, models, used, averages = [], [], [], []
    for window in windows:
        spectra = cross_spectra(records, maneuvers[0].dt, omega, window, overlap)
        used.append(spectra.window)
        averages.append(spectra.n_effective)
        g = spectra.matrix
        pair = [0, len(order)]
        single = attrs.evolve(spectra, matrix=g[:, pair][:, :, pair])
        with single_threaded():
            truth = miso_response(single)
        with np.errstate(divide="ignore", invalid="ignore"):
            seen = np.einsum("mk,mk->m", gains, g[:, 0, :len(order)]) / g[:, 0, 0]
        truths.append(truth)
        models.append(attrs.evolve(truth, response=seen[:, None]))
    merged = [composite(estimates, used, omega) for estimates in (models, truths)]
    return tuple(
        FrequencyResponse(input=input, output=output, omega=omega, response=m.response[:, 0],
                          coherence=m.coherence[:, 0], random_error=m.random_error[:, 0],
                          windows=used, n_effective=averages)
        for m in merged)
