"""Flight cases: what a study identifies at one flight condition, declared as data.

A case names its data source and the maneuvers for identification and verification, the
structure, the estimator, the reduction criteria, the delays added after selection and the
verification envelopes. The built-in cases ``hover`` and ``forward`` (70 kt) ship as TOML files
in :mod:`rotorid.study.cases`; a user's own case is a TOML file of the same form, e.g. flight data::

    name = "my-hover"
    [data]
    source = "files"
    identification = "flight/hover/*.csv"
    verification = "flight/hover-sweeps/*.csv"
    [condition]
    airspeed_kt = 0.0
    theta0_deg = 2.5
    phi0_deg = -2.0
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from importlib import resources
from pathlib import Path

import attrs

from rotorid.errors import DataFileError, MissingFileError, StructureError

BUILTIN = ("hover", "forward")
_SECTIONS = {"name", "description", "data", "condition", "identification", "verification",
             "structure", "derivatives", "estimator", "reduction", "delays", "quick"}
_REDUCTION_KEYS = {"criteria", "continue_to_zero", "rule", "rmse_tolerance", "warm_start"}
_QUICK_KEYS = {"duration_scale", "continue_to_zero", "warm_start"}


def _table(mapping: Mapping, key: str, source: str) -> dict:
    value = mapping.get(key, {})
    if not isinstance(value, Mapping):
        raise DataFileError(f"{source}: [{key}] must be a table")
    return dict(value)


def _criteria(entries, source: str) -> tuple[tuple[str, dict], ...]:
    result = []
    for entry in entries:
        if isinstance(entry, str):
            result.append((entry, {}))
        elif isinstance(entry, Mapping) and "name" in entry:
            options = {k: v for k, v in entry.items() if k != "name"}
            result.append((entry["name"], options))
        else:
            raise DataFileError(f"{source}: each reduction criterion is a name or a table with "
                                f"'name' (and options such as threshold), got {entry!r}")
    if not result:
        raise DataFileError(f"{source}: [reduction] criteria must name at least one criterion")
    return tuple(result)


def _relative_to(mapping: Mapping, base: Path) -> dict:
    """The case with relative data-file paths (or globs) resolved against ``base``, the case
    file's folder, so that a case runs the same from any working directory."""
    data = mapping.get("data")
    if not isinstance(data, Mapping) or data.get("source") != "files":
        return dict(mapping)

    def resolve(entry):
        if isinstance(entry, str):
            return entry if Path(entry).is_absolute() else str(base / entry)
        if isinstance(entry, list):
            return [resolve(item) for item in entry]
        return entry

    data = {key: resolve(value) if key in ("identification", "verification") else value
            for key, value in data.items()}
    return {**mapping, "data": data}


