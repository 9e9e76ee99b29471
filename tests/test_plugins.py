"""The plugin system: documented hooks, entry points, registries and their failure modes."""

import inspect
import re
import subprocess
import sys
import textwrap
import types
from importlib.metadata import entry_points
from pathlib import Path

import pytest
from rotorid.errors import PluginError
from rotorid.plugin import hookspecs
from rotorid.plugin.hookspecs import PluginDescriptor, hookimpl
from rotorid.plugin.manager import (
    FAMILIES,
    create,
    new_plugin_manager,
    notify,
    registry,
)

DOCS = Path(__file__).resolve().parents[1] / "docs" / "hooks.md"
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


def test_create_builds_with_options_and_lists_alternatives():
    manager = new_plugin_manager([plugin("p", rotorid_estimators=descriptors("output-error"))],
                                 load_entry_points=False)
    assert create("estimators", "output-error", manager, tolerance=1e-6) == {"tolerance": 1e-6}
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
