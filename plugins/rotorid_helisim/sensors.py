"""Sensor model: perturbations from trim in flight-test units plus white measurement noise.

Outputs are ``[ax az q θ ay p φ r]``: specific force at the CG in body axes (accelerometers,
ft/s²), body rates (rate gyros, deg/s) and Euler attitudes (deg). The noise is zero-mean,
Gaussian, white at the sample rate and independent between channels, with the standard
deviations of :data:`DEFAULT_SIGMA` unless given. Every draw comes from a generator seeded by
the user's seed and the maneuver name (:func:`noise_generator`), so the same seed gives the
same numbers whatever subset of maneuvers is generated.

Default σ (engineering values for a flight-test instrumentation package, see
docs/maneuvers.md): accelerometers 0.2 ft/s² (0.06 m/s², about 6 mg: residual rotor vibration
after the usual N/rev filtering dominates the transducer noise); rate gyros 0.1 deg/s
(tactical-grade gyro noise at 50 Hz); attitudes 0.1 deg (INS/AHRS attitude noise).

The optional rotor channels ``beta0 beta1c beta1s`` (coning and tip-path-plane tilts, deg;
:data:`ROTOR_CHANNELS`) get the same white noise, σ :data:`ROTOR_SIGMA` unless given, drawn
from a generator of their own so that the eight body channels' noise does not change when
they are written.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Mapping

import attrs
import numpy as np
from rotorid.data import OUTPUT_CHANNELS, Maneuver, ManeuverSet
from rotorid.errors import DataError
from rotorid.units import FLIGHT_TEST, channel_scale

#: Default noise standard deviations in flight-test units (ft/s², deg/s, deg).
DEFAULT_SIGMA = {"ax": 0.2, "az": 0.2, "ay": 0.2, "q": 0.1, "p": 0.1, "r": 0.1,
                 "theta": 0.1, "phi": 0.1}

#: Optional rotor channels (coning, tip-path-plane tilts), extra channels of a maneuver.
ROTOR_CHANNELS = ("beta0", "beta1c", "beta1s")
#: Default σ of a rotor channel, deg: blade-root flap sensors resolved into multi-blade
#: coordinates, about as good as the attitudes.
ROTOR_SIGMA = 0.1


def _sigma_mapping(value) -> dict:
    merged = dict(DEFAULT_SIGMA)
    merged.update({str(k): float(v) for k, v in dict(value).items()})
    return merged


@attrs.frozen
class SensorNoise:
    """White measurement noise with per-channel standard deviations ``sigma`` (flight-test
    units). Channels not named keep their default; give 0 to switch a channel's noise off.
    The rotor channels :data:`ROTOR_CHANNELS` may be named too (default :data:`ROTOR_SIGMA`)."""

    sigma: Mapping = attrs.field(factory=dict, converter=_sigma_mapping)

    def __attrs_post_init__(self):
        unknown = set(self.sigma) - set(OUTPUT_CHANNELS + ROTOR_CHANNELS)
        if unknown:
            raise DataError(f"sensor noise for unknown channel(s) {sorted(unknown)}; channels: "
                            f"{', '.join(OUTPUT_CHANNELS + ROTOR_CHANNELS)}")
        bad = {k: v for k, v in self.sigma.items() if not (math.isfinite(v) and v >= 0)}
        if bad:
            raise DataError(f"sensor noise σ must be finite and ≥ 0, got {bad}")

    @property
    def vector(self) -> np.ndarray:
        """σ per output channel (8,) in :data:`rotorid.data.OUTPUT_CHANNELS` order."""
        return np.array([self.sigma[c] for c in OUTPUT_CHANNELS])

    @property
    def rotor_vector(self) -> np.ndarray:
        """σ per rotor channel (3,) in :data:`ROTOR_CHANNELS` order, deg."""
        return np.array([self.sigma.get(c, ROTOR_SIGMA) for c in ROTOR_CHANNELS])

    def silenced(self, rotor: bool) -> "SensorNoise":
        """No noise on the channels named in :attr:`sigma`, nor on the rotor channels when
        ``rotor`` (their σ is then stated, so a set without them keeps its settings)."""
        return SensorNoise({c: 0.0 for c in self.sigma}
                           | ({c: 0.0 for c in ROTOR_CHANNELS} if rotor else {}))

    def draw(self, n_samples: int, rng: np.random.Generator) -> np.ndarray:
        """Noise samples (n_samples, 8) in flight-test units."""
        return rng.standard_normal((n_samples, 8)) * self.vector


def noise_generator(seed: int, name: str) -> np.random.Generator:
    """The generator for maneuver ``name`` under data-set ``seed`` (stable across subsets)."""
    return np.random.default_rng(np.random.SeedSequence([int(seed), zlib.crc32(name.encode())]))


def with_noise(outputs: np.ndarray, noise: SensorNoise, seed: int, name: str) -> np.ndarray:
    """``outputs`` (N, 8) plus the sensor noise of maneuver ``name`` under data-set ``seed``."""
    return outputs + noise.draw(outputs.shape[0], noise_generator(seed, name))


def with_rotor_noise(rotor: Mapping[str, np.ndarray], noise: SensorNoise, seed: int,
                     name: str) -> dict[str, np.ndarray]:
    """Rotor channels (name → (N,) deg) plus their sensor noise for maneuver ``name`` under
    data-set ``seed``, from a generator apart from the body channels'."""
    rng = noise_generator(seed, f"{name}:rotor")
    values = np.column_stack([rotor[c] for c in ROTOR_CHANNELS])
    noisy = values + rng.standard_normal(values.shape) * noise.rotor_vector
    return dict(zip(ROTOR_CHANNELS, noisy.T))


