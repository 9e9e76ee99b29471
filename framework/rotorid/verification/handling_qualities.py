"""ADS-33 bandwidth and phase delay of the attitude responses (ADS-33E-PRF, §3.3 / 3.4:
small-amplitude attitude changes, short-term response).

For an attitude response Φ(ω) = ∠H(jω) in deg (unwrapped) and |H| in dB:

* ω180: the lowest frequency where the phase reaches −180°;
* ω_BW,phase: where the phase reaches −135° (45° phase margin);
* ω_BW,gain: where the gain exceeds its value at ω180 by 6 dB (6 dB gain margin);
* bandwidth ω_BW = min(ω_BW,gain, ω_BW,phase) (rate-response types);
* phase delay τ_p = −(Φ(2ω180) + 180°) / (57.3·2ω180) in s.

The pairs are pitch attitude over longitudinal cyclic (``theta/long``), roll attitude over
lateral cyclic (``phi/lat``) and heading over pedal (``psi/ped``), and an aeroplane's over its
elevator, ailerons and rudder (``theta/elevator``, ``phi/aileron``, ``psi/rudder``), for which
MIL-STD-1797A's bandwidth criterion uses the same definitions. The heading is not a model
output; its response is taken as that of the yaw rate integrated, ψ = r/(jω) (ψ̇ = r about
level trim). Crossings are interpolated linearly in log ω between grid points. A response
whose low-frequency phase is positive (a control whose positive sense reduces the attitude)
is negated first, so that every attitude starts at −90° as an integrator does. The ADS-33
boundary charts (Level 1/2/3 regions) are not encoded here: these are the numbers to read
against them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import attrs
import numpy as np

from rotorid.errors import VerificationError
from rotorid.simulation.transfer import frequency_response
from rotorid.verification.compare import default_omega
from rotorid.verification.frequency import (
    FrequencyResponse,
    response_from_maneuvers,
    unwrapped_phase_deg,
)
from rotorid.verification.pairs import primary_axis

#: The attitude pairs: ADS-33's and an aeroplane's; ``psi`` is the heading (integrated yaw
#: rate).
HQ_PAIRS = ("theta/long", "phi/lat", "psi/ped", "theta/elevator", "phi/aileron", "psi/rudder")
#: deg per rad as ADS-33 writes it in the phase-delay formula.
DEG_PER_RAD = 57.3


@attrs.frozen
class HandlingQualities:
    """Bandwidth and phase delay of one attitude response.

    Attributes:
        pair: ``attitude/control``.
        source: ``"model"`` or ``"measured"``.
        omega_180, gain_bandwidth, phase_bandwidth, bandwidth: rad/s, ``None`` where the
            response does not reach the crossing inside the frequencies given.
        phase_delay: τ_p in s, ``None`` when 2ω180 lies beyond the frequencies given.
        sign_reversed: the response was negated (its control's positive sense reduces the
            attitude).
    """

    pair: str
    source: str
    omega_180: float | None
    gain_bandwidth: float | None
    phase_bandwidth: float | None
    bandwidth: float | None
    phase_delay: float | None
    sign_reversed: bool = False

    def as_dict(self) -> dict:
        return attrs.asdict(self)


def _crossing(omega: np.ndarray, values: np.ndarray, level: float) -> float | None:
    """The lowest frequency where ``values`` falls through ``level`` (log-ω interpolation)."""
    below = np.flatnonzero((values[:-1] > level) & (values[1:] <= level))
    if below.size == 0:
        return None
    k = below[0]
    share = (values[k] - level) / (values[k] - values[k + 1])
    return float(10.0 ** (np.log10(omega[k]) + share * np.log10(omega[k + 1] / omega[k])))


def _at(omega: np.ndarray, values: np.ndarray, frequency: float) -> float | None:
    if not omega[0] <= frequency <= omega[-1]:
        return None
    return float(np.interp(np.log10(frequency), np.log10(omega), values))


def bandwidth_phase_delay(omega, response, pair: str = "", source: str = "model"
                          ) -> HandlingQualities:
    """ADS-33 bandwidth and phase delay of an attitude response.

    Args:
        omega: increasing frequencies in rad/s, shape (M,).
        response: complex attitude response per control unit, shape (M,).
        pair, source: labels for the result.
    """
    omega = np.asarray(omega, dtype=float)
    response = np.asarray(response, dtype=complex)
    if omega.ndim != 1 or omega.shape != response.shape or omega.size < 2 \
            or np.any(np.diff(omega) <= 0) or np.any(omega <= 0):
        raise VerificationError("bandwidth needs increasing positive frequencies (rad/s) and "
                                "a response of the same shape (M,)")
    if not np.all(np.isfinite(response)) or np.any(response == 0):
        raise VerificationError(f"{pair or 'the response'}: the response must be finite and "
                                f"non-zero at every frequency; keep only the coherent ones")
    reversed_sign = bool(np.angle(response[0]) > 0)
    if reversed_sign:
        response = -response
    phase = unwrapped_phase_deg(response)
    phase -= 360.0 * np.round((phase[0] + 90.0) / 360.0)     # the branch starting near −90°
    gain = 20.0 * np.log10(np.abs(response))
    omega_180 = _crossing(omega, phase, -180.0)
    phase_bandwidth = _crossing(omega, phase, -135.0)
    gain_bandwidth = delay = None
    if omega_180 is not None:
        gain_bandwidth = _crossing(omega, gain, _at(omega, gain, omega_180) + 6.0)
        phase_at_double = _at(omega, phase, 2.0 * omega_180)
        if phase_at_double is not None:
            delay = -(phase_at_double + 180.0) / (DEG_PER_RAD * 2.0 * omega_180)
    candidates = [w for w in (gain_bandwidth, phase_bandwidth) if w is not None]
    return HandlingQualities(pair, source, omega_180, gain_bandwidth, phase_bandwidth,
                             min(candidates) if candidates else None, delay, reversed_sign)


def _measured_channel(pair: str) -> tuple[str, str]:
    """(output, control) whose response gives the attitude pair: the heading's is the yaw
    rate's."""
    if pair not in HQ_PAIRS:
        raise VerificationError(f"unknown handling-qualities pair {pair!r}; pairs: "
                                f"{', '.join(HQ_PAIRS)}")
    attitude, control = pair.split("/")
    return ("r" if attitude == "psi" else attitude), control