@attrs.frozen
class FlightCase:
    """One flight case of a study (see the module docstring for the file form)."""

    name: str
    description: str = ""
    data: Mapping = attrs.field(factory=dict, converter=dict)
    condition: Mapping = attrs.field(factory=dict, converter=dict)
    identification_kinds: tuple[str, ...] = ("3211", "2311")
    verification_kinds: tuple[str, ...] = ("sweep",)
    pairs: tuple[str, ...] = ("q/long", "p/long", "q/lat", "p/lat", "r/coll", "az/coll",
                              "r/ped", "ay/ped")
    envelopes: tuple[str, ...] = ("muad", "aee", "mismatch-cost")
    structure: Mapping = attrs.field(factory=lambda: {"populate": "six-dof"}, converter=dict)
    derivatives: Mapping = attrs.field(factory=dict, converter=dict)
    estimator: str = "output-error"
    estimator_options: Mapping = attrs.field(factory=dict, converter=dict)
    criteria: tuple[tuple[str, Mapping], ...] = (("insensitivity", {}), ("cramer-rao", {}))
    continue_to_zero: bool = True
    rule: str = "lowest-rmse"
    rmse_tolerance: float = 0.01
    warm_start: bool = False
    delay_derivatives: tuple[str, ...] = ("L_p", "L_q", "L_long", "L_lat", "M_p", "M_q",
                                          "M_long", "M_lat")
    delay_initial: float = 0.0
    delay_upper: float | None = 0.3
    delay_starts: int = attrs.field(default=1, validator=attrs.validators.ge(1))
    delay_seed: int = 0
    quick_settings: Mapping = attrs.field(factory=dict, converter=dict)
    is_quick: bool = False

    # ----------------------------------------------------------------- construction
    @classmethod
    def from_mapping(cls, mapping: Mapping, source: str = "<case>") -> "FlightCase":
        """Build a case from a parsed TOML document; unknown keys are errors."""
        unknown = set(mapping) - _SECTIONS
        if unknown:
            raise DataFileError(f"{source}: unknown key(s) {sorted(unknown)}; "
                                f"known: {', '.join(sorted(_SECTIONS))}")
        if "name" not in mapping:
            raise DataFileError(f"{source}: a case needs a name")
        data = _table(mapping, "data", source)
        if "source" not in data:
            raise DataFileError(f"{source}: [data] needs a source ('helisim' or 'files')")
        ident = _table(mapping, "identification", source)
        verif = _table(mapping, "verification", source)
        estimator = _table(mapping, "estimator", source)
        reduction = _table(mapping, "reduction", source)
        delays = _table(mapping, "delays", source)
        quick = _table(mapping, "quick", source)
        for table, keys, label in ((reduction, _REDUCTION_KEYS, "reduction"),
                                   (quick, _QUICK_KEYS, "quick"),
                                   (delays, {"derivatives", "initial", "upper", "starts",
                                             "seed"}, "delays")):
            extra = set(table) - keys
            if extra:
                raise DataFileError(f"{source}: [{label}] unknown key(s) {sorted(extra)}; "
                                    f"known: {', '.join(sorted(keys))}")
        if int(delays.get("starts", 1)) < 1:
            raise DataFileError(f"{source}: [delays] starts must be at least 1 (the fit from "
                                f"the initial delays), got {delays['starts']}")
        defaults = cls(name="defaults")
        kwargs = dict(
            name=str(mapping["name"]), description=str(mapping.get("description", "")),
            data=data, condition=_table(mapping, "condition", source),
            identification_kinds=tuple(ident.get("kinds", defaults.identification_kinds)),
            verification_kinds=tuple(verif.get("kinds", defaults.verification_kinds)),
            pairs=tuple(verif.get("pairs", defaults.pairs)),
            envelopes=tuple(verif.get("envelopes", defaults.envelopes)),
            structure=_table(mapping, "structure", source) or defaults.structure,
            derivatives=_table(mapping, "derivatives", source),
            estimator=str(estimator.pop("name", defaults.estimator)),
            estimator_options=estimator,
            delay_derivatives=tuple(delays.get("derivatives", defaults.delay_derivatives)),
            delay_initial=float(delays.get("initial", defaults.delay_initial)),
            delay_upper=delays.get("upper", defaults.delay_upper),
            delay_starts=int(delays.get("starts", defaults.delay_starts)),
            delay_seed=int(delays.get("seed", defaults.delay_seed)),
            quick_settings=quick)
        if "criteria" in reduction:
            kwargs["criteria"] = _criteria(reduction.pop("criteria"), source)
        kwargs.update(reduction)
        return cls(**kwargs)

    @classmethod
    def load(cls, name_or_path: str | Path) -> "FlightCase":
        """A built-in case by name (``hover``, ``forward``) or a case TOML file."""
        if str(name_or_path) in BUILTIN:
            text = resources.files("rotorid.study.cases").joinpath(f"{name_or_path}.toml").read_text()
            return cls.from_mapping(tomllib.loads(text), f"built-in case {name_or_path}")
        path = Path(name_or_path)
        if not path.is_file():
            raise MissingFileError(f"no built-in case or case file {str(name_or_path)!r}; "
                                   f"built-in cases: {', '.join(BUILTIN)}")
        try:
            mapping = tomllib.loads(path.read_text(encoding="utf-8"))
        except tomllib.TOMLDecodeError as error:
            raise DataFileError(f"{path}: not valid TOML: {error}") from None
        return cls.from_mapping(_relative_to(mapping, path.parent), str(path))

    # ----------------------------------------------------------------- variants
    def quick(self) -> "FlightCase":
        """The reduced but honest variant: shorter records, criteria-stopped reduction."""
        settings = dict(self.quick_settings)
        data = dict(self.data)
        if "duration_scale" in settings:
            data["duration_scale"] = settings.pop("duration_scale")
        return attrs.evolve(self, data=data, is_quick=True, **settings)

    def with_seed(self, seed: int) -> "FlightCase":
        """The case with another noise seed for generated data."""
        if self.data.get("source") != "helisim":
            raise StructureError(f"case {self.name}: a seed only applies to generated data")
        return attrs.evolve(self, data={**self.data, "seed": int(seed)})

    def as_dict(self) -> dict:
        """Plain settings, as recorded in ``result.json``."""
        return attrs.asdict(self)
