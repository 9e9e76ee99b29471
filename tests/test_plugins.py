"""The plugin system: documented hooks, entry points, registries and their failure modes."""

import inspect
import re
import subprocess
import sys
import textwrap
import types
from importlib.metadata import entry_points
from pathlib import Path

import attrs
import numpy as np
import pytest
import rotorid
from rotorid.errors import PluginError
from rotorid.estimation.reduction import reduce
from rotorid.plugin import hookspecs
from rotorid.plugin.contracts import CONTRACTS, Removal, members, violations
from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl
from rotorid.plugin.manager import (
    FAMILIES,
    create,
    current_manager,
    get_plugin_manager,
    new_plugin_manager,
    notify,
    register_plugin,
    registry,
    using,
)
from rotorid.verification.compare import envelopes_by_name
from rotorid.verification.envelopes import EnvelopeBounds, check_bounds

DOCS = Path(__file__).resolve().parents[1] / "docs" / "hooks.md"
PLUGINS_DOC = DOCS.with_name("plugins.md")
ENTRY_POINTS = sorted(entry_points(group=hookspecs.PROJECT), key=lambda e: e.name)


def hook_specs() -> dict[str, list[str]]:
    """Every hook in hookspecs.py with its argument names."""
    return {name: list(inspect.signature(function).parameters)
            for name, function in vars(hookspecs).items()
            if callable(function) and hasattr(function, f"{hookspecs.PROJECT}_spec")}


def documented_hooks() -> dict[str, list[str]]:
    """Every ``### rotorid_*`` section of docs/hooks.md with the arguments of its signature."""
    sections = re.split(r"^### ", DOCS.read_text(), flags=re.MULTILINE)[1:]
    found = {}
    for section in sections:
        name = section.splitlines()[0].strip().strip("`")
        signature = re.search(rf"^{name}\((.*?)\)", section, flags=re.MULTILINE)
        assert signature, f"docs/hooks.md: section {name} has no '{name}(...)' signature line"
        found[name] = [a.split(":")[0].split("=")[0].strip()
                       for a in signature[1].split(",") if a.strip()]
    return found


def plugin(name: str, **hooks) -> types.ModuleType:
    """A plugin module called ``name`` implementing ``hooks``."""
    module = types.ModuleType(name)
    for hook_name, function in hooks.items():
        function.__name__ = hook_name
        setattr(module, hook_name, hookimpl(function))
    return module


def descriptors(*names):
    return lambda: [PluginDescriptor(n, dict, f"component {n}") for n in names]


def test_every_hook_is_documented_with_its_exact_signature():
    specs, documented = hook_specs(), documented_hooks()
    assert len(specs) >= 9
    for name, arguments in specs.items():
        assert name in documented, f"hook {name} has no section in docs/hooks.md"
        assert documented[name] == arguments, (
            f"docs/hooks.md documents {name}({', '.join(documented[name])}); hookspecs.py "
            f"declares {name}({', '.join(arguments)})")
    assert not set(documented) - set(specs), "docs/hooks.md documents hooks that do not exist"


def test_every_family_has_a_registration_hook():
    assert set(FAMILIES.values()) <= set(hook_specs())


def test_built_in_plugins_come_through_entry_points():
    assert ("files", "rotorid_files.plugin") in [(e.name, e.value) for e in ENTRY_POINTS]
    manager = new_plugin_manager()
    assert manager.get_plugin("files").__name__ == "rotorid_files.plugin"
    files = registry("data-sources", manager)["files"]
    assert files.provider == "files" and "CSV" in files.summary


def test_registry_sorts_by_name_and_names_the_provider():
    manager = new_plugin_manager([plugin("zeta_plugin", rotorid_estimators=descriptors("z", "b")),
                                  plugin("alpha_plugin", rotorid_estimators=descriptors("m"))],
                                 load_entry_points=False)
    found = registry("estimators", manager)
    assert list(found) == ["b", "m", "z"]
    assert found["m"].provider == "alpha_plugin" and found["z"].provider == "zeta_plugin"


