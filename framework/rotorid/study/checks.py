"""Checks of flight cases before any data exist: a misspelt derivative, an unknown envelope or
an unsafe case name is reported at once, one line naming the case file (or case) and the key,
instead of after the data have been flown.

:func:`check_case` checks one case (:class:`~rotorid.study.case.FlightCase`);
:func:`check_cases` every case of a study and that their names differ.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence

from rotorid.data import HOLDS
from rotorid.errors import DataFileError, RotoridError
from rotorid.model.signals import ChannelMap
from rotorid.estimation.reduction import RULES
from rotorid.model.modelfile import case_model
from rotorid.model.structure import FlightCondition
from rotorid.plugin.manager import create, registry
from rotorid.study.comparison import FREQUENCY_ESTIMATOR
from rotorid.study.hybrid_comparison import HYBRID_OMEGA_MAX
from rotorid.study.reference import check_reference_names
from rotorid.units import FLIGHT_TEST, unit_fits_kind, units_of_kind
from rotorid.verification.compare import envelopes_by_name
from rotorid.verification.pairs import parse_pair

#: The records' time column, which a channel map may link (in s or ms) beside the signals;
#: also the name of its kind (rotorid.units).
TIME = "time"

#: A case name is a directory of the results: letters, digits and ``_ . + -``, never a path.
SAFE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+-]*")


def check_cases(cases: Sequence) -> None:
    """Check every case (:func:`check_case`) and that no two share a name (a results
    directory)."""
    names = [case.name for case in cases]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise DataFileError(f"case name(s) {', '.join(twice)} used twice; give each case its "
                            f"own name (it is its results directory)")
    for case in cases:
        check_case(case, f"case {case.name}")


def _check_actuators(case, controls, where: str) -> None:
    """``[actuators]``: a lag in s > 0, inputs the structure has (and only with a lag)."""
    lag = case.actuator_lag_s
    if lag is not None and not (math.isfinite(lag) and lag > 0):
        raise DataFileError(f"{where}: [actuators] lag_s must be the actuators' first-order "
                            f"time constant in s (> 0), got {lag!r}")
    if case.actuator_inputs is not None:
        if lag is None:
            raise DataFileError(f"{where}: [actuators] inputs needs lag_s, the time constant "
                                f"of their lag")
        unknown = [name for name in case.actuator_inputs if name not in controls]
        if unknown:
            raise DataFileError(f"{where}: [actuators] inputs names {', '.join(unknown)}, not "
                                f"an input of the structure ({', '.join(controls)})")


def check_case(case, where: str) -> None:
    """Raise :class:`~rotorid.errors.DataFileError` naming ``where`` (the case file) and the
    key of the first setting of ``case`` that cannot work."""
    _check_name(case.name, where)
    if "source" not in case.data:
        raise DataFileError(f"{where}: [data] needs a source, e.g. source = \"files\"")
    check_registered("data-sources", case.data_source, where, "[data] source")
    links = _channel_links(case, where)
    structure = _starting_structure(case, where)
    _check_channels(links, structure, where)
    if "states" in case.structure and "units" not in case.data:
        raise DataFileError(f"{where}: [structure] declares its own signals, whose known terms "
                            f"are numbers in one unit system; say which in [data] units = "
                            f"\"si\" (or \"flight-test\"), so the data are read in it")
    _check_delays(case, structure.names, where)
    _check_actuators(case, structure.controls, where)
    check_reference_names(case.reference, structure.names, where)
    for pair in case.pairs:
        _wrapped(lambda: parse_pair(pair, structure.outputs, structure.controls), where,
                 "[verification] pairs")
    for envelope in case.envelopes:
        check_registered("validation-envelopes", envelope, where, "[verification] envelopes")
    _wrapped(lambda: envelopes_by_name(case.envelopes, band=case.band), where,
             "[verification] envelopes")
    check_registered("estimators", case.estimator, where, "[estimator] name")
    estimator = _wrapped(lambda: create("estimators", case.estimator,
                                        **case.estimator_options), where, "[estimator]")
    if hasattr(estimator, "check_structure"):
        _wrapped(lambda: estimator.check_structure(structure), where, "[estimator]")
    for criterion, options in case.criteria:
        check_registered("reduction-criteria", criterion, where, "[reduction] criteria")
        _wrapped(lambda: create("reduction-criteria", criterion, **options), where,
                 "[reduction] criteria")
    if case.rule not in RULES:
        raise DataFileError(f"{where}: [reduction] rule {case.rule!r} is unknown; use "
                            f"{', '.join(RULES)}")
    if not (math.isfinite(case.rmse_tolerance) and case.rmse_tolerance >= 0):
        raise DataFileError(f"{where}: [reduction] rmse_tolerance must be a fraction ≥ 0 "
                            f"(e.g. 0.01), got {case.rmse_tolerance!r}")
    _check_compare(case, where)
    _check_band_limit(case, where)


def _check_band_limit(case, where: str) -> None:
    """``[resampling]``: a cutoff > 0 Hz, a decimation factor ≥ 1 only with it, a
    known hold."""
    if case.identification_hold not in (None, *HOLDS):
        raise DataFileError(f"{where}: [resampling] hold must be \"zoh\" (zero-order) or "
                            f"\"foh\" (first-order), got {case.identification_hold!r}")
    if case.cutoff_hz is not None and not (math.isfinite(case.cutoff_hz)
                                           and case.cutoff_hz > 0):
        raise DataFileError(f"{where}: [resampling] cutoff_hz must be a frequency > 0 Hz "
                            f"(below the records' Nyquist frequency), got {case.cutoff_hz!r}")
    if case.decimate is not None:
        if case.cutoff_hz is None:
            raise DataFileError(f"{where}: [resampling] decimate needs cutoff_hz, the "
                                f"low-pass that comes before it")
        if case.decimate < 1:
            raise DataFileError(f"{where}: [resampling] decimate must be a whole number "
                                f"≥ 1 (samples per kept sample), got {case.decimate!r}")
        if case.keeps_every_sample:
            raise DataFileError(f"{where}: give [resampling] decimate or [estimator] "
                                f"update_every, not both: with update_every the low-passed "
                                f"records keep every sample and the filter updates once per "
                                f"update_every of them")


def _check_compare(case, where: str) -> None:
    """The ``[compare]`` settings: the frequency-domain estimator, the pairs and the band,
    and the estimators compared on the identification data."""
    if case.compare_frequency:
        check_registered("estimators", FREQUENCY_ESTIMATOR, where, "[compare] frequency needs "
                         "the estimator")
    elif case.compare_pairs or case.compare_band_max is not None:
        raise DataFileError(f"{where}: [compare] pairs and band_max apply to the "
                            f"frequency-domain fit only; add frequency = true or drop them")
    top = case.compare_hybrid_band_max
    if not (math.isfinite(top) and top > 1.0):
        raise DataFileError(f"{where}: [compare] hybrid_band_max must be the sweeps' top "
                            f"frequency in rad/s, above 1, got {top!r}")
    if (top != HYBRID_OMEGA_MAX or case.compare_hybrid_reduction) and not case.compare_hybrid:
        raise DataFileError(f"{where}: [compare] hybrid_band_max and hybrid_reduction apply to "
                            f"the hybrid comparison only; add hybrid = true or drop them")
    for pair in case.compare_pairs:
        _wrapped(lambda: parse_pair(pair), where, "[compare] pairs")
    band_max = case.compare_band_max
    if band_max is not None and not (math.isfinite(band_max) and band_max > 0):
        raise DataFileError(f"{where}: [compare] band_max must be a positive frequency in "
                            f"rad/s (e.g. 10.0), got {band_max!r}")
    _check_compared_estimators(case, where)


def _check_compared_estimators(case, where: str) -> None:
    names = case.compare_estimators
    if not names:
        return
    key = "[compare] estimators"
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise DataFileError(f"{where}: {key} names {', '.join(twice)} twice; name each once")
    for name in names:
        check_registered("estimators", name, where, key)
    if FREQUENCY_ESTIMATOR in names:
        raise DataFileError(f"{where}: {key}: {FREQUENCY_ESTIMATOR} fits the sweeps' "
                            f"frequency responses, not the identification time histories; "
                            f"use [compare] frequency = true for it")
    if set(names) <= {case.estimator}:
        raise DataFileError(f"{where}: {key} names only the case's own estimator "
                            f"({case.estimator}); add another, e.g. estimators = "
                            f"[\"output-error\", \"filter-error\"]")


def _check_name(name: str, where: str) -> None:
    if not SAFE_NAME.fullmatch(name):
        raise DataFileError(f"{where}: name {name!r} cannot name a results directory; use "
                            f"letters, digits and _ . + - only, starting with a letter or digit")


def check_registered(family: str, name: str, where: str, key: str) -> None:
    """Raise when no plugin of ``family`` is registered as ``name`` (the setting ``key``)."""
    known = registry(family)
    if name not in known:
        raise DataFileError(f"{where}: {key} {name!r} is not registered in the {family} "
                            f"family; use one of {', '.join(known)} (rotorid plugins)")


def _wrapped(check, where: str, key: str | None = None):
    """``check()``, its rotorid error reported as one line naming ``where`` and ``key`` (when
    the error does not name it already)."""
    try:
        return check()
    except RotoridError as error:
        raise DataFileError(f"{where}: {f'{key}: ' if key else ''}{error}") from None


def _starting_structure(case, where: str):
    """The case's starting structure (its ``[structure]`` and ``[derivatives]`` tables checked
    at a placeholder trim), after checking ``[condition]``."""
    if case.condition:
        _wrapped(lambda: FlightCondition.from_mapping(case.condition), where)
    structure = case_model(case.as_dict(), {"airspeed_kt": 0.0}, FLIGHT_TEST.name, where)
    if not structure.parameter_names:
        raise DataFileError(f"{where}: [structure]/[derivatives] leave no free derivative to "
                            f"estimate; declare at least one without 'fixed'")
    return structure


def _channel_links(case, where: str) -> tuple:
    """The links of a ``[data] channels`` map (a files case's; none without one), checked as
    a channel map before the structure reads its control units."""
    table = case.data.get("channels")
    if table is None:
        return ()
    if not isinstance(table, Mapping):
        raise DataFileError(f"{where}: [data] channels must be a table of COLUMN = {{ signal "
                            f"= \"q\", unit = \"deg/s\" }}, got {table!r}")
    return _wrapped(lambda: ChannelMap.from_mapping(table, "[data] channels").links, where)


def _check_channels(links, structure, where: str) -> None:
    """The channel map's ``links`` name signals of the case's structure (or the records'
    time), each in a unit that fits the signal's kind; its columns are checked when the files
    are read."""
    signals = structure.signals.all
    for link in links:
        if link.signal != TIME and link.signal not in signals:
            raise DataFileError(f"{where}: [data] channels: column {link.column!r} is linked to "
                                f"{link.signal!r}, which is not a signal of the case's "
                                f"structure ({', '.join(signals.names)}) nor {TIME}; link it to "
                                f"one of them")
        kind = TIME if link.signal == TIME else signals[link.signal].kind
        if not unit_fits_kind(link.unit, kind):
            raise DataFileError(f"{where}: [data] channels: column {link.column!r} has unit "
                                f"{link.unit}, which does not fit {link.signal!r} ({kind}); "
                                f"give one of {', '.join(units_of_kind(kind))}")


def _check_delays(case, names: tuple[str, ...], where: str) -> None:
    unknown = [name for name in case.delay_derivatives or () if name not in names]
    if unknown:
        raise DataFileError(f"{where}: [delays] derivatives {', '.join(unknown)} are not in "
                            f"the case's structure; delay only derivatives it declares")
    upper, initial = case.delay_upper, case.delay_initial
    if not upper > 0 or not math.isfinite(upper):
        raise DataFileError(f"{where}: [delays] upper must be a positive time in s (the "
                            f"paper's delays stay below 0.3 s), got {upper!r}")
    if not (math.isfinite(initial) and 0 <= initial <= upper):
        raise DataFileError(f"{where}: [delays] initial must lie in [0, upper = {upper:g}] s, "
                            f"got {initial!r}")
    if not (math.isfinite(case.delay_threshold) and case.delay_threshold > 0):
        raise DataFileError(f"{where}: [delays] threshold must be a positive percentage (a "
                            f"normalised Cramér-Rao bound), got {case.delay_threshold!r}")
