"""The ``helisim`` data source: trims the truth model and flies the Table-1 data sets.

``HelisimSource().generate("hover")`` returns the 20 maneuvers of the hover data set;
``generate_many(["hover", "forward"])`` flies both conditions in one batch. With a
``cache_dir`` each condition's set is stored in ``cache_dir/<condition>/`` and read back while
its configuration (including the seed) is unchanged.

In a flight case (:meth:`HelisimSource.case_data`) the ``[data]`` settings are the data set's
(:class:`~.datasets.DataSetConfig`) with ``identification`` and ``verification`` naming the
maneuver kinds of each set (default: the paper's 3211/2311 multisteps and sweeps); the source
also serves as the case's truth model.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

import attrs
import numpy as np
from rotorid.data import ManeuverSet
from rotorid.errors import DataError
from rotorid.model.structure import FlightCondition
from rotorid.plugin.contracts import CaseData

from . import store
from .datasets import DataSetConfig, Job, fly_jobs
from .sensors import NoiseRealisations

#: The paper's split of a data set: multisteps identify, sweeps verify.
IDENTIFICATION_KINDS = ("3211", "2311")
VERIFICATION_KINDS = ("sweep",)


def resolve_case(case) -> DataSetConfig:
    """A :class:`DataSetConfig` from a condition name, a mapping of settings, a config, or
    any attrs object carrying some of the settings (other attributes are ignored)."""
    if isinstance(case, DataSetConfig):
        return case
    if isinstance(case, str):
        return DataSetConfig.for_condition(case)
    if isinstance(case, Mapping):
        return DataSetConfig.from_mapping(case)
    if attrs.has(type(case)):
        known = {a.name for a in attrs.fields(DataSetConfig)} | {"quick"}
        values = attrs.asdict(case, recurse=False)
        return DataSetConfig.from_mapping({k: v for k, v in values.items() if k in known})
    raise DataError(f"cannot build a helisim data set from {case!r}; give 'hover', 'forward', "
                    f"a mapping of settings or a DataSetConfig")


def _default_plant():
    from .model import Bo105Model

    return Bo105Model()


def _default_trim(plant, airspeed_kt: float):
    from .trim import trim

    return trim(plant, airspeed_kt)


def plant_id(plant) -> str:
    """Identity of a plant for the cache key: class path and its configuration, if any."""
    kind = f"{type(plant).__module__}.{type(plant).__qualname__}"
    config = getattr(plant, "config", None)
    return kind if config is None else f"{kind}:{config!r}"


@attrs.frozen(eq=False)
class HelisimSource:
    """Generates maneuver sets from a plant.

    Attributes:
        plant: the plant; by default a :class:`~.model.Bo105Model` with its default config.
        trimmer: ``trimmer(plant, airspeed_kt)`` returning an object with ``state`` and
            ``stick``; ``None`` uses :func:`~.trim.trim`.
        cache_dir: directory of cached sets (``None``: no cache).
        progress: optional callback receiving the completed fraction of a flight (0–1).
    """

    plant: object = attrs.field(factory=lambda: _default_plant())
    trimmer: Callable | None = None
    cache_dir: str | Path | None = None
    progress: Callable[[float], None] | None = None

    def trim(self, airspeed_kt: float = 0.0):
        """Trim of the plant in level flight at ``airspeed_kt``."""
        return (self.trimmer or _default_trim)(self.plant, airspeed_kt)

    def linearize(self, airspeed_kt: float = 0.0, **options):
        """Linear model of the truth model about its trim (delegates to :mod:`.linearize`)."""
        from .linearize import linearize

        return linearize(self.plant, self.trim(airspeed_kt), **options)

    def generate(self, case) -> ManeuverSet:
        """The data set of one case (``"hover"``, ``"forward"``, settings or a config)."""
        return self.generate_many([case])[0]

    def generate_many(self, cases: Iterable) -> list[ManeuverSet]:
        """Data sets of several cases; the ones not cached are flown together as one batch."""
        configs = [resolve_case(case) for case in cases]
        names = [c.condition for c in configs]
        if len(set(names)) != len(names):
            raise DataError(f"conditions must have distinct names, got {names}")
        identity = plant_id(self.plant)
        results: dict[int, ManeuverSet] = {}
        if self.cache_dir is not None:
            for index, config in enumerate(configs):
                cached = store.load_cached(self._directory(config), config.digest(identity))
                if cached is not None:
                    results[index] = cached
        todo = [i for i in range(len(configs)) if i not in results]
        if todo:
            jobs = []
            for index in todo:
                point = self.trim(configs[index].airspeed_kt)
                jobs.append(Job(np.asarray(point.state, dtype=float),
                                np.asarray(point.stick, dtype=float), configs[index]))
            for index, flown in zip(todo, fly_jobs(self.plant, jobs, self.progress, identity)):
                results[index] = flown
                if self.cache_dir is not None:
                    config = configs[index]
                    store.save(flown, self._directory(config), config.digest(identity),
                               config.as_dict())
        return [results[i] for i in range(len(configs))]

    def generate_into(self, case, directory) -> tuple[ManeuverSet, bool]:
        """The data set of ``case`` stored directly in ``directory``; flown only when the
        directory does not already hold it. Returns the set and whether it came from there."""
        config = resolve_case(case)
        digest = config.digest(plant_id(self.plant))
        cached = store.load_cached(directory, digest)
        if cached is not None:
            return cached, True
        flown = attrs.evolve(self, cache_dir=None).generate(config)
        store.save(flown, directory, digest, config.as_dict())
        return flown, False

    def case_data(self, settings: Mapping, directory) -> CaseData:
        """A flight case's identification and verification maneuvers, flown at their trim
        (stored in ``directory``), with this source as the truth model."""
        config, identification, verification = case_config(settings)
        flown, _ = self.generate_into(config, directory)
        condition = FlightCondition.from_airspeed(*(flown[0].metadata[key] for key in (
            "airspeed_kt", "trim_theta_deg", "trim_phi_deg")))
        return CaseData(_of_kinds(flown, identification), _of_kinds(flown, verification),
                        condition, self)

    def noise_realisations(self, settings: Mapping, directory
                           ) -> NoiseRealisations | TurbulentFlights:
        """A case's identification maneuvers for any noise seed, for Monte Carlo runs, equal
        to :meth:`case_data`'s for the same seed. In still air the noise-free set is flown
        once (stored in ``directory``) and each seed adds its own noise; in turbulence each
        seed flies its own gusts (:class:`TurbulentFlights`)."""
        config, identification, _ = case_config(settings)
        if config.turbulence is not None:
            return TurbulentFlights(self, attrs.evolve(config, kinds=identification),
                                    Path(directory))
        quiet = attrs.evolve(config, kinds=identification,
                             noise=config.noise.silenced(config.rotor_channels))
        clean, _ = self.generate_into(quiet, directory)
        return NoiseRealisations(clean, config.noise)

    def _directory(self, config: DataSetConfig) -> Path:
        return Path(self.cache_dir) / config.condition


@attrs.frozen(eq=False)
class TurbulentFlights:
    """Data sets in turbulence for any seed: ``flights(seed)`` flies ``config`` with that
    seed, so gusts and sensor noise are both drawn anew, and stores the set in
    ``directory/seed-<seed>`` (read back from there when it is already flown)."""

    source: HelisimSource
    config: DataSetConfig
    directory: Path

    def __call__(self, seed: int) -> ManeuverSet:
        """The data set flown with ``seed``."""
        flown, _ = self.source.generate_into(attrs.evolve(self.config, seed=int(seed)),
                                             self.directory / f"seed-{int(seed)}")
        return flown


def case_config(settings: Mapping) -> tuple[DataSetConfig, tuple[str, ...], tuple[str, ...]]:
    """The data set a case's ``[data]`` settings fly (every kind either set uses), and the
    identification and verification kinds."""
    settings = dict(settings)
    if "kinds" in settings:
        raise DataError("helisim case data: name the maneuver kinds as identification = [...] "
                        "and verification = [...] instead of kinds")
    identification = tuple(settings.pop("identification", IDENTIFICATION_KINDS))
    verification = tuple(settings.pop("verification", VERIFICATION_KINDS))
    if not identification:
        raise DataError("helisim case data: identification names no maneuver kind; use e.g. "
                        "identification = [\"3211\", \"2311\"]")
    config = DataSetConfig.from_mapping({**settings, "kinds": identification + verification})
    return config, identification, verification


def _of_kinds(maneuvers: ManeuverSet, kinds: tuple[str, ...]) -> ManeuverSet | None:
    """The maneuvers of ``kinds``, or ``None`` when there are none."""
    chosen = [m for m in maneuvers if m.metadata.get("kind") in kinds]
    return ManeuverSet(chosen, hold=maneuvers.hold) if chosen else None
