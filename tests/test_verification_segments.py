"""Segment-restarted simulation of unstable models for sweep verification."""

import numpy as np
import pytest
from hover_reference import closed_loop_maneuvers, true_structure
from rotorid import ManeuverSet
from rotorid.errors import VerificationError
from rotorid.simulation.simulator import simulate
from rotorid.verification.segments import segmented_simulation
from rotorid.verification.verify import DRIFT_LIMIT, verify_model


@pytest.fixture(scope="module")
def hover():
    structure, truth = true_structure()
    data = closed_loop_maneuvers(structure, truth, seed=5, noise_scale=0.0)
    return structure, truth, ManeuverSet(list(data)[:4])


def test_restarts_from_the_data_reproduce_the_model_that_made_the_data(hover):
    structure, truth, data = hover
    plain = simulate(structure, truth, data)
    segmented = segmented_simulation(structure, truth, data, segment=4.0)
    for m, a, b in zip(data, plain, segmented):
        assert b.shape == a.shape
        scale = np.sqrt(np.mean(a**2, axis=0)) + 1e-9
        assert np.all(np.sqrt(np.mean((a - b) ** 2, axis=0)) < 0.1 * scale), m.name


def test_restarts_bound_the_drift_of_a_wrong_unstable_model(hover):
    structure, truth, data = hover
    wrong = truth.copy()
    wrong[structure.parameter_names.index("M_u")] *= 3.0     # a faster unstable phugoid
    plain = simulate(structure, wrong, data)
    segmented = segmented_simulation(structure, wrong, data, segment=3.0)
    q = structure.outputs.index("q")
    for m, a, b in zip(data, plain, segmented):
        error_plain = np.sqrt(np.mean((m.outputs[:, q] - a[:, q]) ** 2))
        error_segmented = np.sqrt(np.mean((m.outputs[:, q] - b[:, q]) ** 2))
        assert error_segmented < error_plain, m.name


def test_segment_must_be_positive(hover):
    structure, truth, data = hover
    with pytest.raises(VerificationError, match="positive duration"):
        segmented_simulation(structure, truth, data, segment=0.0)


def test_only_a_fast_instability_over_the_record_is_simulated_in_segments(hover):
    structure, truth, data = hover
    faster = truth.copy()
    faster[structure.parameter_names.index("M_u")] *= 20.0
    longest = max(m.duration for m in data)

    def growth_over_record(values):
        return np.max(np.linalg.eigvals(structure.matrices(values)[0]).real) * longest

    def segmented(values):
        result = verify_model(structure, values, data, pairs=("q/long",), envelopes=["muad"])
        return any("segments" in note for note in result.notes)

    # The hover phugoid grows less than 100-fold over the records, the faster one more.
    assert 0 < growth_over_record(truth) < np.log(DRIFT_LIMIT) < growth_over_record(faster)
    assert not segmented(truth)
    assert segmented(faster)
