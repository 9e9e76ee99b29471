"""The linearised truth plant against the truth model's own linearisation and physics."""

import numpy as np
import pytest
from rotorid import FlightCondition, ModelStructure
from rotorid.errors import DataError
from rotorid.study.truth import truth_derivatives
from rotorid_helisim.linear_truth import LinearisedPlant, linearised_trim
from rotorid_helisim.linearize import PADFIELD_STATES, linearize
from rotorid_helisim.loops import BODY
from rotorid_helisim.model import Bo105Model
from rotorid_helisim.source import HelisimSource
from rotorid_helisim.trim import trim


@pytest.fixture(scope="module")
def hover():
    model = Bo105Model()
    point = trim(model, 0.0)
    return model, point, LinearisedPlant.about(model, point)


def test_state_and_stick_matrices_are_the_residualised_linearisation(hover):
    """A and B (per % of stick through the stick mixing) equal linearize()'s in SI."""
    model, point, plant = hover
    reference = linearize(model, point, units="si")
    order = [BODY.index(name) for name in PADFIELD_STATES]
    np.testing.assert_allclose(plant.a[np.ix_(order, order)], reference.A, rtol=1e-6,
                               atol=1e-6 * np.abs(reference.A).max())
    np.testing.assert_allclose(plant.b[order], reference.B @ model.config.mixing.matrix,
                               rtol=1e-6, atol=1e-6 * np.abs(reference.B).max())