def available_pairs(outputs: Sequence[str], controls: Sequence[str]) -> tuple[str, ...]:
    """The pairs of :data:`HQ_PAIRS` a model or a data set with these outputs and controls
    has (the heading through ``r``)."""
    return tuple(pair for pair in HQ_PAIRS
                 if (channel := _measured_channel(pair))[0] in outputs
                 and channel[1] in controls)


def _attitude_response(pair: str, omega: np.ndarray, response: np.ndarray) -> np.ndarray:
    """The attitude response of ``pair`` from its channel's (integrated for the heading)."""
    return response / (1j * omega) if pair.startswith("psi/") else response


def model_handling_qualities(structure, values, omega=None,
                             pairs: Sequence[str] | None = None
                             ) -> tuple[HandlingQualities, ...]:
    """Bandwidth and phase delay of a model's attitude responses (analytic, exact delays).

    Args:
        structure, values: the model (any structure with the attitude outputs and cyclic or
            pedal controls, e.g. a hybrid) and its parameter vector.
        omega: frequencies in rad/s; default 400 log-spaced over 0.1–100 rad/s.
        pairs: default every pair of :data:`HQ_PAIRS` the structure has
            (:func:`available_pairs`).
    """
    omega = np.geomspace(0.1, 100.0, 400) if omega is None else np.asarray(omega, float)
    outputs, controls = list(structure.outputs), list(structure.controls)
    pairs = available_pairs(outputs, controls) if pairs is None else pairs
    full = frequency_response(structure, values, omega)
    results = []
    for pair in pairs:
        output, control = _measured_channel(pair)
        if output not in outputs or control not in controls:
            raise VerificationError(f"{pair}: the model has no {output}/{control} response; "
                                    f"its pairs: {', '.join(available_pairs(outputs, controls))}")
        response = full[:, outputs.index(output), controls.index(control)]
        if not np.any(response):        # the model has no path from the control
            results.append(HandlingQualities(pair, "model", None, None, None, None, None))
            continue
        results.append(bandwidth_phase_delay(omega, _attitude_response(pair, omega, response),
                                             pair, "model"))
    return tuple(results)


