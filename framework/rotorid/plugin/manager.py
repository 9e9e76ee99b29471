"""Plugin discovery: the plugin manager and the registries of named components.

Built-in plugins are registered exactly like third-party ones, through the ``rotorid``
entry-point group in ``pyproject.toml``. :func:`get_plugin_manager` builds the manager once
per process; :func:`new_plugin_manager` builds a separate one and :func:`register_plugin` adds
an in-process plugin to either, checked. :func:`registry` gives one family's components by
name; :func:`create` builds one and checks it against its family's contract
(:mod:`rotorid.plugin.contracts`); :func:`notify` calls a lifecycle hook.

Which manager: every function here takes ``manager=None``, meaning the manager of the
innermost :func:`using` block (``Study(manager=...)`` and the ``rotorid`` commands run inside
one), else the process-wide one. So a component that calls :func:`notify` itself (an
estimator reporting iterations) reaches the observers of the run that created it.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import importlib.metadata
import inspect
from collections.abc import Iterable, Iterator

import attrs
import pluggy

from rotorid.errors import PluginError
from rotorid.plugin import hookspecs
from rotorid.plugin.contracts import CONTRACTS, violations
from rotorid.plugin.hookspecs import PluginDescriptor

#: Plugin families and the registration hook of each.
FAMILIES = {
    "estimators": "rotorid_estimators",
    "reduction-criteria": "rotorid_reduction_criteria",
    "validation-envelopes": "rotorid_validation_envelopes",
    "data-sources": "rotorid_data_sources",
    "input-signals": "rotorid_input_signals",
    "commands": "rotorid_commands",
}
#: One component of each family, as messages name it.
COMPONENT_OF = {"estimators": "estimator", "reduction-criteria": "reduction criterion",
                "validation-envelopes": "validation envelope", "data-sources": "data source",
                "input-signals": "input signal", "commands": "command"}


@attrs.frozen
class Registered:
    """A registered component: its descriptor and the plugin that provided it."""

    descriptor: PluginDescriptor
    provider: str

    @property
    def name(self) -> str:
        return self.descriptor.name

    @property
    def summary(self) -> str:
        return self.descriptor.summary


def new_plugin_manager(extra_plugins: Iterable[object] = (), load_entry_points: bool = True
                       ) -> pluggy.PluginManager:
    """A fresh plugin manager with the hookspecs, entry-point plugins and ``extra_plugins``."""
    manager = pluggy.PluginManager(hookspecs.PROJECT)
    manager.add_hookspecs(hookspecs)
    try:
        if load_entry_points:
            manager.load_setuptools_entrypoints(hookspecs.PROJECT)
    except Exception as error:                 # a plugin's import may raise anything
        raise _import_failure(error) from error
    _checked(manager.check_pending)
    for plugin in extra_plugins:
        register_plugin(plugin, manager)
    return manager


def _import_failure(error: Exception) -> PluginError:
    """What a failing ``rotorid`` entry point gets: the entry point that fails to import
    (each tried again), its distribution and the error."""
    for entry_point in importlib.metadata.entry_points(group=hookspecs.PROJECT):
        try:
            entry_point.load()
        except Exception as failure:           # the one that fails, whatever it raises
            distribution = entry_point.dist.name if entry_point.dist else "its distribution"
            return PluginError(
                f"plugin {entry_point.name!r} ({entry_point.value}, from {distribution}) "
                f"cannot be imported: {type(failure).__name__}: {failure}; fix it or "
                f"uninstall it (pip uninstall {distribution})")
    return PluginError(f"a plugin of the {hookspecs.PROJECT!r} entry-point group cannot be "
                       f"imported: {type(error).__name__}: {error}; fix or uninstall it")


def register_plugin(plugin: object, manager: pluggy.PluginManager | None = None,
                    name: str | None = None) -> str:
    """Register an in-process ``plugin`` (a module or an object with hook methods), checked.

    Its hooks are validated against the specifications as for an installed plugin (unknown
    hook names, wrong arguments); a bad plugin leaves the manager unchanged and a
    :class:`PluginError` names it. ``manager`` defaults as in :func:`current_manager`.
    Returns the name it was registered under (``manager.unregister(name=...)`` removes it).
    """
    manager = current_manager(manager)
    try:
        registered = _checked(lambda: manager.register(plugin, name=name))
    except ValueError as error:
        reason = str(error).splitlines()[0]
        raise PluginError(f"plugin {name or plugin!r} cannot be registered ({reason}); "
                          f"register each plugin once, under a name of its own") from error
    if registered is None:
        raise PluginError(f"plugin {name or plugin!r} is blocked in this plugin manager")
    try:
        _checked(manager.check_pending)
    except PluginError:
        manager.unregister(name=registered)
        raise
    return registered


def _checked(check):
    """Run ``check`` (hook validation); a pluggy validation error becomes a PluginError."""
    try:
        return check()
    except pluggy.PluginValidationError as error:
        name = getattr(error.plugin, "__name__", None) or type(error.plugin).__name__
        raise PluginError(f"plugin {name!r} is invalid: {error}; fix or uninstall it"
                          ) from error


@functools.lru_cache(maxsize=1)
def get_plugin_manager() -> pluggy.PluginManager:
    """The process-wide plugin manager (entry-point plugins loaded, hooks checked)."""
    return new_plugin_manager()


_ACTIVE: contextvars.ContextVar[pluggy.PluginManager | None] = contextvars.ContextVar(
    "rotorid_plugin_manager", default=None)


@contextlib.contextmanager
def using(manager: pluggy.PluginManager | None) -> Iterator[pluggy.PluginManager]:
    """Make ``manager`` the one ``manager=None`` means inside the block (None: unchanged)."""
    manager = current_manager(manager)
    token = _ACTIVE.set(manager)
    try:
        yield manager
    finally:
        _ACTIVE.reset(token)


def current_manager(manager: pluggy.PluginManager | None = None) -> pluggy.PluginManager:
    """``manager`` if given, else the innermost :func:`using` block's, else the process-wide."""
    return manager or _ACTIVE.get() or get_plugin_manager()


