"""Flight cases: what a study identifies at one flight condition, declared as data.

A case names its data source and the data settings, the structure, the estimator, the
reduction criteria, the delays added after selection and the verification pairs and
envelopes. The built-in cases ``hover`` and ``forward`` (70 kt) ship as TOML files in
:mod:`rotorid.study.cases`; a user's own case is a TOML file of the same form, e.g. flight
data::

    name = "my-hover"
    [data]
    source = "files"
    identification = "flight/hover/*.csv"
    verification = "flight/hover-sweeps/*.csv"
    [condition]
    airspeed_kt = 0.0
    theta0_deg = 2.5
    phi0_deg = -2.0

Every setting is checked when the case is read (:mod:`rotorid.study.checks`), before any
data exist.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable, Mapping
from importlib import resources
from pathlib import Path

import attrs

from rotorid.actuators import lagged_inputs
from rotorid.errors import DataFileError, MissingFileError, VerificationError
from rotorid.io import read_toml
from rotorid.model.structure import PAPER_DELAYED
from rotorid.plugin.manager import create
from rotorid.resampling import decimated, low_passed
from rotorid.study.checks import check_case, check_registered
from rotorid.study.hybrid_comparison import HYBRID_OMEGA_MAX
from rotorid.study.reference import ReferenceValue, parse_reference
from rotorid.verification.band import BAND_KEYS, DEFAULT_BAND, VerificationBand
from rotorid.verification.compare import PAPER_ENVELOPES

BUILTIN = ("hover", "forward")
#: Templates whose rotor dynamics the paper's delays stand for.
HELICOPTER_TEMPLATES = ("six-dof", "longitudinal", "lateral")
#: Tables of a case file and the keys each may hold (``None``: checked where it is used).
_TABLES = {
    "data": None, "condition": None, "structure": None, "derivatives": None, "estimator": None,
    "verification": {"pairs", "envelopes", *BAND_KEYS},
    "reduction": {"criteria", "continue_to_zero", "rule", "rmse_tolerance", "warm_start"},
    "delays": {"derivatives", "initial", "upper", "threshold", "starts", "seed",
               "profile_points"},
    "quick": {"duration_scale", "continue_to_zero", "warm_start", "delay_profile_points"},
    "compare": {"frequency", "pairs", "band_max", "estimators", "hybrid", "hybrid_band_max",
                "hybrid_reduction"},
    "reference": None,
    "resampling": {"cutoff_hz", "decimate", "hold"},
    "actuators": {"lag_s", "inputs"},
}
_TOP_LEVEL = {"name", "description", *_TABLES}
#: Case settings by table and key: the :class:`FlightCase` field and its converter.
_FIELDS = {
    ("verification", "pairs"): ("pairs", tuple),
    ("verification", "envelopes"): ("envelopes", tuple),
    ("reduction", "continue_to_zero"): ("continue_to_zero", bool),
    ("reduction", "rule"): ("rule", str),
    ("reduction", "rmse_tolerance"): ("rmse_tolerance", float),
    ("reduction", "warm_start"): ("warm_start", bool),
    ("delays", "derivatives"): ("delay_derivatives", tuple),
    ("delays", "initial"): ("delay_initial", float),
    ("delays", "upper"): ("delay_upper", float),
    ("delays", "threshold"): ("delay_threshold", float),
    ("delays", "starts"): ("delay_starts", int),
    ("delays", "seed"): ("delay_seed", int),
    ("delays", "profile_points"): ("delay_profile_points", int),
    ("compare", "frequency"): ("compare_frequency", bool),
    ("compare", "pairs"): ("compare_pairs", tuple),
    ("compare", "band_max"): ("compare_band_max", float),
    ("compare", "estimators"): ("compare_estimators", tuple),
    ("compare", "hybrid"): ("compare_hybrid", bool),
    ("compare", "hybrid_band_max"): ("compare_hybrid_band_max", float),
    ("compare", "hybrid_reduction"): ("compare_hybrid_reduction", bool),
    ("resampling", "cutoff_hz"): ("cutoff_hz", float),
    ("resampling", "decimate"): ("decimate", int),
    ("resampling", "hold"): ("identification_hold", str),
    ("actuators", "lag_s"): ("actuator_lag_s", float),
    ("actuators", "inputs"): ("actuator_inputs", tuple),
}

#: What each converter of :data:`_FIELDS` reads, for the error messages.
_KINDS = {tuple: "a list", bool: "true or false", float: "a number", int: "an integer",
          str: "a string"}


@attrs.frozen
class FlightCase:
    """One flight case of a study (see the module docstring for the file form).

    ``data`` is the ``[data]`` table: ``source`` names the data source, the other keys are
    its settings. ``band`` is the verification band every frequency-domain verdict counts
    points in (``[verification] coherence``, ``omega_min``, ``omega_max`` in rad/s; default
    γ² ≥ 0.8 over 0.1–10 rad/s). ``reference`` holds the user's reference values by
    derivative name (``[reference]``, :mod:`rotorid.study.reference`). Delay bounds and the initial delay are in s; ``delay_threshold`` is the
    normalised Cramér-Rao bound (%) above which a delay counts as undetermined and is dropped.
    With ``compare_frequency`` each identified model is also fitted to the verification
    sweeps' frequency responses (:mod:`rotorid.study.comparison`) on ``compare_pairs``
    (default: the verification pairs) and the on-axis translational accelerations up to
    ``compare_band_max`` rad/s (default: each pair's coherent range). With ``compare_estimators`` each listed estimator also fits the model
    with delays to the identification data (:mod:`rotorid.study.estimator_comparison`). With
    ``compare_hybrid`` the hybrid rotor-body model is built on the selected model and compared
    with both (:mod:`rotorid.study.hybrid_comparison`), J up to ``compare_hybrid_band_max``
    rad/s (the sweeps' top frequency; default 20); with ``compare_hybrid_reduction`` the hybrid
    is first reduced by the case's criteria and selection rule.
    Empty ``pairs`` are the structure's own default pairs
    (:func:`rotorid.verification.pairs.default_pairs`: the paper's pairs it has).
    ``delay_profile_points`` is the number of grid values in [0, ``delay_upper``] of each kept
    delay's profile (0: no profiles). With ``cutoff_hz`` (``[resampling]``) the
    identification records are low-passed there and kept at every ``decimate``-th sample
    before any fit (:meth:`identification_records`; ``decimate`` by default the factor that
    keeps the sensor noise white), in the study and in its Monte Carlo runs alike;
    ``identification_hold`` (``[resampling] hold``) sets their input hold. With
    ``actuator_lag_s`` (``[actuators] lag_s``) every record, identification and verification
    alike, has its inputs (``actuator_inputs``, ``[actuators] inputs``; default all) passed
    through the actuators' known first-order lag first (:func:`rotorid.actuators.lagged_inputs`):
    the models then map the actuators' output, not the stick, to the response.
    """

    name: str
    description: str = ""
    data: Mapping = attrs.field(factory=dict, converter=dict)
    condition: Mapping = attrs.field(factory=dict, converter=dict)
    pairs: tuple[str, ...] = ()
    envelopes: tuple[str, ...] = PAPER_ENVELOPES
    band: VerificationBand = DEFAULT_BAND
    reference: Mapping[str, ReferenceValue] = attrs.field(factory=dict, converter=dict)
    structure: Mapping = attrs.field(factory=lambda: {"populate": "all"}, converter=dict)
    derivatives: Mapping = attrs.field(factory=dict, converter=dict)
    estimator: str = "output-error"
    estimator_options: Mapping = attrs.field(factory=dict, converter=dict)
    criteria: tuple[tuple[str, Mapping], ...] = (("insensitivity", {}), ("cramer-rao", {}))
    continue_to_zero: bool = True
    rule: str = "lowest-rmse"
    rmse_tolerance: float = 0.01
    warm_start: bool = False
    delay_derivatives: tuple[str, ...] | None = None   # None: the paper's that the structure has
    delay_initial: float = 0.0
    delay_upper: float = 0.3
    delay_threshold: float = 20.0        # the paper's Cramér-Rao threshold
    delay_starts: int = attrs.field(default=1, validator=attrs.validators.ge(1))
    delay_seed: int = 0
    delay_profile_points: int = attrs.field(default=0, validator=attrs.validators.ge(0))
    compare_frequency: bool = False
    compare_pairs: tuple[str, ...] = ()
    compare_band_max: float | None = None
    compare_estimators: tuple[str, ...] = ()
    compare_hybrid: bool = False
    compare_hybrid_band_max: float = HYBRID_OMEGA_MAX
    compare_hybrid_reduction: bool = False
    cutoff_hz: float | None = None
    decimate: int | None = None
    identification_hold: str | None = None
    actuator_lag_s: float | None = None
    actuator_inputs: tuple[str, ...] | None = None
    quick_settings: Mapping = attrs.field(factory=dict, converter=dict)
    is_quick: bool = False

    def delayed(self, template: str) -> tuple[str, ...]:
        """The derivatives to delay in a structure of ``template`` (its name):
        ``[delays] derivatives``, by default the paper's eight for the helicopter templates
        (those the reduced structure still has are delayed) and none for any other model."""
        if self.delay_derivatives is not None:
            return self.delay_derivatives
        return PAPER_DELAYED if template in HELICOPTER_TEMPLATES else ()

    @property
    def data_source(self) -> str:
        """Name of the registered data source (``[data] source``)."""
        return self.data["source"]

    @property
    def keeps_every_sample(self) -> bool:
        """True when the estimator updates once per several samples (the filter-error
        estimator's ``update_every``): the low-passed records are then not decimated."""
        return self.estimator_options.get("update_every", 1) != 1

    @property
    def data_settings(self) -> dict:
        """The data source's settings: ``[data]`` without ``source``."""
        return {k: v for k, v in self.data.items() if k != "source"}

    def identification_records(self, maneuvers):
        """The identification ``maneuvers`` as the fits see them: low-passed at ``cutoff_hz``
        and decimated (:func:`rotorid.resampling.decimated`), with ``identification_hold``;
        unchanged without those settings. With the filter-error estimator's ``update_every``
        the low-passed records keep every sample (:func:`rotorid.resampling.low_passed`): the
        filter then updates once per that many. The actuators' lag (``actuator_lag_s``)
        comes first."""
        maneuvers = self.actuated(maneuvers)
        if self.cutoff_hz is not None and self.keeps_every_sample:
            maneuvers = low_passed(maneuvers, self.cutoff_hz)
        elif self.cutoff_hz is not None:
            maneuvers = decimated(maneuvers, self.decimate, self.cutoff_hz)
        if self.identification_hold is not None:
            maneuvers = attrs.evolve(maneuvers, hold=self.identification_hold)
        return maneuvers

    def actuated(self, maneuvers):
        """``maneuvers`` (or None) with the inputs through the actuators' known lag
        (``[actuators]``), as every model of the case sees them; unchanged without it."""
        if maneuvers is None or self.actuator_lag_s is None:
            return maneuvers
        return lagged_inputs(maneuvers, self.actuator_lag_s, self.actuator_inputs)

    def verification_records(self, maneuvers):
        """The verification ``maneuvers`` (or None) as the models see them: through the
        actuators' lag (:meth:`actuated`) and with ``identification_hold``, the records' input
        hold, which the sweeps share with the identification records."""
        maneuvers = self.actuated(maneuvers)
        if maneuvers is None or self.identification_hold is None:
            return maneuvers
        return attrs.evolve(maneuvers, hold=self.identification_hold)

    @property
    def frequency_pairs(self) -> tuple[str, ...]:
        """The pairs the frequency-domain comparison compares (``[compare] pairs``, default
        the verification pairs); it fits them with the translational accelerations."""
        return self.compare_pairs or self.pairs

    # ----------------------------------------------------------------- construction
    @classmethod
    def from_mapping(cls, mapping: Mapping, source: str = "<case>",
                     folder: Path | None = None) -> "FlightCase":
        """Build and check a case from a parsed TOML document (``source`` names it in
        errors); relative file settings of its data source are read from ``folder``."""
        tables = _tables(mapping, source)
        if "name" not in mapping:
            raise DataFileError(f"{source}: a case needs a name, e.g. name = \"my-hover\"")
        data = tables["data"]
        if "source" in data:              # the files it names are read from the case's folder
            check_registered("data-sources", data["source"], source, "[data] source")
        estimator = dict(tables["estimator"])
        case = cls(name=str(mapping["name"]), description=str(mapping.get("description", "")),
                   data=_resolved(data, folder), condition=tables["condition"],
                   structure=tables["structure"] or {"populate": "all"},
                   derivatives=tables["derivatives"],
                   estimator=str(estimator.pop("name", "output-error")),
                   estimator_options=estimator, quick_settings=tables["quick"],
                   reference=parse_reference(tables["reference"], f"{source}: [reference]"),
                   **_settings(tables, source))
        check_case(case, source)
        return case

    @classmethod
    def load(cls, name_or_path: str | Path) -> "FlightCase":
        """A built-in case by name (``hover``, ``forward``) or a case TOML file."""
        if str(name_or_path) in BUILTIN:
            text = resources.files("rotorid.study.cases").joinpath(
                f"{name_or_path}.toml").read_text()
            return cls.from_mapping(tomllib.loads(text), f"built-in case {name_or_path}")
        path = Path(name_or_path)
        if not path.exists():
            raise MissingFileError(f"no built-in case or case file {str(name_or_path)!r}; "
                                   f"built-in cases: {', '.join(BUILTIN)}")
        return cls.from_mapping(read_toml(path, "case file"), str(path), path.parent)

    @property
    def run_label(self) -> str:
        """``"quick set"`` or ``"full set"`` of data a source generates; for recorded files
        ``"quick run"`` under a ``[quick]`` table (the files are what they are), else ``""``."""
        if self.data_source == "files":
            return "quick run" if self.is_quick else ""
        return "quick set" if self.is_quick else "full set"

    # ----------------------------------------------------------------- variants
    def quick(self) -> "FlightCase":
        """The reduced but honest variant: shorter records, criteria-stopped reduction (the
        case's ``[quick]`` table); the case itself when it has none."""
        if not self.quick_settings:
            return self
        settings = dict(self.quick_settings)
        data = dict(self.data)
        if "duration_scale" in settings:
            data["duration_scale"] = settings.pop("duration_scale")
        return attrs.evolve(self, data=data, is_quick=True, **settings)

    def with_seed(self, seed: int) -> "FlightCase":
        """The case with another noise seed for generated data (``[data] seed``)."""
        return attrs.evolve(self, data={**self.data, "seed": int(seed)})

    def as_dict(self) -> dict:
        """Plain settings, as recorded in ``result.json``; ``compare_estimators``,
        ``compare_hybrid``, ``compare_hybrid_reduction``, the ``[resampling]`` and the
        ``[actuators]`` settings only when set, so that cases without them keep the record
        they had before those settings existed."""
        return attrs.asdict(self, filter=lambda a, v: not (
            a.name in ("compare_estimators", "compare_hybrid", "compare_hybrid_reduction",
                       "cutoff_hz", "decimate", "identification_hold", "actuator_lag_s",
                       "actuator_inputs")
            and not v
            or a.name == "compare_hybrid_band_max" and not self.compare_hybrid))


def _tables(mapping: Mapping, source: str) -> dict[str, dict]:
    """Every table of a case file (empty when absent), checked for unknown keys."""
    unknown = set(mapping) - _TOP_LEVEL
    if unknown:
        raise DataFileError(f"{source}: unknown key(s) {sorted(unknown)}; known: "
                            f"{', '.join(sorted(_TOP_LEVEL))}")
    tables = {}
    for key, known in _TABLES.items():
        table = mapping.get(key, {})
        if not isinstance(table, Mapping):
            raise DataFileError(f"{source}: [{key}] must be a table")
        extra = set(table) - known if known is not None else set()
        if extra:
            raise DataFileError(f"{source}: [{key}] unknown key(s) {sorted(extra)}; known: "
                                f"{', '.join(sorted(known))}")
        tables[key] = dict(table)
    return tables


def _settings(tables: Mapping[str, dict], source: str) -> dict:
    """The :class:`FlightCase` fields the case's tables set, converted."""
    fields = {}
    for (table, key), (field, convert) in _FIELDS.items():
        if key in tables[table]:
            fields[field] = _converted(tables[table][key], convert, source, f"[{table}] {key}")
    if "criteria" in tables["reduction"]:
        fields["criteria"] = _criteria(tables["reduction"]["criteria"], source)
    if set(BAND_KEYS) & set(tables["verification"]):
        try:
            fields["band"] = VerificationBand.from_mapping(tables["verification"],
                                                           f"{source}: [verification]")
        except VerificationError as error:
            raise DataFileError(str(error)) from None
    if fields.get("delay_starts", 1) < 1:
        raise DataFileError(f"{source}: [delays] starts must be at least 1 (the fit from the "
                            f"initial delays), got {fields['delay_starts']}")
    return fields


def _converted(value, convert: Callable, source: str, key: str):
    if (convert is tuple and isinstance(value, str)) or (convert is bool
                                                          and not isinstance(value, bool)):
        raise DataFileError(f"{source}: {key} must be {_KINDS[convert]}, got {value!r}")
    try:
        return convert(value)
    except (TypeError, ValueError):
        raise DataFileError(f"{source}: {key} must be {_KINDS[convert]}, got "
                            f"{value!r}") from None


def _criteria(entries, source: str) -> tuple[tuple[str, dict], ...]:
    result = []
    for entry in entries if isinstance(entries, list) else [entries]:
        if isinstance(entry, str):
            result.append((entry, {}))
        elif isinstance(entry, Mapping) and "name" in entry:
            options = {k: v for k, v in entry.items() if k != "name"}
            result.append((entry["name"], options))
        else:
            raise DataFileError(f"{source}: [reduction] criteria: each is a name or a table "
                                f"with 'name' (and options such as threshold), got {entry!r}")
    if not result:
        raise DataFileError(f"{source}: [reduction] criteria must name at least one criterion")
    return tuple(result)


def _resolved(data: Mapping, folder: Path | None) -> dict:
    """``data`` with the relative file settings its source declares (``path_settings``)
    resolved against ``folder``, the case file's, so that a case runs the same from any
    working directory."""
    if folder is None or "source" not in data:
        return dict(data)
    source = create("data-sources", data["source"])

    def resolve(entry):
        if isinstance(entry, str):
            return entry if Path(entry).is_absolute() else str(folder / entry)
        if isinstance(entry, list):
            return [resolve(item) for item in entry]
        return entry

    return {key: resolve(value) if key in getattr(source, "path_settings", ()) else value
            for key, value in data.items()}