def test_a_name_registered_twice_names_both_providers():
    manager = new_plugin_manager([plugin("first_plugin", rotorid_input_signals=descriptors("3211")),
                                  plugin("second_plugin", rotorid_input_signals=descriptors("3211"))],
                                 load_entry_points=False)
    with pytest.raises(PluginError, match=r"input-signals name '3211' is registered twice: by "
                                          r"'(first|second)_plugin' and by '(second|first)_plugin'"):
        registry("input-signals", manager)


def test_an_unknown_hook_fails_check_pending():
    def rotorid_estimatorz():
        return []

    with pytest.raises(PluginError, match=r"typo_plugin.*is invalid.*rotorid_estimatorz"):
        new_plugin_manager([plugin("typo_plugin", rotorid_estimatorz=rotorid_estimatorz)],
                           load_entry_points=False)


def test_a_hook_with_wrong_arguments_is_rejected():
    def rotorid_case_started(case, extra):
        return None

    with pytest.raises(PluginError, match="bad_arguments"):
        new_plugin_manager([plugin("bad_arguments", rotorid_case_started=rotorid_case_started)],
                           load_entry_points=False)


@pytest.mark.parametrize("returned, fragment", [
    (lambda: PluginDescriptor("solo", dict, "one"), "must return an iterable of PluginDescriptor"),
    (lambda: "output-error", "must return an iterable"),
    (lambda: [("output-error", dict, "tuple")], "must yield PluginDescriptor objects"),
    (lambda: [PluginDescriptor("", dict, "no name")], "needs a non-empty name"),
    (lambda: [PluginDescriptor("x", "not callable", "bad factory")], "factory must be callable"),
    (lambda: [PluginDescriptor("x", dict, None)], "summary must be a string"),
])
def test_malformed_descriptors_name_the_plugin(returned, fragment):
    manager = new_plugin_manager([plugin("sloppy_plugin", rotorid_estimators=returned)],
                                 load_entry_points=False)
    with pytest.raises(PluginError, match=rf"plugin 'sloppy_plugin': .*{fragment}"):
        registry("estimators", manager)


@attrs.frozen
class RecordingEstimator:
    """An estimator that only records the options it was built with."""

    tolerance: float = 0.0

    def estimate(self, structure, maneuvers, *, start=None):
        raise NotImplementedError


def test_create_builds_with_options_and_lists_alternatives():
    registers = lambda: [PluginDescriptor("output-error", RecordingEstimator, "rec")]  # noqa: E731
    manager = new_plugin_manager([plugin("p", rotorid_estimators=registers)],
                                 load_entry_points=False)
    built = create("estimators", "output-error", manager, tolerance=1e-6)
    assert built == RecordingEstimator(1e-6)
    with pytest.raises(PluginError, match=r"no estimator named 'ls'; available: output-error"):
        create("estimators", "ls", manager)
    with pytest.raises(PluginError, match="unknown plugin family 'estimator'"):
        registry("estimator", manager)


def test_lifecycle_hooks_reach_observers():
    seen = []

    def rotorid_reduction_step(case, step):
        seen.append((case, step))

    manager = new_plugin_manager([plugin("observer", rotorid_reduction_step=rotorid_reduction_step)],
                                 load_entry_points=False)
    notify("rotorid_reduction_step", manager, case="hover", step=3)
    assert seen == [("hover", 3)]


@pytest.mark.parametrize("entry", ENTRY_POINTS, ids=lambda e: e.name)
def test_plugin_modules_import_cheaply(entry):
    """Importing a plugin module adds no heavy library to what ``import rotorid`` loads."""
    script = textwrap.dedent(f"""
        import sys
        import rotorid
        before = set(sys.modules)
        import {entry.value}
        heavy = ("scipy", "matplotlib", "rotorid_files.formats")
        print(" ".join(sorted(m for m in set(sys.modules) - before if m.split(".")[0] in heavy
                               or m in heavy)))
    """)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            check=True)
    assert result.stdout.strip() == "", f"{entry.value} imports {result.stdout.strip()}"


