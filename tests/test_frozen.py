"""Read-only containers of frozen values: arrays that refuse writes and are copies, mappings
that refuse changes and survive pickling (results travel between processes)."""

import pickle

import numpy as np
import pytest
from rotorid.frozen import FrozenMapping, readonly_array
from rotorid.model.derivatives import delay_parameter, delayed_derivative, parameter_label


def test_a_readonly_array_is_a_copy_that_refuses_writes():
    source = [1, 2, 3]
    array = readonly_array(source, complex)
    assert array.dtype == complex and array.tolist() == [1, 2, 3]
    with pytest.raises(ValueError):
        array[0] = 5
    original = np.zeros(2)
    readonly_array(original)
    original[0] = 1.0                                  # the copy leaves the caller's array alone


def test_a_frozen_mapping_refuses_changes_and_pickles():
    mapping = FrozenMapping({"muad": 1, "aee": 2})
    with pytest.raises(TypeError):
        mapping["muad"] = 3
    again = pickle.loads(pickle.dumps(mapping))
    assert dict(again) == {"muad": 1, "aee": 2} and list(again) == ["muad", "aee"]


def test_delay_parameter_names_round_trip():
    assert delay_parameter("L_lat") == "tau_L_lat"
    assert delayed_derivative("tau_L_lat") == "L_lat"
    assert delayed_derivative("L_lat") is None
    assert parameter_label("tau_M_q") == "τ M_q" and parameter_label("M_q") == "M_q"