def _attitude_pair(measured_pair: str) -> str:
    """The attitude pair a measured channel pair gives (``r/ped`` gives the heading's)."""
    return "psi/ped" if measured_pair == "r/ped" else measured_pair


def sweep_attitude_pairs(sweeps) -> tuple[str, ...]:
    """The measured channel pairs behind the attitude pairs of :data:`HQ_PAIRS` whose channels
    the sweeps hold and whose control one of them excites (its primary axis): ``theta/long``,
    ``phi/lat`` and, for the heading, ``r/ped``."""
    axes = {primary_axis(m) for m in sweeps}
    return tuple("/".join(channel) for pair in available_pairs(sweeps.output_names,
                                                                sweeps.input_names)
                 if (channel := _measured_channel(pair))[1] in axes)


def sweep_attitude_responses(sweeps, omega) -> tuple[FrequencyResponse, ...]:
    """The composite responses of :func:`sweep_attitude_pairs`, each over the sweeps that
    excite its control, on ``omega`` (rad/s, shape (M,))."""
    responses = []
    for pair in sweep_attitude_pairs(sweeps):
        output, control = pair.split("/")
        subset = sweeps.select(lambda m, c=control: primary_axis(m) == c)
        responses.append(response_from_maneuvers(subset, control, output, omega))
    return tuple(responses)


def _coherent(measured: FrequencyResponse, threshold: float) -> np.ndarray:
    """Where a measured response counts: finite, non-zero, coherence ≥ ``threshold``."""
    return (np.isfinite(measured.response) & (measured.coherence >= threshold)
            & (np.abs(np.nan_to_num(measured.response)) > 0))


def measured_handling_qualities(responses: Sequence[FrequencyResponse],
                                threshold: float = 0.6) -> tuple[HandlingQualities, ...]:
    """Bandwidth and phase delay from measured attitude responses (``theta/long``,
    ``phi/lat``; ``r/ped`` gives ``psi/ped``), over the frequencies with coherence ≥
    ``threshold``; responses of other pairs are ignored."""
    results = []
    for measured in responses:
        pair = _attitude_pair(measured.pair)
        if pair not in HQ_PAIRS:
            continue
        keep = _coherent(measured, threshold)
        if np.count_nonzero(keep) < 2:
            results.append(HandlingQualities(pair, "measured", None, None, None, None, None))
            continue
        omega = measured.omega[keep]
        results.append(bandwidth_phase_delay(
            omega, _attitude_response(pair, omega, measured.response[keep]), pair,
            "measured"))
    return tuple(results)


def handling_qualities_table(models: Mapping[str, tuple], sweeps=None,
                             threshold: float = 0.6) -> dict[str, tuple[HandlingQualities, ...]]:
    """ADS-33 bandwidth and phase delay by source: each model's (analytic) and, with sweeps,
    the measured ones (``measured``).

    With sweeps, a model's numbers are taken on the frequencies where the sweeps' response of
    the same pair is coherent (γ² ≥ ``threshold``), as the measured ones are: the crossings
    are then those of the band the data show, not of the slow modes below it (an unstable
    hover model's phase passes −180° below 0.5 rad/s). Without sweeps, over 0.1–100 rad/s.

    Args:
        models: label → (structure, parameter vector).
        sweeps: the frequency sweeps, or None.
    """
    if sweeps is None or not len(sweeps):
        return {label: model_handling_qualities(structure, values)
                for label, (structure, values) in models.items()}
    responses = sweep_attitude_responses(sweeps, default_omega(sweeps))
    table = {}
    for label, (structure, values) in models.items():
        own = available_pairs(structure.outputs, structure.controls)
        items = []
        for measured in responses:
            pair = _attitude_pair(measured.pair)
            omega = measured.omega[_coherent(measured, threshold)]
            if pair in own and omega.size >= 2:
                items.extend(model_handling_qualities(structure, values, omega, [pair]))
        table[label] = tuple(items)
    table["measured"] = measured_handling_qualities(responses, threshold)
    return table