def test_reading_files_does_load_scipy_only_for_mat(tmp_path):
    """The probe above can fail: the files source does import scipy once a .mat is read."""
    script = textwrap.dedent(f"""
        import sys
        import numpy as np
        from rotorid.data import Maneuver
        from rotorid_files.formats import read_maneuver, write_maneuver
        m = Maneuver("m", np.arange(3.0), np.zeros((3, 4)), np.zeros((3, 8)))
        read_maneuver(write_maneuver(m, {str(tmp_path / 'm.npz')!r}))
        print("scipy.io" in sys.modules, end=" ")
        read_maneuver(write_maneuver(m, {str(tmp_path / 'm.mat')!r}))
        print("scipy.io" in sys.modules)
    """)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            check=True)
    assert result.stdout.split() == ["False", "True"]


# ----------------------------------------------------------------- explicit managers
class StepObserver:
    """An observer plugin collecting the reduction steps it is told about."""

    def __init__(self):
        self.steps = []

    @hookimpl
    def rotorid_reduction_step(self, case, step):
        self.steps.append((case, step.index))


def test_register_plugin_validates_and_leaves_a_bad_plugin_out():
    manager = new_plugin_manager(load_entry_points=False)
    observer = StepObserver()
    assert register_plugin(observer, manager, name="observer") == "observer"
    assert manager.get_plugin("observer") is observer

    def rotorid_case_started(case, extra):
        return None

    bad = plugin("bad_arguments", rotorid_case_started=rotorid_case_started)
    with pytest.raises(PluginError, match=r"plugin 'bad_arguments' is invalid(.|\n)*extra"):
        register_plugin(bad, manager)
    assert manager.get_plugin("bad_arguments") is None

    def rotorid_estimatorz():
        return []

    typo = plugin("typo_plugin", rotorid_estimatorz=rotorid_estimatorz)
    with pytest.raises(PluginError, match=r"typo_plugin.*is invalid.*rotorid_estimatorz"):
        register_plugin(typo, manager)
    assert manager.get_plugin("typo_plugin") is None
    with pytest.raises(PluginError, match="cannot be registered.*register each plugin once"):
        register_plugin(observer, manager, name="again")


def test_notify_reaches_the_manager_given_or_made_current():
    given, current = StepObserver(), StepObserver()
    first = new_plugin_manager([given], load_entry_points=False)
    second = new_plugin_manager([current], load_entry_points=False)
    notify("rotorid_reduction_step", first, case="a", step=types.SimpleNamespace(index=1))
    with using(second):
        assert current_manager() is second
        notify("rotorid_reduction_step", case="b", step=types.SimpleNamespace(index=2))
    assert current_manager() is get_plugin_manager()
    assert given.steps == [("a", 1)] and current.steps == [("b", 2)]


def test_reduce_notifies_its_manager_and_estimates_inside_it():
    """A stub estimator (its estimate from the Estimate builder) and the built-in Cramér-Rao
    criterion: M_u's bound is 100 % of its value, so it goes; the hooks reach ``manager``."""
    structure = rotorid.ModelStructure(rotorid.FlightCondition.from_airspeed(0.0),
                                       [rotorid.Derivative("M_q"), rotorid.Derivative("M_u")])
    residuals = [np.ones((4, 8))]
    managers = []

    class StubEstimator:
        def estimate(self, structure, maneuvers, *, start=None):
            managers.append(current_manager())
            values = {"M_q": -2.0, "M_u": 0.1}
            names = structure.parameter_names
            information = 100.0 * np.eye(len(names))         # bounds 0.1: M_u's is 100 %
            return rotorid.Estimate.from_fit(structure, [values[n] for n in names],
                                             information, residuals, estimator="stub")

    observer = StepObserver()
    manager = new_plugin_manager([observer])
    criterion = create("reduction-criteria", "cramer-rao", manager)
    path = reduce(structure, None, StubEstimator(), [criterion], case="stub", manager=manager)
    assert [s.removal.parameter for s in path.steps[1:]] == ["M_u"]
    assert observer.steps == [("stub", 0), ("stub", 1)]
    assert managers == [manager, manager]


