"""Speed sweeps: the same case identified at a list of airspeeds, results side by side.

:func:`speed_sweep` expands a template case (by default the built-in ``hover`` case, whose
data come from the ``helisim`` truth model) into one case per airspeed, named ``speed-000kt``,
``speed-010kt`` …: the truth model is trimmed in level flight at that airspeed and flown
through the template's maneuvers; structure, reduction, delays and verification are the
template's. On the command line::

    rotorid study speed-sweep --speeds 0:120:10 --quick --out results/sweep

Each case is an independent task of the :class:`~rotorid.study.pipeline.Study`. :func:`sweep_points`
gathers the delayed model's derivatives with their Cramér-Rao bounds and the truth model's
linearisation per airspeed; :func:`write_sweep_summary` writes them as ``speed-sweep.json``
with the summary figure of :mod:`rotorid.report.plots.sweep`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping
from pathlib import Path

import attrs

from rotorid.errors import DataError
from rotorid.io import atomic_write, jsonable, parse_number
from rotorid.study.case import FlightCase

#: Name of the built-in case family on the command line.
FAMILY = "speed-sweep"
#: Airspeeds of ``rotorid study speed-sweep`` without ``--speeds``: 0 to 120 kt every 10 kt.
DEFAULT_SPEEDS = "0:120:10"
MAX_SPEED_KT = 200.0
#: Most airspeeds one sweep may hold: one per kt from 0 to MAX_SPEED_KT.
MAX_SPEED_COUNT = 201


def parse_speeds(text: str) -> tuple[float, ...]:
    """Airspeeds in kt from ``"0,10,40"`` or ``"START:STOP:STEP"`` (STOP included).

    The result is sorted and free of duplicates; every speed is in [0, 200] kt.
    """
    form = ("give airspeeds in kt as a comma list such as '0,40,80' or as START:STOP:STEP "
            "such as '0:120:10'")
    text = str(text).strip()
    try:
        if ":" in text:
            start, stop, step = (parse_number(part) for part in text.split(":"))
            if not (step > 0 and start <= stop and math.isfinite(stop - start)):
                raise ValueError
        else:
            speeds = [parse_number(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise DataError(f"cannot read the airspeed list {text!r}: {form}") from None
    if ":" in text:
        span = (stop - start) / step
        _check_count(text, span + 1)
        count = int(math.floor(span + 1e-9)) + 1
        speeds = [round(start + k * step, 9) for k in range(count)]
    if not speeds:
        raise DataError(f"empty airspeed list {text!r}: {form}")
    _check_count(text, len(speeds))
    return _checked(speeds)


def _check_count(text: str, count: float) -> None:
    if count > MAX_SPEED_COUNT:
        raise DataError(f"the airspeed list {text!r} gives {count:.0f} airspeeds; a sweep holds "
                        f"at most {MAX_SPEED_COUNT}: choose a larger step")


def _checked(speeds) -> tuple[float, ...]:
    bad = [v for v in speeds if not (math.isfinite(v) and 0.0 <= v <= MAX_SPEED_KT)]
    if bad:
        raise DataError(f"airspeeds must lie in 0–{MAX_SPEED_KT:.0f} kt, got {bad}")
    speeds = sorted(set(speeds))
    names = [case_name(v) for v in speeds]
    for (lower, upper), (first, second) in zip(zip(speeds, speeds[1:]), zip(names, names[1:])):
        if first == second:
            raise DataError(f"airspeeds {lower:g} and {upper:g} kt share the case name {first} "
                            f"(names resolve 0.1 kt); choose airspeeds at least 0.1 kt apart")
    return tuple(speeds)


def case_name(airspeed_kt: float) -> str:
    """``speed-070kt`` (``speed-012.5kt`` for a fractional airspeed)."""
    if float(airspeed_kt).is_integer():
        return f"speed-{int(airspeed_kt):03d}kt"
    return f"speed-{airspeed_kt:05.1f}kt"


def speed_case(template: FlightCase, airspeed_kt: float) -> FlightCase:
    """``template`` with its generated data trimmed and flown at ``airspeed_kt``."""
    if "airspeed_kt" not in template.data:
        raise DataError(f"a speed sweep regenerates data at each airspeed, so its template "
                        f"case needs generated data flown at [data] airspeed_kt; case "
                        f"{template.name} reads {template.data_source!r} data without one")
    name = case_name(airspeed_kt)
    data = {**template.data, "condition": name, "airspeed_kt": float(airspeed_kt)}
    return attrs.evolve(template, name=name, data=data,
                        description=f"{template.name} pipeline at {airspeed_kt:g} kt")


def speed_sweep(speeds: Iterable[float] | str = DEFAULT_SPEEDS,
                template: FlightCase | str = "hover") -> tuple[FlightCase, ...]:
    """One case per airspeed (kt), from a list or a :func:`parse_speeds` string."""
    speeds = parse_speeds(speeds) if isinstance(speeds, str) else _checked(
        [float(v) for v in speeds])
    base = template if isinstance(template, FlightCase) else FlightCase.load(template)
    return tuple(speed_case(base, v) for v in speeds)


@attrs.frozen
class SweepPoint:
    """The identified model of one case of a sweep (the model with delays).

    ``values`` and ``cramer_rao`` map derivative names (delays as ``tau_<derivative>``, in s)
    to the estimate and its Cramér-Rao bound; ``truth`` maps derivative names to the truth
    model's residualised linearisation at the same trim (empty for flight data). Units are
    the structure's (flight-test by default).
    """

    case: str
    airspeed_kt: float
    values: Mapping[str, float] = attrs.field(converter=dict)
    cramer_rao: Mapping[str, float] = attrs.field(converter=dict)
    truth: Mapping[str, float] = attrs.field(factory=dict, converter=dict)
    units: str = "flight-test"

    def as_dict(self) -> dict:
        return {"case": self.case, "airspeed_kt": self.airspeed_kt, "units": self.units,
                "values": dict(self.values),
                "cramer_rao": jsonable(dict(self.cramer_rao)),
                "truth": dict(self.truth)}

    @classmethod
    def from_dict(cls, record: Mapping) -> "SweepPoint":
        return cls(record["case"], record["airspeed_kt"], record["values"],
                   {k: (math.inf if v is None else v) for k, v in record["cramer_rao"].items()},
                   record.get("truth") or {}, record.get("units", "flight-test"))


def sweep_points(results: Mapping) -> list[SweepPoint]:
    """One :class:`SweepPoint` per :class:`~rotorid.study.result.CaseResult`, by airspeed."""
    points = []
    for name, result in results.items():
        estimate = result.estimates["with delays"]
        points.append(SweepPoint(
            name, float(result.case.data.get("airspeed_kt", result.condition.airspeed_kt)),
            estimate.as_mapping(),
            dict(zip(estimate.parameter_names, estimate.cramer_rao.tolist())),
            result.truth_derivatives or {}, estimate.units))
    return sorted(points, key=lambda p: p.airspeed_kt)


def write_sweep_summary(points: list[SweepPoint], directory: str | Path,
                        stem: str = FAMILY) -> Path:
    """Write ``<stem>.json`` in ``directory`` (its figure:
    :func:`rotorid.report.plots.sweep.plot_speed_sweep`); returns its path."""
    return atomic_write(Path(directory) / f"{stem}.json",
                        json.dumps({"points": [p.as_dict() for p in points]}, indent=1))


def load_sweep_summary(path: str | Path) -> list[SweepPoint]:
    """The points of a ``speed-sweep.json`` written by :func:`write_sweep_summary`."""
    record = json.loads(Path(path).read_text())
    return [SweepPoint.from_dict(p) for p in record["points"]]
