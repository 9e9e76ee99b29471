"""A data source known only through the contract (``case_data``) runs a flight case: the
study uses the trim and the truth model it gives, and passes it the case's settings."""

from types import SimpleNamespace

import pytest
from rotorid import CONTROLS, STATES, Derivative, ModelStructure
from rotorid.errors import DataError
from rotorid.plugin.contracts import CaseData
from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl
from rotorid.plugin.manager import get_plugin_manager, register_plugin
from rotorid.study.case import FlightCase
from rotorid.study.montecarlo import case_monte_carlo
from rotorid.study.pipeline import Study
from test_reduction_study import HOVER, TRUE, data  # noqa: F401 (data: a fixture)

TRUTH = ModelStructure(HOVER, [Derivative(n) for n in TRUE])


class LinearTruth:
    """The linear model that made the data, as a truth model."""

    def linearize(self, airspeed_kt, *, full=False, units="flight-test"):
        a, b, _, _ = TRUTH.matrices(TRUTH.as_vector(TRUE))
        return SimpleNamespace(A=a, B=b, states=STATES, controls=CONTROLS)


class RenamedSource:
    """Maneuvers handed over in memory, with their trim and truth model."""

    received = []

    def __init__(self, maneuvers):
        self.maneuvers = maneuvers

    def case_data(self, settings, directory):
        self.received.append((dict(settings), directory))
        return CaseData(self.maneuvers, None, HOVER, LinearTruth())


@pytest.fixture
def renamed_source(data):
    class Plugin:
        @hookimpl
        def rotorid_data_sources(self):
            return [PluginDescriptor("renamed-csv", lambda: RenamedSource(data),
                                     "maneuvers from memory (test)")]

    name = register_plugin(Plugin())
    yield
    get_plugin_manager().unregister(name=name)


def test_a_third_party_source_runs_a_case_with_its_trim_and_truth(tmp_path, renamed_source):
    case = FlightCase(name="third", data={"source": "renamed-csv", "flavour": "plain"},
                      structure={"populate": "none"}, derivatives={n: {} for n in TRUE},
                      delay_derivatives=("X_long",), continue_to_zero=False)
    result = Study([case], tmp_path / "out", progress=None).run()["third"]
    assert RenamedSource.received[-1] == ({"flavour": "plain"}, tmp_path / "out" / "third" / "data")
    assert result.condition == HOVER
    assert set(result.structures["no delays"].names) == set(TRUE)
    for name, value in TRUE.items():
        assert result.truth_derivatives[name] == pytest.approx(value, abs=1e-12)
    assert result.truth_derivatives["L_u"] == 0.0
    assert result.truth_delays is None          # no rotor delay kept


def test_a_monte_carlo_names_a_source_that_cannot_regenerate_noise(tmp_path, renamed_source):
    case = FlightCase(name="third", data={"source": "renamed-csv"})
    with pytest.raises(DataError, match="the 'renamed-csv' data source cannot do"):
        case_monte_carlo(case, 3, tmp_path / "out")