@attrs.frozen
class FlatEnvelope:
    """±3 dB, ±30° everywhere (a bounds-kind envelope)."""

    name: str = "flat"
    kind: str = "bounds"
    provenance: str = "a test"
    verified: bool = False
    threshold: float = 0.8

    def bounds(self, omega):
        ones = np.ones_like(omega)
        return EnvelopeBounds(self.name, omega, -3 * ones, 3 * ones, -30 * ones, 30 * ones,
                              np.zeros(omega.shape, bool))

    def check(self, error, coherence, omega):
        return check_bounds(self, error, coherence, omega)


def test_envelopes_by_name_come_from_the_manager_given():
    registers = lambda: [PluginDescriptor("flat", FlatEnvelope, "test")]  # noqa: E731
    manager = new_plugin_manager([plugin("flat_plugin", rotorid_validation_envelopes=registers)],
                                 load_entry_points=False)
    assert envelopes_by_name(["flat"], manager) == {"flat": FlatEnvelope()}
    with pytest.raises(PluginError, match="no validation envelope named 'muad'"):
        envelopes_by_name(["muad"], manager)


def test_study_resume_default_is_the_command_lines():
    from rotorid.cli.main import build_parser
    from rotorid.study.pipeline import Study

    study = build_parser().parse_args(["study", "hover", "--out", "results"])
    assert inspect.signature(Study).parameters["resume"].default is study.resume is False


# ----------------------------------------------------------------- contracts
#: Options that build one component of each registered input signal.
SIGNAL_OPTIONS = {"sweep": dict(amplitude=1.0, omega_min=0.5, omega_max=10.0, sweep_time=20.0)}


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_every_installed_component_satisfies_its_contract(family):
    for name in registry(family):
        options = (SIGNAL_OPTIONS.get(name, dict(amplitude=1.0, step_width=0.5))
                   if family == "input-signals" else {})
        component = create(family, name, **options)
        assert violations(family, component) == (), (family, name)
        assert isinstance(component, CONTRACTS[family])


def test_create_names_the_plugin_the_component_and_what_is_missing():
    @attrs.frozen
    class HalfEnvelope:
        name: str = "half"
        provenance: str = ""
        verified: bool = False
        threshold: float = 0.8
        check: str = "not callable"

    registers = lambda: [PluginDescriptor("half", HalfEnvelope, "test")]  # noqa: E731
    manager = new_plugin_manager([plugin("half_plugin", rotorid_validation_envelopes=registers)],
                                 load_entry_points=False)
    with pytest.raises(PluginError, match=r"plugin 'half_plugin': validation-envelopes component "
                                          r"'half' does not satisfy the ValidationEnvelope "
                                          r"contract: missing kind; missing bounds; check is not "
                                          r"callable; see docs/plugins.md"):
        create("validation-envelopes", "half", manager)


def test_an_envelope_kind_must_be_bounds_or_cost():
    assert violations("validation-envelopes", FlatEnvelope()) == ()
    odd = types.SimpleNamespace(**attrs.asdict(FlatEnvelope()), bounds=len, check=len)
    odd.kind = "score"
    assert violations("validation-envelopes", odd) == (
        "kind 'score' is not one of bounds, cost",)


def test_a_command_module_is_a_command():
    from rotorid.cli.commands import identify

    assert violations("commands", identify) == ()
    assert violations("commands", types.ModuleType("empty")) == ("missing add_arguments",
                                                                 "missing run")


