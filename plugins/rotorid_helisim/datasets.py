"""The paper's data sets (Table 1) per flight condition: which maneuvers, flown how.

Per condition: 3211 and 2311 multisteps in both directions on each control (16 identification
maneuvers) and one frequency sweep per control (4 verification maneuvers). Every maneuver
starts in trim, applies its signal to one control and is kept near trim by the loops of
:mod:`.loops`. Names follow ``<condition>_<kind>_<axis>[_pos|_neg]``, e.g.
``hover_3211_long_pos`` and ``forward_sweep_ped``.

Inputs (documented in docs/maneuvers.md):

* multisteps: step width Δt and amplitude per axis (:data:`STEP_WIDTH`, :data:`AMPLITUDE`),
  starting after 2 s of trim, records of :data:`MULTISTEP_RECORD` s;
* sweeps: the validation.md §6.1 log sweep from :data:`SWEEP_OMEGA` with 2 cycles at ω_min,
  3 s of trim before and 5 s after, sine amplitude :data:`SWEEP_AMPLITUDE` per axis.

``duration_scale`` < 1 shortens every record (quick runs for tests): the multistep records and
the sweep time shrink by the factor and the sweep's lowest frequency rises by its inverse.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping

import attrs
import numpy as np
from rotorid.data import GUST_CHANNELS, Maneuver, ManeuverSet
from rotorid.errors import DataError
from rotorid.units import FLIGHT_TEST, KNOT, channel_scale
from rotorid_signals.signals import Multistep, Sweep

from .loops import AXES, LoopDesign, design_loops, quasi_steady_model
from .sensors import (
    SensorNoise,
    perturbations,
    rotor_perturbations,
    with_noise,
    with_rotor_noise,
)
from .turbulence import Turbulence, gust_generator, turbulence_setting

KINDS = ("3211", "2311", "sweep")
#: Factors from SI of the true gusts a turbulent record carries as extra channels
#: (:data:`rotorid.data.GUST_CHANNELS`, in :data:`.turbulence.COMPONENTS` order: the air's
#: velocity, ft/s, and rotation, deg/s, at the sample instants, no sensor noise).
GUST_SCALE = channel_scale(GUST_CHANNELS, FLIGHT_TEST)
#: Flight conditions by name: airspeed in kt.
CONDITIONS = {"hover": 0.0, "forward": 70.0}
#: Multistep basic time step Δt per axis, s (validation.md §6.2: Δt ≈ 1.6/ω_n).
STEP_WIDTH = {"long": 0.4, "lat": 0.3, "coll": 1.0, "ped": 1.0}
#: Multistep amplitude per axis, % of travel.
AMPLITUDE = {"long": 5.0, "lat": 3.0, "coll": 6.0, "ped": 6.0}
#: Sweep sine amplitude per axis, % of travel.
SWEEP_AMPLITUDE = {"long": 1.0, "lat": 1.4, "coll": 4.0, "ped": 5.0}
#: Sweep law: ω_min, ω_max (rad/s) and T_rec (s) at duration_scale 1.
SWEEP_OMEGA = (0.45, 14.0)
SWEEP_TIME = 40.0
#: Sweep amplitude at ω_max over that at ω_min (the amplitude grows with frequency).
SWEEP_AMPLITUDE_RATIO = 3.0
MULTISTEP_START = 2.0  #: s of trim before the first pulse
MULTISTEP_RECORD = 15.0  #: s, whole record at duration_scale 1


#: Settings left out of :meth:`DataSetConfig.as_dict` (and so of the digest) at these values.
_OPTIONAL = {"turbulence": None, "rotor_channels": False}


def _choice(allowed):
    def convert(value):
        values = (value,) if isinstance(value, (str, int)) else tuple(value)
        bad = [v for v in values if v not in allowed]
        if bad or not values:
            raise DataError(f"unknown or empty selection {list(values)}; choose from "
                            f"{', '.join(allowed)}")
        return tuple(v for v in allowed if v in values)
    return convert


def _per_axis(defaults):
    def convert(value):
        merged = dict(defaults)
        merged.update({str(k): float(v) for k, v in dict(value or {}).items()})
        if set(merged) != set(AXES) or not all(math.isfinite(v) and v > 0
                                               for v in merged.values()):
            raise DataError(f"per-axis values must be finite and > 0 for axes "
                            f"{', '.join(AXES)}, got {merged}")
        return merged
    return convert


def _boolean(instance, attribute, value):
    if not isinstance(value, bool):
        raise DataError(f"data set: {attribute.name} must be true or false, got {value!r}")


def _in_range(low, high, what):
    def check(instance, attribute, value):
        if not (math.isfinite(value) and low < value <= high):
            raise DataError(f"data set: {attribute.name} must be in ({low}, {high}] {what}, "
                            f"got {value!r}")
    return check


@attrs.frozen
class DataSetConfig:
    """Everything that determines a generated data set (its hash keys the cache).

    Attributes:
        condition: name used in maneuver names and metadata (``"hover"``, ``"forward"``).
        airspeed_kt: trim airspeed, level flight.
        seed: seed of every random draw (sensor noise, gusts).
        sample_rate: Hz; substeps: RK4 steps per sample.
        kinds, axes, directions: the maneuver selection (subsets of :data:`KINDS`,
            ``long lat coll ped`` and the multistep directions ``1, -1``).
        duration_scale: record-length factor in (0, 1]; 1 is the full data set.
        amplitude, step_width, sweep_amplitude: per-axis overrides (%, s, %).
        noise: sensor noise (or a mapping of σ per channel);
        loops: loop bandwidths (or a mapping of :class:`~.loops.LoopDesign` fields).
        turbulence: None (still air), a :class:`~.turbulence.Turbulence`, ``"light"``,
            ``"moderate"`` or a mapping (:func:`~.turbulence.turbulence_setting`).
        rotor_channels: also write the coning and tip-path-plane tilts ``beta0 beta1c
            beta1s`` (deg, perturbations from trim, with sensor noise) as extra channels.
    """

    condition: str = "hover"
    airspeed_kt: float = attrs.field(default=0.0, converter=float,
                                     validator=_in_range(-1e-9, 200.0, "kt"))
    seed: int = attrs.field(default=0, converter=int)
    sample_rate: float = attrs.field(default=50.0, converter=float,
                                     validator=_in_range(0.0, 1000.0, "Hz"))
    substeps: int = attrs.field(default=2, converter=int, validator=_in_range(0, 100, "steps"))
    kinds: tuple = attrs.field(default=KINDS, converter=_choice(KINDS))
    axes: tuple = attrs.field(default=AXES, converter=_choice(AXES))
    directions: tuple = attrs.field(default=(1, -1), converter=_choice((1, -1)))
    duration_scale: float = attrs.field(default=1.0, converter=float,
                                        validator=_in_range(0.0, 1.0, ""))
    amplitude: dict = attrs.field(factory=dict, converter=_per_axis(AMPLITUDE))
    step_width: dict = attrs.field(factory=dict, converter=_per_axis(STEP_WIDTH))
    sweep_amplitude: dict = attrs.field(factory=dict, converter=_per_axis(SWEEP_AMPLITUDE))
    noise: SensorNoise = attrs.field(factory=SensorNoise, converter=lambda v: v if isinstance(
        v, SensorNoise) else SensorNoise(v))
    loops: LoopDesign = attrs.field(factory=LoopDesign, converter=lambda v: v if isinstance(
        v, LoopDesign) else LoopDesign(**v))
    turbulence: Turbulence | None = attrs.field(default=None, converter=turbulence_setting)
    rotor_channels: bool = attrs.field(default=False, validator=_boolean)

    @classmethod
    def for_condition(cls, name: str, **options) -> "DataSetConfig":
        """The configuration of a named condition (``"hover"`` or ``"forward"`` = 70 kt)."""
        if name not in CONDITIONS:
            raise DataError(f"unknown flight condition {name!r}; use one of "
                            f"{', '.join(CONDITIONS)} or give airspeed_kt")
        return cls(condition=name, airspeed_kt=CONDITIONS[name], **options)

    @classmethod
    def from_mapping(cls, settings: Mapping) -> "DataSetConfig":
        """Build from plain settings; ``quick=True`` means ``duration_scale=0.3``."""
        settings = dict(settings)
        if settings.pop("quick", False):
            settings.setdefault("duration_scale", 0.3)
        known = {a.name for a in attrs.fields(cls)}
        unknown = set(settings) - known
        if unknown:
            raise DataError(f"unknown data-set setting(s) {sorted(unknown)}; known: "
                            f"{', '.join(sorted(known | {'quick'}))}")
        name = settings.get("condition", "hover")
        if "airspeed_kt" not in settings and name in CONDITIONS:
            settings["airspeed_kt"] = CONDITIONS[name]
        return cls(**settings)

    @property
    def sample_time(self) -> float:
        return 1.0 / self.sample_rate

    def as_dict(self) -> dict:
        """Plain JSON-able settings (also the content hashed by :meth:`digest`). Still air
        leaves ``turbulence`` out and a set without rotor channels ``rotor_channels``, so
        such sets keep the keys they had before either existed."""
        def stated(attribute, value):
            return attribute.name not in _OPTIONAL or value != _OPTIONAL[attribute.name]

        return attrs.asdict(self, filter=stated,
                            value_serializer=lambda _, __, v: list(v)
                            if isinstance(v, tuple) else v)

    def digest(self, plant_id: str = "") -> str:
        """SHA-256 of the settings, the fixed input design of this module, the rotorid
        version and ``plant_id``: the cache key."""
        from rotorid import __version__

        design = {"sweep_omega": SWEEP_OMEGA, "sweep_time": SWEEP_TIME,
                  "sweep_amplitude_ratio": SWEEP_AMPLITUDE_RATIO,
                  "multistep_start": MULTISTEP_START, "multistep_record": MULTISTEP_RECORD}
        if self.turbulence is not None:         # sets cached before they carried the gusts
            design["gust_channels"] = list(GUST_CHANNELS)
        text = json.dumps({"config": self.as_dict(), "design": design, "plant": plant_id,
                           "version": __version__}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()


@attrs.frozen
class ManeuverSpec:
    """One maneuver of a data set: its name, kind, axis, direction (+1/−1) and pilot signal."""

    name: str
    kind: str
    axis: str
    direction: int
    signal: Multistep | Sweep


def _on_grid(seconds: float, sample_time: float) -> float:
    return max(1, round(seconds / sample_time)) * sample_time


def maneuver_specs(config: DataSetConfig) -> tuple[ManeuverSpec, ...]:
    """The Table-1 maneuvers selected by ``config`` (multisteps first, then sweeps)."""
    dt, scale = config.sample_time, config.duration_scale
    specs = []
    for kind in config.kinds:
        for axis in config.axes:
            if kind == "sweep":
                low, high = SWEEP_OMEGA
                signal = Sweep(config.sweep_amplitude[axis], low / scale, high,
                               SWEEP_TIME * scale, amplitude_ratio=SWEEP_AMPLITUDE_RATIO,
                               sample_time=dt)
                specs.append(ManeuverSpec(f"{config.condition}_sweep_{axis}", kind, axis, 1,
                                          signal))
                continue
            width = _on_grid(config.step_width[axis], dt)
            excitation = MULTISTEP_START + 7 * width
            trailing = max(MULTISTEP_RECORD * scale - excitation, 2.0)
            for direction in config.directions:
                label = "pos" if direction > 0 else "neg"
                signal = Multistep(kind, direction * config.amplitude[axis], width,
                                   start=MULTISTEP_START, trailing=trailing, sample_time=dt)
                specs.append(ManeuverSpec(f"{config.condition}_{kind}_{axis}_{label}", kind,
                                          axis, direction, signal))
    return tuple(specs)


@attrs.frozen(eq=False)
class Job:
    """A condition to fly: plant trim (state, stick) and the data-set configuration."""

    trim_state: np.ndarray
    trim_stick: np.ndarray
    config: DataSetConfig


def _pilot_block(specs, dt):
    counts = np.array([int(math.floor(s.signal.duration / dt + 1e-9)) + 1 for s in specs])
    time = np.arange(counts.max()) * dt
    pilot = np.zeros((len(specs), time.size, 4))
    for row, spec in enumerate(specs):
        pilot[row, :, AXES.index(spec.axis)] = spec.signal(time)
    return counts, pilot


def _gusts(rows, n_samples: int, dt: float) -> np.ndarray | None:
    """(B, N, 6) gusts of the maneuvers (zero in still air), None when every job flies in
    still air; each maneuver draws from its own seeded generator."""
    if all(job.config.turbulence is None for job, _ in rows):
        return None
    gusts = np.zeros((len(rows), n_samples, 6))
    for row, (job, spec) in enumerate(rows):
        turbulence = job.config.turbulence
        if turbulence is not None:
            gusts[row] = turbulence.gusts(n_samples, dt, job.config.airspeed_kt * KNOT,
                                          gust_generator(job.config.seed, spec.name))
    return gusts


def fly_jobs(plant, jobs, progress=None, plant_id: str = "", with_record: bool = False):
    """Fly every maneuver of every job as one batch; one :class:`ManeuverSet` per job.

    All jobs must share the sample rate and substeps (they share the time grid). With
    ``with_record`` the result is ``(sets, record, names)``: also the
    :class:`~.flight.FlightRecord` (plant states included) and the maneuver name of each row.
    """
    from .flight import fly

    rates = {(job.config.sample_rate, job.config.substeps) for job in jobs}
    if len(rates) != 1:
        raise DataError(f"conditions flown together need the same sample rate and substeps, "
                        f"got {sorted(rates)}")
    dt = jobs[0].config.sample_time
    rows, gains, trims, sticks = [], [], [], []
    for job in jobs:
        model = quasi_steady_model(plant, job.trim_state, job.trim_stick)
        theta0 = job.trim_state[tuple(plant.state_names).index("theta")]
        for spec in maneuver_specs(job.config):
            rows.append((job, spec))
            gains.append(design_loops(model, job.config.loops, spec.axis, theta0))
            trims.append(job.trim_state)
            sticks.append(job.trim_stick)
    counts, pilot = _pilot_block([spec for _, spec in rows], dt)
    gusts = _gusts(rows, pilot.shape[1], dt)
    record = fly(plant, np.array(trims), np.array(sticks), pilot, counts,
                 np.array([g.matrix for g in gains]), dt, jobs[0].config.substeps, progress,
                 gusts)
    trim_outputs = {id(job): plant.measurements(job.trim_state[None], job.trim_stick[None])[0]
                    for job in jobs}
    by_job = {id(job): [] for job in jobs}
    for row, ((job, spec), loop) in enumerate(zip(rows, gains)):
        n = counts[row]
        outputs = with_noise(perturbations(record.measurements[row, :n], trim_outputs[id(job)]),
                             job.config.noise, job.config.seed, spec.name)
        metadata = _metadata(job, spec, loop, plant_id, plant.state_names)
        metadata["excursion"] = excursion(record.states[row, :n], job.trim_state,
                                          plant.state_names)
        extra = {}
        if job.config.turbulence is not None:
            metadata["turbulence"] = job.config.as_dict()["turbulence"]
            extra.update(zip(GUST_CHANNELS, (gusts[row, :n] * GUST_SCALE).T))
        if job.config.rotor_channels:
            extra.update(with_rotor_noise(rotor_perturbations(record.states[row, :n],
                                                              job.trim_state, plant.state_names),
                                          job.config.noise, job.config.seed, spec.name))
        by_job[id(job)].append(Maneuver(spec.name, record.time[:n],
                                        record.stick[row, :n] - job.trim_stick, outputs,
                                        metadata, extra_channels=extra))
    sets = [ManeuverSet(by_job[id(job)]) for job in jobs]
    if with_record:
        return sets, record, [spec.name for _, spec in rows]
    return sets


def excursion(states, trim_state, state_names) -> dict:
    """Largest departures from trim over a record: attitudes in deg, speeds in kt.

    ``states`` (N, n_states) SI. ``airspeed_kt`` is the change of the total velocity's
    magnitude (no wind), ``u_kt v_kt w_kt`` the body components' changes.
    """
    index = {name: tuple(state_names).index(name) for name in ("u", "v", "w", "theta", "phi")}
    delta = np.abs(states - trim_state)
    velocity = states[:, [index["u"], index["v"], index["w"]]]
    trim_speed = np.linalg.norm(trim_state[[index["u"], index["v"], index["w"]]])
    result = {f"{k}_deg": math.degrees(delta[:, index[k]].max()) for k in ("theta", "phi")}
    result["airspeed_kt"] = float(np.abs(np.linalg.norm(velocity, axis=1) - trim_speed).max()
                                  / KNOT)
    result.update({f"{k}_kt": float(delta[:, index[k]].max() / KNOT) for k in ("u", "v", "w")})
    return result


def _metadata(job, spec, loop, plant_id, state_names) -> dict:
    config = job.config
    attitude = {name: math.degrees(job.trim_state[tuple(state_names).index(name)])
                for name in ("theta", "phi")}
    return {
        "condition": config.condition, "kind": spec.kind,
        "axis": spec.axis, "direction": spec.direction,
        "role": "verification" if spec.kind == "sweep" else "identification",
        "airspeed_kt": config.airspeed_kt, "seed": config.seed,
        "sample_rate_hz": config.sample_rate,
        "signal": {"type": type(spec.signal).__name__, **attrs.asdict(spec.signal)},
        "loop_gains": loop.as_dict(),
        "noise_sigma": dict(config.noise.sigma),
        "trim_stick_percent": [float(v) for v in job.trim_stick],
        "trim_theta_deg": attitude["theta"], "trim_phi_deg": attitude["phi"],
        "config_hash": config.digest(plant_id),
        "plant": plant_id,
    }
