"""An estimator's estimates of the model's states along each maneuver.

Filter error's Kalman filter estimates, at each measurement update n, the state x̂(n|n) from
the samples up to n: the aircraft's states and its noise model's (a disturbance acceleration
``d_<state>``, a gust velocity ``g_<state>``). These are what the turbulence was on a flight,
as the identified model sees it (docs/estimation.md, "The filter's state estimates"). An
estimator that can give them has the optional method ``state_estimates(structure, maneuvers,
estimate)`` (:class:`rotorid.plugin.contracts.Estimator`); ``rotorid identify --states DIR``
writes them as maneuver files and plots them.
"""

from __future__ import annotations

import attrs
import numpy as np

from rotorid.data import Maneuver, ManeuverSet
from rotorid.errors import EstimationError
from rotorid.frozen import readonly_array

#: What the files' ``content`` header says.
CONTENT = "state estimates"
#: Where a study writes them, in the case's directory.
STUDY_DIRECTORY = "state_estimates"


def _arrays(values) -> tuple[np.ndarray, ...]:
    return tuple(readonly_array(v) for v in values)


@attrs.frozen(eq=False)
class StateEstimates:
    """States estimated along each maneuver.

    Attributes:
        names: (s,) the states, in the estimator's order.
        units: (s,) their units (the structure's; a disturbance's is its state's per s).
        maneuvers: the maneuvers' names.
        time: per maneuver (N_i,) the instants estimated, s (every sample, or every
            measurement update).
        values: per maneuver (N_i, s) the estimates.
        standard_deviation: (s,) the standard deviation of each estimate's error as the
            estimator states it (the steady-state filter's covariance), units of ``units``.
        method: one line on what the estimates are (e.g. ``"Kalman filter x̂(n|n)"``).
    """

    names: tuple[str, ...] = attrs.field(converter=tuple)
    units: tuple[str, ...] = attrs.field(converter=tuple)
    maneuvers: tuple[str, ...] = attrs.field(converter=tuple)
    time: tuple[np.ndarray, ...] = attrs.field(converter=_arrays)
    values: tuple[np.ndarray, ...] = attrs.field(converter=_arrays)
    standard_deviation: np.ndarray = attrs.field(converter=readonly_array)
    method: str = ""

    def __attrs_post_init__(self):
        count = len(self.names)
        if len(self.units) != count or self.standard_deviation.shape != (count,):
            raise EstimationError(f"state estimates: {count} names need as many units and "
                                  f"standard deviations, got {len(self.units)} and "
                                  f"{self.standard_deviation.shape}")
        if not len(self.maneuvers) == len(self.time) == len(self.values):
            raise EstimationError("state estimates: one time and one value array per maneuver")
        for name, time, values in zip(self.maneuvers, self.time, self.values):
            if values.shape != (time.size, count):
                raise EstimationError(f"state estimates of maneuver {name!r}: values of shape "
                                      f"{values.shape}, expected ({time.size}, {count})")

    def summary(self) -> dict:
        """What a result record says of them: the states, units, error spreads, the method,
        the maneuvers, and where a study writes them (``state_estimates/<maneuver>.csv``)."""
        return {"names": list(self.names), "units": dict(zip(self.names, self.units)),
                "standard_deviation": dict(zip(self.names, self.standard_deviation.tolist())),
                "method": self.method, "maneuvers": list(self.maneuvers),
                "files": f"{STUDY_DIRECTORY}/<maneuver>.csv"}

    def of(self, name: str) -> np.ndarray:
        """(ΣN_i,) the estimates of state ``name``, the maneuvers one after the other."""
        if name not in self.names:
            raise EstimationError(f"no state estimate named {name!r}; the estimates are "
                                  f"{', '.join(self.names)}")
        column = self.names.index(name)
        return np.concatenate([v[:, column] for v in self.values])

    def as_maneuvers(self, maneuvers: ManeuverSet) -> ManeuverSet:
        """The estimates as maneuver files hold them: per maneuver of ``maneuvers`` (the
        records estimated) its inputs at the estimated instants and the estimates as
        outputs; the header names the content, the units and the error's standard deviation
        (``content``, ``state_units``, ``standard_deviation``)."""
        by_name = {m.name: m for m in maneuvers}
        missing = [n for n in self.maneuvers if n not in by_name]
        if missing:
            raise EstimationError(f"state estimates of {', '.join(missing)}: no such maneuver "
                                  f"among {', '.join(by_name)}")
        header = {"content": CONTENT, "method": self.method,
                  "state_units": dict(zip(self.names, self.units)),
                  "standard_deviation": dict(zip(self.names, self.standard_deviation.tolist()))}
        written = []
        for name, time, values in zip(self.maneuvers, self.time, self.values):
            record = by_name[name]
            rows = np.searchsorted(record.time, time - 1e-9 * record.dt)
            metadata = {k: v for k, v in record.metadata.items() if k != "converted_units"}
            written.append(Maneuver(
                name, time, record.inputs[rows], values, metadata={**metadata, **header},
                units=record.units, input_names=record.input_names, output_names=self.names))
        return ManeuverSet(written, hold=maneuvers.hold)