def test_every_contract_member_is_documented_in_the_plugins_table():
    documented = documented_contracts()
    assert set(documented) == set(CONTRACTS)
    for family, protocol in CONTRACTS.items():
        expected = {name: contract_arguments(protocol, name) for name in members(protocol)}
        assert documented[family] == expected, (
            f"docs/plugins.md documents {family} as {documented[family]}; "
            f"rotorid/plugin/contracts.py declares {expected}")


def contract_arguments(protocol: type, name: str) -> list[str] | None:
    """The argument names of a contract method (without self), None for an attribute."""
    member = vars(protocol).get(name)
    if not callable(member):
        return None
    return [p for p in inspect.signature(member).parameters if p != "self"]


def documented_contracts() -> dict[str, dict[str, list[str] | None]]:
    """Family → member → argument names (None for attributes) from docs/plugins.md's table.

    A row reads ``| `family` (`hook`) | `Protocol`: `method(a, b) -> R`, `attribute: type` |``.
    """
    table = re.search(r"<!-- contracts -->\n(.*?)<!-- /contracts -->", PLUGINS_DOC.read_text(),
                      re.S)
    assert table, "docs/plugins.md: no <!-- contracts --> table"
    found = {}
    for row in table[1].splitlines()[2:]:
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", row.strip().strip("|"))]
        family = re.match(r"`([^`]+)`", cells[0])[1]
        entries = {}
        for span in re.findall(r"`([^`]+)`", cells[1])[1:]:
            call = re.match(r"([\w]+)\((.*?)\)", span)
            if call:
                entries[call[1]] = [a.split("=")[0].split(":")[0].strip()
                                    for a in call[2].split(",")
                                    if a.strip() and a.strip() != "*"]
            else:
                entries[span.split(":")[0].strip()] = None
        found[family] = entries
    return found


def test_a_study_with_a_manager_refuses_a_process_pool(tmp_path):
    from rotorid.errors import StudyError
    from rotorid.study.case import FlightCase
    from rotorid.study.pipeline import Study

    case = FlightCase.load(Path(__file__).parent / "cases" / "tiny.toml")
    with pytest.raises(StudyError, match="cannot be sent to other processes"):
        Study([case], tmp_path, executor="process", manager=new_plugin_manager())


def test_create_names_the_options_a_factory_takes():
    """A misspelt or missing option names the options the factory's signature takes (the
    built-in multisteps' amplitude, step_width …), also for a factory that takes none."""
    with pytest.raises(PluginError, match=r"input signal '3211' has no option 'amplitud'; "
                                          r"its options: amplitude, step_width, start"):
        create("input-signals", "3211", amplitud=3.0)
    with pytest.raises(PluginError, match=r"input signal '3211' needs options it was not "
                                          r"given \('amplitude' and 'step_width'\)"):
        create("input-signals", "3211")
    registers = lambda: [PluginDescriptor("bare", lambda: FlatEnvelope(), "test")]  # noqa: E731
    manager = new_plugin_manager([plugin("bare_plugin", rotorid_validation_envelopes=registers)],
                                 load_entry_points=False)
    with pytest.raises(PluginError, match=r"validation envelope 'bare' has no option "
                                          r"'threshold'; its options: none$"):
        create("validation-envelopes", "bare", manager, threshold=0.8)


def test_a_registration_hook_that_raises_is_named():
    def registers():
        raise ModuleNotFoundError("No module named 'heavy'")

    manager = new_plugin_manager([plugin("heavy_plugin", rotorid_input_signals=registers)],
                                 load_entry_points=False)
    with pytest.raises(PluginError, match=r"plugin 'heavy_plugin': rotorid_input_signals "
                                          r"raised ModuleNotFoundError: No module named"):
        registry("input-signals", manager)


def _stub_fit(structure):
    """An Estimate of ``structure`` with M_q = −2, M_u = 0.1, every bound 0.1."""
    names = structure.parameter_names
    values = {"M_q": -2.0, "M_u": 0.1}
    return rotorid.Estimate.from_fit(structure, [values[n] for n in names],
                                     100.0 * np.eye(len(names)), [np.ones((4, 8))],
                                     estimator="stub")