def _descriptors(impl, hook_name: str) -> list:
    """What one plugin's registration hook returned, as a list; errors name the plugin."""
    try:
        result = impl.function() or ()
        if not isinstance(result, Iterable) or isinstance(result, (str, bytes)):
            raise PluginError(f"{hook_name} must return an iterable of PluginDescriptor "
                              f"objects, got {result!r}")
        return list(result)
    except Exception as error:                 # a plugin's hook may raise anything
        what = error if isinstance(error, PluginError) else f"{hook_name} raised " \
            f"{type(error).__name__}: {error}"
        raise PluginError(f"plugin {impl.plugin_name!r}: {what}") from error


def registry(family: str, manager: pluggy.PluginManager | None = None) -> dict[str, Registered]:
    """Components of one family by name, sorted by name.

    Raises :class:`PluginError` for an unknown family, a malformed descriptor, or a name that
    two providers register (both are named).
    """
    if family not in FAMILIES:
        raise PluginError(f"unknown plugin family {family!r}; families: {', '.join(FAMILIES)}")
    manager = current_manager(manager)
    hook_name = FAMILIES[family]
    hook = getattr(manager.hook, hook_name)
    found: dict[str, Registered] = {}
    for impl in hook.get_hookimpls():
        for descriptor in _descriptors(impl, hook_name):
            if not isinstance(descriptor, PluginDescriptor):
                raise PluginError(f"plugin {impl.plugin_name!r}: {hook_name} must yield "
                                  f"PluginDescriptor objects, got {descriptor!r}")
            if descriptor.name in found:
                raise PluginError(
                    f"{family} name {descriptor.name!r} is registered twice: by "
                    f"{found[descriptor.name].provider!r} and by {impl.plugin_name!r}; "
                    f"uninstall or rename one of them")
            found[descriptor.name] = Registered(descriptor, impl.plugin_name)
    return dict(sorted(found.items()))


def create(family: str, name: str, manager: pluggy.PluginManager | None = None, **options):
    """Build the component ``name`` of ``family`` with keyword ``options``.

    Raises :class:`PluginError` for an unknown name, an option the component does not take
    (listing those it does), or when the built component breaks its family's contract
    (naming the plugin, the component and what is missing).
    """
    components = registry(family, manager)
    if name not in components:
        known = ", ".join(components) or "none"
        raise PluginError(f"no {COMPONENT_OF[family]} named {name!r}; available: {known} "
                          f"(see `rotorid plugins`)")
    factory = components[name].descriptor.factory
    try:
        component = factory(**options)
    except TypeError as error:
        taken = ", ".join(_options_of(factory)) or "none"
        if "unexpected keyword argument" in str(error):
            unknown = str(error).rsplit("unexpected keyword argument", 1)[1].strip()
            raise PluginError(f"{COMPONENT_OF[family]} {name!r} has no option {unknown}; "
                              f"its options: {taken}") from None
        if "missing" in str(error) and "required" in str(error):
            raise PluginError(f"{COMPONENT_OF[family]} {name!r} needs options it was not "
                              f"given ({str(error).split(': ', 1)[-1]}); its options: "
                              f"{taken}") from None
        raise
    problems = violations(family, component)
    if problems:
        raise PluginError(
            f"plugin {components[name].provider!r}: {family} component {name!r} does not "
            f"satisfy the {CONTRACTS[family].__name__} contract: {'; '.join(problems)}; "
            f"see docs/plugins.md")
    return component


def _options_of(factory) -> tuple[str, ...]:
    """The keyword options ``factory`` takes: the named parameters of its signature (a
    class's ``__init__``); for a factory taking ``**options`` (or without a signature), the
    attrs fields or ``__init__`` parameters of the component it builds bare (empty when it
    cannot)."""
    keyword = (inspect.Parameter.KEYWORD_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    try:
        parameters = list(inspect.signature(factory).parameters.values())
    except (TypeError, ValueError):            # a builtin without a signature
        parameters = None
    if parameters is not None and all(p.kind != inspect.Parameter.VAR_KEYWORD
                                      for p in parameters):
        return tuple(p.name for p in parameters if p.kind in keyword)
    try:
        component = factory()
    except Exception:                        # a component that needs options: none to list
        return ()
    if attrs.has(type(component)):
        return tuple(f.name for f in attrs.fields(type(component)) if f.init)
    parameters = inspect.signature(type(component).__init__).parameters.values()
    return tuple(p.name for p in parameters if p.name != "self" and p.kind in keyword)


def notify(hook_name: str, manager: pluggy.PluginManager | None = None, **kwargs) -> None:
    """Call a lifecycle hook on every observer plugin of ``manager`` (default: the current
    one, see :func:`current_manager`)."""
    getattr(current_manager(manager).hook, hook_name)(**kwargs)
