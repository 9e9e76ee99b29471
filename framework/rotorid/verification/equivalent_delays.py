"""Equivalent delays that a truth model's own linear rotor dynamics imply (frequency domain).

A 6-DoF model with delays stands in for the rotor: the flap modes lag the body response, and a
delay on a rate or control derivative absorbs that lag in the band that matters (1–10 rad/s).
How large those delays *should* be follows from the truth model itself: fit the delayed
roll/pitch terms to the exact frequency responses of its full linearisation (rigid body, flap
and inflow states), with everything else fixed at its residualised 6-DoF values.

The fitted model is the residualised one with its q and p rows' rate and cyclic terms replaced
by delayed terms (the paper's eqs. 3-4)::

    q̇ = M_q q(t−τ) + M_p p(t−τ) + M_long δlong(t−τ) + M_lat δlat(t−τ) + (other M terms)
    ṗ = L_p p(t−τ) + L_q q(t−τ) + L_long δlong(t−τ) + L_lat δlat(t−τ) + (other L terms)

fitted to q/long, q/lat, p/long and p/lat by least squares on the complex errors, each pair
normalised by its RMS magnitude. It is independent of the time-domain identification (no
simulation, no noise, no nonlinearity), so it checks whether identified delays are the truth
model's or an artefact of the estimator. The result depends on the band and on which delays
are fitted: compare like with like (the delays the identified model kept).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import attrs
import numpy as np
import scipy.optimize

from rotorid.errors import StructureError
from rotorid.model.structure import STATES
from rotorid.simulation.transfer import state_response

#: The roll/pitch terms that carry the rotor's delays: (derivative, row state, column).
ROTOR_TERMS = (("M_q", "q", "q"), ("M_p", "q", "p"), ("M_long", "q", "long"),
               ("M_lat", "q", "lat"), ("L_q", "p", "q"), ("L_p", "p", "p"),
               ("L_long", "p", "long"), ("L_lat", "p", "lat"))
#: Names of :data:`ROTOR_TERMS`.
ROTOR_DERIVATIVES = tuple(name for name, _, _ in ROTOR_TERMS)
#: Frequency band of the fit, rad/s (the MUAD band where 6-DoF + delays is valid).
DEFAULT_BAND = (1.0, 10.0)
#: Start values of the delays (s); the best fit of all starts is kept.
DELAY_STARTS = (0.0, 0.05, 0.1, 0.2)


@attrs.frozen
class EquivalentDelays:
    """Result of :func:`equivalent_delays`.

    Attributes:
        delays: fitted delay (s) per derivative name, for the derivatives asked for.
        gains: all eight fitted roll/pitch gains (units of the linear models).
        relative_rms: RMS of the normalised complex error over the four pairs (0 = exact).
        band: (lowest, highest) frequency of the fit, rad/s.
    """

    delays: Mapping[str, float]
    gains: Mapping[str, float]
    relative_rms: float
    band: tuple[float, float]

    def as_dict(self) -> dict:
        return {"delays": dict(self.delays), "gains": dict(self.gains),
                "relative_rms": self.relative_rms, "band_rad_s": list(self.band)}


def _indices(model, names, what) -> list[int]:
    missing = [n for n in names if n not in model.states + model.controls]
    if missing:
        raise StructureError(f"the {what} linear model lacks {missing}; it needs the states "
                             f"{', '.join(STATES)} and the controls long, lat")
    return [(model.states + model.controls).index(n) for n in names]


def _truth_response(full, omega: np.ndarray) -> np.ndarray:
    """(F, 2, 2) responses of q, p (rows) to long, lat (columns) of the full model."""
    q, p = _indices(full, ("q", "p"), "full")
    long, lat = (i - len(full.states) for i in _indices(full, ("long", "lat"), "full"))
    b = np.asarray(full.B, float)[:, [long, lat]]
    return state_response(np.asarray(full.A, float), b, omega)[:, [q, p], :]


class _Fit:
    """The residualised model with delayed roll/pitch terms, as a function of the unknowns."""

    def __init__(self, residualised, omega: np.ndarray, delayed: list[str]):
        if tuple(residualised.states) != STATES:
            raise StructureError(f"the residualised linear model must have the states "
                                 f"{', '.join(STATES)}, got {residualised.states}")
        self.omega = omega
        a = np.asarray(residualised.A, float)
        long, lat = (i - 8 for i in _indices(residualised, ("long", "lat"), "residualised"))
        b = np.asarray(residualised.B, float)[:, [long, lat]]
        self.rows = {"q": STATES.index("q"), "p": STATES.index("p")}
        self.columns = {"q": STATES.index("q"), "p": STATES.index("p"), "long": 0, "lat": 1}
        self.delayed = [name for name in ROTOR_DERIVATIVES if name in delayed]
        self.start_gains = np.array([(a if column in ("q", "p") else b)[
            self.rows[row], self.columns[column]] for _, row, column in ROTOR_TERMS])
        # Per frequency, once: the fitted entries are overwritten at every evaluation.
        self.a = np.repeat(a[None].astype(complex), omega.size, axis=0)
        self.b = np.repeat(b[None].astype(complex), omega.size, axis=0)

    def response(self, gains: np.ndarray, delays: Mapping[str, float]) -> np.ndarray:
        """(F, 2, 2) responses of q, p to long, lat."""
        for gain, (name, row, column) in zip(gains, ROTOR_TERMS):
            term = gain * np.exp(-1j * self.omega * delays.get(name, 0.0))
            target = self.a if column in ("q", "p") else self.b
            target[:, self.rows[row], self.columns[column]] = term
        return state_response(self.a, self.b, self.omega)[:, [self.rows["q"], self.rows["p"]], :]


def equivalent_delays(full, residualised, delayed: Iterable[str] = ROTOR_DERIVATIVES,
                      band: tuple[float, float] = DEFAULT_BAND, n_frequencies: int = 60,
                      upper: float = 0.4) -> EquivalentDelays:
    """Fit delayed roll/pitch terms to a full linear model's cyclic responses.

    Args:
        full: linear model with ``states``, ``controls``, ``A`` (n, n), ``B`` (n, m): the
            truth with its rotor (and inflow) states; states include q and p, controls
            long and lat.
        residualised: the same truth's 6-DoF linear model (states u w q θ v p φ r) in the
            same units; its entries outside the fitted terms stay fixed.
        delayed: the derivatives of :data:`ROTOR_TERMS` whose delays are fitted (the others
            keep no delay; all eight gains are fitted).
        band: frequency band, rad/s; ``n_frequencies`` log-spaced points.
        upper: upper bound of every delay, s.
    Returns:
        :class:`EquivalentDelays`.
    """
    delayed = list(delayed)
    unknown = sorted(set(delayed) - set(ROTOR_DERIVATIVES))
    if unknown:
        raise StructureError(f"equivalent delays are fitted for {', '.join(ROTOR_DERIVATIVES)} "
                             f"only, not {unknown}")
    low, high = band
    if not 0 < low < high:
        raise StructureError(f"band must be (low, high) with 0 < low < high rad/s, got {band}")
    omega = np.logspace(np.log10(low), np.log10(high), n_frequencies)
    truth = _truth_response(full, omega)
    scale = np.sqrt(np.mean(np.abs(truth) ** 2, axis=0))[None]
    fit = _Fit(residualised, omega, delayed)
    n_gains = len(ROTOR_TERMS)

    def unpack(x):
        return x[:n_gains], dict(zip(fit.delayed, x[n_gains:]))

    def residuals(x):
        error = (fit.response(*unpack(x)) - truth) / scale
        return np.concatenate([error.real.ravel(), error.imag.ravel()])

    lower = np.concatenate([np.full(n_gains, -np.inf), np.zeros(len(fit.delayed))])
    upper_bounds = np.concatenate([np.full(n_gains, np.inf), np.full(len(fit.delayed), upper)])
    best = None
    for start in DELAY_STARTS if fit.delayed else DELAY_STARTS[:1]:
        x0 = np.concatenate([fit.start_gains, np.full(len(fit.delayed), start)])
        result = scipy.optimize.least_squares(residuals, x0, bounds=(lower, upper_bounds),
                                              x_scale="jac", xtol=1e-12, ftol=1e-12)
        if best is None or result.cost < best.cost:
            best = result
    gains, delays = unpack(best.x)
    return EquivalentDelays(
        delays={n: float(v) for n, v in delays.items()},
        gains={name: float(g) for g, (name, _, _) in zip(gains, ROTOR_TERMS)},
        relative_rms=float(np.sqrt(np.mean(best.fun**2) * 2)), band=(float(low), float(high)))