def test_translational_gusts_act_as_the_negative_velocity(hover):
    """In hover (no body rates at trim) the air sees the velocity minus the gust, so each
    translational gust column is the negative of the velocity's column, in the state
    derivatives and in the accelerometers."""
    _, _, plant = hover
    velocity = [BODY.index(name) for name in ("u", "v", "w")]
    np.testing.assert_allclose(plant.g[:, :3], -plant.a[:, velocity], rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(plant.h[:, :3], -plant.c[:, velocity], rtol=1e-4, atol=1e-6)


def test_flown_plant_reproduces_its_linear_model(hover):
    """derivatives and measurements are affine in state, stick and gust about the trim."""
    _, _, plant = hover
    rng = np.random.default_rng(3)
    x = plant.trim_state + rng.normal(size=(2, 9)) * 0.1
    stick = plant.trim_stick + rng.normal(size=(2, 4))
    gust = rng.normal(size=(2, 6))
    expected = (x - plant.trim_state) @ plant.a.T + (stick - plant.trim_stick) @ plant.b.T
    np.testing.assert_allclose(plant.derivatives(x, stick, gust), expected + gust @ plant.g.T)
    assert plant.measurements(plant.trim_state[None], plant.trim_stick[None]) == (
        pytest.approx(plant.trim_measurements[None]))


def test_longitudinal_cut_keeps_the_longitudinal_block_only(hover):
    _, _, plant = hover
    cut = plant.longitudinal()
    lon = [BODY.index(name) for name in ("u", "w", "q", "theta")]
    lat = [BODY.index(name) for name in ("v", "p", "r", "phi", "psi")]
    np.testing.assert_array_equal(cut.a[np.ix_(lon, lon)], plant.a[np.ix_(lon, lon)])
    assert not np.any(cut.a[np.ix_(lon, lat)]) and not np.any(cut.a[np.ix_(lat, lon)])
    assert not np.any(cut.b[lon][:, [1, 3]]) and not np.any(cut.g[lon][:, [1, 3, 5]])
    assert not np.any(cut.c[:4][:, lat]) and not np.any(cut.h[:4][:, [1, 3, 5]])


def test_trimmer_refuses_another_airspeed(hover):
    _, _, plant = hover
    assert linearised_trim(plant, 0.0).stick is plant.trim_stick
    with pytest.raises(DataError, match="holds at 0 kt, not at 70 kt"):
        linearised_trim(plant, 70.0)


def test_rotor_kept_has_the_truth_models_states_and_the_same_quasi_steady_limit(hover):
    """With the rotor kept the plant runs over the truth model's states; residualising them
    from its matrices gives the rigid-body plant back."""
    model, point, plant = hover
    full = LinearisedPlant.about(model, point, rotor=True)
    assert full.state_names == model.state_names
    body = [full.state_names.index(name) for name in BODY]
    rest = [i for i in range(full.n_states) if i not in body]
    gain = np.linalg.solve(full.a[np.ix_(rest, rest)], full.a[np.ix_(rest, body)])
    quasi_steady = full.a[np.ix_(body, body)] - full.a[np.ix_(body, rest)] @ gain
    np.testing.assert_allclose(quasi_steady, plant.a, rtol=1e-9, atol=1e-12)
    with pytest.raises(DataError, match="rigid-body plant"):
        full.longitudinal()


@pytest.mark.parametrize("template", ["longitudinal", "lateral", "hybrid"])
def test_truth_derivatives_of_a_template_with_fewer_controls_read_their_own_columns(template):
    """A structure with fewer controls than the truth (long and coll of `longitudinal`) reads
    each control's own column of the linearisation: the same values as the six-dof
    structure's (hybrid: the flap-coupled model, whose control columns are checked against
    the full linearisation residualised by hand)."""
    import rotorid
    from rotorid import FlightCondition, ModelStructure
    from rotorid.study.truth import truth_derivatives

    source = rotorid.create("data-sources", "helisim")
    condition = FlightCondition.from_airspeed(0.0)
    six_dof = truth_derivatives(source, condition, ModelStructure.populated(condition))
    reduced = truth_derivatives(source, condition,
                                ModelStructure.populated(condition, template))
    shared = [name for name in reduced if name in six_dof]
    assert any(name.endswith("_coll") or name.endswith("_ped") for name in shared)
    if template != "hybrid":
        for name in shared:
            assert reduced[name] == pytest.approx(six_dof[name], rel=1e-9, abs=1e-12), name
    else:
        # the coll and ped columns reach the body without the flap: as in the six-dof model
        for name in ("Z_coll", "N_ped"):
            assert reduced[name] == pytest.approx(six_dof[name], rel=0.05), name


def test_a_structure_at_the_truths_derivatives_flies_as_the_linearised_truth(hover):
    """The six-dof structure at the truth model's derivatives (read in flight-test units),
    flown as a plant, has the residualised linearisation's A, B, C, D and translational gust
    columns back in SI (the heading row from the Euler kinematics alike)."""
    model, point, plant = hover
    index = {name: i for i, name in enumerate(model.state_names)}
    condition = FlightCondition.from_airspeed(0.0, np.degrees(point.state[index["theta"]]),
                                              np.degrees(point.state[index["phi"]]))
    six_dof = ModelStructure.six_dof(condition)
    source = HelisimSource()
    values = six_dof.as_vector(truth_derivatives(source, condition, six_dof))
    flown = LinearisedPlant.of_structure(six_dof, values, point.stick)
    assert flown.state_names == BODY
    for mine, truths in ((flown.a, plant.a), (flown.b, plant.b), (flown.c, plant.c),
                         (flown.d, plant.d), (flown.g[:, :3], plant.g[:, :3]),
                         (flown.h[:, :3], plant.h[:, :3])):
        np.testing.assert_allclose(mine, truths, rtol=1e-6, atol=1e-9 * np.abs(truths).max())
    assert not np.any(flown.g[:, 3:])
    np.testing.assert_array_equal(flown.trim_state[[BODY.index("theta"), BODY.index("phi")]],
                                  [condition.theta0, condition.phi0])


def test_a_structure_without_the_six_dof_outputs_is_refused():
    lateral = ModelStructure.populated(FlightCondition.from_airspeed(0.0), "lateral")
    with pytest.raises(DataError, match="needs the six-dof states and outputs; 'lateral' "
                                        "lacks u, w, q, theta, ax, az"):
        LinearisedPlant.of_structure(lateral, lateral.initial_values(), np.zeros(4))
