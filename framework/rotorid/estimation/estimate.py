"""Estimates and their statistics.

An :class:`Estimate` is the immutable result of a parameter estimation: values, Cramér-Rao
bounds, insensitivities, correlations, the noise covariance, the cost and RMSE history and how
the iteration stopped. Estimator plugins build it with :func:`statistics` from the information
matrix, so every estimator reports the same quantities the same way:

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

#: Condition number of the scaled information matrix above which parameters count as nearly
#: unidentifiable.
ILL_CONDITIONED = 1e10


def _frozen_array(value):
    array = np.array(value, dtype=float, copy=True)
    array.setflags(write=False)
    return array


@attrs.frozen
class ParameterStatistics:
    """Uncertainty measures derived from the information matrix F (P×P)."""

    cramer_rao: np.ndarray = attrs.field(converter=_frozen_array)
    insensitivity: np.ndarray = attrs.field(converter=_frozen_array)
    correlation: np.ndarray = attrs.field(converter=_frozen_array)
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
    if f.shape != (len(names), len(names)) or not np.all(np.isfinite(f)):
        raise EstimationError(f"information matrix must be a finite {len(names)}×{len(names)} "
                              f"array, got shape {f.shape}")
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


@attrs.frozen(eq=False)
class Estimate:
    """The result of one estimation (immutable).

    Array attributes are read-only; shapes: ``values``, ``cramer_rao``, ``insensitivity``
    (P,), ``correlation`` and ``information`` (P, P), ``noise_covariance`` (n_o, n_o).
    Units follow the model (flight-test by default); delays are in s.
    """

    estimator: str
    parameter_names: tuple[str, ...] = attrs.field(converter=tuple)
    values: np.ndarray = attrs.field(converter=_frozen_array)
    start: np.ndarray = attrs.field(converter=_frozen_array)
    cramer_rao: np.ndarray = attrs.field(converter=_frozen_array)
    insensitivity: np.ndarray = attrs.field(converter=_frozen_array)
    correlation: np.ndarray = attrs.field(converter=_frozen_array)
    information: np.ndarray = attrs.field(converter=_frozen_array)
    noise_covariance: np.ndarray = attrs.field(converter=_frozen_array)
    output_names: tuple[str, ...] = attrs.field(converter=tuple)
    cost: float
    rmse: float
    cost_history: tuple[float, ...] = attrs.field(converter=tuple)
    rmse_history: tuple[float, ...] = attrs.field(converter=tuple)
    iterations: int
    converged: bool
    stop_reason: str
    n_samples: int
    sign_violations: tuple[str, ...] = ()
    at_bound: tuple[str, ...] = ()
    unidentifiable: tuple[tuple[str, ...], ...] = ()
    fixed: Mapping[str, float] = attrs.field(factory=dict, converter=dict)
    signs: Mapping[str, str] = attrs.field(factory=dict, converter=dict)
    units: str = "flight-test"
    notes: tuple[str, ...] = ()

    # ----------------------------------------------------------------- access
    def index(self, name: str) -> int:
        try:
            return self.parameter_names.index(name)
        except ValueError:
            raise EstimationError(f"no estimated parameter {name!r}; estimated: "
                                  f"{', '.join(self.parameter_names)}") from None

    def value(self, name: str) -> float:
        """Estimated value of one parameter (fixed derivatives give their fixed value)."""
        if name in self.fixed:
            return float(self.fixed[name])
        return float(self.values[self.index(name)])

    def as_mapping(self) -> dict[str, float]:
        """Name → value of the estimated parameters."""
        return dict(zip(self.parameter_names, self.values.tolist()))

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
        return np.array([n.startswith("tau_") for n in self.parameter_names], dtype=bool)

    # ----------------------------------------------------------------- export
    def as_dict(self) -> dict:
        """JSON-ready record (the ``rotorid identify`` format)."""
        def number(x):
            return float(x) if math.isfinite(x) else None

        parameters, delays = {}, {}
        for i, name in enumerate(self.parameter_names):
            entry = {"value": float(self.values[i]), "cramer_rao": number(self.cramer_rao[i]),
                     "cramer_rao_pct": number(self.cramer_rao_pct[i]),
                     "insensitivity": number(self.insensitivity[i]),
                     "insensitivity_pct": number(self.insensitivity_pct[i])}
            if name.startswith("tau_"):
                delays[name[4:]] = entry
            else:
                entry["sign"] = self.signs.get(name, "none")
                parameters[name] = entry
        return {"estimator": self.estimator, "converged": self.converged,
                "stop_reason": self.stop_reason, "iterations": self.iterations,
                "cost": self.cost, "rmse": self.rmse,
                "cost_history": list(self.cost_history), "rmse_history": list(self.rmse_history),
                "n_samples": self.n_samples, "outputs": list(self.output_names),
                "noise_covariance": self.noise_covariance.tolist(),
                "parameters": parameters, "delays": delays, "fixed": dict(self.fixed),
                "correlation": self.correlation.tolist(),
                "sign_violations": list(self.sign_violations), "at_bound": list(self.at_bound),
                "unidentifiable": [list(c) for c in self.unidentifiable],
                "notes": list(self.notes), "units": self.units,
                "parameter_names": list(self.parameter_names), "start": self.start.tolist(),
                "information": self.information.tolist()}

    @classmethod
    def from_dict(cls, record: Mapping) -> "Estimate":
        """Rebuild an estimate from :meth:`as_dict` output (e.g. a saved ``result.json``)."""
        try:
            names = tuple(record["parameter_names"])
            entries = {**record["parameters"],
                       **{f"tau_{k}": v for k, v in record["delays"].items()}}

            def column(key):
                return [np.inf if entries[n][key] is None else entries[n][key] for n in names]

            return cls(
                estimator=record["estimator"], parameter_names=names,
                values=column("value"), start=record["start"],
                cramer_rao=column("cramer_rao"), insensitivity=column("insensitivity"),
                correlation=np.array(record["correlation"], dtype=float).reshape(
                    len(names), len(names)),
                information=np.array(record["information"], dtype=float).reshape(
                    len(names), len(names)),
                noise_covariance=record["noise_covariance"], output_names=record["outputs"],
                cost=record["cost"], rmse=record["rmse"], cost_history=record["cost_history"],
                rmse_history=record["rmse_history"], iterations=record["iterations"],
                converged=record["converged"], stop_reason=record["stop_reason"],
                n_samples=record["n_samples"],
                sign_violations=tuple(record["sign_violations"]),
                at_bound=tuple(record["at_bound"]),
                unidentifiable=tuple(tuple(c) for c in record["unidentifiable"]),
                fixed=record["fixed"],
                signs={n: e["sign"] for n, e in record["parameters"].items() if "sign" in e},
                units=record["units"], notes=tuple(record["notes"]))
        except (KeyError, TypeError, ValueError) as error:
            raise EstimationError(f"not a complete rotorid estimate record: {error!r}") from None

    def to_json(self) -> str:
        return json.dumps(self.as_dict(), indent=2)

    def report(self, correlation_threshold: float = 0.9) -> str:
        """Sectioned text report: fit statistics, parameters, flags, strong correlations."""
        lines = ["[[Fit statistics]]",
                 f"    estimator          = {self.estimator}",
                 f"    converged          = {self.converged} ({self.stop_reason})",
                 f"    iterations         = {self.iterations}",
                 f"    samples            = {self.n_samples} × {len(self.output_names)} outputs",
                 f"    cost det(R)        = {self.cost:.6g}",
                 f"    RMSE (eq. 18)      = {self.rmse:.6g}",
                 "[[Parameters]]",
                 f"    {'name':<12}{'value':>14}{'CR bound':>13}{'CR %':>9}{'insens %':>10}  flags"]
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
                         f"  {', '.join(flags)}")
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


def _pct(value: float) -> str:
    return "inf" if not math.isfinite(value) else f"{value:.1f}"
