"""Time-domain verification metrics: RMSE (the paper's eq. 18), J_rms and Theil's U1.

With ``z`` the measured and ``y`` the simulated outputs, ``N`` samples and ``n_o`` outputs:

* RMSE (paper eq. 18) ``= sqrt( (1/(N n_o)) Σ_i (z_i − y_i)ᵀ (z_i − y_i) )``;
* J_rms (Tischler) is the same sum with an output weighting ``W`` (diagonal, default the
  identity) and, by Tischler's procedure, after removing per-output biases; guideline
  ≤ 1.0–2.0 with outputs in deg, deg/s, ft/s, ft/s²;
* TIC (Theil's inequality coefficient U1) per output
  ``= RMS(z − y) / (RMS(z) + RMS(y))``, 0 perfect, 1 no agreement; guideline ≤ 0.25–0.3.
  The stacked form replaces squares by ``yᵀy``.

Every function takes arrays of shape (N, n_o) (or sequences of them, one per maneuver) in the
data's units; the values returned are in those units (RMSE, J_rms) or dimensionless (TIC).
:func:`time_domain_metrics` given the outputs' units pools RMSE and J_rms over residuals
counted in their reference units (:data:`rotorid.units.RMSE_REFERENCE_UNITS`: ft/s, ft/s²,
deg, deg/s), as the fit's RMSE does, so they are the same numbers whether a model computes in
flight-test or SI units.
"""

from __future__ import annotations

from collections.abc import Sequence

import attrs
import numpy as np

from rotorid.data import ManeuverSet
from rotorid.errors import DataError
from rotorid.units import RMSE_REFERENCE_UNITS, UNITS, rmse_reference_factors


def _pair(measured, simulated) -> tuple[np.ndarray, np.ndarray]:
    z = np.asarray(measured, dtype=float)
    y = np.asarray(simulated, dtype=float)
    if z.ndim != 2 or z.shape != y.shape:
        raise DataError(f"measured and simulated outputs must be 2-D arrays of one shape "
                        f"(N, n_outputs); got {z.shape} and {y.shape}")
    if not (np.all(np.isfinite(z)) and np.all(np.isfinite(y))):
        raise DataError("measured or simulated outputs contain NaN or infinite values")
    return z, y


def _records(measured, simulated) -> list[tuple[np.ndarray, np.ndarray]]:
    """Accept one (N, n_o) array each or sequences of them (one per maneuver)."""
    if isinstance(measured, np.ndarray) and measured.ndim == 2:
        return [_pair(measured, simulated)]
    if len(measured) != len(simulated) or not len(measured):
        raise DataError(f"{len(measured)} measured and {len(simulated)} simulated records; "
                        f"give one simulated array per maneuver")
    return [_pair(z, y) for z, y in zip(measured, simulated)]


def _list(arrays) -> list:
    """One (N, n_o) array, or a sequence of them, as a list of arrays."""
    return [arrays] if isinstance(arrays, np.ndarray) and arrays.ndim == 2 else list(arrays)


def _stack(measured, simulated) -> tuple[np.ndarray, np.ndarray]:
    pairs = _records(measured, simulated)
    return np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs])


def rmse(measured, simulated, per_output: bool = False):
    """The paper's eq. 18 pooled over all samples (and maneuvers) and outputs; with
    ``per_output`` the same per output channel, shape (n_o,)."""
    z, y = _stack(measured, simulated)
    if per_output:
        return np.sqrt(np.mean((z - y) ** 2, axis=0))
    return float(np.sqrt(np.mean((z - y) ** 2)))


def j_rms(measured, simulated, weights=None, remove_bias: bool = True) -> float:
    """Tischler's J_rms; ``weights`` (n_o,) is the diagonal of W; with ``remove_bias`` each
    record's mean residual per output is removed first (the bias fit of the procedure)."""
    residuals = [z - y for z, y in _records(measured, simulated)]
    if remove_bias:
        residuals = [r - r.mean(axis=0) for r in residuals]
    residual = np.concatenate(residuals)
    w = np.ones(residual.shape[1]) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != (residual.shape[1],) or np.any(w < 0) or not np.all(np.isfinite(w)):
        raise DataError(f"weights must be {residual.shape[1]} finite non-negative numbers, "
                        f"one per output")
    return float(np.sqrt(np.mean(residual ** 2 * w)))


def tic(measured, simulated, per_output: bool = True):
    """Theil's inequality coefficient U1: per output, shape (n_o,), or stacked (a float).

    An output with zero RMS in both records has TIC 0 (perfect, trivially).
    """
    z, y = _stack(measured, simulated)

    def rms(a):
        return np.sqrt(np.mean(a ** 2, axis=0)) if per_output else np.sqrt(np.mean(
            np.sum(a ** 2, axis=1)))

    numerator, denominator = rms(z - y), rms(z) + rms(y)
    with np.errstate(invalid="ignore", divide="ignore"):
        value = np.where(denominator > 0, numerator / denominator, 0.0)
    return value if per_output else float(value)


