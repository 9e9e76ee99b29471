"""A user's reference values of derivatives (a case file's ``[reference]`` table) and the
identified model held against them.

A case on the user's own data is compared with no published aircraft; ``[reference]`` names
the values it should be compared with instead, e.g. a previous model or wind-tunnel data::

    [reference]
    source = "previous model, report TR-12 table 4"   # default source of every entry
    M_q = -3.9
    L_v = { value = -0.41, uncertainty = 0.05, source = "wind tunnel, run 12" }

Values and uncertainties (one standard deviation, e.g. the reference's own Cramér-Rao bound)
are in the unit system of the identified model, that of the data (``Estimate.units``). Every
name must be a derivative of the case's structure; that is checked when the case is read.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import attrs

from rotorid.errors import DataFileError
from rotorid.study.expectations import SIGNIFICANCE, derivative_unit

#: Keys of a ``[reference]`` entry given as a table.
ENTRY_KEYS = ("value", "uncertainty", "source")


@attrs.frozen
class ReferenceValue:
    """One reference value; ``uncertainty`` (one standard deviation, same unit) may be None."""

    value: float
    uncertainty: float | None = None
    source: str = ""


def _number(value, where: str, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(value) or (positive and value <= 0):
        kind = "a positive number" if positive else "a finite number"
        raise DataFileError(f"{where} must be {kind}, got {value!r}")
    return float(value)


def parse_reference(table: Mapping, where: str) -> dict[str, ReferenceValue]:
    """Reference values by derivative name from a ``[reference]`` table (see the module
    docstring); ``where`` names the table in errors. Names are checked against the structure
    by :func:`check_reference_names`."""
    default_source = table.get("source", "")
    if not isinstance(default_source, str):
        raise DataFileError(f"{where} source must be a text, got {default_source!r}")
    values = {}
    for name, entry in table.items():
        if name == "source":
            continue
        if not isinstance(entry, Mapping):
            values[name] = ReferenceValue(_number(entry, f"{where} {name}"), None,
                                          default_source)
            continue
        unknown = sorted(set(entry) - set(ENTRY_KEYS))
        if unknown or "value" not in entry:
            raise DataFileError(f"{where} {name}: give a number or a table with value (and "
                                f"optionally uncertainty, source), got keys {sorted(entry)}")
        uncertainty = entry.get("uncertainty")
        source = entry.get("source", default_source)
        if not isinstance(source, str):
            raise DataFileError(f"{where} {name}.source must be a text, got {source!r}")
        values[name] = ReferenceValue(
            _number(entry["value"], f"{where} {name}.value"),
            None if uncertainty is None else _number(uncertainty, f"{where} {name}.uncertainty",
                                                     positive=True),
            source)
    return values


def check_reference_names(reference: Mapping[str, ReferenceValue], names, where: str) -> None:
    """Refuse reference names that are not derivatives of the case's structure ``names``."""
    unknown = [name for name in reference if name not in names]
    if unknown:
        raise DataFileError(f"{where}: [reference] {', '.join(unknown)} are not derivatives of "
                            f"the case's structure; give values only for derivatives it "
                            f"declares (e.g. M_q, L_v)")


@attrs.frozen
class ReferenceComparison:
    """An identified derivative beside its reference value (the identified model's units).

    ``identified`` and ``cramer_rao`` are None when the reduction removed the derivative.
    ``verdict``: ``"agrees"`` when the difference is within :data:`SIGNIFICANCE` combined
    bounds √(CR² + uncertainty²), ``"differs"`` beyond, ``"removed"``.
    """

    name: str
    unit: str
    identified: float | None
    cramer_rao: float | None
    reference: ReferenceValue

    @property
    def difference(self) -> float | None:
        """identified − reference, or None when removed."""
        return None if self.identified is None else self.identified - self.reference.value

    @property
    def combined_bound(self) -> float | None:
        """√(CR² + uncertainty²), or None when removed."""
        if self.cramer_rao is None:
            return None
        return math.hypot(self.cramer_rao, self.reference.uncertainty or 0.0)

    @property
    def verdict(self) -> str:
        if self.identified is None:
            return "removed"
        return ("agrees" if abs(self.difference) <= SIGNIFICANCE * self.combined_bound
                else "differs")

    def as_dict(self) -> dict:
        return {"name": self.name, "unit": self.unit, "identified": self.identified,
                "cramer_rao": self.cramer_rao, "reference": self.reference.value,
                "reference_uncertainty": self.reference.uncertainty,
                "source": self.reference.source, "difference": self.difference,
                "combined_bound": self.combined_bound, "verdict": self.verdict}


def compare_with_reference(estimate, reference: Mapping[str, ReferenceValue]
                           ) -> list[ReferenceComparison]:
    """Each reference value beside the identified ``estimate``'s, in the table's order."""
    rows = []
    for name, value in reference.items():
        item = estimate[name] if name in estimate else None
        rows.append(ReferenceComparison(
            name, estimate.parameter_units.get(name) or derivative_unit(name, estimate.units),
            None if item is None else item.value,
            None if item is None else item.cramer_rao, value))
    return rows
