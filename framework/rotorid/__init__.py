"""rotorid: time-domain system identification of helicopter flight dynamics.

The public API is importable from the package top level::

    import rotorid
    structure = rotorid.ModelStructure.six_dof(rotorid.FlightCondition.from_airspeed(0.0))
"""

from importlib.metadata import PackageNotFoundError, version

from rotorid.data import Maneuver, ManeuverSet
from rotorid.errors import (
    ConvergenceWarning,
    DataError,
    DataFileError,
    DataWarning,
    DerivativeError,
    EstimationError,
    IdentifiabilityWarning,
    MissingFileError,
    PluginError,
    RotoridError,
    RotoridWarning,
    SignalError,
    SimulationDivergedError,
    StructureError,
)
from rotorid.estimation.integrated import InitialConditions, IntegratedModel
from rotorid.estimation.result_file import IdentifiedModel, load_result, to_statespace
from rotorid.ingestion import Ingestion
from rotorid.model.derivatives import Delay, Derivative, Sign
from rotorid.model.nonlinear import NonlinearModel, Parameter
from rotorid.model.signals import ChannelLink, ChannelMap, ModelSignals, Signal, SignalSet
from rotorid.model.statespace import NamedStateSpace, state_space
from rotorid.model.structure import (
    CONTROLS,
    OUTPUTS,
    STATES,
    FlightCondition,
    ModelStructure,
)
from rotorid.estimation.estimate import Estimate, ParameterEstimate, statistics
from rotorid.plugin.contracts import (
    CaseData,
    Command,
    DataSource,
    Estimator,
    InputSignal,
    LinearSystem,
    ReductionCriterion,
    Removal,
    TruthModel,
    ValidationEnvelope,
)
from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl
from rotorid.plugin.manager import (
    create,
    get_plugin_manager,
    new_plugin_manager,
    notify,
    register_plugin,
    registry,
)
from rotorid.simulation.integrators import Integration
from rotorid.simulation.simulator import Simulator, sensitivities, simulate
from rotorid.simulation.transfer import frequency_response
from rotorid.units import FLIGHT_TEST, SI, UnitSystem, unit_system
from rotorid.verification.envelopes import EnvelopeBounds, EnvelopeCheck, check_bounds

try:
    __version__ = version("rotorid")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"

__all__ = [
    "CONTROLS", "OUTPUTS", "STATES", "FLIGHT_TEST", "SI",
    "CaseData", "ChannelLink", "ChannelMap", "Command", "ConvergenceWarning", "DataError",
    "DataFileError", "DataSource", "DataWarning", "Delay", "Derivative", "DerivativeError", "EnvelopeBounds",
    "EnvelopeCheck", "Estimate", "EstimationError", "Estimator", "FlightCondition",
    "IdentifiabilityWarning", "IdentifiedModel", "Ingestion", "InitialConditions", "InputSignal",
    "IntegratedModel", "Integration", "LinearSystem", "Maneuver", "ManeuverSet",
    "MissingFileError", "ModelSignals", "ModelStructure", "NamedStateSpace", "NonlinearModel",
    "Parameter", "ParameterEstimate",
    "PluginDescriptor", "PluginError", "ReductionCriterion", "Removal", "RotoridError",
    "RotoridWarning", "Sign", "Signal", "SignalError", "SignalSet", "SimulationDivergedError",
    "Simulator", "StructureError", "TruthModel", "UnitSystem", "ValidationEnvelope",
    "check_bounds", "create", "frequency_response", "get_plugin_manager", "hookimpl",
    "load_result", "new_plugin_manager", "notify", "register_plugin", "registry",
    "sensitivities", "simulate", "state_space", "statistics", "to_statespace", "unit_system",
]
