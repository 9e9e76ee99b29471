"""Estimates and their statistics.

An :class:`Estimate` is the immutable result of a parameter estimation: values, Cramér-Rao
bounds, insensitivities, correlations, the noise covariance, the cost and RMSE history and how
the iteration stopped. Estimator plugins build it with :meth:`Estimate.from_fit`, which takes
the statistics from the information matrix (:func:`statistics`) and the noise covariance, cost
and RMSE from the residuals, so every estimator reports the same quantities the same way:

    CR_i = sqrt((F⁻¹)_ii)          normalised: |CR_i / Θ_i|·100 %   (paper eqs. 13-14)
    I_i  = 1 / sqrt(F_ii)          normalised: |I_i / Θ_i|·100 %    (paper eqs. 15-16)
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Mapping

import attrs
import numpy as np

from rotorid.errors import EstimationError, IdentifiabilityWarning
from rotorid.frozen import readonly_array
from rotorid.model.derivatives import delay_parameter, delayed_derivative
from rotorid.model.parameter_units import structure_parameter_units
from rotorid.model.structure import ModelStructure
from rotorid.notebook import estimate_html, estimate_summary
from rotorid.units import RMSE_REFERENCE_UNITS, UNITS, rmse_reference_factors

#: Condition number of the scaled information matrix above which parameters count as nearly
#: unidentifiable.
ILL_CONDITIONED = 1e10


@attrs.frozen
class ParameterStatistics:
    """Uncertainty measures derived from the information matrix F (P×P)."""

    cramer_rao: np.ndarray = attrs.field(converter=readonly_array)
    insensitivity: np.ndarray = attrs.field(converter=readonly_array)
    correlation: np.ndarray = attrs.field(converter=readonly_array)
    unidentifiable: tuple[tuple[str, ...], ...] = ()


def _normalised(measure: np.ndarray, values: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        pct = np.abs(measure / values) * 100.0
    return np.where(values == 0.0, np.inf, pct)


def statistics(information: np.ndarray, names) -> ParameterStatistics:
    """Cramér-Rao bounds, insensitivities and correlations from the information matrix.

    The inverse is taken on the diagonally scaled matrix. When it is ill-conditioned an
    :class:`IdentifiabilityWarning` names the parameter combinations behind the smallest
    eigenvalues; those parameters get infinite Cramér-Rao bounds (never a silent
    pseudo-inverse).
    """
    f = np.asarray(information, dtype=float)
    names = tuple(names)
    if f.shape != (len(names), len(names)):
        raise EstimationError(f"information matrix must be a {len(names)}×{len(names)} array, "
                              f"got shape {f.shape}")
    if not np.all(np.isfinite(f)):
        unfinished = sorted({names[i] for i in np.argwhere(~np.isfinite(f))[:, 0]})
        raise EstimationError(f"the information matrix is not finite in the rows of "
                              f"{', '.join(unfinished)}: the sensitivities overflow at the "
                              f"estimate; check the model's stability there")
    diag = np.diag(f).copy()
    insensitivity = np.where(diag > 0, 1.0 / np.sqrt(np.maximum(diag, 1e-300)), np.inf)
    scale = np.where(diag > 0, np.sqrt(np.maximum(diag, 1e-300)), 1.0)
    scaled = f / np.outer(scale, scale)
    eigval, eigvec = np.linalg.eigh(scaled)
    top = max(eigval[-1], 1e-300) if eigval.size else 1.0
    weak = eigval <= top / ILL_CONDITIONED
    combos: list[tuple[str, ...]] = []
    if np.any(weak):
        for k in np.flatnonzero(weak):
            vec = eigvec[:, k]
            members = np.flatnonzero(np.abs(vec) >= 0.2 * np.abs(vec).max())
            combo = tuple(names[i] for i in members)
            if combo not in combos:
                combos.append(combo)
        warnings.warn(IdentifiabilityWarning(
            "information matrix is ill-conditioned; nearly unidentifiable combination(s): "
            + "; ".join(" + ".join(c) for c in combos)
            + ". Their Cramér-Rao bounds are reported as infinite; remove or fix one parameter "
              "of each combination, or add excitation."), stacklevel=2)
    good = ~weak
    inv_scaled = (eigvec[:, good] / eigval[good]) @ eigvec[:, good].T
    covariance = inv_scaled / np.outer(scale, scale)
    variance = np.diag(covariance).copy()
    involved = np.zeros(len(names), dtype=bool)
    for k in np.flatnonzero(weak):
        vec = eigvec[:, k]
        involved |= np.abs(vec) >= 0.2 * np.abs(vec).max()
    cramer_rao = np.where(involved | (diag <= 0), np.inf, np.sqrt(np.maximum(variance, 0.0)))
    with np.errstate(divide="ignore", invalid="ignore"):
        sd = np.sqrt(np.maximum(variance, 1e-300))
        correlation = covariance / np.outer(sd, sd)
    correlation = np.clip(np.nan_to_num(correlation), -1.0, 1.0)
    return ParameterStatistics(cramer_rao, insensitivity, correlation, tuple(combos))


def rmse(residuals: np.ndarray) -> float:
    """The paper's eq. 18: sqrt(Σ (z − y)ᵀ(z − y) / (N·n_o)) over (N, n_o) residuals."""
    residuals = np.asarray(residuals, dtype=float)
    return float(np.sqrt(np.mean(residuals**2)))


