"""Several delay starts for the delayed fit: the lowest det R wins, reproducibly."""

from __future__ import annotations

import numpy as np
import pytest
import rotorid
from rotorid.errors import DataFileError
from rotorid.study.case import FlightCase
from rotorid.study.delays import best_delayed_fit
from test_output_error import (
    SMALL_TRUTH,
    doublet_maneuvers,
    small_structure,
    with_outputs,
)

DELAYS = ("L_lat", "M_long", "L_p", "M_q")


@pytest.fixture(scope="module")
def problem():
    structure = small_structure(DELAYS)
    truth = structure.as_vector({**SMALL_TRUTH, "tau_L_lat": 0.07, "tau_M_long": 0.05,
                                 "tau_L_p": 0.03, "tau_M_q": 0.02})
    data = with_outputs(structure, truth, doublet_maneuvers(), noise=0.02, seed=5)
    return structure, data, dict(SMALL_TRUTH)


def case(**delays):
    return FlightCase.from_mapping({"name": "t", "data": {"source": "files"},
                                    "delays": {"upper": 0.3, **delays}})


def test_one_start_is_the_plain_fit_from_the_initial_delays(problem):
    structure, data, values = problem
    estimator = rotorid.create("estimators", "output-error")
    single = best_delayed_fit(case(), estimator, structure, data, values)
    plain = estimator.estimate(structure, data, start={**values, **{
        f"tau_{n}": 0.0 for n in DELAYS}})
    assert np.array_equal(single.values, plain.values)
    assert not any("delay starts" in note for note in single.notes)


def test_more_starts_never_end_higher_and_repeat_exactly(problem):
    structure, data, values = problem
    estimator = rotorid.create("estimators", "output-error")
    single = best_delayed_fit(case(), estimator, structure, data, values)
    several = best_delayed_fit(case(starts=4, seed=3), estimator, structure, data, values)
    again = best_delayed_fit(case(starts=4, seed=3), estimator, structure, data, values)
    assert several.cost <= single.cost
    assert np.array_equal(several.values, again.values)
    assert any(note.startswith("best of 4 delay starts") for note in several.notes)


def test_the_case_file_keys_are_read_and_checked():
    parsed = case(starts=5, seed=7)
    assert parsed.delay_starts == 5 and parsed.delay_seed == 7
    with pytest.raises(DataFileError, match=r"\[delays\] starts must be at least 1"):
        case(starts=0)