@attrs.frozen(eq=False)
class ManeuverMetrics:
    """Metrics of one maneuver (or of all pooled, ``name="all"``).

    Attributes:
        outputs: the names of the outputs compared.
        rmse, j_rms: over all outputs, each residual in the unit ``pooled_units`` names for
            its output.
        rmse_per_output: RMSE of each output, shape (n_o,), in ``units`` (the data's).
        tic: Theil's U1 of each output, shape (n_o,).
        pooled_units: the unit each output's residuals count in for ``rmse`` and ``j_rms``
            (its reference unit), or ``()``: the data's units, mixed.
        units: each output's unit in the data (``()``: not known).
    """

    name: str
    rmse: float
    j_rms: float
    rmse_per_output: np.ndarray
    tic: np.ndarray
    outputs: tuple[str, ...] = attrs.field(converter=tuple)
    pooled_units: tuple[str, ...] = attrs.field(default=(), converter=tuple)
    units: tuple[str, ...] = attrs.field(default=(), converter=tuple)

    @classmethod
    def of(cls, name: str, outputs, measured, simulated, weights=None,
           units=()) -> "ManeuverMetrics":
        """The metrics of ``simulated`` against ``measured`` (one (N, n_o) array each or one
        per maneuver), outputs ``outputs`` in ``units`` (default: not known)."""
        factors = rmse_reference_factors(units)
        if factors is None:
            pooled, scaled = (), (measured, simulated)
        else:
            pooled = tuple(RMSE_REFERENCE_UNITS[UNITS[u][0]] for u in units)
            scaled = tuple([np.asarray(a, dtype=float) * factors for a in _list(arrays)]
                           for arrays in (measured, simulated))
        return cls(name, rmse(*scaled), j_rms(*scaled, weights),
                   rmse(measured, simulated, per_output=True), tic(measured, simulated),
                   outputs, pooled, units)

    def summary(self) -> dict:
        return {"maneuver": self.name, "rmse": self.rmse, "j_rms": self.j_rms,
                "pooled_units": (dict(zip(self.outputs, self.pooled_units))
                                 if self.pooled_units else "data units"),
                "rmse_per_output": dict(zip(self.outputs, map(float, self.rmse_per_output))),
                "rmse_per_output_units": (dict(zip(self.outputs, self.units)) if self.units
                                          else "data units"),
                "tic": dict(zip(self.outputs, map(float, self.tic)))}

    def rows(self) -> list[str]:
        return [f"{self.name:<20} {self.rmse:8.3f} {self.j_rms:8.3f}  RMSE "
                + " ".join(f"{v:7.3f}" for v in self.rmse_per_output),
                f"{'':<38}  TIC  " + " ".join(f"{v:7.3f}" for v in self.tic)]


@attrs.frozen(eq=False)
class TimeDomainMetrics:
    """Metrics per maneuver and pooled over all of them (``overall``)."""

    maneuvers: tuple[ManeuverMetrics, ...]
    overall: ManeuverMetrics

    @property
    def rmse(self) -> float:
        return self.overall.rmse

    @property
    def j_rms(self) -> float:
        return self.overall.j_rms

    @property
    def tic(self) -> np.ndarray:
        return self.overall.tic

    def summary(self) -> dict:
        return {**self.overall.summary(), "maneuvers": [m.summary() for m in self.maneuvers]}

    def report(self) -> str:
        outputs = self.overall.outputs
        lines = [f"{'maneuver':<20} {'RMSE':>8} {'J_rms':>8}       "
                 + " ".join(f"{o:>7}" for o in outputs)]
        if self.overall.units:
            lines.append(f"{'':<38}  in   " + " ".join(f"{u:>7}" for u in self.overall.units))
        for m in (*self.maneuvers, self.overall):
            lines.extend(m.rows())
        return "\n".join(lines)


def time_domain_metrics(maneuvers: ManeuverSet, simulated: Sequence[np.ndarray],
                        weights=None, outputs: Sequence[str] | None = None,
                        units: Sequence[str] = ()) -> TimeDomainMetrics:
    """RMSE, J_rms and TIC of simulated outputs (one (N_i, n_o) array per maneuver, columns
    ``outputs``: a model's output names, default the maneuvers' own outputs) against the
    recorded channels of those names, per maneuver and pooled; ``weights`` (n_o,) is J_rms's
    output weighting. With the outputs' ``units`` (a model's ``signals.outputs.units``),
    RMSE and J_rms count each residual in its reference unit when every output has one
    (module docstring)."""
    if len(simulated) != len(maneuvers):
        raise DataError(f"{len(simulated)} simulated records for {len(maneuvers)} maneuvers")
    outputs = tuple(maneuvers.output_names if outputs is None else outputs)
    measured = [m.columns(outputs) for m in maneuvers]
    per = tuple(ManeuverMetrics.of(m.name, outputs, z, y, weights, units)
                for m, z, y in zip(maneuvers, measured, simulated))
    overall = ManeuverMetrics.of("all", outputs, measured, list(simulated), weights, units)
    return TimeDomainMetrics(per, overall)