def rmse_counted_units(output_units) -> tuple[str, ...]:
    """The distinct reference units (:data:`rotorid.units.RMSE_REFERENCE_UNITS`) the residuals
    of outputs in ``output_units`` count in for the RMSE, in output order; ``()`` when an
    output has none, so that the RMSE mixes units."""
    if rmse_reference_factors(output_units) is None:
        return ()
    return tuple(dict.fromkeys(RMSE_REFERENCE_UNITS[UNITS[u][0]] for u in output_units))


def rmse_unit(output_units) -> str:
    """The unit label of an RMSE over outputs in ``output_units``: ``-`` where it is a pure
    number (:func:`rmse_counted_units`), else ``mixed units``."""
    return "-" if rmse_counted_units(output_units) else "mixed units"


def rmse_basis(output_units) -> str:
    """What makes the RMSE over outputs in ``output_units`` a pure number: the reference
    units its residuals are counted in (:func:`rmse_counted_units`); ``""`` when an output
    has none, so that the RMSE mixes units."""
    counted = rmse_counted_units(output_units)
    return (f"dimensionless: eq. 18 with the residuals counted in {', '.join(counted)}"
            if counted else "")


# attrs metadata that drive the JSON record (Estimate.as_dict / from_dict):
#: (P,) array stored per parameter, under this key of the parameter's entry;
_COLUMN = "column"
#: its normalised form (a property of the same name) stored next to it;
_NORMALISED = "normalised"
#: a name → text mapping stored per derivative (not per delay) under this key;
_PER_DERIVATIVE = "per_derivative"
#: a name → text mapping stored per parameter (delays included) under this key;
_PER_PARAMETER = "per_parameter"
#: a field stored under another key of the record;
_KEY = "key"
#: a (P, P) array (reshaped on reading, so that P = 0 round-trips).
_SQUARE = "square"


@attrs.frozen
class ParameterEstimate:
    """One parameter of an :class:`Estimate` (``estimate["L_p"]``).

    ``cramer_rao_pct`` and ``insensitivity_pct`` are normalised by the value (inf at 0);
    ``sign`` is the prior (``"negative"``, ``"positive"`` or ``"none"``); ``unit`` the unit of
    the value and the bounds (``""`` when the model does not say).
    """

    name: str
    value: float
    start: float
    cramer_rao: float
    cramer_rao_pct: float
    insensitivity: float
    insensitivity_pct: float
    sign: str
    unit: str = ""