@pytest.mark.parametrize("proposal, message", [
    ("M_u", r"reduction criterion Proposer: propose returned str, not Removal or None"),
    (Removal("Q_zz", "proposer", 1.0, 0.5, "test"),
     r"reduction criterion Proposer: propose proposed 'Q_zz', which is not one of the "
     r"candidates \(M_q, M_u\); fix the criterion"),
])
def test_what_a_plugin_returns_is_checked_where_it_is_used(proposal, message):
    """A criterion returning a name instead of a Removal, or proposing a parameter that is
    no candidate, and an estimator returning a dict each get a PluginError naming them."""
    structure = rotorid.ModelStructure(rotorid.FlightCondition.from_airspeed(0.0),
                                       [rotorid.Derivative("M_q"), rotorid.Derivative("M_u")])

    class Fitter:
        def estimate(self, structure, maneuvers, *, start=None):
            return _stub_fit(structure)

    class Proposer:
        def propose(self, estimate):
            return proposal

        def rank(self, estimate):
            return None

    class DictEstimator:
        def estimate(self, structure, maneuvers, *, start=None):
            return {"M_q": -2.0}

    with pytest.raises(PluginError, match=message):
        reduce(structure, None, Fitter(), [Proposer()], case="stub")
    with pytest.raises(PluginError, match=r"estimator DictEstimator: estimate returned dict, "
                                          r"not Estimate"):
        reduce(structure, None, DictEstimator(), [Proposer()], case="stub")


def test_an_envelopes_bounds_off_the_grid_given_are_named():
    @attrs.frozen
    class ShortEnvelope(FlatEnvelope):
        def bounds(self, omega):
            return FlatEnvelope.bounds(self, omega[:3])

    omega = np.linspace(1.0, 10.0, 20)
    with pytest.raises(PluginError, match=r"validation envelope 'flat': bounds\(omega\) was "
                                          r"asked for 20 frequencies and returned bounds on 3"):
        check_bounds(ShortEnvelope(), np.ones(20, complex), np.ones(20), omega)
    with pytest.raises(rotorid.errors.VerificationError, match=r"envelope 'x': bounds on 3 "
                                                               r"frequencies need arrays"):
        EnvelopeBounds("x", omega[:3], np.ones(2), np.ones(3), np.ones(3), np.ones(3),
                       np.zeros(3, bool))


def test_a_plugins_cost_is_not_reported_as_the_mismatch_cost():
    """A cost-kind envelope of one's own: its score is a cost without J's guideline and
    without margins it does not have; the mismatch cost keeps J and its guideline."""
    from rotorid.verification.envelopes import EnvelopeCheck

    points = np.ones(3)
    nan = np.full(3, np.nan)

    def check(name, guideline):
        return EnvelopeCheck(name, "a test", True, points, points, points, points,
                             np.ones(3, bool), np.ones(3, bool), np.zeros(3, bool), nan, nan,
                             0.8, True, "pass", 0.25, guideline)

    own = check("rms-db", "")
    assert "; cost 0.25 [" in own.report() and "J =" not in own.report()
    assert "worst margin" not in own.report() and "cost_guideline" not in own.summary()
    mismatch = check("mismatch-cost", "J ≤ 100 (a few pairs ≤ 200, average ≤ 100)")
    assert "; J = 0.2 (guideline J ≤ 100" in mismatch.report()
    assert mismatch.summary()["cost_guideline"].startswith("J ≤ 100")


def test_a_removal_states_its_criterions_own_unit():
    assert Removal("M_u", "cramer-rao", 47.34, 30.0, "bound").metric_text == "47.3 %"
    assert Removal("M_u", "t-ratio", 0.52, 2.0, "small", unit="").metric_text == "0.52"