def rotor_perturbations(states, trim_state, state_names) -> dict[str, np.ndarray]:
    """The rotor channels of plant states (N, n_states) SI: coning and tip-path-plane tilts
    as perturbations from trim, deg (:data:`ROTOR_CHANNELS`)."""
    columns = [tuple(state_names).index(c) for c in ROTOR_CHANNELS]
    delta = np.degrees(np.asarray(states)[:, columns] - np.asarray(trim_state)[columns])
    return dict(zip(ROTOR_CHANNELS, delta.T))


def perturbations(measurements, trim_outputs) -> np.ndarray:
    """Total SI outputs (N, 8) → perturbations from trim in flight-test units (N, 8)."""
    scale = channel_scale(OUTPUT_CHANNELS, FLIGHT_TEST)
    return (np.asarray(measurements) - np.asarray(trim_outputs)) * scale


@attrs.frozen(eq=False)
class NoiseRealisations:
    """Data sets that differ only in their noise seed: noise-free maneuvers plus, for each
    seed, the sensor noise a data set generated with that seed carries.

    The stabilising loops feed back the noise-free states, so the flight itself does not
    depend on the noise: ``realisations(seed)`` equals the data set generated with ``seed``
    sample for sample, without flying it again.
    """

    clean: ManeuverSet
    noise: SensorNoise

    def __call__(self, seed: int) -> ManeuverSet:
        """The data set with noise seed ``seed``."""
        return ManeuverSet([self._noisy(m, int(seed)) for m in self.clean],
                           hold=self.clean.hold)

    def _noisy(self, maneuver: Maneuver, seed: int) -> Maneuver:
        extra = dict(maneuver.extra_channels)
        if all(c in extra for c in ROTOR_CHANNELS):
            extra.update(with_rotor_noise(extra, self.noise, seed, maneuver.name))
        return attrs.evolve(maneuver, extra_channels=extra,
                            outputs=with_noise(maneuver.outputs, self.noise, seed, maneuver.name),
                            metadata={**maneuver.metadata, "seed": seed})