@attrs.frozen(eq=False)
class Estimate:
    """The result of one estimation (immutable).

    Array attributes are read-only; shapes: ``values``, ``start``, ``cramer_rao``,
    ``insensitivity`` (P,), ``correlation`` and ``information`` (P, P), ``noise_covariance``
    (n_o, n_o), ``residual_rms`` (n_o,) or (0,) when the estimator gives none. Units follow
    the model (flight-test by default): ``output_units`` per output, ``parameter_units`` per
    parameter (delays in s). ``rmse`` is dimensionless when ``rmse_basis`` says how; an empty
    ``rmse_basis`` means it mixes the outputs' units and is not reported.
    An estimator builds one with :meth:`from_fit`; ``estimate["L_p"]`` gives one parameter.
    """

    estimator: str
    parameter_names: tuple[str, ...] = attrs.field(converter=tuple)
    values: np.ndarray = attrs.field(converter=readonly_array, metadata={_COLUMN: "value"})
    start: np.ndarray = attrs.field(converter=readonly_array)
    cramer_rao: np.ndarray = attrs.field(
        converter=readonly_array, metadata={_COLUMN: "cramer_rao", _NORMALISED: "cramer_rao_pct"})
    insensitivity: np.ndarray = attrs.field(
        converter=readonly_array,
        metadata={_COLUMN: "insensitivity", _NORMALISED: "insensitivity_pct"})
    correlation: np.ndarray = attrs.field(converter=readonly_array, metadata={_SQUARE: True})
    information: np.ndarray = attrs.field(converter=readonly_array, metadata={_SQUARE: True})
    noise_covariance: np.ndarray = attrs.field(converter=readonly_array)
    output_names: tuple[str, ...] = attrs.field(converter=tuple, metadata={_KEY: "outputs"})
    cost: float
    rmse: float
    cost_history: tuple[float, ...] = attrs.field(converter=tuple)
    rmse_history: tuple[float, ...] = attrs.field(converter=tuple)
    iterations: int
    converged: bool
    stop_reason: str
    n_samples: int
    sign_violations: tuple[str, ...] = attrs.field(default=(), converter=tuple)
    at_bound: tuple[str, ...] = attrs.field(default=(), converter=tuple)
    unidentifiable: tuple[tuple[str, ...], ...] = attrs.field(
        default=(), converter=lambda combos: tuple(tuple(c) for c in combos))
    fixed: Mapping[str, float] = attrs.field(factory=dict, converter=dict)
    signs: Mapping[str, str] = attrs.field(factory=dict, converter=dict,
                                           metadata={_PER_DERIVATIVE: "sign"})
    units: str = "flight-test"
    notes: tuple[str, ...] = attrs.field(default=(), converter=tuple)
    output_units: tuple[str, ...] = attrs.field(default=(), converter=tuple)
    residual_rms: np.ndarray = attrs.field(factory=lambda: np.zeros(0),
                                           converter=readonly_array)
    parameter_units: Mapping[str, str] = attrs.field(factory=dict, converter=dict,
                                                     metadata={_PER_PARAMETER: "unit"})
    rmse_basis: str = ""

    # ----------------------------------------------------------------- building
    @classmethod
    def from_fit(cls, model, values, information, residuals=None, *, estimator: str,
                 **fields) -> "Estimate":
        """Build an estimate from a fit, deriving what follows from it.

        Args:
            model: the fitted :class:`~rotorid.model.structure.ModelStructure` (or a model
                with ``parameter_names`` and ``output_names``, and optionally a ``structure``).
            values: the estimated parameters, shape (P,) in ``model.parameter_names`` order.
            information: the information matrix F at ``values``, shape (P, P).
            residuals: measured minus model outputs per maneuver, shapes (N_i, n_o); give
                them unless ``fields`` sets ``noise_covariance``, ``cost``, ``rmse`` and
                ``n_samples``.
            estimator: the estimator's registered name.
            fields: any other :class:`Estimate` field, overriding the derived one (an
                estimator with its own cost definition passes ``cost`` and so on). Not given:
                ``iterations`` 0, ``converged`` True, ``stop_reason`` ``"converged"``, one-point
                cost and RMSE histories, ``start`` the model's initial values.

        Derived: Cramér-Rao bounds, insensitivities, correlations and unidentifiable
        combinations from F (:func:`statistics`); R = Σ eᵀe / N, cost det R, each output's
        residual RMS and the RMSE (eq. 18, each residual in its reference unit when the
        outputs have one: :func:`rmse_basis`) from the residuals; sign priors, fixed
        derivatives, unit system and sign violations from the structure; output and
        parameter units from the structure or the model's ``output_units`` and
        ``parameter_units``. An estimator that passes its own ``rmse`` computes it over the
        same reference units (:func:`rotorid.units.rmse_reference_factors`) or passes
        ``rmse_basis`` too.
        """
        names = tuple(model.parameter_names)
        values = np.asarray(values, dtype=float)
        stats = statistics(information, names)
        derived = _structure_facts(model)
        if "output_names" in fields:          # outputs of the estimator's own: their units
            derived["output_units"] = ()      # only when it gives them
        derived.update(_residual_facts(residuals,
                                       fields.get("output_units", derived["output_units"])))
        derived.update(fields)
        derived.setdefault("rmse_basis", rmse_basis(derived["output_units"]))
        signs = derived.get("signs", {})
        derived.setdefault("sign_violations", tuple(
            n for n, v in zip(names, values)
            if (signs.get(n) == "negative" and v > 0) or (signs.get(n) == "positive" and v < 0)))
        derived.setdefault("cost_history", (derived.get("cost"),))
        derived.setdefault("rmse_history", (derived.get("rmse"),))
        missing = [k for k in ("noise_covariance", "cost", "rmse", "n_samples")
                   if k not in derived]
        if missing:
            raise EstimationError(f"Estimate.from_fit needs the residuals, or "
                                  f"{', '.join(missing)} given explicitly")
        if "start" not in derived:
            derived["start"] = model.initial_values()
        return cls(estimator=estimator, parameter_names=names, values=values,
                   cramer_rao=stats.cramer_rao, insensitivity=stats.insensitivity,
                   correlation=stats.correlation, information=information,
                   unidentifiable=stats.unidentifiable,
                   **{"iterations": 0, "converged": True, "stop_reason": "converged",
                      **derived})

    def __repr__(self) -> str:
        return estimate_summary(self)

    def _repr_html_(self) -> str:
        return estimate_html(self)

    # ----------------------------------------------------------------- access
    def index(self, name: str) -> int:
        try:
            return self.parameter_names.index(name)
        except ValueError:
            raise EstimationError(f"no estimated parameter {name!r}; estimated: "
                                  f"{', '.join(self.parameter_names)}") from None

    def __getitem__(self, name: str) -> ParameterEstimate:
        """One estimated parameter by name (``estimate["L_p"].cramer_rao``)."""
        i = self.index(name)
        return ParameterEstimate(
            name, float(self.values[i]), float(self.start[i]), float(self.cramer_rao[i]),
            float(self.cramer_rao_pct[i]), float(self.insensitivity[i]),
            float(self.insensitivity_pct[i]), self.signs.get(name, "none"),
            self.parameter_units.get(name, ""))

    def __contains__(self, name: object) -> bool:
        return name in self.parameter_names

    def __iter__(self):
        """The estimated parameters, in order (:class:`ParameterEstimate`)."""
        return (self[name] for name in self.parameter_names)

    def value(self, name: str) -> float:
        """Estimated value of one parameter (fixed derivatives give their fixed value)."""
        if name in self.fixed:
            return float(self.fixed[name])
        return float(self.values[self.index(name)])

    def as_mapping(self) -> dict[str, float]:
        """Name → value of the estimated parameters."""
        return dict(zip(self.parameter_names, self.values.tolist()))

    def restricted(self, names) -> "Estimate":
        """This estimate seen on some of its parameters, ``names`` in that order (e.g. a
        structure's ``parameter_names``, leaving out filter error's noise parameters ``F_*``
        and ``R_*``): their values, start values, Cramér-Rao bounds, insensitivities and
        correlations as estimated with every parameter, and their block of the information
        matrix. Returns this estimate itself when ``names`` are all of its parameters."""
        names = tuple(names)
        if names == self.parameter_names:
            return self
        index = [self.index(n) for n in names]
        block = np.ix_(index, index)
        kept = set(names)
        return attrs.evolve(
            self, parameter_names=names, values=self.values[index], start=self.start[index],
            cramer_rao=self.cramer_rao[index], insensitivity=self.insensitivity[index],
            correlation=self.correlation[block], information=self.information[block],
            sign_violations=[n for n in self.sign_violations if n in kept],
            at_bound=[n for n in self.at_bound if n in kept],
            unidentifiable=[c for c in self.unidentifiable if kept.intersection(c)],
            parameter_units={n: u for n, u in self.parameter_units.items() if n in kept})

    def propagated(self, function, relative_step: float = 1e-6
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Values and Cramér-Rao bounds of quantities computed from the parameters.

        Args:
            function: maps a parameter vector (P,) to the quantities (K,), e.g. a hybrid
                model's quasi-steady derivatives.
            relative_step: central-difference step per parameter, relative to its value
                (at least ``relative_step``·10⁻³ absolute).
        Returns:
            ``function(values)`` (K,) and its bounds (K,): √diag(J·C·Jᵀ) with J the
            central-difference Jacobian and C the covariance (correlation times the bounds);
            infinite where the quantity depends on a parameter with an infinite bound.
        """
        values = np.asarray(self.values, dtype=float)
        centre = np.asarray(function(values), dtype=float)
        jacobian = np.zeros((centre.size, values.size))
        for i, value in enumerate(values):
            step = relative_step * max(abs(value), 1e-3)
            up, down = values.copy(), values.copy()
            up[i] += step
            down[i] -= step
            jacobian[:, i] = (np.asarray(function(up)) - np.asarray(function(down))) / (2 * step)
        finite = np.isfinite(self.cramer_rao)
        bounded = np.where(finite, self.cramer_rao, 0.0)
        covariance = np.nan_to_num(self.correlation) * np.outer(bounded, bounded)
        bounds = np.sqrt(np.maximum(np.einsum("ki,ij,kj->k", jacobian, covariance, jacobian),
                                    0.0))
        unbounded = np.any((jacobian != 0.0) & ~finite[None, :], axis=1)
        return centre, np.where(unbounded, np.inf, bounds)

    @property
    def cramer_rao_pct(self) -> np.ndarray:
        """Normalised Cramér-Rao bounds |CR/Θ|·100 (inf where Θ = 0)."""
        return _normalised(self.cramer_rao, self.values)

    @property
    def insensitivity_pct(self) -> np.ndarray:
        """Normalised insensitivities |I/Θ|·100 (inf where Θ = 0)."""
        return _normalised(self.insensitivity, self.values)

    @property
    def is_delay(self) -> np.ndarray:
        return np.array([delayed_derivative(n) is not None for n in self.parameter_names],
                        dtype=bool)

    # ----------------------------------------------------------------- export
    def as_dict(self) -> dict:
        """JSON-ready record (the ``rotorid identify`` format), driven by the fields' metadata.

        Each parameter gets an entry under ``"parameters"`` (delays: under ``"delays"``,
        keyed without ``tau_``) holding the per-parameter columns, their normalised forms
        (null where not finite), its unit when known and, for derivatives, the sign prior.
        Every other field is stored under its name or its metadata ``key``; ``rmse`` and
        ``rmse_history`` are null when ``rmse_basis`` is empty (the RMSE would mix units).
        """
        fields = attrs.fields(type(self))
        parameters, delays = {}, {}
        for i, name in enumerate(self.parameter_names):
            entry = {}
            for field in (f for f in fields if _COLUMN in f.metadata):
                entry[field.metadata[_COLUMN]] = _number(getattr(self, field.name)[i])
                if _NORMALISED in field.metadata:
                    normalised = field.metadata[_NORMALISED]
                    entry[normalised] = _number(getattr(self, normalised)[i])
            for field in (f for f in fields if _PER_PARAMETER in f.metadata):
                if name in getattr(self, field.name):
                    entry[field.metadata[_PER_PARAMETER]] = getattr(self, field.name)[name]
            derivative = delayed_derivative(name)
            if derivative is not None:
                delays[derivative] = entry
                continue
            for field in (f for f in fields if _PER_DERIVATIVE in f.metadata):
                entry[field.metadata[_PER_DERIVATIVE]] = getattr(self, field.name).get(name,
                                                                                      "none")
            parameters[name] = entry
        per_parameter = (_COLUMN, _PER_DERIVATIVE, _PER_PARAMETER)
        record = {field.metadata.get(_KEY, field.name): _plain(getattr(self, field.name))
                  for field in fields
                  if not any(key in field.metadata for key in per_parameter)}
        if not self.rmse_basis:
            record.update(rmse=None, rmse_history=None)
        return {**record, "parameters": parameters, "delays": delays}

    @classmethod
    def from_dict(cls, record: Mapping) -> "Estimate":
        """Rebuild an estimate from :meth:`as_dict` output (e.g. a saved ``result.json``).

        Fields the record lacks take their defaults when they have one (records written
        before the field existed); a null ``rmse`` becomes NaN."""
        try:
            names = tuple(record["parameter_names"])
            entries = {**record["parameters"],
                       **{delay_parameter(k): v for k, v in record["delays"].items()}}
            fields = {}
            for field in attrs.fields(cls):
                metadata = field.metadata
                if _COLUMN in metadata:
                    key = metadata[_COLUMN]
                    fields[field.name] = [np.inf if entries[n][key] is None else entries[n][key]
                                          for n in names]
                elif _PER_DERIVATIVE in metadata or _PER_PARAMETER in metadata:
                    key = metadata.get(_PER_DERIVATIVE) or metadata[_PER_PARAMETER]
                    table = (record["parameters"] if _PER_DERIVATIVE in metadata
                             else entries)
                    fields[field.name] = {n: e[key] for n, e in table.items() if key in e}
                elif metadata.get(_SQUARE):
                    fields[field.name] = np.array(record[field.name], dtype=float).reshape(
                        len(names), len(names))
                elif metadata.get(_KEY, field.name) in record:
                    fields[field.name] = record[metadata.get(_KEY, field.name)]
                elif field.default is attrs.NOTHING:
                    raise KeyError(metadata.get(_KEY, field.name))
            if fields.get("rmse", 0.0) is None:
                fields["rmse"] = math.nan
            if fields.get("rmse_history", ()) is None:
                fields["rmse_history"] = ()
            return cls(**fields)
        except (KeyError, TypeError, ValueError) as error:
            raise EstimationError(f"not a complete rotorid estimate record: {error!r}") from None

    def to_json(self) -> str:
        return json.dumps(self.as_dict(), indent=2)

    def report(self, correlation_threshold: float = 0.9) -> str:
        """Sectioned text report: fit statistics, each output's residual RMS and noise
        standard deviation in its unit, parameters with their units and flags, fixed
        derivatives, strong correlations and notes."""
        lines = ["[[Fit statistics]]",
                 f"    estimator          = {self.estimator}",
                 f"    converged          = {self.converged} ({self.stop_reason})",
                 f"    iterations         = {self.iterations}",
                 (f"    J points           = {self.n_samples} over "
                  f"{len(self.output_names)} pairs" if self.estimator == "frequency-response"
                  else f"    samples            = {self.n_samples} × "
                       f"{len(self.output_names)} outputs"),
                 f"    cost               = {self.cost:.6g}",
                 f"    RMSE               = {self._rmse_line()}"]
        lines.extend(self._output_lines())
        lines += ["[[Parameters]]",
                  f"    {'name':<12}{'value':>14}{'CR bound':>13}{'CR %':>9}{'insens %':>10}"
                  f"  {'unit':<24}flags"]
        for i, name in enumerate(self.parameter_names):
            flags = []
            if name in self.sign_violations:
                flags.append(f"sign ≠ {self.signs.get(name)}")
            if name in self.at_bound:
                flags.append("at bound")
            if any(name in combo for combo in self.unidentifiable):
                flags.append("unidentifiable")
            lines.append(f"    {name:<12}{self.values[i]:>14.6g}{self.cramer_rao[i]:>13.4g}"
                         f"{_pct(self.cramer_rao_pct[i]):>9}{_pct(self.insensitivity_pct[i]):>10}"
                         f"  {self.parameter_units.get(name, '–'):<24}{', '.join(flags)}".rstrip())
        if self.fixed:
            lines.append("[[Fixed]]")
            lines.extend(f"    {name:<12}{value:>14.6g}" for name, value in self.fixed.items())
        pairs = [(self.parameter_names[i], self.parameter_names[j], self.correlation[i, j])
                 for i in range(len(self.parameter_names))
                 for j in range(i + 1, len(self.parameter_names))
                 if abs(self.correlation[i, j]) >= correlation_threshold]
        lines.append(f"[[Correlations]] (|r| ≥ {correlation_threshold})")
        if not pairs:
            lines.append("    none")
        for a, b, r in sorted(pairs, key=lambda t: -abs(t[2])):
            lines.append(f"    C({a}, {b}) = {r:+.3f}")
        if self.notes:
            lines.append("[[Notes]]")
            lines.extend(f"    {note}" for note in self.notes)
        return "\n".join(lines)


    def _rmse_line(self) -> str:
        """The RMSE and what makes it dimensionless, or why it is not given."""
        if self.rmse_basis:
            return f"{self.rmse:.6g} ({self.rmse_basis})"
        if self.output_units:
            units = sorted({u for u in self.output_units
                            if rmse_reference_factors([u]) is None})
            return (f"not given: outputs in {', '.join(units)} have no reference unit, so the "
                    f"RMSE would mix units; see [[Outputs]]")
        return "not given: the model declares no output units, so the RMSE would mix units"

    def _output_lines(self) -> list[str]:
        """The [[Outputs]] section: residual RMS and √R_jj per output, in its unit."""
        if not self.residual_rms.size:
            return []
        units = self.output_units or ("–",) * len(self.output_names)
        noise = np.sqrt(np.diag(self.noise_covariance))
        return ["[[Outputs]] (residual RMS and noise standard deviation √R_jj, output units)",
                f"    {'name':<12}{'unit':<10}{'residual RMS':>14}{'√R_jj':>14}",
                *(f"    {name:<12}{unit:<10}{rms:>14.4g}{sd:>14.4g}"
                  for name, unit, rms, sd in zip(self.output_names, units, self.residual_rms,
                                                 noise))]


def _number(value: float) -> float | None:
    """A finite float, or None (JSON has no infinity)."""
    return float(value) if math.isfinite(value) else None


def _plain(value):
    """A field value as JSON-ready lists, dicts and scalars."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return dict(value)
    return value


def _structure_facts(model) -> dict:
    """Output names and units, parameter units, sign priors, fixed derivatives and unit
    system of a fitted model (a structure, or a model with optional ``output_units``,
    ``parameter_units`` and ``structure``)."""
    if isinstance(model, ModelStructure):
        structure, outputs = model, model.outputs
        output_units, parameter_units = model.signals.outputs.units, {}
    else:
        structure, outputs = getattr(model, "structure", None), model.output_names
        output_units = getattr(model, "output_units", ())
        parameter_units = getattr(model, "parameter_units", {})
    facts = {"output_names": tuple(outputs), "output_units": tuple(output_units)}
    if isinstance(structure, ModelStructure):
        parameter_units = {**structure_parameter_units(structure), **parameter_units}
        facts.update(signs={d.name: d.sign.value for d in structure.free_derivatives},
                     fixed={d.name: d.initial for d in structure.derivatives if d.fixed},
                     units=structure.units.name)
    names = set(model.parameter_names)
    facts["parameter_units"] = {n: u for n, u in parameter_units.items() if n in names and u}
    return facts


def _residual_facts(residuals, output_units) -> dict:
    """R = Σ eᵀe / N, its determinant (the cost), each output's residual RMS, the RMSE
    (residuals in their reference units where ``output_units`` have them) and N, from
    per-maneuver (N_i, n_o) residuals."""
    if residuals is None:
        return {}
    stacked = np.concatenate([np.asarray(e, dtype=float) for e in residuals])
    noise = stacked.T @ stacked / len(stacked)
    factors = rmse_reference_factors(output_units)
    return {"noise_covariance": noise, "cost": float(np.linalg.det(noise)),
            "rmse": rmse(stacked if factors is None else stacked * factors),
            "residual_rms": np.sqrt(np.diag(noise)), "n_samples": len(stacked)}


def _pct(value: float) -> str:
    """A percentage for an 8-character column (an exponent from 1e5 %)."""
    if not math.isfinite(value):
        return "inf"
    return f"{value:.1f}" if abs(value) < 1e5 else f"{value:.2e}"
